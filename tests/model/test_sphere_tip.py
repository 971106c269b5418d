"""The torque a spherical fingertip adds (:mod:`regrasp.model.sphere_tip`), against finite differences of the contact
point's forward kinematics: the material point of the distal link that sits at p + r n."""

import math
from pathlib import Path

import numpy as np
import pytest

from regrasp import load_scenario
from regrasp.core.exceptions import InvalidParameterError
from regrasp.model.sphere_tip import sphere_tip_torque

SC2 = load_scenario(Path(__file__).resolve().parents[2] / "examples" / "scenarios" / "paper_trajectory_2.toml")
R_TIP = 2.5e-4  # [m]


def test_the_torque_is_the_contact_points_jacobian_less_the_tips():
    """J_c^T f - J^T f, with J_c the Jacobian of the distal link's point at the contact, p + r n (finite differences
    of that point's forward kinematics)."""
    finger = SC2.contacts[0].finger
    rng = np.random.default_rng(7)
    for _ in range(5):
        q = rng.uniform(-2.0, 2.0, 2)
        n = rng.normal(size=2)
        n /= np.linalg.norm(n)
        f = rng.normal(size=2)

        def contact_point(qq):  # the material point of link 2 that sits at p + r n at q
            turn = (qq[0] + qq[1]) - (q[0] + q[1])
            c, s = math.cos(turn), math.sin(turn)
            return finger.forward_kinematics(qq) + R_TIP * np.array([[c, -s], [s, c]]) @ n

        h = 1e-6
        jac_c = np.column_stack([(contact_point(q + h * e) - contact_point(q - h * e)) / (2 * h) for e in np.eye(2)])
        expected = jac_c.T @ f - finger.tip_jacobian(q).T @ f
        np.testing.assert_allclose(sphere_tip_torque([n], [f], R_TIP), expected, atol=1e-9)
    with pytest.raises(InvalidParameterError):
        sphere_tip_torque([[1.0, 0.0]], [[1.0, 0.0], [0.0, 1.0]], R_TIP)
    with pytest.raises(InvalidParameterError):
        sphere_tip_torque([[1.0, 0.0, 0.0]], [[1.0, 0.0, 0.0]], R_TIP)
    with pytest.raises(InvalidParameterError):
        sphere_tip_torque([[1.0, 0.0]], [[1.0, 0.0]], -R_TIP)

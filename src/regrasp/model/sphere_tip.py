r"""The torque a spherical fingertip adds to the point-contact model's (``docs/derivations.md``, "A second plant").

The control laws model each fingertip as a point, the tip frame p, touching the edge. A real fingertip is a
sphere of radius r centred on p; with the object's edge at distance r from p (the MuJoCo plant's eroded object,
:mod:`regrasp.plants.mujoco.mjcf`), it touches the edge at :math:`c = p + r n` (n the edge's inward normal). The contact
force f on the object (and −f on the finger) acts at c instead of p. Moved to p it is the same force plus a couple

.. math:: d = r\,(n \times f) = r\,f_t \qquad (f_t = t\cdot f, \ t = \perp n),

+d on the object and −d on the distal link. On the finger the couple −d is the generalized force
:math:`-d\,(1, 1)` (both joints turn the distal link). A law that applies :math:`J^T f` at p therefore leaves
the finger short of :math:`d\,(1, 1)`: at r = 0.25 mm and f_t = 0.78 N that decelerates Figure 3.4's slider by
about 1 m/s², and the slide stalls. :func:`sphere_tip_torque` is that missing torque; the object's couple +d is
left to the feedback (it is a small moment on the object, not on a light fingertip).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..core.exceptions import InvalidParameterError
from ..core.validation import as_finite_array, as_positive_float

__all__ = ["sphere_tip_torque"]


def sphere_tip_torque(normals: ArrayLike, forces: ArrayLike, radius: float) -> np.ndarray:
    r"""Joint torques (2m,) [N m] that apply the contact forces at spherical tips' contact points: finger i
    gets :math:`r\,(n_i \times f_i)\,(1, 1)` (module docstring).

    Args:
        normals: Each contact's inward edge normal, hand frame, (m, 2).
        forces: Each contact's force on the object, hand frame, (m, 2) [N].
        radius: The tips' radius r [m].
    """
    n = as_finite_array("normals", normals)
    f = as_finite_array("forces", forces)
    if n.ndim != 2 or n.shape[1] != 2:
        raise InvalidParameterError("normals", n.shape, "one normal per contact, shape (m, 2)")
    if f.shape != n.shape:
        raise InvalidParameterError("forces", f.shape, f"one force per contact, shape {n.shape}")
    r = as_positive_float("radius", radius, allow_zero=True)
    couple = r * (n[:, 0] * f[:, 1] - n[:, 1] * f[:, 0])
    return np.repeat(couple, 2)

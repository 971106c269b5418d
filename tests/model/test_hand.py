"""Hand dynamics from Pinocchio against the textbook closed form of a planar 2R arm, and J̇q̇ against
finite differences."""

from pathlib import Path

import numpy as np
import pytest

from regrasp import Finger, Hand
from regrasp.core import SingularFingerError

ROOT = Path(__file__).resolve().parents[2]
URDF = ROOT / "urdf" / "planar_2r_finger.urdf"


def make_hand(gravity=(0.0, -9.81), damping=True, theta=np.pi / 2):
    f1 = Finger.from_urdf(URDF, base_in_hand=(-0.05, 0.0, theta), configuration="left", name="f1")
    f2 = Finger.from_urdf(URDF, base_in_hand=(0.05, 0.0, theta), configuration="right", name="f2")
    return Hand([f1, f2], gravity_in_hand=gravity, damping=damping)


def textbook_2r(finger, q, v, g_hand, theta_base):
    """M, Coriolis + gravity of a planar 2R arm with links along x (Spong's closed form)."""
    model = finger.model
    m1, m2 = model.inertias[1].mass, model.inertias[2].mass
    c1, c2 = model.inertias[1].lever[0], model.inertias[2].lever[0]
    I1, I2 = model.inertias[1].inertia[2, 2], model.inertias[2].inertia[2, 2]
    l1 = finger.link_lengths[0]
    a, b = q
    M = np.array([
        [m1 * c1**2 + I1 + m2 * (l1**2 + c2**2 + 2 * l1 * c2 * np.cos(b)) + I2,
         m2 * (c2**2 + l1 * c2 * np.cos(b)) + I2],
        [m2 * (c2**2 + l1 * c2 * np.cos(b)) + I2, m2 * c2**2 + I2],
    ])
    hh = -m2 * l1 * c2 * np.sin(b)
    coriolis = np.array([hh * v[1] * (2 * v[0] + v[1]), -hh * v[0] ** 2])
    # gravity torques: tau_g = -d/dq (-m g . com), com in the hand frame
    psi1, psi2 = theta_base + a, theta_base + a + b
    g = np.asarray(g_hand)
    d1 = np.array([-np.sin(psi1), np.cos(psi1)])
    d2 = np.array([-np.sin(psi2), np.cos(psi2)])
    grav = -np.array([
        m1 * c1 * g @ d1 + m2 * (l1 * g @ d1 + c2 * g @ d2),
        m2 * c2 * g @ d2,
    ])
    return M, coriolis + grav


@pytest.mark.parametrize("seed", range(8))
def test_mass_matrix_and_nonlinear_effects_match_the_closed_form(seed):
    rng = np.random.default_rng(seed)
    g = rng.normal(size=2) * 9.81
    hand = make_hand(gravity=g, damping=False)
    q, v = rng.uniform(-np.pi, np.pi, 4), rng.normal(size=4) * 3
    dyn = hand.dynamics(q, v)
    for i, f in enumerate(hand.fingers):
        M, n = textbook_2r(f, q[2 * i:2 * i + 2], v[2 * i:2 * i + 2], g, np.pi / 2)
        np.testing.assert_allclose(dyn.mass_matrix[2 * i:2 * i + 2, 2 * i:2 * i + 2], M, rtol=1e-12, atol=1e-16)
        np.testing.assert_allclose(dyn.nonlinear[2 * i:2 * i + 2], n, rtol=1e-10, atol=1e-13)
    assert np.all(dyn.mass_matrix[0:2, 2:4] == 0)
    assert 0.5 * v @ dyn.mass_matrix @ v == pytest.approx(hand.kinetic_energy(q, v), rel=1e-12)


def test_damping_is_read_from_the_urdf():
    q, v = np.array([0.1, -0.5, 0.2, 0.6]), np.array([1.0, -2.0, 0.5, 0.3])
    with_d, without = make_hand(damping=True).dynamics(q, v), make_hand(damping=False).dynamics(q, v)
    np.testing.assert_allclose(with_d.nonlinear - without.nonlinear, 0.0005 * v, atol=1e-15)


@pytest.mark.parametrize("seed", range(8))
def test_jacobian_dot_times_v_matches_finite_differences(seed):
    rng = np.random.default_rng(seed)
    hand = make_hand()
    q, v = rng.uniform(-np.pi, np.pi, 4), rng.normal(size=4)
    h = 1e-6
    dJ = (hand.jacobian(q + h * v) - hand.jacobian(q - h * v)) / (2 * h)
    # central differences: O(h^2 |v|^3 l) truncation + O(eps l / h) roundoff
    np.testing.assert_allclose(hand.dynamics(q, v).jacobian_dot_v, dJ @ v, atol=1e-9)
    tips = hand.tip_positions(q)
    np.testing.assert_allclose(hand.dynamics(q, v).tips, tips, atol=1e-15)


def test_gravity_in_hand_frame_and_no_mutation():
    finger = Finger.from_urdf(URDF, name="f")
    before = finger.model.gravity.linear.copy()
    up = Hand([finger], gravity_in_hand=(0.0, 9.81))
    down = Hand([finger], gravity_in_hand=(0.0, -9.81))
    q, v = np.array([0.3, 0.4]), np.zeros(2)
    np.testing.assert_allclose(up.dynamics(q, v).nonlinear, -down.dynamics(q, v).nonlinear, rtol=1e-12)
    np.testing.assert_array_equal(finger.model.gravity.linear, before)
    assert up.potential_energy(q) == pytest.approx(-down.potential_energy(q))


def test_singular_finger_is_a_typed_error_carrying_q():
    hand = make_hand()
    q = np.array([0.2, 0.0, 0.1, 0.5])  # finger f1 stretched: theta2 = 0
    with pytest.raises(SingularFingerError) as err:
        hand.check_singular(q)
    assert err.value.finger == "f1"
    np.testing.assert_allclose(err.value.q, [0.2, 0.0])
    assert "f1" in str(err.value) and "condition number" in str(err.value)
    conds = hand.check_singular(np.array([0.2, -1.0, 0.1, 1.0]))
    assert np.all(conds < 10)


def test_link_mass_scale_scales_M_and_gravity_but_not_the_callers_model():
    q, v = np.array([0.1, -0.5, 0.2, 0.6]), np.zeros(4)
    base = make_hand(damping=False)
    heavy = Hand(base.fingers, gravity_in_hand=(0.0, -9.81), damping=False, link_mass_scale=1.5)
    np.testing.assert_allclose(heavy.dynamics(q, v).mass_matrix, 1.5 * base.dynamics(q, v).mass_matrix, rtol=1e-12)
    np.testing.assert_allclose(heavy.dynamics(q, v).nonlinear, 1.5 * base.dynamics(q, v).nonlinear, rtol=1e-12)
    assert base.fingers[0].model.inertias[1].mass == pytest.approx(make_hand().fingers[0].model.inertias[1].mass)


@pytest.mark.parametrize("q, v, name", [
    (np.zeros(4), np.full(4, 1e308), "v"),  # issue 25: the kinetic energy was NaN
    (np.zeros(4), np.full(4, 1e160), "v"),  # (its square overflows)
    (np.full(4, 1e308), np.zeros(4), "q"),  # (q1 + q2 overflows)
    (np.array([0.0, 0.0, 0.0, -2e4]), np.zeros(4), "q"),
])
def test_joint_states_beyond_the_physical_bounds_are_named(q, v, name):
    from regrasp.core.exceptions import InvalidParameterError

    hand = make_hand()
    unit = "rad/s" if name == "v" else "rad"
    for energy in (lambda: hand.kinetic_energy(q, v), lambda: hand.dynamics(q, v)):
        with pytest.raises(InvalidParameterError, match=rf"invalid {name} = .*: expected entries of magnitude at most "
                                                        rf"10000 \[{unit}\]"):
            energy()
    if name == "q":
        with pytest.raises(InvalidParameterError, match="invalid q"):
            hand.potential_energy(q)


def test_kinetic_energy_at_the_largest_joint_speed_is_finite():
    energy = make_hand().kinetic_energy(np.array([0.1, -0.5, 0.2, 0.6]), np.full(4, 1e4))
    assert np.isfinite(energy) and energy > 0.0


def test_closed_form_condition_number_matches_numpy():
    from regrasp.model.hand import condition_2x2

    rng = np.random.default_rng(5)
    for _ in range(500):
        a = rng.normal(size=(2, 2)) * rng.uniform(1e-3, 1e3)
        assert condition_2x2(a) == pytest.approx(np.linalg.cond(a), rel=1e-8)
    assert condition_2x2(np.array([[1.0, 2.0], [2.0, 4.0]])) == float("inf")
    assert condition_2x2(np.zeros((2, 2))) == float("inf")


@pytest.mark.parametrize("seed", range(3))
def test_whole_hand_pass_matches_one_pinocchio_model_per_finger(seed):
    """Hand.dynamics runs one Pinocchio model of the whole hand (the fingers appended as chains from
    the hand frame); every block equals the finger's own model: crba, nonLinearEffects (+ damping),
    the tip's frame Jacobian, classical acceleration and placement."""
    import pinocchio as pin

    rng = np.random.default_rng(seed)
    f1, f2 = make_hand().fingers
    f3 = f1.with_placement(base_in_hand=(0.0, -0.06, 0.3), configuration="right", name="f3")
    hand = Hand([f1, f2, f3], gravity_in_hand=(1.2, -9.0), link_mass_scale=1.3)
    q, v = rng.uniform(-1.5, 1.5, size=6), rng.normal(size=6)
    dyn = hand.dynamics(q, v)
    zero = np.zeros(2)
    for i, f in enumerate(hand.fingers):
        model, fid, sl = hand.finger_models[i], f.tip_frame_id, slice(2 * i, 2 * i + 2)
        data = model.createData()
        qi, vi = q[sl], v[sl]
        np.testing.assert_allclose(dyn.mass_matrix[sl, sl], pin.crba(model, data, qi), rtol=1e-13, atol=1e-18)
        nle = pin.nonLinearEffects(model, data, qi, vi) + np.asarray(model.damping) * vi
        np.testing.assert_allclose(dyn.nonlinear[sl], nle, rtol=1e-13, atol=1e-16)
        jac = pin.computeFrameJacobian(model, data, qi, fid, pin.LOCAL_WORLD_ALIGNED)[:2]
        np.testing.assert_allclose(dyn.jacobian[sl, sl], jac, rtol=1e-13, atol=1e-16)
        pin.forwardKinematics(model, data, qi, vi, zero)
        acc = pin.getFrameClassicalAcceleration(model, data, fid, pin.LOCAL_WORLD_ALIGNED).linear[:2]
        np.testing.assert_allclose(dyn.jacobian_dot_v[sl], acc, rtol=1e-13, atol=1e-16)
        np.testing.assert_allclose(dyn.tips[i], pin.updateFramePlacement(model, data, fid).translation[:2],
                                   rtol=0, atol=1e-16)
        others = np.ones(6, dtype=bool)
        others[sl] = False
        assert not dyn.mass_matrix[sl][:, others].any() and not dyn.jacobian[sl][:, others].any()

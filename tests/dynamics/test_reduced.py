"""The reduced model of paper §3 against finite differences and against the independent plant.

The decisive test for eq. (3.2.11): the reduced dynamics without the paper's extra
G R_f B_v f_ξ term agree with the full-coordinate plant to 1e-8 (relative); with the term
they do not (docs/derivations.md). Both put the sliding contacts at their kinetic coefficient
(random μ_s > μ_k per contact there).
"""

from pathlib import Path

import numpy as np
import pytest

from regrasp import ConvexPolygon, Finger, Grasp, Hand, Plant, PlantContact, ReducedModel
from regrasp.core import SingularFingerError
from regrasp.core.contact import Friction

ROOT = Path(__file__).resolve().parents[2]
URDF = ROOT / "urdf" / "planar_2r_finger.urdf"
RECT = ConvexPolygon.rectangle(0.10, 0.04, mass=0.08)


def make_model(m: int, modes, xi, gravity=(0.0, -9.81)):
    """m = 2: the paper's hand (left/right edges); m = 3 adds a finger under the bottom edge."""
    fingers = [
        Finger.from_urdf(URDF, base_in_hand=(-0.05, 0.0, np.pi / 2), configuration="left", name="f1"),
        Finger.from_urdf(URDF, base_in_hand=(0.05, 0.0, np.pi / 2), configuration="right", name="f2"),
        Finger.from_urdf(URDF, base_in_hand=(0.0, 0.0, np.pi / 2), configuration="left", name="f3"),
    ][:m]
    edges = [1, 3, 2][:m]
    hand = Hand(fingers, gravity_in_hand=gravity)
    return ReducedModel(hand, Grasp(RECT, edges, modes), xi=xi)


CASES = [
    (2, ("fixed", "fixed")),
    (2, ("sliding", "fixed")),
    (2, ("fixed", "sliding")),
    (3, ("fixed", "fixed", "fixed")),
    (3, ("fixed", "sliding", "fixed")),
    (3, ("sliding", "fixed", "sliding")),
]


def random_state(rng, model):
    p = model.grasp.p
    xi = rng.uniform(-0.012, 0.012, size=model.grasp.m)
    model.xi = xi
    S = np.concatenate([[rng.uniform(-0.01, 0.01), rng.uniform(0.115, 0.125), rng.uniform(-0.15, 0.15)],
                        xi[list(model.grasp.sliding)]])
    S_dot = np.concatenate([rng.normal(size=3) * [0.05, 0.05, 0.5],
                            rng.choice([-1, 1], size=p) * rng.uniform(0.005, 0.03, size=p)])
    return S, S_dot


@pytest.mark.parametrize("m,modes", CASES)
@pytest.mark.parametrize("seed", range(4))
def test_H_matches_finite_differences_of_the_joint_positions(m, modes, seed):
    rng = np.random.default_rng(seed)
    model = make_model(m, modes, np.zeros(m))
    S, S_dot = random_state(rng, model)
    st = model.state(S, S_dot)
    h = 1e-6
    dq = (model.joint_positions(S + h * S_dot) - model.joint_positions(S - h * S_dot)) / (2 * h)
    # truncation ~ h^2 |q'''| (< 1e-9 for these rates) + roundoff ~ 1e-16 / h
    np.testing.assert_allclose(st.H @ S_dot, dq, atol=1e-8)
    # and q̇ = H Ṡ moves each tip exactly with its contact point (eq. 3.1.7)
    pose, xi, twist, xi_dot = model.split(S, S_dot)
    tips_dot = (st.hand.jacobian @ st.q_dot).reshape(m, 2)
    r = model.grasp.lever_arms(pose, xi)
    t = model.grasp.surface_frames(pose)[:, :, 1]
    expected = twist[:2] + twist[2] * np.stack([-r[:, 1], r[:, 0]], axis=1) + xi_dot[:, None] * t
    np.testing.assert_allclose(tips_dot, expected, atol=1e-14)


@pytest.mark.parametrize("m,modes", CASES)
@pytest.mark.parametrize("seed", range(4))
def test_H_dot_S_dot_matches_finite_differences(m, modes, seed):
    rng = np.random.default_rng(100 + seed)
    model = make_model(m, modes, np.zeros(m))
    S, S_dot = random_state(rng, model)
    st = model.state(S, S_dot)
    h = 1e-6

    def h_s_dot(s):  # along S(t) = S + t Ṡ (S̈ = 0), d/dt (H Ṡ) = Ḣ Ṡ
        return model.state(s, S_dot).H @ S_dot

    fd = (h_s_dot(S + h * S_dot) - h_s_dot(S - h * S_dot)) / (2 * h)
    np.testing.assert_allclose(st.H_dot_S_dot, fd, atol=1e-7 * max(1.0, np.abs(fd).max()))


def plant_for(model, st, friction, gravity):
    contacts = []
    k = 0
    for i, mode in enumerate(model.grasp.modes):
        sign = 1.0
        if mode.value == "sliding":
            sign = float(np.sign(st.S_dot[3 + k]))
            k += 1
        contacts.append(PlantContact(model.grasp.edges[i].index, mode.value, float(st.xi[i]), sign))
    hand = Hand(model.hand.fingers, gravity_in_hand=gravity)
    plant = Plant(hand, RECT, contacts, friction=friction, collision_check=False)
    plant.reset(st.q, st.q_dot, st.S[:3], st.S_dot[:3])
    return plant


@pytest.mark.parametrize("m,modes", CASES)
@pytest.mark.parametrize("seed", range(5))
def test_reduced_model_and_plant_agree_on_accelerations_and_forces(m, modes, seed):
    rng = np.random.default_rng(200 + seed)
    gravity = rng.normal(size=2) * 5
    model = make_model(m, modes, np.zeros(m), gravity=gravity)
    S, S_dot = random_state(rng, model)
    st = model.state(S, S_dot)
    tau = rng.normal(size=2 * m) * 0.05
    kinetic = rng.uniform(0.0, 0.8, size=m)  # per contact, μ_s = μ_k + 0.1 ... 0.7
    friction = [Friction(k + rng.uniform(0.1, 0.7), k) for k in kinetic]
    S_ddot, forces = model.forward_dynamics(st, tau, friction)
    plant = plant_for(model, st, friction, gravity)
    assert plant.constraint_error(plant.state) < 1e-15
    q_ddot, X_ddot, plant_forces = plant.accelerations(plant.state, tau)

    def rel(a, b):
        return np.abs(a - b).max() / max(np.abs(b).max(), 1e-12)

    assert rel(X_ddot, S_ddot[:3]) < 1e-8
    assert rel(q_ddot, st.H @ S_ddot + st.H_dot_S_dot) < 1e-8
    assert rel(plant_forces, forces) < 1e-8
    # ξ̈ of the sliding contacts, from the plant's own accelerations (rigid-body kinematics), and
    # their forces on the kinetic cone edge, t·f = s μ_k n·f
    pose = st.S[:3]
    for j, i in enumerate(model.grasp.sliding):
        n, t = model.grasp.surface_frames(pose)[i].T
        sign = np.sign(st.S_dot[3 + j])
        assert t @ plant_forces[i] == pytest.approx(sign * kinetic[i] * (n @ plant_forces[i]), rel=1e-12, abs=1e-15)
        assert t @ forces[i] == pytest.approx(sign * kinetic[i] * (n @ forces[i]), rel=1e-12, abs=1e-15)
        J = st.hand.jacobian[2 * i:2 * i + 2, 2 * i:2 * i + 2]
        tip_acc = J @ q_ddot[2 * i:2 * i + 2] + st.hand.jacobian_dot_v[2 * i:2 * i + 2]
        r = st.hand.tips[i] - pose[:2]
        w, w_dot = st.S_dot[2], X_ddot[2]
        t = model.grasp.surface_frames(pose)[i][:, 1]
        point_acc = X_ddot[:2] + w_dot * np.array([-r[1], r[0]]) - w**2 * r
        xi_ddot = t @ (tip_acc - point_acc)  # Coriolis term 2ω ξ̇ n is normal to t
        assert abs(xi_ddot - S_ddot[3 + j]) <= 1e-8 * max(1.0, np.abs(S_ddot).max())


@pytest.mark.parametrize("modes", [("sliding", "fixed"), ("fixed", "sliding")])
def test_the_papers_extra_friction_term_disagrees_with_the_plant(modes):
    """Eq. (3.2.11) as printed adds +G R_f B_v f_ξ to the object rows. With it, the predicted object
    acceleration misses the plant's by far more than rounding; without it, they agree to 1e-8."""
    rng = np.random.default_rng(7)
    model = make_model(2, modes, np.zeros(2))
    S, S_dot = random_state(rng, model)
    st = model.state(S, S_dot)
    tau = rng.normal(size=4) * 0.05
    mu = 0.5
    plant = plant_for(model, st, mu, (0.0, -9.81))
    _, X_ddot, _ = plant.accelerations(plant.state, tau)
    ours, _ = model.forward_dynamics(st, tau, mu)
    paper, _ = model.forward_dynamics(st, tau, mu, paper_friction_term=True)
    scale = np.abs(X_ddot).max()
    assert np.abs(ours[:3] - X_ddot).max() < 1e-8 * scale
    assert np.abs(paper[:3] - X_ddot).max() > 1e-2 * scale
    # at mu = 0 the term vanishes and both agree
    a, _ = model.forward_dynamics(st, tau, 0.0)
    b, _ = model.forward_dynamics(st, tau, 0.0, paper_friction_term=True)
    np.testing.assert_allclose(a, b, rtol=1e-12)


@pytest.mark.parametrize("seed", range(5))
def test_friction_from_P_matches_the_dynamics(seed):
    """m = 2, p = 1: f_ξ = P (M_o Ẍ - f_g) (eq. 3.4.9) equals the friction force of the solved dynamics."""
    rng = np.random.default_rng(300 + seed)
    model = make_model(2, ("sliding", "fixed"), np.zeros(2))
    S, S_dot = random_state(rng, model)
    st = model.state(S, S_dot)
    mu = 0.4
    S_ddot, forces = model.forward_dynamics(st, rng.normal(size=4) * 0.05, mu)
    P = model.grasp.friction_map(S[:3], st.xi, np.sign(S_dot[3:]), mu)
    t1 = model.grasp.surface_frames(S[:3])[0][:, 1]
    assert (P @ (model.M_o @ S_ddot[:3] - model.f_g))[0] == pytest.approx(t1 @ forces[0], rel=1e-9, abs=1e-12)
    # the contacts' generalized force on S is pure friction: its power is -mu lambda_n |xi_dot|
    # (dissipative whenever the contact pushes, lambda_n >= 0)
    gen = model.contact_generalized_force(st, forces)
    n1 = model.grasp.surface_frames(S[:3])[0][:, 0]
    assert np.all(gen[:3] == 0)
    assert gen[3:] @ S_dot[3:] == pytest.approx(-mu * (n1 @ forces[0]) * abs(S_dot[3]), rel=1e-12)


def test_singular_finger_raises_with_q():
    model = make_model(2, ("fixed", "fixed"), np.zeros(2))
    # put the object where finger f1 must stretch fully: the left edge's point at full reach
    reach = sum(model.hand.fingers[0].link_lengths)
    S = np.array([-0.05 + 0.05 + 0.0, reach, 0.0])  # left edge point (x=-0.05, y=reach) is at distance reach
    with pytest.raises(SingularFingerError) as err:
        model.state(S, np.zeros(3))
    assert err.value.finger == "f1" and err.value.q.shape == (2,)


def test_plant_accepts_mismatched_parameters():
    """A plant with other object mass, inertia, mu and link masses predicts other accelerations than
    the nominal model, and agrees with a reduced model built with the same parameters."""
    rng = np.random.default_rng(11)
    model = make_model(2, ("sliding", "fixed"), np.zeros(2))
    S, S_dot = random_state(rng, model)
    st = model.state(S, S_dot)
    tau = rng.normal(size=4) * 0.05
    heavy_hand = Hand(model.hand.fingers, gravity_in_hand=(0.0, -9.81), link_mass_scale=1.3)
    plant = Plant(heavy_hand, RECT, [PlantContact(1, "sliding", st.xi[0], float(np.sign(S_dot[3]))),
                                     PlantContact(3, "fixed", st.xi[1])],
                  friction=0.6, object_mass=0.1, object_inertia=2e-4, collision_check=False)
    plant.reset(st.q, st.q_dot, S[:3], S_dot[:3])
    _, X_plant, _ = plant.accelerations(plant.state, tau)
    nominal, _ = model.forward_dynamics(st, tau, 0.3)
    assert np.abs(nominal[:3] - X_plant).max() > 1e-3 * np.abs(X_plant).max()
    same = ReducedModel(heavy_hand, model.grasp, xi=st.xi, object_mass=0.1, object_inertia=2e-4)
    matched, _ = same.forward_dynamics(same.state(S, S_dot), tau, 0.6)
    np.testing.assert_allclose(matched[:3], X_plant, rtol=1e-8, atol=1e-12)

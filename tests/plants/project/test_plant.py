"""The full-coordinate plant (``regrasp.plants.project.plant``) against physics it must respect.

Set-up: the two-finger hand of ``examples/scenarios/paper_trajectory_2.toml`` holding its
0.10 x 0.04 m rectangle, finger 1 on edge 1 (left side, ξ up), finger 2 on edge 3 (right side,
ξ down). Initial states come from the reduced model (``ReducedModel.state``), and so do the test
inputs: a computed torque :math:`\\tau = M(H\\ddot S + \\dot H\\dot S) + N + J^T f` for a chosen
:math:`\\ddot S` and contact forces f with :math:`G f = M_o\\ddot X - f_g` (class ``Driver``). The
reduced model only produces inputs; what is checked is the plant's response.

* Energy: with no gravity, damping or friction work, :math:`E(t) - E(0)` equals the work of the
  applied torques, summed independently as :math:`\\sum_k \\tau_k\\cdot(q_{k+1} - q_k)` (the torque
  is constant over a step). The torque is a *rubber band* between the fingertips
  (:math:`\\tau = -J^T \\nabla U`, :math:`U = k|p_1 - p_2|^2/2`): an internal squeeze. Zero torque
  is impossible here: a torque-free moving grasp pulls on its contacts (checked below), so they
  separate at the first step. Fixed contacts need μ > 0 (with μ = 0 any tangential force slips);
  friction does no work at fixed contacts, so the fixed-contact case uses μ = 1, and the
  frictionless sliding case slides *both* fingers (the plant allows it).
* Friction: :math:`E(t) - E(0)` = torque + damping + contact work, contact work < 0.
* Events: separation, slip, stick, left_edge, collision, singular, each at a predicted time.
* Forces of a fixed hold under gravity: normal forces > 0, designed forces reproduced, and the
  object's equation holds with the recorded forces (finite differences of V).
* Bad input: typed errors.

``test_stick_holds_the_contact_where_it_stuck`` fails on purpose: after a stick the plant keeps
the step's residual relative velocity at the new fixed contact (see that test).
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pytest

from regrasp import ContactMode, Friction, Grasp, Hand, Plant, PlantContact, ReducedModel, load_scenario
from regrasp.core.events import EventKind
from regrasp.core.exceptions import InvalidParameterError, UnknownEdgeError
from regrasp.core.planar import rotation
from regrasp.model import UrdfCollisionChecker

ROOT = Path(__file__).resolve().parents[3]
SCENARIO = ROOT / "examples" / "scenarios" / "paper_trajectory_2.toml"
EDGES = (1, 3)
GRAVITY = 9.81
DT = 1e-3
EPS = 1e-9  # float slack on event times


# ---------------------------------------------------------------------------- helpers
@functools.lru_cache(maxsize=None)
def scenario():
    return load_scenario(SCENARIO)


def polygon():
    return scenario().polygon


def make_hand(gravity=(0.0, -GRAVITY), damping=True, singular_threshold=1e4) -> Hand:
    return Hand([c.finger for c in scenario().contacts], gravity_in_hand=gravity, damping=damping,
                singular_threshold=singular_threshold)


def surface_frames(beta: float) -> np.ndarray:
    """R(β) [n_i t_i] per contact, (2, 2, 2) (columns: inward normal, ξ direction)."""
    rot = rotation(beta)
    return np.stack([rot @ np.column_stack([polygon().edge(k).inward_normal, polygon().edge(k).xi_direction])
                     for k in EDGES])


def to_surface(beta: float, forces) -> np.ndarray:
    """Hand-frame forces (2, 2) -> (normal, tangential) per contact."""
    frames = surface_frames(beta)
    return np.stack([frames[i].T @ np.asarray(forces)[i] for i in range(2)])


def from_surface(beta: float, surface) -> np.ndarray:
    frames = surface_frames(beta)
    return np.stack([frames[i] @ np.asarray(surface)[i] for i in range(2)])


def start(hand: Hand, modes, xi, S, S_dot, *, friction, model_modes=None, **plant_kw):
    """A plant in the reduced state (S, Ṡ) (sliding signs = sign ξ̇), and that reduced state.

    The reduced model uses a hand with the default singular threshold (its ``state`` refuses
    singular fingers); the plant uses ``hand``.
    """
    model_modes = modes if model_modes is None else model_modes
    model = ReducedModel(make_hand(hand.gravity_in_hand, hand.damping_enabled),
                         Grasp(polygon(), EDGES, model_modes), xi)
    rst = model.state(S, S_dot)
    contacts = []
    for i, (edge, mode) in enumerate(zip(EDGES, modes)):
        sign = float(np.sign(rst.xi_dot[i])) if mode == "sliding" else 1.0
        contacts.append(PlantContact(edge=edge, mode=mode, xi=float(rst.xi[i]), sign=sign or 1.0))
    plant = Plant(hand, polygon(), contacts, friction=friction, dt=DT, **plant_kw)
    plant.reset(rst.q, rst.q_dot, np.asarray(S, float)[:3], np.asarray(S_dot, float)[:3])
    return plant, rst


class Driver:
    """Computed-torque test input from the reduced model (one sliding contact at most).

    ``forces_for`` gives contact forces f (hand frame, on the object) with
    :math:`G f = M_o\\ddot X - f_g` (plus an internal squeeze along null(G) for two fixed
    contacts; unique with a sliding contact); ``torque`` gives
    :math:`\\tau = M(H\\ddot S + \\dot H\\dot S) + N + J^T f`.
    """

    def __init__(self, hand: Hand, modes, xi, friction):
        self.friction = friction
        self.grasp = Grasp(polygon(), EDGES, modes)
        self.model = ReducedModel(make_hand(hand.gravity_in_hand, hand.damping_enabled), self.grasp, xi)

    def reduced(self, plant: Plant):
        st = plant.state
        S, S_dot = list(st.X), list(st.V)
        for i in self.grasp.sliding:
            xi, xi_dot = plant.contact_xi(st, i)
            S.append(xi)
            S_dot.append(xi_dot)
        return self.model.state(S, S_dot)

    def forces_for(self, rst, X_ddot, squeeze: float = 0.0, signs=None) -> np.ndarray:
        w = self.model.M_o @ np.asarray(X_ddot, float) - self.model.f_g
        pose = rst.S[:3]
        if self.grasp.p == 0:
            f = np.linalg.lstsq(rst.G, w, rcond=None)[0]
            null = np.linalg.svd(rst.G)[2][-1]
            frames = surface_frames(pose[2])
            inward = sum(frames[i][:, 0] @ null[2 * i:2 * i + 2] for i in range(2))
            f = f + squeeze * np.sign(inward) * null
        else:
            gf = self.grasp.sliding_grasp_matrix(pose, rst.xi, signs, self.friction)
            eta = np.linalg.solve(gf, w)
            f = self.grasp.surface_rotation(pose) @ self.grasp.force_basis(signs, self.friction) @ eta
        return f.reshape(2, 2)

    def object_acceleration(self, rst, forces) -> np.ndarray:
        """Ẍ = M_o^-1 (G f + f_g) for chosen contact forces."""
        return np.linalg.solve(self.model.M_o, rst.G @ np.asarray(forces).reshape(-1) + self.model.f_g)

    @staticmethod
    def torque(rst, S_ddot, forces) -> np.ndarray:
        q_ddot = rst.H @ np.asarray(S_ddot, float) + rst.H_dot_S_dot
        return rst.hand.mass_matrix @ q_ddot + rst.hand.nonlinear + rst.hand.jacobian.T @ np.asarray(forces).reshape(-1)


def pd(x, x_dot, ref, ref_dot, ref_ddot, wn: float = 40.0) -> np.ndarray:
    """Critically damped tracking acceleration (the torque is held over a step, so open-loop
    feedforward drifts)."""
    x, x_dot = np.asarray(x, float), np.asarray(x_dot, float)
    return (np.asarray(ref_ddot, float) + wn * wn * (np.asarray(ref, float) - x)
            + 2 * wn * (np.asarray(ref_dot, float) - x_dot))


def object_wrench(plant: Plant, st, forces_surface) -> np.ndarray:
    """Σ (f_i, (p_i - x_o) x f_i) from recorded surface forces at state ``st`` (own algebra)."""
    forces = from_surface(st.X[2], forces_surface)
    tips = plant.hand.tip_positions(st.q)
    w = np.zeros(3)
    for i in range(2):
        r = tips[i] - st.X[:2]
        w[:2] += forces[i]
        w[2] += r[0] * forces[i][1] - r[1] * forces[i][0]
    return w


def kinds(events):
    return [(e.kind, e.contact) for e in events]


def slide_torque(driver, plant, S0, xi0, rate):
    """Torques that hold the object at S0 while contact 0 slides from xi0 at ``rate`` [m/s];
    returns (reduced state, τ)."""
    rst = driver.reduced(plant)
    t = plant.state.t
    S_ddot = pd(rst.S, rst.S_dot, [*S0, xi0 + rate * t], [0, 0, 0, rate], [0, 0, 0, 0])
    forces = driver.forces_for(rst, S_ddot[:3], signs=[plant.contacts[0].sign])
    return rst, driver.torque(rst, S_ddot, forces)


def assert_event(step, kind, contact, t_expected):
    """The step reports exactly one event, of this kind and contact, within two steps after t_expected."""
    assert step is not None, f"no {kind} event"
    assert kinds(step.events) == [(kind, contact)]
    t_event = step.events[0].time
    assert t_expected <= t_event <= t_expected + 2 * DT + EPS, (t_event, t_expected)


def run_until_event(plant, driver, torque_fn, max_steps=100, check=None):
    """Step the plant with τ = torque_fn(reduced state, t) until a step reports events.
    Returns that step, or None; ``check(step)`` runs on every event-free step."""
    for _ in range(max_steps):
        rst = driver.reduced(plant)
        step = plant.step(torque_fn(rst, plant.state.t))
        if step.events:
            return step
        if check is not None:
            check(step)
    return None


# ---------------------------------------------------------------------------- 1. energy
K_BAND = 0.5  # [N/m]: about 0.05 N of squeeze at 0.1 m


def band_torque(hand: Hand, q) -> tuple[np.ndarray, float]:
    """τ = -Jᵀ ∇U of a rubber band U = k |p1 - p2|² / 2 between the fingertips, and U."""
    tips = hand.tip_positions(q)
    d = tips[0] - tips[1]
    force = -K_BAND * np.concatenate([d, -d])
    return hand.jacobian(q).T @ force, 0.5 * K_BAND * float(d @ d)


def random_pose_and_twist(rng):
    S = np.array([rng.uniform(-0.005, 0.005), 0.12 + rng.uniform(-0.005, 0.005), rng.uniform(-0.1, 0.1)])
    S_dot = rng.normal(size=3) * np.array([0.01, 0.01, 0.1])
    return S, S_dot


def run_energy(plant: Plant, hand: Hand, steps: int = 1000):
    E0 = plant.energy()
    work = 0.0
    min_normal = np.inf
    xis = []
    for _ in range(steps):
        q0 = plant.state.q.copy()
        tau, _ = band_torque(hand, q0)
        step = plant.step(tau)
        work += float(tau @ (plant.state.q - q0))
        min_normal = min(min_normal, float(step.forces_surface[:, 0].min()))
        xis.append(step.xi)
        assert not step.events, step.events
    return E0, work, min_normal, np.array(xis)


@pytest.mark.parametrize("seed", [0, 1])
def test_energy_conserved_two_fixed_contacts(seed):
    rng = np.random.default_rng(seed)
    hand = make_hand(gravity=(0.0, 0.0), damping=False)
    S, S_dot = random_pose_and_twist(rng)
    xi = rng.uniform(-0.005, 0.005, 2)
    plant, _ = start(hand, ["fixed", "fixed"], xi, S, S_dot, friction=1.0)
    E0, work, min_normal, _ = run_energy(plant, hand)
    st = plant.state
    assert st.t == pytest.approx(1.0)
    drift = abs(plant.energy() - E0 - work) / E0
    assert drift < 1e-6, drift
    assert st.torque_work == pytest.approx(work, rel=1e-9, abs=1e-15)
    assert st.damping_work == 0.0
    assert abs(st.contact_work) < 1e-7 * E0  # fixed contacts do no work (only constraint drift)
    assert plant.max_constraint_error < 1e-9
    assert min_normal > 0.02  # the band squeezes (about 0.05 N)
    assert plant.events == [] and not plant.stopped
    assert [c.mode for c in plant.contacts] == ["fixed", "fixed"]


@pytest.mark.parametrize("seed", [0, 1])
def test_energy_conserved_frictionless_sliding(seed):
    rng = np.random.default_rng(100 + seed)
    hand = make_hand(gravity=(0.0, 0.0), damping=False)
    S, S_dot = random_pose_and_twist(rng)
    xi = rng.uniform(-0.003, 0.003, 2)
    xi_dot = rng.choice([-1.0, 1.0], 2) * rng.uniform(0.001, 0.003, 2)
    # finger 1 slides by the reduced model; finger 2's sliding velocity is added by hand
    plant, rst = start(hand, ["sliding", "sliding"], xi, np.append(S, xi[0]), np.append(S_dot, xi_dot[0]),
                       friction=0.0, model_modes=["sliding", "fixed"])
    t2 = surface_frames(S[2])[1][:, 1]
    v = rst.q_dot.copy()
    v[2:] += np.linalg.solve(rst.hand.jacobian[2:, 2:], t2 * xi_dot[1])
    plant.contacts[1].sign = float(np.sign(xi_dot[1]))
    plant.reset(rst.q, v, S, S_dot)
    for i in range(2):
        assert plant.contact_xi(plant.state, i) == pytest.approx((xi[i], xi_dot[i]), abs=1e-12)
    E0, work, min_normal, xis = run_energy(plant, hand)
    st = plant.state
    drift = abs(plant.energy() - E0 - work) / E0
    assert drift < 1e-6, drift
    assert st.torque_work == pytest.approx(work, rel=1e-9, abs=1e-15)
    assert st.damping_work == 0.0
    assert abs(st.contact_work) < 1e-7 * E0  # μ = 0: normal forces do no work (only constraint drift)
    assert plant.max_constraint_error < 1e-9
    assert min_normal > 0.02
    assert np.abs(xis).max() < 0.02
    assert np.ptp(xis[:, 0]) > 1e-3  # it did slide
    assert plant.events == [] and [c.mode for c in plant.contacts] == ["sliding", "sliding"]


def test_torque_free_motion_pulls_on_contacts():
    """Why the energy tests squeeze: without torque, a moving grasp is held together by tension
    (the tips, carried on circles, need a pull towards the object), which a unilateral contact
    cannot give. The plant agrees with the reduced model's forces and releases both contacts."""
    rng = np.random.default_rng(7)
    hand = make_hand(gravity=(0.0, 0.0), damping=False)
    S, S_dot = random_pose_and_twist(rng)
    plant, rst = start(hand, ["fixed", "fixed"], [0.0, 0.0], S, S_dot, friction=1.0, stop_on=())
    _, f_model = ReducedModel(make_hand((0.0, 0.0), False), Grasp(polygon(), EDGES, ["fixed", "fixed"]),
                              [0.0, 0.0]).forward_dynamics(rst, np.zeros(4))
    step = plant.step(np.zeros(4))
    expected = to_surface(S[2], f_model)
    assert np.all(expected[:, 0] < 0)
    np.testing.assert_allclose(step.forces_surface, expected, rtol=1e-6, atol=1e-12)
    assert kinds(step.events) == [("separation", "finger1"), ("separation", "finger2")]
    assert [c.mode for c in plant.contacts] == ["separated", "separated"]
    assert not plant.stopped  # separation not in stop_on here
    # released, the tips leave their edges: the next step reports how far (the tips' distance from the edges'
    # lines, written here), and no slip
    step = plant.step(np.zeros(4))
    tips = hand.tip_positions(step.state.q).reshape(-1, 2)
    c, s = np.cos(step.state.X[2]), np.sin(step.state.X[2])
    for i, k in enumerate(EDGES):
        e = polygon().edge(k)
        p_obj = np.array([[c, s], [-s, c]]) @ (tips[i] - step.state.X[:2])
        assert step.gap[i] == pytest.approx(-e.inward_normal @ (p_obj - e.xi_origin), abs=1e-12)
    assert (step.gap > 0).all() and (step.slip == 0).all()


# ---------------------------------------------------------------------------- 2. friction
@pytest.mark.parametrize("friction", [Friction(0.3), [Friction(0.7, 0.3), Friction(0.8, 0.6)]],
                         ids=["mu=0.3", "mu_s!=mu_k"])
def test_friction_work_balance(friction):
    """Finger 1 slides up its edge at 10 mm/s (μ_k = 0.3, gravity, joint damping) while the
    object is held still; the energy change is the sum of the three integrated works. With
    μ_s ≠ μ_k (0.7 and 0.3 at the slider, 0.8 and 0.6 at the holder) the slider carries μ_k f_n and
    dissipates μ_k ∫ λ ξ̇ dt: the same run as with μ = 0.3 (the holder stays fixed in both)."""
    mu = 0.3  # the slider's kinetic coefficient in both cases
    hand = make_hand(gravity=(0.0, -GRAVITY), damping=True)
    modes, xi = ["sliding", "fixed"], [-0.015, 0.0]
    S0 = np.array([0.0, 0.12, 0.0])
    xi_dot = 0.01
    plant, _ = start(hand, modes, xi, np.append(S0, xi[0]), [0.0, 0.0, 0.0, xi_dot], friction=friction)
    driver = Driver(hand, modes, xi, friction)
    E0 = plant.energy()
    residuals, lam_xi_dot = [], 0.0
    for k in range(300):
        rst, tau = slide_torque(driver, plant, S0, xi[0], xi_dot)
        step = plant.step(tau)
        assert not step.events, step.events
        assert step.modes == ("sliding", "fixed")
        assert step.xi_dot[0] > 0.5 * xi_dot
        assert np.all(step.forces_surface[:, 0] > 0)
        # friction force on the object is +μ λ along t (the tip drags it)
        assert step.forces_surface[0, 1] == pytest.approx(mu * step.forces_surface[0, 0], rel=1e-12)
        lam_xi_dot += step.forces_surface[0, 0] * 0.5 * (rst.S_dot[3] + step.xi_dot[0]) * DT
        if (k + 1) % 50 == 0:
            st = plant.state
            balance = plant.energy() - E0 - (st.torque_work + st.damping_work + st.contact_work)
            residuals.append(abs(balance) / abs(st.contact_work))
    st = plant.state
    assert st.contact_work < 0 and st.damping_work < 0 and st.torque_work > 0
    assert max(residuals) < 1e-4, residuals
    # the friction dissipation is μ ∫ λ ξ̇ dt (own quadrature of the recorded forces)
    assert st.contact_work == pytest.approx(-mu * lam_xi_dot, rel=1e-2)
    assert plant.max_constraint_error < 1e-7


# ---------------------------------------------------------------------------- 2b. static and kinetic
# The object as an immovable wall (mass and inertia 1e9: under ~1 N it accelerates by ~1e-9 m/s²),
# gravity off. Each finger then meets the wall on its own, and a commanded tip force
# τ = N(q, q̇) + Jᵀ F gives the closed forms below. μ_s = 0.8 and μ_k = 0.4: a slip at μ_k, or a
# slide at μ_s, would be a different event time, force and acceleration.
WALL, MU_S, MU_K = 1e9, 0.8, 0.4


def wall_plant(friction, contacts, v=None) -> Plant:
    """Tips at the middles of edges 1 and 3 of the object (a wall) at (0, 0.12, 0), velocities ``v``."""
    hand = make_hand(gravity=(0.0, 0.0), damping=True)
    q = hand.inverse_kinematics(np.array([[-0.05, 0.12], [0.05, 0.12]]))
    plant = Plant(hand, polygon(), contacts, friction=friction, dt=DT, object_mass=WALL, object_inertia=WALL)
    plant.reset(q, np.zeros(4) if v is None else v, [0.0, 0.12, 0.0], np.zeros(3))
    return plant


def tip_force_torque(plant: Plant, st, forces) -> np.ndarray:
    """τ = N(q, q̇) + Jᵀ F for tip forces F (2, 2) on the object: a tip at rest against the wall,
    held fixed, pushes with exactly F (M q̈ = Jᵀ (F - f) and q̈ = 0)."""
    dyn = plant.hand.dynamics(st.q, st.v)
    return dyn.nonlinear + dyn.jacobian.T @ np.asarray(forces, dtype=float).reshape(-1)


def wall_slide(plant: Plant, st, tau, sign: float, mu_k: float):
    r"""Closed form for finger 1 sliding on the wall (edge 1) at state ``st`` under ``tau``: its tip
    acceleration is :math:`\ddot p = a - \Lambda^{-1} f` with :math:`a = J M^{-1}(\tau - N) + \dot J\dot q`,
    :math:`\Lambda^{-1} = J M^{-1} J^T`, the force :math:`f = \lambda d`, :math:`d = n + \mu_k s t`, and
    the (Baumgarte-stabilised) constraint :math:`n\cdot\ddot p = -2\alpha\dot\psi - \alpha^2\psi` of the
    straight edge, :math:`\psi = n\cdot(p - x_o) - e`, gives
    :math:`\lambda = (n\cdot a + 2\alpha\dot\psi + \alpha^2\psi) / (n\cdot\Lambda^{-1} d)`.
    Returns (f, p̈); the wall's own motion (~1e-9 m/s²) is neglected."""
    dyn = plant.hand.dynamics(st.q, st.v)
    J, M = dyn.jacobian[:2, :2], dyn.mass_matrix[:2, :2]
    tip_inertia_inv = J @ np.linalg.solve(M, J.T)
    free = J @ np.linalg.solve(M, tau[:2] - dyn.nonlinear[:2]) + dyn.jacobian_dot_v[:2]
    edge = polygon().edge(1)
    n, t = rotation(st.X[2]) @ edge.inward_normal, rotation(st.X[2]) @ edge.xi_direction
    psi = n @ (dyn.tips[0] - st.X[:2]) - edge.inward_normal @ edge.xi_origin
    psi_dot = n @ (dyn.tip_velocities[0] - st.V[:2])
    d = n + mu_k * sign * t
    lam = (n @ free + 2 * plant.alpha * psi_dot + plant.alpha**2 * psi) / (n @ tip_inertia_inv @ d)
    return lam * d, free - tip_inertia_inv @ (lam * d)


def test_breakaway_at_the_static_coefficient_then_sliding_at_the_kinetic_one():
    """Finger 1 presses the wall with 1 N and a tangential push along its ξ ramped at μ_s / 40.5 ms
    (finger 2 presses with 1 N). While it is fixed the plant's force is the commanded one (closed
    form: the push itself), so |f_t| / f_n = rate t: the contact holds past μ_k (at 20 ms) and up to
    μ_s, and slips in the step whose force first exceeds μ_s f_n (from t = 41 ms, reported at 42 ms).
    Then it slides with |f_t| = μ_k f_n (to 1e-9), and its force and tip acceleration are the closed
    form of a tip sliding on a wall (:func:`wall_slide`), the object's acceleration
    M_o⁻¹ Σ (f_i, r_i × f_i)."""
    friction = [Friction(MU_S, MU_K), Friction(MU_S, MU_K)]
    plant = wall_plant(friction, [PlantContact(1, ContactMode.FIXED), PlantContact(3, ContactMode.FIXED)])
    push, t_cross = 1.0, 0.0405
    rate = MU_S * push / t_cross  # [N/s]
    (n1, t1), n2 = surface_frames(0.0)[0].T, surface_frames(0.0)[1][:, 0]

    def command(t):
        return [push * n1 + rate * t * t1, push * n2]

    k_slip = int(t_cross / DT) + 1  # the first step whose push exceeds μ_s f_n
    ratios = []
    for k in range(k_slip + 1):
        st = plant.state.copy()
        step = plant.step(tip_force_torque(plant, st, command(st.t)))
        assert step.modes[0] is ContactMode.FIXED
        np.testing.assert_allclose(step.forces_surface[0], [push, rate * st.t], rtol=0, atol=1e-9)
        f_n, f_t = step.forces_surface[0]
        ratios.append(abs(f_t) / f_n)
        if k < k_slip:
            assert not step.events, (k, step.events)
            assert abs(f_t) <= MU_S * f_n
    assert max(ratios[:k_slip]) > MU_K + 0.35  # held far past μ_k f_n ...
    assert ratios[k_slip - 1] < MU_S < ratios[k_slip]  # ... and slipped where the force crossed μ_s f_n
    assert kinds(step.events) == [("slip", "finger1")]
    assert step.events[0].time == pytest.approx((k_slip + 1) * DT)
    assert plant.contacts[0].mode is ContactMode.SLIDING and plant.contacts[0].sign == 1.0
    assert plant.contacts[1].mode is ContactMode.FIXED
    speeds = []
    for _ in range(3):
        st = plant.state.copy()
        tau = tip_force_torque(plant, st, command(st.t))
        force, tip_acceleration = wall_slide(plant, st, tau, 1.0, MU_K)
        q_ddot, X_ddot, forces = plant.accelerations(st, tau)
        step = plant.step(tau)
        assert not step.events and step.modes == (ContactMode.SLIDING, ContactMode.FIXED)
        f_n, f_t = step.forces_surface[0]
        assert f_t / f_n == pytest.approx(MU_K, rel=0, abs=1e-9)
        np.testing.assert_allclose(forces[0], force, rtol=1e-9)
        dyn = plant.hand.dynamics(st.q, st.v)
        # (the closed form neglects the wall's motion, ~1e-9 m/s², against ~100 m/s² of tip acceleration)
        np.testing.assert_allclose(dyn.jacobian[:2, :2] @ q_ddot[:2] + dyn.jacobian_dot_v[:2], tip_acceleration,
                                   rtol=0, atol=1e-8)
        r = dyn.tips - st.X[:2]
        wrench = [forces[:, 0].sum(), forces[:, 1].sum(),
                  float(np.sum(r[:, 0] * forces[:, 1] - r[:, 1] * forces[:, 0]))]
        np.testing.assert_allclose(X_ddot, np.array(wrench) / [WALL, WALL, WALL], rtol=1e-9, atol=1e-22)
        speeds.append(step.xi_dot[0])
    assert 0.0 < speeds[0] < speeds[1] < speeds[2]  # the push exceeds the kinetic friction: it speeds up


@pytest.mark.parametrize("mu_s,sticks", [(MU_S, True), (0.5, False)], ids=["inside", "outside"])
def test_a_reversing_slider_sticks_only_inside_its_static_cone(mu_s, sticks):
    """Finger 1 slides down the wall at 0.3 m/s (μ_k = 0.4) while it is commanded to push with 1 N and
    0.6 N up its edge: friction and the push stop it within a few ms. Where ξ̇ reverses, the fixed-
    contact force is the push (|f_t| / f_n = 0.6, the tip at rest against the wall): inside the static
    cone for μ_s = 0.8, so it sticks and then holds that force; outside it for μ_s = 0.5 (though
    0.6 > μ_k), so it keeps sliding, now up, with |f_t| = μ_k f_n and speeding up."""
    hand = make_hand(gravity=(0.0, 0.0), damping=True)
    q = hand.inverse_kinematics(np.array([[-0.05, 0.12], [0.05, 0.12]]))
    t1 = surface_frames(0.0)[0][:, 1]
    v = np.zeros(4)
    v[:2] = np.linalg.solve(hand.jacobian(q)[:2, :2], -0.3 * t1)
    plant = wall_plant(Friction(mu_s, MU_K), [PlantContact(1, ContactMode.SLIDING, 0.0, -1.0),
                                              PlantContact(3, ContactMode.FIXED)], v)
    (n1, _), n2 = surface_frames(0.0)[0].T, surface_frames(0.0)[1][:, 0]
    push = [n1 + 0.6 * t1, n2]
    events, reversed_at = [], None
    for k in range(30):
        step = plant.step(tip_force_torque(plant, plant.state, push))
        events += step.events
        if reversed_at is None and step.xi_dot[0] > 0:
            reversed_at = k
        if reversed_at is None or k == reversed_at:
            assert step.modes[0] is ContactMode.SLIDING
            assert step.forces_surface[0, 1] == pytest.approx(-MU_K * step.forces_surface[0, 0], rel=1e-12)
        elif sticks:
            assert step.modes[0] is ContactMode.FIXED
            f_n, f_t = step.forces_surface[0]
            assert f_t / f_n == pytest.approx(0.6, abs=1e-6) and f_t <= mu_s * f_n
        else:
            assert step.modes[0] is ContactMode.SLIDING and step.xi_dot[0] > 0
            assert step.forces_surface[0, 1] == pytest.approx(MU_K * step.forces_surface[0, 0], rel=1e-12)
    assert reversed_at is not None and reversed_at >= 1
    if sticks:
        assert kinds(events) == [("stick", "finger1")]
        assert events[0].time == pytest.approx((reversed_at + 1) * DT)
    else:
        assert events == [] and plant.contacts[0].sign == 1.0


# ---------------------------------------------------------------------------- 3. events
def test_separation_event():
    """Finger 1's normal force is ramped from +0.2 N to -0.2 N (gravity off, finger 2 keeps
    pushing with 0.2 N, the object accelerates accordingly): it separates when the ramp crosses 0."""
    hand = make_hand(gravity=(0.0, 0.0), damping=True)
    modes, xi = ["fixed", "fixed"], [0.0, 0.0]
    S0 = np.array([0.0, 0.12, 0.0])
    plant, _ = start(hand, modes, xi, S0, np.zeros(3), friction=1.0)
    driver = Driver(hand, modes, xi, 1.0)
    t_cross = 0.0405  # between two steps
    normal = lambda t: 0.2 * (1.0 - t / t_cross)  # noqa: E731
    def torque(rst, t):
        forces = from_surface(rst.S[2], [[normal(t), 0.0], [0.2, 0.0]])
        return driver.torque(rst, driver.object_acceleration(rst, forces), forces)

    def pushing(step):
        assert np.all(step.forces_surface[:, 0] > 0)

    event_step = run_until_event(plant, driver, torque, check=pushing)
    assert_event(event_step, "separation", "finger1", t_cross)
    assert [c.mode for c in plant.contacts] == ["separated", "fixed"]
    assert plant.stopped
    with pytest.raises(InvalidParameterError):
        plant.step(np.zeros(4))


def test_slip_event():
    """μ = 0.05, 1 N squeeze, a tangential push on finger 1 ramped at 1 N/s (gravity off; the
    object accelerates and turns accordingly): finger 1 slips when the push exceeds μ f_n."""
    mu, squeeze, t_slip = 0.05, 1.0, 0.0505
    rate = mu * squeeze / t_slip  # [N/s]
    hand = make_hand(gravity=(0.0, 0.0), damping=True)
    modes, xi = ["fixed", "fixed"], [0.0, 0.0]
    plant, _ = start(hand, modes, xi, [0.0, 0.12, 0.0], np.zeros(3), friction=mu)
    driver = Driver(hand, modes, xi, mu)
    def torque(rst, t):
        forces = from_surface(rst.S[2], [[squeeze, rate * t], [squeeze, 0.0]])
        return driver.torque(rst, driver.object_acceleration(rst, forces), forces)

    event_step = run_until_event(plant, driver, torque)
    assert_event(event_step, "slip", "finger1", t_slip)
    assert plant.contacts[0].mode == "sliding" and plant.contacts[1].mode == "fixed"
    assert plant.contacts[0].sign == np.sign(event_step.forces_surface[0, 1]) == 1.0
    assert not plant.stopped  # slip is not in stop_on
    # the push keeps growing: finger 1 then slides the way it was pushed (ξ̇ > 0, speeding up)
    speeds = []
    for _ in range(10):
        rst = driver.reduced(plant)
        forces = from_surface(rst.S[2], [[squeeze, rate * plant.state.t], [squeeze, 0.0]])
        step = plant.step(driver.torque(rst, driver.object_acceleration(rst, forces), forces))
        assert not step.events, step.events
        assert step.modes == ("sliding", "fixed")
        # Coulomb: on the cone, in the sliding direction
        assert step.forces_surface[0, 1] == pytest.approx(mu * step.forces_surface[0, 0], rel=1e-12)
        speeds.append(step.xi_dot[0])
    assert speeds[0] > 0 and np.all(np.diff(speeds) > 0)


def test_stick_event():
    """μ = 1, gravity on, the object held still: finger 1 slides up at 50 mm/s and is decelerated
    at 5 m/s² (the torque then pushes less than friction can hold): it sticks when ξ̇ reaches 0,
    at t = 10 ms, and the contact becomes fixed where it stopped.

    (Joint damping is off here: the URDF's 0.002 N m s/rad on the 3 g distal link is a ~1 ms
    mode that a torque held over 1 ms steps cannot command precisely; it would only delay the
    stop, not change the event.)"""
    plant, event_step, previous = run_until_stick()
    t_stop = STICK_V0 / STICK_DECEL
    assert event_step is not None and previous is not None
    assert kinds(event_step.events) == [("stick", "finger1")]
    t_event = event_step.events[0].time
    assert t_stop - DT <= t_event <= t_stop + 2 * DT + EPS, t_event
    # reported on the first step that ends with ξ̇ <= 0 (the one before still slid up)
    assert event_step.xi_dot[0] <= 0 < previous.xi_dot[0]
    assert event_step.state.t == pytest.approx(previous.state.t + DT)
    assert plant.contacts[0].mode == "fixed" and plant.contacts[1].mode == "fixed"
    assert plant.contacts[0].xi == pytest.approx(event_step.xi[0], abs=1e-12)
    assert not plant.stopped


STICK_V0, STICK_DECEL, STICK_XI, STICK_S0 = 0.05, 5.0, [-0.01, -0.01], np.array([0.0, 0.12, 0.0])


def run_until_stick():
    """Finger 1 slides up (μ = 1, gravity, object held still) and is decelerated to a stop."""
    mu = 1.0
    hand = make_hand(gravity=(0.0, -GRAVITY), damping=False)
    modes, xi, S0 = ["sliding", "fixed"], STICK_XI, STICK_S0
    v0, decel = STICK_V0, STICK_DECEL
    plant, _ = start(hand, modes, xi, np.append(S0, xi[0]), [0.0, 0.0, 0.0, v0], friction=mu)
    driver = Driver(hand, modes, xi, mu)
    event_step, previous = None, None
    for _ in range(40):
        rst = driver.reduced(plant)
        t = plant.state.t
        ref = [*S0, xi[0] + v0 * t - 0.5 * decel * t * t]
        S_ddot = pd(rst.S, rst.S_dot, ref, [0, 0, 0, v0 - decel * t], [0, 0, 0, -decel])
        forces = driver.forces_for(rst, S_ddot[:3], signs=[plant.contacts[0].sign])
        step = plant.step(driver.torque(rst, S_ddot, forces))
        if step.events:
            event_step = step
            break
        assert step.xi_dot[0] > 0 and step.modes == ("sliding", "fixed")
        previous = step
    return plant, event_step, previous


def test_stick_holds_the_contact_where_it_stuck():
    """After a stick the contact is fixed: the tip must stay at the object point where it stuck,
    with no relative velocity. The plant switches the mode but keeps the step's residual sliding
    velocity (ξ̇ crossed zero somewhere inside the step, here ξ̇ = -4 mm/s at the switch); nothing
    removes it but the Baumgarte term, so the "fixed" tip keeps sliding and drifts off its anchor
    by ~30 µm (constraint error 3e-5 m, against 1e-10 m elsewhere) over the next ~20 ms."""
    plant, event_step, _ = run_until_stick()
    assert kinds(event_step.events) == [("stick", "finger1")]
    xi_stuck = plant.contacts[0].xi
    hand = plant.hand
    hold = Driver(hand, ["fixed", "fixed"], [xi_stuck, STICK_XI[1]], 1.0)
    drift, slip_speed = 0.0, 0.0
    for _ in range(30):
        rst = hold.reduced(plant)
        X_ddot = pd(rst.S, rst.S_dot, STICK_S0, np.zeros(3), np.zeros(3))
        step = plant.step(hold.torque(rst, X_ddot, hold.forces_for(rst, X_ddot, squeeze=2.0)))
        assert not step.events, step.events  # held well inside the cone: no slip
        assert step.modes == ("fixed", "fixed")
        drift = max(drift, abs(step.xi[0] - xi_stuck))
        slip_speed = max(slip_speed, abs(step.xi_dot[0]))
    assert slip_speed < 1e-4, f"a fixed contact slides at {slip_speed:.3g} m/s after the stick"
    assert drift < 1e-6, f"the stuck tip drifts {drift:.3g} m from where it stuck"
    assert plant.max_constraint_error < 1e-6, plant.max_constraint_error


def test_left_edge_event():
    """The hand on its side (gravity along +x: the object rests on finger 2, μ = 0.3): finger 1
    slides up at 0.3 m/s from ξ = 12 mm and leaves its edge (ξ = 20 mm) at t = 26.7 ms."""
    mu = 0.3
    hand = make_hand(gravity=(GRAVITY, 0.0), damping=True)
    modes, xi = ["sliding", "fixed"], [0.012, -0.01]
    S0 = np.array([0.0, 0.12, 0.0])
    v = 0.3
    t_leave = (0.02 - xi[0]) / v
    plant, _ = start(hand, modes, xi, np.append(S0, xi[0]), [0.0, 0.0, 0.0, v], friction=mu)
    driver = Driver(hand, modes, xi, mu)
    event_step, last_xi = None, xi[0]
    for _ in range(60):
        step = plant.step(slide_torque(driver, plant, S0, xi[0], v)[1])
        assert np.all(step.forces_surface[:, 0] > 0)
        if step.events:
            event_step = step
            break
        last_xi = step.xi[0]
    assert_event(event_step, "left_edge", "finger1", t_leave)
    assert last_xi <= 0.02 < event_step.xi[0]
    assert plant.stopped
    assert [c.mode for c in plant.contacts] == ["sliding", "fixed"]  # left_edge switches no mode


def _first_crossing(fun, lo: float, hi: float) -> float:
    """Bisection for the root of fun (fun(lo) < 0 < fun(hi))."""
    assert fun(lo) < 0 < fun(hi)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if fun(mid) < 0 else (lo, mid)
    return 0.5 * (lo + hi)


def test_collision_event():
    """The object, held by both fingers (1 N squeeze, gravity, μ = 1), is turned counter-clockwise
    at 2 rad/s from β = 0.45: finger 2's distal link dips into the object at the angle β* found by
    an own bisection on the static grasp (coal signed distances along the same path)."""
    mu, omega, beta0 = 1.0, 2.0, 0.45
    hand = make_hand(gravity=(0.0, -GRAVITY), damping=True)
    modes, xi = ["fixed", "fixed"], [0.0, 0.0]
    x0, y0 = 0.0, 0.12
    plant, _ = start(hand, modes, xi, [x0, y0, beta0], [0.0, 0.0, omega], friction=mu)
    driver = Driver(hand, modes, xi, mu)
    fingers = [c.finger for c in scenario().contacts]
    radius = max(float(s.geometry.radius) for s in fingers[1].link_shapes() if s.link == 1)
    checkers = [UrdfCollisionChecker(f, polygon(), 3.0 * radius) for f in fingers]

    def min_distance(i, beta):
        q = driver.model.joint_positions([x0, y0, beta])
        return float(checkers[i].signed_distances(q[2 * i:2 * i + 2], np.array([x0, y0, beta])).min())

    assert min_distance(0, beta0) > 0 and min_distance(1, beta0) > 0
    beta_star = _first_crossing(lambda b: -min_distance(1, b), beta0, 0.7)
    assert min_distance(0, beta_star + 0.02) > 0  # finger 1 is clear past β*
    t_star = (beta_star - beta0) / omega

    def torque(rst, t):
        X_ddot = pd(rst.S, rst.S_dot, [x0, y0, beta0 + omega * t], [0, 0, omega], [0, 0, 0])
        return driver.torque(rst, X_ddot, driver.forces_for(rst, X_ddot, squeeze=1.0))

    def clear(step):  # the plant calls coal only where the links may have reached the object: coal agrees
        st = step.state
        assert all(checkers[i].signed_distances(st.q[2 * i:2 * i + 2], st.X).min() >= 0.0 for i in range(2))

    event_step = run_until_event(plant, driver, torque, check=clear)
    assert_event(event_step, "collision", "finger2", t_star)
    st = plant.state
    assert checkers[1].signed_distances(st.q[2:], st.X).min() < 0
    assert plant.stopped
    assert [c.mode for c in plant.contacts] == ["fixed", "fixed"]


def test_singular_event():
    """Both fingers hold the object (finger 1's contact 20 mm above finger 2's) and lift it at
    0.2 m/s; finger 1 stretches first. With singular_threshold = 20 the plant reports it when
    cond(J_1) crosses 20, at the height found by an own bisection on the static grasp."""
    threshold, v = 20.0, 0.2
    hand = make_hand(gravity=(0.0, 0.0), damping=True, singular_threshold=threshold)
    modes, xi = ["fixed", "fixed"], [0.01, 0.01]
    x0, y0 = 0.0, 0.145
    # stretched along its (vertical) edge, finger 1's distal link necessarily dips into the object
    # (the urdf geometry's grazing-angle limit): collisions are not what this test is about
    plant, _ = start(hand, modes, xi, [x0, y0, 0.0], [0.0, v, 0.0], friction=1.0, collision_check=False)
    driver = Driver(hand, modes, xi, 1.0)
    fingers = [c.finger for c in scenario().contacts]

    def cond(i, y):
        q = driver.model.joint_positions([x0, y, 0.0])
        return float(np.linalg.cond(fingers[i].tip_jacobian(q[2 * i:2 * i + 2])))

    y_star = _first_crossing(lambda y: cond(0, y) - threshold, y0, 0.1549)
    assert cond(1, y_star) < threshold / 2
    t_star = (y_star - y0) / v

    def torque(rst, t):
        X_ddot = pd(rst.S, rst.S_dot, [x0, y0 + v * t, 0.0], [0, v, 0], [0, 0, 0])
        return driver.torque(rst, X_ddot, driver.forces_for(rst, X_ddot, squeeze=0.5))

    event_step = run_until_event(plant, driver, torque)
    assert_event(event_step, "singular", "finger1", t_star)
    theta2 = fingers[0].theta2(plant.state.q[:2])
    assert abs(theta2) < 0.3  # nearly stretched
    assert plant.stopped
    assert [c.mode for c in plant.contacts] == ["fixed", "fixed"]


# ---------------------------------------------------------------------------- 4. forces
def test_fixed_hold_forces_and_object_equation():
    """Both fingers hold the object under gravity (1 N squeeze, μ = 1) and move it along a smooth
    path in x, y and β. Every step: normal forces > 0 and the recorded forces are the designed
    ones (the plant agrees with the reduced model); and the object's equation holds with them:
    M_o ΔV/dt - f_g equals the wrench of the recorded forces (own lever arms from the tips) to
    first order, and the mean of the wrenches at both ends of the step (same torque) to second
    order in dt."""
    mu = 1.0
    hand = make_hand(gravity=(0.0, -GRAVITY), damping=True)
    modes, xi = ["fixed", "fixed"], [0.005, -0.008]
    S0 = np.array([0.0, 0.12, 0.0])
    amp, w = np.array([0.01, 0.005, 0.2]), 2 * np.pi * 2.0
    ref = lambda t: (S0 + amp * np.sin(w * t), amp * w * np.cos(w * t), -amp * w * w * np.sin(w * t))  # noqa: E731
    plant, _ = start(hand, modes, xi, S0, amp * w, friction=mu)
    driver = Driver(hand, modes, xi, mu)
    M_o = np.diag([plant.mass, plant.mass, plant.inertia])
    f_g = np.append(plant.mass * hand.gravity_in_hand, 0.0)
    for k in range(250):
        st = plant.state.copy()
        rst = driver.reduced(plant)
        X_ddot = pd(rst.S, rst.S_dot, *ref(st.t))
        forces = driver.forces_for(rst, X_ddot, squeeze=1.0)
        tau = driver.torque(rst, X_ddot, forces)
        step = plant.step(tau)
        assert not step.events, step.events
        assert np.all(step.forces_surface[:, 0] > 0.5)
        np.testing.assert_allclose(step.forces_surface, to_surface(st.X[2], forces), rtol=0, atol=1e-7)
        w_start = object_wrench(plant, st, step.forces_surface)
        # the same torque at the step's end (the plant holds τ over the step)
        _, _, forces_end = plant.accelerations(step.state, tau)
        w_end = object_wrench(plant, step.state, to_surface(step.state.X[2], forces_end))
        lhs = M_o @ (step.state.V - st.V) / DT - f_g
        change = np.abs(w_end - w_start).max()
        first = np.abs(lhs - w_start).max()
        second = np.abs(lhs - 0.5 * (w_start + w_end)).max()
        assert first <= 0.6 * change + 1e-9, (k, first, change)
        assert second <= 0.02 * change + 1e-9, (k, second, change)
    assert np.abs(plant.state.X - ref(plant.state.t)[0]).max() < 1e-3  # it followed the path
    assert plant.max_constraint_error < 1e-8


# ---------------------------------------------------------------------------- 5. bad input
def _plant(contacts, **kw):
    return Plant(make_hand(), polygon(), contacts, **kw)


def test_bad_input():
    good = [PlantContact(1, "fixed"), PlantContact(3, "fixed")]
    with pytest.raises(InvalidParameterError):
        _plant(good[:1])
    with pytest.raises(InvalidParameterError):
        _plant(good + [PlantContact(0, "fixed")])
    with pytest.raises(InvalidParameterError):
        _plant([PlantContact(1, "rolling"), PlantContact(3, "fixed")])
    with pytest.raises(InvalidParameterError):
        _plant([PlantContact(1, "sliding", sign=0.0), PlantContact(3, "fixed")])
    with pytest.raises(UnknownEdgeError):
        _plant([PlantContact(4, "fixed"), PlantContact(3, "fixed")])
    for friction in (-0.1, float("nan"), float("inf"), [0.5], "0.5", None, (0.5, 0.6, 0.7)):
        with pytest.raises(InvalidParameterError):
            _plant(good, friction=friction)
    for kw in ({"dt": 0.0}, {"dt": -1e-3}, {"object_mass": -1.0}, {"baumgarte": -1.0}):
        with pytest.raises(InvalidParameterError):
            _plant(good, **kw)
    plant = _plant(good)
    with pytest.raises(InvalidParameterError):
        plant.step(np.zeros(4))
    with pytest.raises(InvalidParameterError):
        plant.reset(np.zeros(3), np.zeros(4), np.zeros(3), np.zeros(3))
    with pytest.raises(InvalidParameterError):
        plant.reset(np.zeros(4), np.zeros(4), [0.0, np.nan, 0.0], np.zeros(3))
    rst = ReducedModel(make_hand(), Grasp(polygon(), EDGES, ["fixed", "fixed"]), [0.0, 0.0]).state(
        [0.0, 0.12, 0.0], np.zeros(3))
    plant.reset(rst.q, rst.q_dot, [0.0, 0.12, 0.0], np.zeros(3))
    with pytest.raises(InvalidParameterError):
        plant.step(np.zeros(3))
    with pytest.raises(InvalidParameterError):
        plant.step([0.0, 0.0, np.inf, 0.0])


@pytest.mark.parametrize("stop_on", [None, object(), 5, "separation", ["separation", None], ["explosion"]])
def test_stop_on_that_is_no_sequence_of_event_kinds_is_named(stop_on):
    """Issue 25: ``stop_on=None`` or ``object()`` was a ``TypeError`` (not iterable)."""
    with pytest.raises(InvalidParameterError, match="invalid stop_on = .*: expected a sequence of plant event kinds"):
        _plant([PlantContact(1, "fixed"), PlantContact(3, "fixed")], stop_on=stop_on)


def _held(**kw) -> tuple[Plant, np.ndarray]:
    plant = _plant([PlantContact(1, "fixed"), PlantContact(3, "fixed")], **kw)
    rst = ReducedModel(make_hand(), Grasp(polygon(), EDGES, ["fixed", "fixed"]), [0.0, 0.0]).state(
        [0.0, 0.12, 0.0], np.zeros(3))
    return plant, rst.q


@pytest.mark.parametrize("which, value, name, bound", [
    ("q", np.full(4, 1e308), "q", r"10000 \[rad\]"),  # issue 25: a LinAlgError at the step before
    ("v", np.full(4, 1e308), "v", r"10000 \[rad/s\]"),
    ("v", np.full(4, 2e4), "v", r"10000 \[rad/s\]"),
    ("X", [1e5, 0.12, 0.0], "X", r"\(1000, 1000, 10000\) \[m, m, rad\]"),
    ("X", [0.0, 0.12, 1e308], "X", r"\(1000, 1000, 10000\) \[m, m, rad\]"),
    ("V", [0.0, 1e308, 0.0], "V", r"10000 \[m/s, m/s, rad/s\]"),
])
@pytest.mark.parametrize("compiled", [None, False])
def test_reset_refuses_a_state_beyond_the_physical_bounds(compiled, which, value, name, bound):
    plant, q = _held(compiled=compiled)
    state = {"q": q, "v": np.zeros(4), "X": [0.0, 0.12, 0.0], "V": np.zeros(3), which: value}
    with pytest.raises(InvalidParameterError, match=f"invalid {name} = .*: expected entries of magnitude at most "
                                                    f"{bound}"):
        plant.reset(state["q"], state["v"], state["X"], state["V"])


@pytest.mark.parametrize("compiled", [None, False])
@pytest.mark.parametrize("v, V", [(1e4, 0.0), (0.0, 1e4), (1e4, 1e4)])
def test_a_run_that_diverges_ends_in_a_plant_state_error_at_the_last_good_state(compiled, v, V):
    """A reset within the bounds but far from the contacts' constraints (joints at 10 000 rad/s) diverges: with no
    event to stop it, the step whose equations fail or overflow raises a PlantStateError (a LinAlgError, a
    ``math domain error``, an ``OverflowError`` or a NaN before), the plant left at the state it started from."""
    from regrasp.core.exceptions import PlantStateError

    plant, q = _held(compiled=compiled, stop_on=(), collision_check=False)
    plant.reset(q, np.full(4, v), [0.0, 0.12, 0.0], np.full(3, V))
    with pytest.raises(PlantStateError, match="the plant cannot step from its state at t = .* s: ") as info:
        for _ in range(50):
            before = plant.state.copy()
            plant.step(np.zeros(4))
    message = str(info.value)
    assert "\n" not in message and len(message) < 400 and isinstance(info.value, np.linalg.LinAlgError), message
    assert plant.state.t == before.t == info.value.t and np.array_equal(plant.state.q, before.q)
    assert np.isfinite(plant.state.flat()).all()


def test_reset_can_set_contact_modes_and_validates_them():
    from regrasp import Hand, Plant, PlantContact, load_scenario
    from regrasp.core.exceptions import InvalidParameterError

    root = __import__("pathlib").Path(__file__).resolve().parents[3]
    sc = load_scenario(root / "examples" / "scenarios" / "paper_trajectory_2.toml")
    hand = Hand([c.finger for c in sc.contacts])
    plant = Plant(hand, sc.polygon, [PlantContact(1, "fixed", 0.0), PlantContact(3, "fixed", 0.0)],
                  collision_check=False)
    q = hand.inverse_kinematics(np.array([[-0.05, 0.12], [0.05, 0.12]]))
    plant.reset(q, np.zeros(4), [0.0, 0.12, 0.0], np.zeros(3),
                contacts=[PlantContact(1, "sliding", 0.0, -1.0), PlantContact(3, "fixed", 0.0)])
    assert [c.mode for c in plant.contacts] == ["sliding", "fixed"]
    with pytest.raises(InvalidParameterError, match="'fixed', 'sliding' or 'separated'"):
        plant.reset(q, np.zeros(4), [0.0, 0.12, 0.0], np.zeros(3),
                    contacts=[PlantContact(1, "glued", 0.0), PlantContact(3, "fixed", 0.0)])


@pytest.mark.parametrize("modes", [("fixed", "fixed"), ("sliding", "fixed"), ("fixed", "sliding")])
@pytest.mark.parametrize("seed", range(2))
def test_torque_free_energy_conservation_with_ideal_contacts(modes, seed):
    """No torque, gravity, friction or damping, contacts as ideal bilateral constraints
    (contact_events=False, since a torque-free motion pulls on them): the plant's total energy
    drifts by less than 1e-6 (relative) over 1 s of RK4 at 1 ms."""
    from regrasp import Grasp, Hand, Plant, PlantContact, ReducedModel

    rng = np.random.default_rng(900 + seed)
    sc = scenario()
    hand = Hand([c.finger for c in sc.contacts], gravity_in_hand=(0.0, 0.0), damping=False)
    xi = rng.uniform(-0.005, 0.005, size=2)
    grasp = Grasp(sc.polygon, [1, 3], modes)
    model = ReducedModel(hand, grasp, xi=xi)
    S = np.concatenate([[0.0, 0.12, 0.0], xi[list(grasp.sliding)]])
    S_dot = np.concatenate([rng.normal(size=3) * [0.01, 0.01, 0.1], rng.choice([-1, 1], size=grasp.p) * 0.004])
    st = model.state(S, S_dot)
    contacts = [PlantContact(e, mo, x, float(np.sign(S_dot[3])) if mo == "sliding" else 1.0)
                for e, mo, x in zip([1, 3], modes, xi)]
    plant = Plant(hand, sc.polygon, contacts, friction=0.0, collision_check=False, contact_events=False)
    plant.reset(st.q, st.q_dot, S[:3], S_dot[:3])
    e0 = plant.energy()
    for _ in range(1000):
        step = plant.step(np.zeros(4))
        assert not step.events, step.events
    assert abs(plant.energy() - e0) / e0 < 1e-6
    assert plant.max_constraint_error < 1e-9
    assert [c.mode for c in plant.contacts] == list(modes)


@pytest.mark.parametrize("damping,link_mass_scale", [(True, 1.0), (False, 1.3)])
def test_private_dynamics_pass_matches_the_hand(damping, link_mass_scale):
    """The plant's own Pinocchio pass (M, N, J from Pinocchio; the tip and J̇q̇ from J's columns,
    the planar revolute identities) equals :meth:`Hand.dynamics` (crba, nonLinearEffects, frame
    placement and classical acceleration), and so do M⁻¹ and J M⁻¹ Jᵀ."""
    rng = np.random.default_rng(5)
    fingers = [c.finger for c in scenario().contacts]
    hand = Hand(fingers, gravity_in_hand=(3.0, -GRAVITY), damping=damping, link_mass_scale=link_mass_scale)
    plant = Plant(hand, polygon(), [PlantContact(1, "fixed"), PlantContact(3, "fixed")], collision_check=False)
    for _ in range(5):
        q, v = rng.uniform(-2.5, 2.5, 4), rng.normal(size=4) * 3.0
        dyn = hand.dynamics(q, v)
        for i, f in enumerate(plant.equations.pin_pass(q, v)):
            sl = slice(2 * i, 2 * i + 2)
            mass, jac = dyn.mass_matrix[sl, sl], dyn.jacobian[sl, sl]
            scale = np.abs(mass).max()
            np.testing.assert_allclose(f[:3], [mass[0, 0], mass[0, 1], mass[1, 1]], rtol=0, atol=1e-14 * scale)
            np.testing.assert_allclose(f[3:5], dyn.nonlinear[sl], rtol=0, atol=1e-13 * np.abs(dyn.nonlinear).max())
            np.testing.assert_array_equal(np.reshape(f[5:9], (2, 2)), jac)
            jdv = dyn.jacobian_dot_v[sl]
            np.testing.assert_allclose(f[9:11], jdv, rtol=0, atol=1e-12 * np.abs(dyn.jacobian_dot_v).max())
            np.testing.assert_allclose(f[11:13], dyn.tips[i], rtol=0, atol=1e-15)
            np.testing.assert_allclose(f[13:15], dyn.tip_velocities[i], rtol=0, atol=1e-15)
            inverse = np.linalg.inv(mass)
            np.testing.assert_allclose(f[15:18], [inverse[0, 0], inverse[0, 1], inverse[1, 1]], rtol=1e-12)
            tip_space = jac @ inverse @ jac.T
            np.testing.assert_allclose(f[18:21], [tip_space[0, 0], tip_space[0, 1], tip_space[1, 1]], rtol=1e-12)


# ---------------------------------------------------------------------------- actuator limits
EFFORT = (0.05, 0.03)  # [N m] per joint of both fingers


def _limited_hand(effort) -> Hand:
    return Hand([c.finger.with_placement(effort_limit=effort) for c in scenario().contacts],
                gravity_in_hand=(0.0, -GRAVITY))


@pytest.mark.parametrize("compiled", [True, False])
def test_the_plant_saturates_the_torques_at_the_joints_limits(compiled):
    """The torque the plant applies is clip(τ, -effort, effort): a limited plant driven beyond its limits steps
    exactly as an unlimited one driven with the clipped torques; a joint's saturation is an event when it starts,
    once until it is back within its limit."""
    limited, free = _limited_hand(EFFORT), _limited_hand(np.inf)
    assert limited.effort_limit.tolist() == list(EFFORT) * 2 and np.isinf(free.effort_limit).all()
    xi = [0.0, 0.005]
    plants = [start(hand, ["fixed", "fixed"], xi, [0.0, 0.12, 0.0], [0.0, 0.0, 0.0], friction=1.0,
                    compiled=compiled, collision_check=False, stop_on=())[0] for hand in (limited, free)]
    assert plants[0].compiled == compiled
    rng = np.random.default_rng(3)
    commands = [np.array([0.2, -0.1, -0.2, 0.1])] * 3 + [np.array([0.01, 0.01, -0.01, 0.0])] \
        + [np.array([0.2, 0.02, -0.02, -0.1])] + [rng.uniform(-0.08, 0.08, 4) for _ in range(5)]
    effort = np.array(EFFORT * 2)
    onsets = []
    for tau in commands:
        step = plants[0].step(tau)
        clipped = np.clip(tau, -effort, effort)
        expected = plants[1].step(clipped)
        assert np.array_equal(step.state.q, expected.state.q) and np.array_equal(step.state.X, expected.state.X)
        assert step.state.torque_work == expected.state.torque_work  # (the work of the applied torques)
        assert plants[0].saturated == tuple(bool(s) for s in (clipped != tau))
        onsets.append([(e.contact, int(e.values["joint"]), e.values["torque"]) for e in step.events
                       if e.kind is EventKind.SATURATION])
    names = [f.name for f in limited.fingers]
    assert onsets[0] == [(names[0], 1, 0.2), (names[0], 2, -0.1), (names[1], 1, -0.2), (names[1], 2, 0.1)]
    assert onsets[1] == onsets[2] == onsets[3] == []  # (still saturated, then within)
    assert onsets[4] == [(names[0], 1, 0.2), (names[1], 2, -0.1)]
    assert all(e.source.value == "plant" for e in plants[0].events)
    assert sum(e.kind is EventKind.SATURATION for e in plants[0].events) == sum(map(len, onsets))


def test_the_compiled_and_reference_plants_saturate_alike():
    plants = [start(_limited_hand(EFFORT), ["fixed", "fixed"], [0.0, 0.005], [0.0, 0.12, 0.0], [0.0, 0.0, 0.0],
                    friction=1.0, compiled=c, collision_check=False, stop_on=())[0] for c in (True, False)]
    for tau in ([0.2, -0.1, -0.2, 0.1], [0.04, 0.0, -0.06, 0.02]):
        a, b = (p.step(tau) for p in plants)
        np.testing.assert_allclose(a.state.q, b.state.q, rtol=0, atol=1e-12)
        assert [e.detail for e in a.events] == [e.detail for e in b.events]

"""The project plant with compliant pads (``regrasp.plants.project.soft``, ``Plant(pad=...)``) against physics it must
respect, each claim checked by something independent of the plant's code.

Set-up: the two-finger hand of ``examples/scenarios/paper_trajectory_2.toml`` holding its 0.10 x 0.04 m rectangle,
finger 1 on edge 1, finger 2 on edge 3; initial states from the reduced model (tips on the edges' lines).

* The force law: the reported forces are k δ + c δ̇ along the edge's normal (and a slider's μ_k s f_n along its
  tangent), with δ from the tips' forward kinematics and δ̇ by central differences, here; never a pull.
* The equations of motion: M q̈ + N = τ - Jᵀ f and M_o Ẍ = (Σ f, Σ r × f) + f_g with the reported forces
  (``Hand.dynamics``, own algebra).
* A hold: as k grows the forces converge to the rigid plant's (1/k), and they agree with MuJoCo's.
* Energy: undamped pads, no torque, gravity, damping or friction: a bounce conserves kinetic + pad energy.
* A contact pulled away carries nothing (not a pull) and separates 25 µm off; slip and stick still fire.
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pytest

from regrasp import Grasp, Hand, Plant, PlantContact, ReducedModel, load_scenario
from regrasp.core.events import EventKind
from regrasp.core.exceptions import InvalidParameterError
from regrasp.core.pad import Pad
from regrasp.core.planar import rotation

ROOT = Path(__file__).resolve().parents[3]
SCENARIO = ROOT / "examples" / "scenarios" / "paper_trajectory_2.toml"
EDGES = (1, 3)
S0 = np.array([0.0, 0.12, 0.0])
TIP_MASS = 0.01  # [kg]: the pads below are critically damped for a 10 g tip


@functools.lru_cache(maxsize=None)
def scenario():
    return load_scenario(SCENARIO)


def make_hand(gravity=(0.0, -9.81), damping=True) -> Hand:
    return Hand([c.finger for c in scenario().contacts], gravity_in_hand=gravity, damping=damping)


def reduced(hand: Hand, xi) -> ReducedModel:
    return ReducedModel(hand, Grasp(scenario().polygon, EDGES, ["fixed", "fixed"]), list(xi))


def start(hand, pad, modes=("fixed", "fixed"), xi=(0.005, -0.008), X=S0, V=np.zeros(3), signs=(1.0, 1.0),
          q_from=S0, friction=1.0, **kw) -> Plant:
    """A plant whose fingers are where the reduced model puts them for the object at ``q_from`` (tips on the edges'
    lines), with the object at X, V."""
    rst = reduced(hand, xi).state(q_from, np.zeros(3))
    contacts = [PlantContact(e, m, x, s) for e, m, x, s in zip(EDGES, modes, xi, signs)]
    plant = Plant(hand, scenario().polygon, contacts, friction=friction, pad=pad, **kw)
    plant.reset(rst.q, rst.q_dot, X, V)
    return plant


def frames(beta: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """Each contact's (inward normal, ξ direction) in the hand frame at object angle β."""
    rot = rotation(beta)
    return [(rot @ scenario().polygon.edge(k).inward_normal, rot @ scenario().polygon.edge(k).xi_direction)
            for k in EDGES]


def depths(hand: Hand, pad: Pad, q, X) -> np.ndarray:
    """Each pad's penetration δ [m] from the tips' forward kinematics (own algebra)."""
    tips = hand.tip_positions(q)
    out = []
    for i, k in enumerate(EDGES):
        e = scenario().polygon.edge(k)
        on_edge = X[:2] + rotation(X[2]) @ e.xi_origin
        out.append(frames(X[2])[i][0] @ (tips[i] - on_edge) + pad.preload_depth)
    return np.array(out)


def depth_rates(hand, pad, st, eps=1e-7) -> np.ndarray:
    """δ̇ by central differences along the state's velocities."""
    return (depths(hand, pad, st.q + eps * st.v, st.X + eps * st.V)
            - depths(hand, pad, st.q - eps * st.v, st.X - eps * st.V)) / (2 * eps)


# ---------------------------------------------------------------------------- the force law and the equations
@pytest.mark.parametrize("modes", [("sliding", "sliding"), ("fixed", "sliding")])
def test_forces_are_the_pads_law_and_the_equations_of_motion_hold(modes):
    """A random state near the grasp: each touching pad pushes k δ + c δ̇ along its normal (0 when δ <= 0 or the
    tip leaves faster than the spring pushes), a slider carries μ_k s f_n along its edge; and the accelerations
    satisfy the fingers' and the object's equations with the reported forces."""
    rng = np.random.default_rng(3)
    hand = make_hand()
    pad, mu = Pad(2e4, 30.0, preload=0.5), 0.4
    M_o = np.diag([scenario().polygon.mass, scenario().polygon.mass, scenario().polygon.inertia])
    seen = set()
    for trial in range(12):
        shift = rng.uniform(-60e-6, 60e-6, 2)
        X = S0 + np.array([*shift, rng.uniform(-2e-3, 2e-3)])
        V = rng.normal(size=3) * np.array([0.01, 0.01, 0.2])
        plant = start(hand, pad, modes, X=X, V=V, signs=(1.0, -1.0), friction=mu)
        plant.state.v = rng.normal(size=4) * 0.2
        st = plant.state
        tau = rng.normal(size=4) * 0.05
        q_ddot, X_ddot, forces = plant.accelerations(st, tau)
        delta, rate = depths(hand, pad, st.q, st.X), depth_rates(hand, pad, st)
        for i, (n, t) in enumerate(frames(st.X[2])):
            fn = max(0.0, pad.stiffness * delta[i] + pad.damping * rate[i]) if delta[i] > 0 else 0.0
            seen.add("pushes" if fn > 0 else ("off" if delta[i] <= 0 else "leaving"))
            assert forces[i] @ n == pytest.approx(fn, rel=1e-6, abs=1e-9)
            if modes[i] == "sliding":
                sign = (1.0, -1.0)[i]
                assert forces[i] @ t == pytest.approx(mu * sign * fn, rel=1e-6, abs=1e-9)
        dyn = hand.dynamics(st.q, st.v)
        np.testing.assert_allclose(dyn.mass_matrix @ q_ddot + dyn.nonlinear,
                                   tau - dyn.jacobian.T @ forces.reshape(-1), atol=1e-10)
        wrench = np.zeros(3)
        for i, f in enumerate(forces):
            r = dyn.tips[i] - st.X[:2]
            wrench += [f[0], f[1], r[0] * f[1] - r[1] * f[0]]
        f_g = np.append(scenario().polygon.mass * hand.gravity_in_hand, 0.0)
        np.testing.assert_allclose(M_o @ X_ddot, wrench + f_g, atol=1e-10)
        del trial
    assert {"pushes", "off"} <= seen


def test_a_fixed_pad_keeps_its_material_point_on_the_edge():
    """A fixed contact's tangential row: over a moving hold the tip's ξ stays where it is held (the drift is the
    Baumgarte-stabilised constraint error), while its normal position moves with the pad's load."""
    hand = make_hand()
    pad = Pad.critically_damped(1e4, TIP_MASS, preload=0.7)
    plant = start(hand, pad)
    for k in range(200):
        step = plant.step(hold_torque(plant, hand, ref=S0 + np.array([0.003, 0.002, 0.05]) * np.sin(20 * k * 1e-3)))
    xi = [plant.contact_xi(plant.state, i)[0] for i in range(2)]
    np.testing.assert_allclose(xi, [0.005, -0.008], atol=1e-8)
    assert plant.max_constraint_error < 1e-8
    # the tips sit in the pads by their loads' depths (quasi-static: the damping's share is small), reported as -δ
    delta = depths(hand, pad, plant.state.q, plant.state.X)
    np.testing.assert_allclose(step.gap, -delta, atol=1e-12)
    np.testing.assert_allclose(pad.stiffness * delta, step.forces_surface[:, 0], rtol=0.02)


# ---------------------------------------------------------------------------- a hold: rigid, pads, MuJoCo
def hold_torque(plant, hand, ref=S0, squeeze=1.0, wn=40.0, xi=(0.005, -0.008)):
    """Computed torque of the reduced model (a fixed grasp) driving the object to ``ref`` at rest with a squeeze
    [N]: τ = M(H S̈ + Ḣ Ṡ) + N + Jᵀ f, G f = M_o S̈ - f_g."""
    st = plant.state
    model = reduced(hand, xi)
    rst = model.state(st.X, st.V)
    S_ddot = wn * wn * (ref - st.X) - 2 * wn * st.V
    f = np.linalg.lstsq(rst.G, model.M_o @ S_ddot - model.f_g, rcond=None)[0]
    null = np.linalg.svd(rst.G)[2][-1]
    inward = sum(frames(st.X[2])[i][0] @ null[2 * i:2 * i + 2] for i in range(2))
    f = f + squeeze * np.sign(inward) * null
    q_ddot = rst.H @ S_ddot + rst.H_dot_S_dot
    return rst.hand.mass_matrix @ q_ddot + rst.hand.nonlinear + rst.hand.jacobian.T @ f


def run_hold(plant, hand, steps=300):
    out = []
    for _ in range(steps):
        step = plant.step(hold_torque(plant, hand))
        assert not step.events, step.events
        out.append(step.forces_surface.copy())
    return np.array(out)


@functools.lru_cache(maxsize=None)
def rigid_hold() -> np.ndarray:
    hand = make_hand()
    return run_hold(start(hand, None), hand)


def test_a_hold_converges_to_the_rigid_plants_forces_as_k_grows():
    """The same law on pads of k = 1e3, 1e4, 1e5 N/m (critically damped for 10 g, preloaded 1 N: the law squeezes
    0.71 N) and on rigid contacts: after 20 ms the forces differ by O(1/k), within 1 % of the load at 1e5 N/m."""
    rigid = rigid_hold()
    hand = make_hand()
    errors = []
    for k in (1e3, 1e4, 1e5):
        soft = run_hold(start(hand, Pad.critically_damped(k, TIP_MASS, preload=1.0)), hand)
        errors.append(np.abs(soft - rigid)[20:].max())
    load = np.abs(rigid).max()
    assert errors[2] < 0.01 * load
    assert errors[0] > errors[1] > errors[2]
    assert errors[0] / errors[1] > 5 and errors[1] / errors[2] > 5  # first order in 1/k


def test_a_hold_agrees_with_mujoco():
    """The same law on MuJoCo (sphere tips of 10 µm, its soft contacts; independent physics): the forces after 0.3 s
    agree with the pads' (k = 1e5 N/m) to 0.5 mN of 0.8 N (measured: 0.05 mN; what differs is MuJoCo's creep of stuck
    contacts, below 0.07 mm/s, which the law answers with its feedback; ``docs/derivations.md``, "A compliant
    pad")."""
    mujoco = pytest.importorskip("regrasp.plants.mujoco.plant")
    from regrasp.plants.mujoco.mjcf import MujocoSettings

    hand = make_hand()
    soft = run_hold(start(hand, Pad.critically_damped(1e5, TIP_MASS, preload=1.0)), hand)
    rst = reduced(hand, (0.005, -0.008)).state(S0, np.zeros(3))
    contacts = [PlantContact(e, "fixed", x) for e, x in zip(EDGES, (0.005, -0.008))]
    plant = mujoco.MujocoPlant(hand, scenario().polygon, contacts, friction=1.0,
                               settings=MujocoSettings(tip_radius=1e-5))
    plant.reset(rst.q, rst.q_dot, S0, np.zeros(3))
    other = run_hold(plant, hand)
    np.testing.assert_allclose(other[-1], soft[-1], atol=5e-4)
    np.testing.assert_allclose(soft[-1], rigid_hold()[-1], atol=1e-4)


# ---------------------------------------------------------------------------- energy
def bounce(substeps: int) -> tuple[np.ndarray, np.ndarray]:
    """The object (0.05 m/s) hits finger 1's undamped pad and leaves it: no gravity, joint damping, friction or
    torque. Per step: the energy (fingers' and object's kinetic + the pads' k δ₊²/2, own algebra) and finger 1's
    gap -δ [m]."""
    hand = make_hand(gravity=(0.0, 0.0), damping=False)
    pad = Pad(1e4, 0.0, preload=0.0, substeps=substeps)
    n1 = frames(0.0)[0][0]
    plant = start(hand, pad, ("sliding", "sliding"), V=np.array([*(-0.05 * n1), 0.0]), friction=0.0,
                  contact_events=False)
    mass, inertia = scenario().polygon.mass, scenario().polygon.inertia

    def energy(st):
        delta = depths(hand, pad, st.q, st.X)
        return (hand.kinetic_energy(st.q, st.v) + 0.5 * mass * st.V[:2] @ st.V[:2] + 0.5 * inertia * st.V[2] ** 2
                + 0.5 * pad.stiffness * np.sum(np.maximum(delta, 0.0) ** 2))

    energies, gaps = [energy(plant.state)], [0.0]
    for _ in range(8):
        step = plant.step(np.zeros(4))
        energies.append(energy(step.state))
        gaps.append(step.gap[0])
    return np.array(energies), np.array(gaps)


def test_an_undamped_bounce_conserves_energy_to_rk4s_accuracy():
    """While the pad is pressed the energy is conserved to 1e-5 (RK4, 4th order); the step whose substep crosses
    δ = 0 on the way out (the force's kink) loses order, and its error shrinks faster than the substep (8 times for
    4 times shorter ones; 176 ppm at 0.25 ms, 16 ppm at 62.5 µs)."""
    coarse, gaps = bounce(4)
    fine, _ = bounce(16)
    assert gaps.min() < -40e-6 and gaps[-1] > 100e-6  # pressed 60 µm, then off
    pressed = np.flatnonzero(gaps < 0)
    for energies in (coarse, fine):
        assert np.abs(energies[pressed] - energies[0]).max() < 1e-5 * energies[0]
    drift_coarse, drift_fine = (abs(e[-1] - e[0]) / e[0] for e in (coarse, fine))
    assert drift_fine < 3e-5 and drift_fine < drift_coarse / 8


# ---------------------------------------------------------------------------- separation, slip, stick
def test_a_contact_pulled_away_carries_no_force_and_separates():
    """Finger 1 pulls its tip out with 0.05 N (no gravity, finger 2 idle, pads preloaded 0.1 N): its pad's force
    falls to zero, never below, is exactly zero over every step that starts off the surface, and the contact
    separates once the pad is 25 µm off its edge (the gap the step reports, -δ, there)."""
    hand = make_hand(gravity=(0.0, 0.0))
    pad = Pad.critically_damped(1e4, TIP_MASS, preload=0.1)
    plant = start(hand, pad)
    n1 = frames(0.0)[0][0]
    normals, gaps, separation = [], [0.0], None
    for _ in range(40):
        st = plant.state
        tau = np.concatenate([hand.jacobian(st.q)[:2, :2].T @ (-0.05 * n1), np.zeros(2)])
        step = plant.step(tau)
        normals.append(step.forces_surface[0, 0])
        gaps.append(step.gap[0])
        if (EventKind.SEPARATION, "finger1") in [(e.kind, e.contact) for e in step.events]:
            separation = step
            break
    assert separation is not None
    normals, gaps = np.array(normals), np.array(gaps)
    assert normals.min() >= 0.0 and normals[0] > 0.0
    off = gaps[:-1] > 0.0  # the steps that start with the pad off the surface
    assert off.sum() >= 2 and np.all(normals[off] == 0.0)
    event = next(e for e in separation.events if e.kind is EventKind.SEPARATION)
    assert event.values["gap"] > pad.separation_gap
    assert separation.gap[0] == pytest.approx(event.values["gap"], rel=1e-9)
    assert separation.gap[0] == pytest.approx(-depths(hand, pad, separation.state.q, separation.state.X)[0],
                                              abs=1e-12)
    assert plant.contacts[0].mode == "separated"


def test_slip_then_stick_on_pads():
    """μ = 0.05, 1 N squeeze on pads preloaded 1 N (no gravity), a tangential push on finger 1 ramped at 1 N/s: it
    slips when the push passes μ_s f_n (50 ms), then, the push removed, kinetic friction stops it and it sticks."""
    hand = make_hand(gravity=(0.0, 0.0))
    mu, rate = 0.05, 1.0
    plant = start(hand, Pad.critically_damped(1e5, TIP_MASS, preload=1.0), friction=mu)
    model = reduced(hand, (0.005, -0.008))

    def torque(push):
        st = plant.state
        rst = model.state(st.X, st.V)
        forces = np.concatenate([fr @ f for fr, f in zip(
            [np.column_stack(nt) for nt in frames(st.X[2])], [[1.0, push], [1.0, 0.0]])])
        X_ddot = np.linalg.solve(model.M_o, rst.G @ forces + model.f_g)
        q_ddot = rst.H @ X_ddot + rst.H_dot_S_dot
        return rst.hand.mass_matrix @ q_ddot + rst.hand.nonlinear + rst.hand.jacobian.T @ forces

    slip = None
    for _ in range(80):
        step = plant.step(torque(rate * plant.state.t))
        if step.events:
            slip = step
            break
    assert slip is not None and [(e.kind, e.contact) for e in slip.events] == [(EventKind.SLIP, "finger1")]
    assert 0.049 <= slip.events[0].time <= 0.055  # (the law delivers its push to a few mN on pads)
    assert plant.contacts[0].mode == "sliding"
    stick = None
    for _ in range(50):
        step = plant.step(torque(0.0))
        if step.events:
            stick = step
            break
    assert stick is not None and [(e.kind, e.contact) for e in stick.events] == [(EventKind.STICK, "finger1")]
    assert plant.contacts[0].mode == "fixed"
    assert plant.contacts[0].xi == pytest.approx(stick.xi[0], abs=1e-12)


def test_a_pad_plant_runs_the_reference_path_and_checks_its_input():
    hand = make_hand()
    pad = Pad(1e4)
    plant = start(hand, pad)
    assert plant.pad is pad and not plant.compiled
    with pytest.raises(InvalidParameterError):
        start(hand, pad, compiled=True)
    with pytest.raises(InvalidParameterError):
        start(hand, 1e4)
    assert start(hand, pad, compiled=False).pad_energy() == pytest.approx(2 * pad.energy(pad.preload_depth))
    assert start(hand, None).pad_energy() == 0.0

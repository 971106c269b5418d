"""Closed-loop tests of the control laws on the independent plant (paper §3.3–3.4).

Every law is run on the full-coordinate plant (never on the model it inverts) from an initial
error, with the reference moving at constant speed so that a sliding contact keeps sliding.
The error must follow Ë + K_v Ė + K_s E = 0; the controller samples at the plant step dt
(zero-order hold), so the match is to within ω·dt of the initial error, and for the laws whose
model is exact the deviation halves when dt halves.
"""

from pathlib import Path

import numpy as np
import pytest

from regrasp import Finger, Friction, Grasp, Hand, Plant, PlantContact, ReducedModel, load_scenario
from regrasp.core.exceptions import InvalidParameterError
from regrasp.dynamics.control import Gains
from regrasp.dynamics.internal_force.problem import InternalForceInfeasibleError
from regrasp.dynamics.internal_force.settings import ConeEdge, InternalForceSettings
from regrasp.dynamics.laws import (
    FixedContactController,
    Proposition1Controller,
    Proposition2Controller,
    Proposition3Controller,
)
from regrasp.plants.closed_loop import run_closed_loop

ROOT = Path(__file__).resolve().parents[2]
SC = load_scenario(ROOT / "examples" / "scenarios" / "paper_trajectory_2.toml")
FINGER3 = Finger.from_urdf(ROOT / "urdf" / "planar_2r_finger.urdf", base_in_hand=(0.04, -0.02, np.pi / 2),
                           configuration="left", name="finger3")
OMEGA = 20.0  # closed-loop bandwidth [rad/s]: K_s = ω², K_v = 2ω
E0 = np.array([0.002, -0.001, 0.02, 0.001, -0.001])  # initial error: x, y [m], β [rad], ξ [m] (one per slider)

# (law, m, modes, xi of every contact, friction per contact, sliding speed [m/s]); the "_kinetic" cases have
# μ_s > μ_k: the plant slides at μ_k, which Proposition 3 must predict
SLOW = [Friction(0.6, 0.3), Friction(0.6, 0.3)]
SLOW3 = [Friction(0.7, 0.3), Friction(0.8, 0.5), Friction(0.8, 0.5)]
CASES = {
    "fixed": (FixedContactController, 2, ["fixed", "fixed"], [0.0, 0.0], [0.5, 0.5], 0.0),
    "prop1_mu0": (Proposition1Controller, 3, ["sliding", "fixed", "fixed"], [-0.01, -0.01, 0.02], [0.0, 0.5, 0.5],
                  0.01),
    "prop1_mu03": (Proposition1Controller, 3, ["sliding", "fixed", "fixed"], [-0.01, -0.01, 0.02], [0.3, 0.5, 0.5],
                   0.01),
    "prop2": (Proposition2Controller, 3, ["sliding", "fixed", "fixed"], [-0.01, -0.01, 0.02], [0.3, 0.5, 0.5], 0.01),
    "prop3_up": (Proposition3Controller, 2, ["sliding", "fixed"], [-0.0075, -0.0075], [0.3, 0.3], 0.01),
    "prop3_down": (Proposition3Controller, 2, ["sliding", "fixed"], [0.005, 0.015], [0.05, 0.8], -0.01),
    "prop3_m3": (Proposition3Controller, 3, ["sliding", "fixed", "fixed"], [-0.01, -0.01, 0.02], [0.3, 0.5, 0.5], 0.01),
    "prop3_m3_down": (Proposition3Controller, 3, ["fixed", "sliding", "fixed"], [0.0, 0.01, 0.02], [0.5, 0.3, 0.5],
                      -0.01),
    "prop3_up_kinetic": (Proposition3Controller, 2, ["sliding", "fixed"], [-0.0075, -0.0075], SLOW, 0.01),
    "prop3_m3_kinetic": (Proposition3Controller, 3, ["sliding", "fixed", "fixed"], [-0.01, -0.01, 0.02], SLOW3, 0.01),
    # p = 2: both side fingers slide down the object (finger 1's ξ points up, finger 2's down: a speed per
    # slider), the bottom finger holds
    "prop3_p2": (Proposition3Controller, 3, ["sliding", "sliding", "fixed"], [0.0, 0.0, 0.0], [0.3, 0.3, 0.6],
                 (-0.01, 0.01)),
    "prop3_p2_kinetic": (Proposition3Controller, 3, ["sliding", "sliding", "fixed"], [0.0, 0.0, 0.0],
                         [Friction(0.6, 0.3), Friction(0.6, 0.3), Friction(0.8, 0.5)], (-0.01, 0.01)),
}


def run(name, duration=0.4, dt=1e-3, force_noise=0.0):
    law, m, modes, xi, mu, speed = CASES[name]
    fingers = [c.finger for c in SC.contacts] + ([FINGER3] if m == 3 else [])
    edges = [1, 3, 2][:m]
    hand = Hand(fingers, gravity_in_hand=(0.0, -9.81))
    grasp = Grasp(SC.polygon, edges, modes)
    model = ReducedModel(hand, grasp, xi=np.array(xi, dtype=float))
    n = model.n
    start = np.concatenate([[0.0, 0.12, 0.0], np.array(xi)[list(grasp.sliding)]])
    velocity = np.concatenate([np.zeros(3), np.broadcast_to(speed, (grasp.p,))])

    def reference(t):
        return start + velocity * t, velocity, np.zeros(n)

    S0 = start - E0[:n]
    st = model.state(S0, velocity)
    xi_plant = np.array(xi, dtype=float)
    for j, i in enumerate(grasp.sliding):
        xi_plant[i] = S0[3 + j]
    signs = [float(np.sign(speed) or 1.0)] * m if np.ndim(speed) == 0 else [1.0] * m
    for j, i in enumerate(grasp.sliding):
        signs[i] = float(np.sign(velocity[3 + j]) or 1.0)
    contacts = [PlantContact(e, mode, x, sign) for e, mode, x, sign in zip(edges, modes, xi_plant, signs)]
    plant = Plant(hand, SC.polygon, contacts, friction=mu, dt=dt)
    plant.reset(st.q, st.q_dot, S0[:3], velocity[:3])
    controller = law(model, Gains.critically_damped(OMEGA, n), friction=mu)
    log = run_closed_loop(plant, controller, reference, duration, force_noise=force_noise,
                          rng=np.random.default_rng(0))
    t = log.times
    predicted = (E0[None, :n] + OMEGA * E0[None, :n] * t[:, None]) * np.exp(-OMEGA * t)[:, None]
    deviation = np.abs(log.errors - predicted).max() / np.abs(E0[:n]).max()
    return log, deviation, np.array([mo == "fixed" for mo in modes])


@pytest.mark.parametrize("name", ["fixed", "prop1_mu0", "prop2", "prop3_up", "prop3_down", "prop3_m3",
                                  "prop3_m3_down", "prop3_up_kinetic", "prop3_m3_kinetic"])
def test_error_follows_the_closed_loop_ode(name):
    log, deviation, fixed = run(name)
    assert log.events == ()
    assert deviation <= 1.5 * OMEGA * 1e-3  # zero-order hold: within ω·dt of the initial error
    assert np.abs(log.errors[-1]).max() <= 1.5 * OMEGA * 1e-3 * np.abs(E0).max()  # settled to the ZOH bound
    # fixed contacts stay inside their (static) friction cones (the plant's forces)
    assert log.cone_margins[:, fixed].min() > 0.0
    assert log.plant_forces[:, :, 0].min() > 0.0  # every contact keeps pushing


@pytest.mark.parametrize("name", ["fixed", "prop1_mu0", "prop3_up"])
def test_exact_laws_converge_to_the_ode_as_dt_shrinks(name):
    _, coarse, _ = run(name, duration=0.2, dt=1e-3)
    _, fine, _ = run(name, duration=0.2, dt=5e-4)
    assert 1.6 < coarse / fine < 2.4  # first order in dt: the only error is the sampling


@pytest.mark.parametrize("name", ["fixed", "prop1_mu0", "prop3_up", "prop3_down", "prop3_m3", "prop3_m3_down",
                                  "prop3_up_kinetic", "prop3_m3_kinetic"])
def test_achieved_internal_force_equals_the_commanded_one(name):
    """The plant's contact forces equal the controller's predicted ones (motion part + f_c), so the
    internal force achieved is the commanded one (τ_I = τ_Ic)."""
    log, _, _ = run(name, duration=0.2)
    assert np.abs(log.plant_forces - log.predicted_forces).max() < 1e-6


def test_proposition1_is_measurably_worse_with_friction():
    _, exact, _ = run("prop1_mu0")
    log, with_friction, _ = run("prop1_mu03")
    assert with_friction > 10 * exact
    assert with_friction > 0.05


def test_proposition2_tracks_with_noisy_friction_measurements():
    log, deviation, fixed = run("prop2", force_noise=0.002)
    assert log.events == ()
    assert deviation < 0.05
    assert log.cone_margins[:, fixed].min() > 0.0


def test_three_fingers_use_a_nontrivial_internal_force():
    """m = 3, p = 1: the null space of [G; B_vᵀ R_fᵀ] is two-dimensional and the QP squeezes."""
    log, _, _ = run("prop1_mu0", duration=0.1)
    norms = np.linalg.norm(log.internal_forces, axis=1)
    assert norms.min() > 0.05  # [N]
    assert np.abs(log.plant_forces - log.predicted_forces).max() < 1e-6


def test_laws_check_their_preconditions():
    hand = Hand([c.finger for c in SC.contacts])
    sliding = ReducedModel(hand, Grasp(SC.polygon, [1, 3], ["sliding", "fixed"]), xi=[0.0, 0.0])
    with pytest.raises(InvalidParameterError, match="p = 0"):
        FixedContactController(sliding, Gains.critically_damped(10, 4))
    fixed = ReducedModel(hand, Grasp(SC.polygon, [1, 3], ["fixed", "fixed"]), xi=[0.0, 0.0])
    with pytest.raises(InvalidParameterError, match="p = 1"):
        Proposition3Controller(fixed, Gains.critically_damped(10, 3))
    with pytest.raises(InvalidParameterError, match="friction"):
        Proposition2Controller(sliding, Gains.critically_damped(10, 4))(
            np.array([0, 0.12, 0, 0]), np.zeros(4), np.array([0, 0.12, 0, 0]), np.zeros(4), np.zeros(4))
    with pytest.raises(InvalidParameterError, match="positive"):
        Proposition1Controller(sliding, Gains(np.ones(4), -np.ones(4)))
    with pytest.raises(InvalidParameterError):
        Proposition1Controller(sliding, Gains(np.ones(3), np.ones(3)))  # wrong size


def model_of(name):
    """The reduced model of a CASES entry, and its state S (x, y, β, ξ_slider) at ξ."""
    law, m, modes, xi, mu, speed = CASES[name]
    fingers = [c.finger for c in SC.contacts] + ([FINGER3] if m == 3 else [])
    grasp = Grasp(SC.polygon, [1, 3, 2][:m], modes)
    model = ReducedModel(Hand(fingers, gravity_in_hand=(0.0, -9.81)), grasp, xi=np.array(xi, dtype=float))
    S = np.concatenate([[0.0, 0.12, 0.0], np.array(xi)[list(grasp.sliding)]])
    return model, S, np.array(mu), speed


@pytest.mark.parametrize("name", ["prop3_up", "prop3_down"])
def test_proposition3_force_distribution_reduces_to_the_papers_P_for_two_fingers(name):
    """With m = 2 the m-finger law's equations have a unique solution, which is (3.4.9)'s."""
    model, S, mu, speed = model_of(name)
    rng = np.random.default_rng(3)
    law = Proposition3Controller(model, Gains.critically_damped(OMEGA, 4), friction=mu)
    for _ in range(5):
        S_dot = np.append(rng.normal(0, 0.01, 3), speed)
        S_d = S + rng.normal(0, 1e-3, 4)
        out = law(S, S_dot, S_d, S_dot, rng.normal(0, 0.5, 4))
        terms = model.terms(S.tolist(), S_dot.tolist())
        st = model.state_from_terms(S, S_dot, terms)
        tau, f_hat, forces, _ = law.distributed_torque(st, terms, out.command, law.directions)
        scale = np.abs(out.tau).max()
        assert np.abs(tau - out.tau).max() < 1e-9 * scale
        assert abs(f_hat[0] - out.friction_estimate[0]) < 1e-9 * scale


def test_proposition3_with_three_fingers_chooses_the_sliders_normal_force():
    """m = 3: the predicted forces move the object as commanded (checked with G and the object's
    equation, not the law's matrices), keep the slider on its cone edge and every contact within
    the QP's margins, also where Proposition 2 on the cone edge fails because the measured
    friction over μ is below the minimum push."""
    model, S, mu, speed = model_of("prop3_m3")
    settings = InternalForceSettings(f_min=0.5, friction_margin=0.05)
    rng = np.random.default_rng(4)
    law = Proposition3Controller(model, Gains.critically_damped(OMEGA, 4), friction=mu, internal_force=settings)
    for _ in range(5):
        S_dot = np.append(rng.normal(0, 0.01, 3), speed)
        out = law(S, S_dot, S + rng.normal(0, 1e-4, 4), S_dot, rng.normal(0, 0.1, 4))
        pose, xi = S[:3], model.xi.copy()
        xi[0] = S[3]
        G = model.grasp.grasp_matrix(pose, xi)
        wrench = model.object_mass * (out.command[:3] * [1, 1, 0] - [0.0, -9.81, 0.0])
        wrench[2] = model.object_inertia * out.command[2]
        assert np.allclose(G @ out.contact_forces.reshape(-1), wrench, atol=1e-9)
        f_n, f_t = out.contact_forces_surface.T
        assert abs(f_t[0] - mu[0] * f_n[0]) < 1e-9  # sliding in +ξ: friction on the object along +t
        assert abs(out.friction_estimate[0] - f_t[0]) < 1e-9  # f̂_ξ is the slider's predicted friction
        assert f_n.min() >= settings.f_min - 1e-6
        assert np.all(np.abs(f_t[1:]) <= (mu[1:] - settings.friction_margin) * f_n[1:] + 1e-6)
    pinned = Proposition2Controller(model, Gains.critically_damped(OMEGA, 4), friction=mu, internal_force=settings,
                                    cone_edge=ConeEdge(0, 1.0, mu[0]))
    with pytest.raises(InternalForceInfeasibleError):
        pinned(S, np.append(np.zeros(3), speed), S, np.append(np.zeros(3), speed), np.zeros(4),
               tangential_force=[0.5 * mu[0] * settings.f_min])
    assert law(S, np.append(np.zeros(3), speed), S, np.append(np.zeros(3), speed), np.zeros(4)).internal.feasible


def test_proposition3_checks_its_arguments():
    model, *_ = model_of("prop3_m3")
    gains = Gains.critically_damped(OMEGA, 4)
    with pytest.raises(InvalidParameterError, match="direction"):
        Proposition3Controller(model, gains, direction=0.0)
    with pytest.raises(InvalidParameterError, match="cone_edge"):
        Proposition3Controller(model, gains, cone_edge=ConeEdge(0, 1.0, 0.5))
    # issue 25: sample_time=object() was a TypeError from np.isfinite
    for sample_time in (object(), None, "1e-3", True, 1 + 0j, [1e-3], 0.0, -1e-3, float("nan"), float("inf"),
                        10**400):
        with pytest.raises(InvalidParameterError, match="invalid sample_time = "):
            Proposition3Controller(model, gains, sample_time=sample_time)
    assert Proposition3Controller(model, gains, sample_time=np.float32(2e-3)).sample_time == float(np.float32(2e-3))


@pytest.mark.parametrize("name", ["prop3_up_kinetic", "prop3_m3_kinetic"])
def test_proposition3_puts_the_slider_on_its_kinetic_edge_and_reports_each_modes_margin(name):
    """μ_s > μ_k: the predicted slider force has t·f = μ_k n·f (m = 2 through P, m > 2 through the
    cone-edge row), the fixed contacts stay inside (μ_s - margin) cones (m > 2: the QP, which
    tests/dynamics/internal_force/test_solver.py checks against μ_k), and the reported cone margins are
    μ_k f_n - |f_t| at the slider (0) and μ_s f_n - |f_t| at the others."""
    law_class, m, modes, xi, friction, speed = CASES[name]
    model, S, _, _ = model_of(name)
    settings = InternalForceSettings(f_min=0.5, friction_margin=0.05)
    law = Proposition3Controller(model, Gains.critically_damped(OMEGA, 4), friction=friction, internal_force=settings)
    static = np.array([f.static for f in friction])
    rng = np.random.default_rng(8)
    for _ in range(5):
        S_dot = np.append(rng.normal(0, 0.01, 3), speed)
        out = law(S, S_dot, S + rng.normal(0, 1e-4, 4), S_dot, rng.normal(0, 0.1, 4))
        f_n, f_t = out.contact_forces_surface.T
        assert f_t[0] == pytest.approx(friction[0].kinetic * f_n[0], rel=1e-9)  # sliding up: along +t
        assert out.friction_estimate[0] == pytest.approx(f_t[0], rel=1e-9)
        expected = np.concatenate([[friction[0].kinetic * f_n[0] - abs(f_t[0])],
                                   static[1:] * f_n[1:] - np.abs(f_t[1:])])
        np.testing.assert_allclose(out.cone_margins, expected, rtol=0, atol=1e-12)
        if m > 2:
            assert np.all(np.abs(f_t[1:]) <= (static[1:] - settings.friction_margin) * f_n[1:] + 1e-6)


# ---------------------------------------------------------------------------- several sliders, several cone edges
@pytest.mark.parametrize("name", ["prop3_p2", "prop3_p2_kinetic"])
def test_proposition3_with_two_sliders_follows_the_ode_with_both_on_their_kinetic_edges(name):
    """m = 3, p = 2 (both side fingers slide down the object, the bottom finger holds; the null space
    of the law's equations is one-dimensional): the error follows the ODE within ω·dt, first order in
    dt; on the plant both sliders keep sliding the asked way with |f_t| = μ_k f_n (friction on the
    object along s_j t_j), the holder stays inside its static cone, and the plant's forces are the
    predicted ones."""
    friction, speed = CASES[name][4:]
    log, deviation, fixed = run(name)
    assert log.events == ()
    assert deviation <= 1.5 * OMEGA * 1e-3
    assert np.abs(log.errors[-1]).max() <= 1.5 * OMEGA * 1e-3 * np.abs(E0).max()
    kinetic = np.array([Friction(f).kinetic if not isinstance(f, Friction) else f.kinetic for f in friction])
    f_n, f_t = log.plant_forces[:, :, 0], log.plant_forces[:, :, 1]
    for column, (i, v) in enumerate(zip((0, 1), speed), start=3):
        assert np.all(np.sign(np.diff(log.S[:, column])) == np.sign(v))  # keeps sliding, the asked way
        np.testing.assert_allclose(f_t[:, i], np.sign(v) * kinetic[i] * f_n[:, i], rtol=0, atol=1e-9)
    assert log.cone_margins[:, fixed].min() > 0.0
    assert f_n.min() > 0.0
    assert np.abs(log.plant_forces - log.predicted_forces).max() < 1e-6
    _, coarse, _ = run(name, duration=0.2, dt=1e-3)
    _, fine, _ = run(name, duration=0.2, dt=5e-4)
    assert 1.6 < coarse / fine < 2.4  # exact law: only the sampling error, first order in dt


def test_proposition3_sliding_directions_per_slider():
    model, _, mu, _ = model_of("prop3_p2")
    gains = Gains.critically_damped(OMEGA, 5)
    law = Proposition3Controller(model, gains, friction=mu, direction=(-1, 1))
    assert law.directions == (-1.0, 1.0)
    # slider 1 keeps its measured sign, slider 2 reverses within the sample under the commanded ξ̈
    assert law.sliding_directions((-0.01, 0.0005), (0.0, -1.0)) == (-1.0, -1.0)
    assert law.directions == (-1.0, -1.0)
    with pytest.raises(InvalidParameterError, match="sliding_directions"):
        law.sliding_direction(0.01, 0.0)
    for direction in ((1, 1, 1), (1, 0), 0.5):
        with pytest.raises(InvalidParameterError, match="direction"):
            Proposition3Controller(model, gains, friction=mu, direction=direction)
    assert Proposition3Controller(model, gains, friction=mu, direction=-1).directions == (-1.0, -1.0)


def test_proposition3_checks_two_m_at_least_three_plus_p():
    """2m >= 3 + p: m = 3 with all three sliding is the square case (f unique, only checked); the law
    refuses a grasp with too many sliders (Grasp itself refuses to build one, Remark 3.2)."""
    from types import SimpleNamespace

    from regrasp.core.exceptions import SlidingContactCountError

    hand = Hand([c.finger for c in SC.contacts] + [FINGER3], gravity_in_hand=(0.0, -9.81))
    all_sliding = ReducedModel(hand, Grasp(SC.polygon, [1, 3, 2], ["sliding"] * 3), xi=[0.0, 0.0, 0.0])
    law = Proposition3Controller(all_sliding, Gains.critically_damped(OMEGA, 6), friction=0.3, direction=(-1, 1, 1))
    S = np.array([0.0, 0.12, 0.0, 0.0, 0.0, 0.0])
    S_dot = np.array([0.0, 0.0, 0.0, -0.01, 0.01, 0.01])
    out = law(S, S_dot, S, S_dot, np.zeros(6))
    assert out.internal.null_space_dim == 0
    f_n, f_t = out.contact_forces_surface.T
    np.testing.assert_allclose(f_t, [-0.3 * f_n[0], 0.3 * f_n[1], 0.3 * f_n[2]], rtol=0, atol=1e-9)
    with pytest.raises(SlidingContactCountError):
        Grasp(SC.polygon, [1, 3], ["sliding", "sliding"])
    too_many = SimpleNamespace(grasp=SimpleNamespace(m=2, p=2, modes=("sliding", "sliding")))
    with pytest.raises(InvalidParameterError, match="2m >= 3 \\+ p"):
        Proposition3Controller(too_many, Gains.critically_damped(OMEGA, 5))


def test_priming_two_contacts_at_once_slips_both_on_the_plant():
    """Fixed-contact law with two cone edges at μ_s + 0.05 (the supervisor's priming, for two contacts
    at once): on the plant both side contacts slip within a few steps, each in its asked direction,
    and the bottom contact keeps sticking."""
    hand = Hand([c.finger for c in SC.contacts] + [FINGER3], gravity_in_hand=(0.0, -9.81))
    edges, xi = [1, 3, 2], [0.0, 0.0, 0.0]
    friction = [Friction(0.5, 0.3), Friction(0.5, 0.3), Friction(0.8, 0.5)]
    model = ReducedModel(hand, Grasp(SC.polygon, edges, ["fixed"] * 3), xi=xi)
    S0 = np.array([0.0, 0.12, 0.0])
    for signs in ((-1.0, 1.0), (1.0, -1.0)):  # both down the object, both up
        primes = (ConeEdge(0, signs[0], 0.55), ConeEdge(1, signs[1], 0.55))
        controller = FixedContactController(model, Gains.critically_damped(OMEGA, 3), friction=friction,
                                            internal_force=InternalForceSettings(f_min=0.2), cone_edge=primes)
        assert controller.cone_edge == primes
        st = model.state(S0, np.zeros(3))
        plant = Plant(hand, SC.polygon, [PlantContact(e, "fixed", x) for e, x in zip(edges, xi)], friction=friction,
                      dt=1e-3)
        plant.reset(st.q, st.q_dot, S0, np.zeros(3))
        log = run_closed_loop(plant, controller, lambda t: (S0, np.zeros(3), np.zeros(3)), 0.005)
        slips = {ev.contact: ev for ev in log.events if ev.kind == "slip"}
        assert set(slips) == {"finger1", "finger2"}, log.events
        assert all(ev.time <= 0.003 for ev in slips.values())
        assert [e.kind for e in log.events if e.contact == "finger3"] == []
        for i in (0, 1):
            assert plant.contacts[i].mode == "sliding" and plant.contacts[i].sign == signs[i]
        assert plant.contacts[2].mode == "fixed"

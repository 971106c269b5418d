"""The regrasp supervisor: its settings, its danger test, its slide targets and its refusals.

Closed-loop behaviour on the independent plant is in tests/rollout/test_build.py.
"""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from factories import DANGER_START_THREE
from regrasp import Friction, Hand, RunSpec, load_scenario
from regrasp.core.exceptions import InvalidParameterError
from regrasp.core.measurement import Measurement
from regrasp.dynamics.sliding import sliding_feasibility
from regrasp.envelope.planner import plan, plan_scenario
from regrasp.model.geometry import Geometry
from regrasp.supervisor.settings import ExecutorSettings, MonitorSettings, PaperSettings, SupervisorSettings
from regrasp.supervisor.supervisor import RegraspSupervisor
from regrasp.supervisor.types import ContactPhase

SCENARIOS = Path(__file__).resolve().parents[2] / "examples" / "scenarios"


@pytest.fixture(scope="module")
def two_fingers():
    return load_scenario(SCENARIOS / "paper_trajectory_2.toml")


#: The settings' branches, by field name (a test names a field; the tree holds it once).
BRANCHES = {**{f.name: ("monitor", f.name) for f in dataclasses.fields(MonitorSettings)},
            **{f.name: ("paper", f.name) for f in dataclasses.fields(PaperSettings)},
            **{f.name: ("executor", f.name) for f in dataclasses.fields(ExecutorSettings)}}


def settings_of(**values) -> SupervisorSettings:
    """SupervisorSettings with each named field set on its branch."""
    branches = {}
    for name, value in values.items():
        branch, field = BRANCHES[name]
        branches.setdefault(branch, {})[field] = value
    classes = {"monitor": MonitorSettings, "paper": PaperSettings, "executor": ExecutorSettings}
    return SupervisorSettings(**{b: classes[b](**v) for b, v in branches.items()})


def make_supervisor(sc, xi, *, plan=None, friction=None, **settings) -> RegraspSupervisor:
    hand = Hand([c.finger for c in sc.contacts], gravity_in_hand=sc.gravity_in_hand)
    return RegraspSupervisor(hand, sc.polygon, [c.edge for c in sc.contacts], sc.trajectory, xi,
                             sc.friction if friction is None else friction, plan=plan,
                             settings=settings_of(**settings))


def measurement(sc, t, xi) -> Measurement:
    m = len(sc.contacts)
    return Measurement(t, sc.trajectory.pose(t), sc.trajectory.velocity(t), np.asarray(xi, float), np.zeros(m),
                       np.zeros(m, bool), np.zeros(m))


@pytest.mark.parametrize("name, value", [
    ("danger_fraction", 0.0), ("danger_fraction", 0.5), ("omega_n", -1.0), ("zeta", 0.0), ("prime_time", np.nan),
    ("reaction_time", -0.1), ("every", 0), ("every", 1.5), ("geometry", "mesh"),
    ("settle_undershoot", 0.0), ("path_checks", 0), ("path_checks", 2.5), ("enabling_candidates", True),
    ("enabling_recheck_time", -1.0), ("track", 1),
])
def test_settings_reject_bad_values(name, value):
    with pytest.raises(InvalidParameterError) as info:
        settings_of(**{name: value})
    assert info.value.name == name


@pytest.mark.parametrize("branch, value", [("executor", None), ("monitor", "ideal"), ("paper", 1.0),
                                           ("scheduled", SupervisorSettings())])
def test_settings_branches_are_their_types(branch, value):
    with pytest.raises(InvalidParameterError) as info:
        SupervisorSettings(**{branch: value})
    assert info.value.name == branch


def test_the_geometry_is_one_type():
    assert settings_of(geometry="urdf").monitor.geometry is Geometry.URDF
    assert SupervisorSettings.robust("urdf").monitor.geometry is Geometry.URDF


def test_a_plan_for_other_fingers_is_rejected(two_fingers):
    one = plan(two_fingers.contacts[:1], two_fingers.polygon, two_fingers.trajectory, samples=5)
    with pytest.raises(InvalidParameterError):
        make_supervisor(two_fingers, [0.0, 0.0], plan=one)


def test_a_contact_in_the_middle_of_a_wide_envelope_is_left_alone(two_fingers):
    # at t = 1.0 s both side fingers' feasible sets span the whole edge (paper_trajectory_2 plan)
    sup = make_supervisor(two_fingers, [0.0, 0.0])
    out = sup.step(measurement(two_fingers, 1.0, [0.0, 0.0]), 1e-3)
    assert out.phases == (ContactPhase.FIXED, ContactPhase.FIXED)
    assert not [e for e in out.events if e.kind in ("danger", "prime")]
    assert np.all(out.margins > 0.1 * (out.bounds[:, 1] - out.bounds[:, 0]))
    assert out.law == "fixed contacts"
    assert np.all(np.isfinite(out.tau))


def test_the_danger_zone_is_a_tenth_of_the_interval(two_fingers):
    # finger 1's feasible set at t = 0 is [-20, -5] mm (ideal geometry): 1.5 mm danger zones
    sample = make_supervisor(two_fingers, [0.0, 0.0]).monitor.envelopes[0].at(two_fingers.trajectory.pose(0.0))
    ((lo, hi),) = sample.feasible
    for xi, expected in ((hi - 0.05 * (hi - lo), True), (hi - 0.15 * (hi - lo), False),
                         (lo + 0.05 * (hi - lo), True), (0.5 * (lo + hi), False)):
        sup = make_supervisor(two_fingers, [xi, 0.012], regrasp=False)
        out = sup.step(measurement(two_fingers, 0.0, [xi, 0.012]), 1e-3)
        flagged = any(e.kind == "danger" and e.contact == "finger1" for e in out.events)
        assert flagged is expected, (xi, lo, hi)
        assert out.phases[0] is ContactPhase.FIXED  # regrasp=False never slides


def test_two_equal_friction_fingers_refuse_to_slide_with_gravity_and_say_why(two_fingers):
    # finger 1 near the top of its interval must slide down (with gravity): impossible (Remark 3.3)
    sample = make_supervisor(two_fingers, [0.0, 0.0]).monitor.envelopes[0].at(two_fingers.trajectory.pose(0.0))
    ((lo, hi),) = sample.feasible
    xi = [hi - 0.02 * (hi - lo), 0.012]
    sup = make_supervisor(two_fingers, xi)
    out = sup.step(measurement(two_fingers, 0.0, xi), 1e-3)
    rejected = [e for e in out.events if e.kind == "slide_rejected"]
    assert rejected and rejected[0].contact == "finger1"
    assert "-xi" in rejected[0].detail and "pull" in rejected[0].detail
    assert out.phases[0] is ContactPhase.FIXED
    # asked again within recheck_time: no new log line, no new predicate call
    out2 = sup.step(measurement(two_fingers, 0.001, xi), 1e-3)
    assert not [e for e in out2.events if e.kind == "slide_rejected"]


def test_a_possible_slide_is_primed_on_the_cone_edge_towards_the_target(two_fingers):
    # finger 1 near the bottom of [-20, -5] mm slides up (against gravity): possible
    sample = make_supervisor(two_fingers, [0.0, 0.0]).monitor.envelopes[0].at(two_fingers.trajectory.pose(0.0))
    ((lo, hi),) = sample.feasible
    xi = [lo + 0.02 * (hi - lo), 0.012]
    sup = make_supervisor(two_fingers, xi, path_checks=1)  # asked where it starts only
    out = sup.step(measurement(two_fingers, 0.0, xi), 1e-3)
    assert out.phases[0] is ContactPhase.PRIMING
    assert out.targets[0] == pytest.approx(0.5 * (lo + hi))
    assert out.law == "fixed contacts (cone edge)"
    f_n, f_t = out.control.contact_forces_surface[0]
    overshoot = sup.settings.executor.prime_overshoot
    # + direction: up the edge
    assert f_t == pytest.approx((sup.context.friction[0].static + overshoot) * f_n, rel=1e-6)


@pytest.mark.parametrize("kinetic,settle", [(0.4, 0.35), (0.06, 0.03)])
def test_priming_breaks_away_past_mu_s_and_settling_stays_inside_mu_k(two_fingers, kinetic, settle):
    """μ_s = 0.8 on both tips: the priming asks for (μ_s + prime_overshoot) f_n = 0.85 f_n at the slider
    (past its static cone: it must break away); a slide that arrives still sliding settles with
    (μ_k - settle_undershoot) f_n, 0.35 f_n for μ_k = 0.4 (inside the kinetic cone; the plant's friction
    μ_k f_n slows it), and μ_k / 2 for a μ_k = 0.06 below twice the undershoot. The controllers report
    the static cone margin at the fixed contact (negative while priming, by the overshoot)."""
    friction = [Friction(0.8, kinetic)] * 2
    sample = make_supervisor(two_fingers, [0.0, 0.0]).monitor.envelopes[0].at(two_fingers.trajectory.pose(0.0))
    ((lo, hi),) = sample.feasible
    xi = [lo + 0.02 * (hi - lo), 0.012]
    sup = make_supervisor(two_fingers, xi, path_checks=1, friction=friction)
    assert sup.context.friction == tuple(friction)
    out = sup.step(measurement(two_fingers, 0.0, xi), 1e-3)
    assert out.phases[0] is ContactPhase.PRIMING and out.law == "fixed contacts (cone edge)"
    f_n, f_t = out.control.contact_forces_surface[0]
    assert f_t == pytest.approx(0.85 * f_n, rel=1e-9)
    assert out.control.cone_margins[0] == pytest.approx(0.8 * f_n - f_t, rel=1e-9) and out.control.cone_margins[0] < 0
    traj = two_fingers.trajectory

    def sensed(t, where, xi_dot):  # finger 1 sensed sliding
        return Measurement(t, traj.pose(t), traj.velocity(t), np.array([where, xi[1]]), np.array([xi_dot, 0.0]),
                           np.array([True, False]), np.zeros(2))

    out = sup.step(sensed(0.001, xi[0], 0.001), 1e-3)
    assert out.phases[0] is ContactPhase.SLIDING and out.law == "Proposition 3"
    f_n, f_t = out.control.contact_forces_surface[0]
    assert f_t == pytest.approx(kinetic * f_n, rel=1e-9)  # the slider on its kinetic edge
    out = sup.step(sensed(0.002, out.targets[0], 0.001), 1e-3)  # arrived, still sliding up
    assert [e.kind for e in out.events] == ["arrived"] and out.phases[0] is ContactPhase.SETTLING
    f_n, f_t = out.control.contact_forces_surface[0]
    assert f_t == pytest.approx(settle * f_n, rel=1e-9)


def test_a_slide_is_refused_when_the_holder_cannot_take_the_breakaway(two_fingers):
    """Finger 1 (μ_s = 0.8, μ_k = 0.1) would slide easily once moving, but its priming must first break
    it away past (0.8 + 0.05) f_n: finger 2 (μ = 0.5) cannot hold the moment of that much friction,
    so the predicate, asked at μ_s + prime_overshoot where the slide starts, refuses it; a slider with
    μ_s = 0.15 (the same μ_k) primes."""
    sample = make_supervisor(two_fingers, [0.0, 0.0]).monitor.envelopes[0].at(two_fingers.trajectory.pose(0.0))
    ((lo, hi),) = sample.feasible
    xi = [lo + 0.02 * (hi - lo), 0.012]
    sticky = make_supervisor(two_fingers, xi, path_checks=1, friction=[Friction(0.8, 0.1), Friction(0.5)])
    out = sticky.step(measurement(two_fingers, 0.0, xi), 1e-3)
    (rejected,) = [e for e in out.events if e.kind == "slide_rejected"]
    assert "fixed contact 1 would slip" in rejected.detail and "on the way" not in rejected.detail
    assert out.phases[0] is ContactPhase.FIXED
    smooth = make_supervisor(two_fingers, xi, path_checks=1, friction=[Friction(0.15, 0.1), Friction(0.5)])
    assert smooth.step(measurement(two_fingers, 0.0, xi), 1e-3).phases[0] is ContactPhase.PRIMING


def test_a_slide_is_asked_about_along_its_path(two_fingers):
    """The same slide, asked at its start, middle and target: at the target (ξ = -12.5 mm) finger 2
    would need more friction than the predicate's margin allows (checked here directly with
    sliding_feasibility), so it is rejected there, and said so."""
    sample = make_supervisor(two_fingers, [0.0, 0.0]).monitor.envelopes[0].at(two_fingers.trajectory.pose(0.0))
    ((lo, hi),) = sample.feasible
    xi = [lo + 0.02 * (hi - lo), 0.012]
    sup = make_supervisor(two_fingers, xi)
    assert sup.settings.paper.path_checks == 3
    out = sup.step(measurement(two_fingers, 0.0, xi), 1e-3)
    assert out.phases[0] is ContactPhase.FIXED
    (rejected,) = [e for e in out.events if e.kind == "slide_rejected"]
    assert "fixed contact 1 would slip" in rejected.detail and "-12.50 mm on the way" in rejected.detail
    target = 0.5 * (lo + hi)
    desired = two_fingers.trajectory.sample(min(6.0 / sup.settings.executor.omega_n, two_fingers.trajectory.t_end))
    at_target = sliding_feasibility(sup.context.grasp, desired.pose, [target, 0.012], desired.acceleration, 0, 1.0,
                                    sup.context.friction,
                                    object_mass=sup.context.object_mass, object_inertia=sup.context.object_inertia,
                                    gravity_in_hand=sup.hand.gravity_in_hand, settings=sup.settings.paper.feasibility)
    at_start = sliding_feasibility(sup.context.grasp, two_fingers.trajectory.pose(0.0), xi,
                                   two_fingers.trajectory.sample(0.0).acceleration, 0, 1.0, sup.context.friction,
                                   object_mass=sup.context.object_mass, object_inertia=sup.context.object_inertia,
                                   gravity_in_hand=sup.hand.gravity_in_hand, settings=sup.settings.paper.feasibility,
                                   edge_mu=sup.context.friction[0].static + sup.settings.executor.prime_overshoot)
    assert at_start.possible and not at_target.possible


def test_with_a_plan_the_supervisor_looks_ahead(two_fingers):
    # at t = 0.25 s finger 2 at 9.8 mm is 2.9 mm from the bound of [6.9, 20] mm (the danger zone is
    # 1.3 mm), but the bound rises to 8.9 mm by t = 0.5 s, inside the reaction time (0.4 s)
    result = plan_scenario(two_fingers)
    xi = [-0.0125, 0.0098]
    blind = make_supervisor(two_fingers, xi, regrasp=False)
    ahead = make_supervisor(two_fingers, xi, plan=result, regrasp=False)
    meas = measurement(two_fingers, 0.25, xi)
    out_blind, out_ahead = blind.step(meas, 1e-3), ahead.step(meas, 1e-3)
    danger_blind = [e for e in out_blind.events if e.kind == "danger" and e.contact == "finger2"]
    danger_ahead = [e for e in out_ahead.events if e.kind == "danger" and e.contact == "finger2"]
    assert not danger_blind
    assert danger_ahead and "the plan squeezes it" in danger_ahead[0].detail


THREE = SCENARIOS / "paper_trajectory_2_three_fingers.toml"


def test_a_rejected_slide_gets_another_contact_to_enable_it():
    """Three fingers at t = 1.737 s: finger 1 must slide down (-ξ) before its bound sweeps down,
    but with the palm under the centre the torque balance forbids it on the way. The supervisor
    slides the palm towards finger 1's side first; at the palm's target the slide is possible
    at every checked point (asked here directly, with the same settings)."""
    sc = load_scenario(THREE)
    xi = [0.01381, -0.01356, 0.00031]
    sup = make_supervisor(sc, xi, plan=plan_scenario(sc), geometry="urdf")
    t = 1.737
    out = sup.step(measurement(sc, t, xi), 1e-3)
    (rejected,) = [e for e in out.events if e.kind == "slide_rejected"]
    assert rejected.contact == "finger1" and "-xi" in rejected.detail and "on the way" in rejected.detail
    (prime,) = [e for e in out.events if e.kind == "prime"]
    assert prime.contact == "palm" and "to let finger1 slide -xi" in prime.detail
    assert out.phases[2] is ContactPhase.PRIMING and out.phases[0] is ContactPhase.FIXED
    (plo, phi), _ = sup.policy.kept_feasible(0, t, tuple(out.bounds[0]))  # what the policy aims finger1 at
    palm_target, finger1_target = out.targets[2], 0.5 * (plo + phi)
    assert palm_target > xi[2] + 1e-3  # +ξ on the bottom edge: towards finger 1's side

    def possible(where, when, palm):
        desired = sc.trajectory.sample(when)
        c = sup.context
        return sliding_feasibility(c.grasp, desired.pose, [where, xi[1], palm], desired.acceleration, 0, -1.0,
                                   c.friction, object_mass=c.object_mass, object_inertia=c.object_inertia,
                                   gravity_in_hand=c.hand.gravity_in_hand,
                                   settings=sup.settings.paper.feasibility).possible

    duration = 6.0 / sup.settings.executor.omega_n
    path = [(xi[0] + f * (finger1_target - xi[0]), t + duration + f * duration) for f in (0.5, 1.0)]
    assert not all(possible(w, when - duration, xi[2]) for w, when in path)  # with the palm where it is
    assert all(possible(w, when, palm_target) for w, when in path)          # with the palm moved


def test_a_slide_that_ends_sliding_settles_just_inside_the_cone_and_sticks():
    """After a slide arrives the contact is still sliding; the settling law asks μ_k f_n - max(0.05 f_n, 0.05 N)
    of friction in the sliding direction, so the plant's kinetic friction slows it and it sticks
    within a few periods, without slipping any other contact."""
    from regrasp import build_rollout

    rollout = build_rollout(load_scenario(THREE), RunSpec(duration=0.3, xi0=DANGER_START_THREE), policy="paper")
    result = rollout.run()
    assert result.success, result.failure
    kinds = [(e.contact, e.kind) for e in result.events]
    arrived = next(e for e in result.events if e.kind == "arrived")
    stick = next(e for e in result.events if e.kind == "stick" and e.contact == arrived.contact)
    assert 0.0 < stick.time - arrived.time <= 0.02
    settling = result.phases[(result.times >= arrived.time) & (result.times < stick.time), :]
    assert settling.size and np.all(settling[:, ["finger1", "finger2", "palm"].index(arrived.contact)] == "settling")
    for k, (contact, kind) in enumerate(kinds):  # every slip is a primed one
        if kind == "slip":
            assert (contact, "prime") in kinds[:k], kinds[:k + 1]


def test_tracked_runtime_envelopes_match_fresh_ones():
    """With track_envelopes the supervisor's urdf envelopes have the pieces of fresh ones, ends within
    the bisection tolerance, at every step along the three-finger trajectory (the measured pose is the
    desired one; no slide starts)."""
    sc = load_scenario(THREE)
    xi = [-0.0125, 0.0125, 0.0]
    tracked = make_supervisor(sc, xi, geometry="urdf", regrasp=False, track=True)
    fresh = make_supervisor(sc, xi, geometry="urdf", regrasp=False)
    assert fresh.monitor.trackers is None and len(tracked.monitor.trackers) == 3
    assert make_supervisor(sc, xi, track=True).monitor.trackers is None  # ideal: nothing to track
    for k in range(150):
        meas = measurement(sc, 1e-3 * k, xi)
        a, b = tracked.monitor.read(meas.t, meas.X, meas.xi), fresh.monitor.read(meas.t, meas.X, meas.xi)
        for i, env in enumerate(fresh.monitor.envelopes):
            tol = env.urdf_tolerance * env.edge.length
            sa, sb = a.samples[i], b.samples[i]
            assert len(sa.feasible) == len(sb.feasible)
            assert np.allclose(sa.feasible, sb.feasible, rtol=0.0, atol=tol)
            assert abs(a.margins[i] - b.margins[i]) <= tol
    assert sum(t.counts["tracked"] for t in tracked.monitor.trackers) > 0.9 * 3 * 150

"""The regrasp schedule planner (regrasp.schedule.planner) on the paper's scenarios.

Every returned schedule is re-checked here with checks that share no code with the planner:

* the envelopes with ``FingerEnvelope.at`` on a time grid four times finer than the planner's time
  step, offset by half a sub-step so that no time is one the planner sampled itself;
* the forces with a linear program (``tests/factories.force_lp``: hand-frame forces, Newton-Euler
  written from scratch, scipy's HiGHS) at the same times, in the schedule's modes: its sliders on
  their kinetic cone edges, its fixed contacts in their static cones by the required margin; and at
  each slide's start with the slider on its static edge (break-away);
* the slide profiles: speed and acceleration within the limits, the rates equal to finite
  differences, rest at both ends, at most min(m - 1, 2m - 3) sliders at once, periodicity.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from regrasp import Friction, load_scenario
from regrasp.core.exceptions import InvalidParameterError
from regrasp.schedule.planner import RegraspSettings, plan_regrasps
from regrasp.schedule.schedule import NoScheduleError, ScheduleLimit
from schedule_checks import check_schedule

pytestmark = pytest.mark.slow  # (rollouts, subprocesses: `pytest -m "not slow"` leaves them out)

SCENARIOS = Path(__file__).resolve().parents[2] / "examples" / "scenarios"


def _scenario(name: str, *, friction: Friction | None = None, gravity=None):
    sc = load_scenario(SCENARIOS / f"{name}.toml")
    if friction is not None:
        sc = dataclasses.replace(sc, contacts=tuple(dataclasses.replace(c, friction=friction) for c in sc.contacts))
    if gravity is not None:
        sc = dataclasses.replace(sc, gravity_in_hand=np.asarray(gravity, dtype=float))
    return sc


@pytest.fixture(scope="module")
def three_fingers():
    scenario = _scenario("paper_trajectory_2_three_fingers")
    settings = RegraspSettings()
    return scenario, settings, plan_regrasps(scenario, settings)


def test_three_fingers_get_a_periodic_schedule_with_the_required_margins(three_fingers):
    scenario, settings, schedule = three_fingers
    assert schedule.periodic
    assert schedule.t_end - schedule.t_start == pytest.approx(np.pi)
    assert schedule.min_envelope_margin >= 1e-3 and schedule.min_cone_margin >= 0.1
    per = schedule.slides_per_contact()
    assert per["finger1"] >= 2 and per["finger2"] >= 2  # each side finger moves both ways every period
    assert schedule.slides_lower_bound <= len(schedule.slides)
    # the reported per-sample values hold the guarantees too
    assert np.nanmin(schedule.envelope_margin) >= settings.envelope_margin - 1e-9
    fixed = schedule.sliding == 0
    assert np.all(schedule.cone_margin[fixed] >= settings.cone_margin - 1e-7)
    assert np.all(np.isnan(schedule.cone_margin[~fixed]))
    assert np.all(schedule.normal_force >= settings.f_min - 1e-7)


def test_three_finger_schedule_passes_the_independent_checks(three_fingers):
    scenario, settings, schedule = three_fingers
    seen = check_schedule(scenario, schedule, settings)
    assert seen["envelope"] >= schedule.min_envelope_margin - 2e-4  # the planner's own minimum is close


def test_the_schedule_repeats_over_the_scenarios_two_periods(three_fingers):
    scenario, _, schedule = three_fingers
    t = np.linspace(0.0, scenario.trajectory.t_end, 997)
    np.testing.assert_allclose(schedule.at(t).xi, schedule.at(np.mod(t, np.pi)).xi, atol=1e-12)


@pytest.mark.parametrize("friction", [None, Friction(0.8, 0.5)], ids=["mu_s=mu_k", "mu_s>mu_k"])
def test_two_fingers_have_no_schedule_and_the_rule_says_why(friction):
    scenario = _scenario("paper_trajectory_2", friction=friction)
    with pytest.raises(NoScheduleError) as info:
        plan_regrasps(scenario)
    err = info.value
    assert err.limit is ScheduleLimit.FORCES
    assert 1.0 < err.latest_time < 2.0
    assert err.rule is not None and "two-finger slide rule" in err.rule and "with gravity" in err.rule
    assert "the lower contact can never slide down" in err.rule
    if friction is None:
        assert "empty range" in err.rule
    assert err.partial is not None and err.partial.t_end == pytest.approx(err.latest_time)


def test_gravity_up_with_the_palm_under_has_no_schedule():
    scenario = _scenario("paper_trajectory_2_three_fingers", gravity=(0.0, 9.81))
    with pytest.raises(NoScheduleError) as info:
        plan_regrasps(scenario)
    assert info.value.limit is ScheduleLimit.FORCES
    assert "palm pushes along gravity" in str(info.value)


def test_gravity_up_with_a_finger_on_top_has_a_schedule():
    scenario = _scenario("paper_trajectory_2_gravity_up")
    settings = RegraspSettings()
    schedule = plan_regrasps(scenario, settings)
    assert schedule.periodic and schedule.min_envelope_margin >= 1e-3 and schedule.min_cone_margin >= 0.1
    check_schedule(scenario, schedule, settings)


def test_an_empty_envelope_is_named():
    scenario = _scenario("paper_trajectory_1")
    with pytest.raises(NoScheduleError) as info:
        plan_regrasps(scenario)
    err = info.value
    # finger2 runs off its edge at t = 0.110 s, and into condition I at 0.243 s (regrasp plan)
    assert err.limit is ScheduleLimit.ENVELOPE and err.contacts == ("finger2",) and "off the edge" in str(err)
    assert err.latest_time < 0.110


def test_slides_too_slow_for_the_envelope_are_named():
    scenario = _scenario("paper_trajectory_2_three_fingers")
    settings = RegraspSettings(max_slide_speed=0.005, max_slide_acceleration=1.0)
    with pytest.raises(NoScheduleError) as info:
        plan_regrasps(scenario, settings)
    assert info.value.limit is ScheduleLimit.SPEED


def test_a_given_start_is_kept_and_static_friction_above_kinetic_is_used(three_fingers):
    _, settings, first = three_fingers
    scenario = _scenario("paper_trajectory_2_three_fingers", friction=Friction(0.6, 0.5))
    again = plan_regrasps(scenario, settings, xi0=first.xi_start)
    np.testing.assert_allclose(again.xi_start, first.xi_start)
    assert again.periodic
    check_schedule(scenario, again, settings)


def test_settings_are_validated():
    for bad in (dict(envelope_margin=1e-4), dict(cone_margin=-1.0), dict(f_max=0.1), dict(max_slide_speed=0.0),
                dict(max_slide_acceleration=0.1), dict(max_sliders=0), dict(comfort_margin=5e-4),
                dict(geometry="mesh"), dict(envelope_substeps=0), dict(periodic="yes")):
        with pytest.raises(InvalidParameterError):
            RegraspSettings(**bad)
    with pytest.raises(InvalidParameterError):
        plan_regrasps("examples/scenarios/paper_trajectory_2.toml")


def test_start_positions_outside_the_envelope_are_named():
    scenario = _scenario("paper_trajectory_2_three_fingers")
    with pytest.raises(NoScheduleError) as info:
        plan_regrasps(scenario, xi0=[0.019, 0.012, 0.0])  # finger1's set at t = 0 is [-20, -5] mm
    err = info.value
    assert err.limit is ScheduleLimit.ENVELOPE and err.contacts == ("finger1",) and err.latest_time == 0.0
    assert "24.01 mm outside its feasible set at t = 3.122 s (where the periodic schedule is back" in str(err)
    with pytest.raises(InvalidParameterError):
        plan_regrasps(scenario, xi0=[0.019, 0.012])
    with pytest.raises(InvalidParameterError):
        plan_regrasps(scenario, xi0=[0.5, 0.0, 0.0])  # off the edge

"""Issue 27's variants of the default three-finger scenario (``tests/fixtures/issue27_variant_*.toml``): the
first plans a schedule and runs it over two periods on the project plant; the second ends with a physical reason
(the forces), not with a verification that never converges; the others: forces that fail between layers, and no
periodic schedule proven over two and over three periods in a row. (The fifth, Painlevé's: test_well_posed.py.)"""

from __future__ import annotations

from pathlib import Path

import pytest

from regrasp import RunSpec, load_scenario
from regrasp.rollout.build import build_rollout
from regrasp.schedule import NoScheduleError, RegraspSettings, ScheduleLimit, plan_regrasps

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures"


@pytest.mark.slow
def test_the_first_variant_runs_its_schedule_over_two_periods():
    scenario = load_scenario(FIXTURES / "issue27_variant_a.toml")
    rollout = build_rollout(scenario, RunSpec(duration=scenario.trajectory.t_end), policy="scheduled")
    result = rollout.run()
    assert result.schedule is not None and len(result.schedule.slides) >= 3
    assert result.success, result.failure
    assert result.replans == 0
    aborted = [e for e in result.events if e.kind.value in ("slide_aborted", "replan_failed")]
    assert not aborted, aborted[:3]


@pytest.mark.slow
def test_the_second_variant_ends_for_a_physical_reason():
    scenario = load_scenario(FIXTURES / "issue27_variant_b.toml")
    with pytest.raises(NoScheduleError) as info:
        plan_regrasps(scenario)
    assert info.value.limit is ScheduleLimit.FORCES
    assert "finger1" in str(info.value)


@pytest.mark.slow
def test_forces_that_fail_between_layers_are_planned_around():
    """The third variant's side fingers, sliding together, pass a thin set of positions without forces between two
    layers: the re-plans keep that move vector out of a widening window of layers, and the schedule verifies."""
    scenario = load_scenario(FIXTURES / "issue27_variant_c.toml")
    schedule = plan_regrasps(scenario)
    assert schedule.periodic and len(schedule.slides) >= 4
    assert schedule.min_envelope_margin >= 1e-3 and schedule.min_cone_margin >= 0.2 - 1e-9


def test_no_two_periods_in_a_row_is_a_proof_that_no_periodic_schedule_exists():
    """The fourth variant has a schedule over one period but none over two in a row: a periodic schedule run twice
    would be one, so the planner says PERIODIC, with when the second period dies; where it only failed to find one
    from the starts it tried, it says SEARCH (no proof)."""
    scenario = load_scenario(FIXTURES / "issue27_variant_d.toml")
    with pytest.raises(NoScheduleError) as info:
        plan_regrasps(scenario)
    assert info.value.limit is ScheduleLimit.PERIODIC
    assert "no schedule runs two periods in a row" in str(info.value)
    assert info.value.latest_time > scenario.trajectory.period
    one = plan_regrasps(scenario, RegraspSettings(periodic=False), t_end=scenario.trajectory.period)
    assert not one.periodic and len(one.slides) >= 1


def test_no_three_periods_in_a_row_is_a_proof_too():
    """The sixth variant, planned with a 3 mm position margin, runs two periods in a row but no periodic schedule comes
    from the starts tried; the third period dies from every state the first two can end in, so none exists: PERIODIC,
    with when it dies, not SEARCH (with the default 1 mm margin it has a periodic schedule)."""
    scenario = load_scenario(FIXTURES / "issue27_variant_f.toml")
    with pytest.raises(NoScheduleError) as info:
        plan_regrasps(scenario, RegraspSettings(position_margin=3e-3))
    assert info.value.limit is ScheduleLimit.PERIODIC
    assert "no schedule runs three periods in a row" in str(info.value)
    assert 2 * scenario.trajectory.period < info.value.latest_time < 3 * scenario.trajectory.period

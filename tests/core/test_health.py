"""Contact health (regrasp.core.health): the criteria, step by step, on hand-made force and slip series."""

import math

import pytest

from field_checks import field_tests, fields_of
from regrasp.core.events import FailureKind
from regrasp.core.exceptions import InvalidParameterError
from regrasp.core.health import HealthCriteria, HealthMonitor

DT = 1e-3


def run(forces, slips=None, held=None, criteria=HealthCriteria()):
    """Feed one contact's series; (the step index of the first loss or None, its failure, the monitor)."""
    monitor = HealthMonitor(criteria, ["f"], DT)
    slips = slips or [0.0] * len(forces)
    held = held or [True] * len(forces)
    for k, (fn, s, h) in enumerate(zip(forces, slips, held)):
        lost = monitor.observe(k * DT, [fn], [s], [h])
        if lost is not None:
            return k, lost, monitor
    return None, None, monitor


@pytest.mark.parametrize("bad", [dict(force_floor=0.0), dict(held_window=-1.0), dict(held_slip=math.nan),
                                 dict(slider_window=math.inf), dict(zero_window="2")])
def test_criteria_refuse_bad_values(bad):
    with pytest.raises(InvalidParameterError):
        HealthCriteria(**bad)


def test_monitor_refuses_bad_arguments():
    with pytest.raises(InvalidParameterError):
        HealthMonitor("strict", ["f"], DT)
    with pytest.raises(InvalidParameterError):
        HealthMonitor(HealthCriteria(), ["f"], 0.0)


def test_a_held_contact_survives_one_step_below_the_floor_and_is_lost_after_two():
    k, lost, _ = run([0.3, 0.01, 0.3, 0.3])
    assert lost is None
    k, lost, monitor = run([0.3, 0.049, 0.0, 0.3])
    assert k == 2 and lost.kind is FailureKind.SEPARATION and lost.contact == "f"
    assert lost.time == pytest.approx(3 * DT)  # (the end of the second step below the floor)
    assert "held f" in lost.reason and "2 ms" in lost.reason
    assert monitor.failure is lost


def test_the_floor_itself_is_enough():
    assert run([0.05] * 10)[1] is None


def test_a_held_contact_that_slips_past_the_limit_is_lost_and_a_new_hold_starts_from_zero():
    k, lost, _ = run([0.3] * 5, slips=[4e-5, 4e-5, 4e-5, 0.0, 0.0])
    assert k == 2 and lost.kind is FailureKind.UNPLANNED_SLIP
    # back and forth is no net slip; a slide in between (not held) resets it
    assert run([0.3] * 6, slips=[8e-5, -8e-5, 8e-5, -8e-5, 0.0, 0.0])[1] is None
    k, lost, monitor = run([0.3] * 4, slips=[8e-5, 5e-3, 8e-5, 0.0], held=[True, False, True, True])
    assert lost is None
    assert monitor.reports()[0].largest_held_slip == pytest.approx(8e-5)


def test_a_slider_may_hop_but_not_lose_its_force():
    # one step without force in five is a hop; two in a row are a loss
    hop = [0.3, 0.0, 0.3, 0.3, 0.3, 0.0, 0.3]
    assert run(hop, held=[False] * 7)[1] is None
    k, lost, _ = run([0.3, 0.3, 0.3, 0.3, 0.3, 0.0, 0.0, 0.3], held=[False] * 8)
    assert k == 6 and "no force for 2 ms" in lost.reason
    # light but never zero: the 5 ms average decides
    k, lost, _ = run([0.3] + [0.02] * 10, held=[False] * 11)
    assert lost is not None and "averaged" in lost.reason
    assert k == 5  # (steps 0-4: (0.3 + 4 × 0.02) / 5 = 0.076 N; steps 1-5: 0.02 N)


def test_reports_keep_the_least_forces_and_the_longest_window():
    monitor = HealthMonitor(HealthCriteria(), ["a", "b"], DT)
    series = [((0.4, 0.3), (True, False)), ((0.2, 0.0), (True, False)), ((0.3, 0.3), (True, False)),
              ((0.35, 0.4), (False, True))]
    for k, (fn, held) in enumerate(series):
        assert monitor.observe(k * DT, fn, (0.0, 0.0), held) is None
    a, b = monitor.reports()
    assert (a.least_held_force, a.least_held_force_at) == (0.2, DT)
    assert a.least_slider_force == pytest.approx((0.4 + 0.2 + 0.3 + 0.35) / 4)
    assert b.longest_zero_force == pytest.approx(DT) and b.longest_zero_force_at == DT
    assert b.least_held_force == 0.4 and b.least_slider_force == pytest.approx(0.15)
    assert a.to_json_dict()["contact"] == "a" and b.to_json_dict()["least_held_force_at"] == 3 * DT


CRITERIA_TABLE = fields_of(HealthCriteria(), {
    "pos": ("force_floor", "held_window", "held_slip", "slider_window", "zero_window")})

test_each_criterion_refuses_bad_values, test_each_criterion_refuses_generated_bad_values = field_tests(CRITERIA_TABLE)

"""Regrasp policies on synthetic inputs: the scheduled one (orders, periods, re-plans) and no regrasp.

No plant and no supervisor here: a policy is fed measurements, monitor readings and phases made up
by the test, and its orders and logged decisions are checked.
"""

import math

import numpy as np
import pytest

from regrasp.core.events import EventKind
from regrasp.core.exceptions import InvalidParameterError, RegraspError
from regrasp.core.measurement import Measurement
from regrasp.schedule.schedule import RegraspSchedule, Slide, slides_at
from regrasp.supervisor.monitor import EnvelopeReading
from regrasp.supervisor.policies.base import NoRegraspPolicy, OrderedSlidesPolicy
from regrasp.supervisor.policies.scheduled import ScheduledPolicy
from regrasp.supervisor.settings import ScheduledSettings
from regrasp.supervisor.types import ContactPhase, SlideEnd, SlideOrder

NAMES = ("a", "b")
FIXED = (ContactPhase.FIXED, ContactPhase.FIXED)


def schedule(slides, *, periodic=True, t_start=0.0, t_end=2.0, margin=0.004, xi_start=(0.0, 0.01)):
    """A hand-made schedule (the planner's fields, with a flat envelope margin)."""
    times = np.linspace(t_start, t_end, 101)
    at = slides_at(np.array(xi_start), slides, times)
    k, m = len(times), len(NAMES)
    return RegraspSchedule(NAMES, (1, 3), t_start, t_end, periodic, np.array(xi_start), tuple(slides), times, at.xi,
                           at.xi_dot, at.xi_ddot, at.direction, np.full((k, m), margin), np.full((k, m), 0.2),
                           np.ones((k, m)), 0.001, 0.1, margin, (0.0, "a"), 0.2, (0.0, "a"), 0.1)


# a slides up 10 mm in [0.5, 1.0] s, and back in [1.2, 1.7] s: the period ends where it starts
UP = Slide(0, "a", 1, 0.5, 1.0, 0.0, 0.01, 0.01)
DOWN = Slide(0, "a", -1, 1.2, 1.7, 0.01, 0.0, 0.01)


def meas(t, xi=(0.0, 0.01)):
    return Measurement(t, np.zeros(3), np.zeros(3), np.array(xi, float), np.zeros(2), np.zeros(2, bool), np.zeros(2))


def reading(t, margins=(0.004, 0.004)):
    return EnvelopeReading(t, (), np.array(margins, float), np.array([[-0.01, 0.02]] * 2), np.zeros((2, 2)), True)


def run_until(policy, t_end, dt=0.01, phases=FIXED):
    orders, events = [], []
    for t in np.arange(0.0, t_end, dt):
        orders += [(round(float(t), 6), o) for o in policy.propose(meas(t), reading(t), phases, events)]
    return orders, events


def test_each_slide_is_ordered_once_prime_lead_before_its_start_with_its_profile():
    policy = ScheduledPolicy(schedule([UP, DOWN]), NAMES, settings=ScheduledSettings(prime_lead=0.02))
    orders, events = run_until(policy, 2.0)
    assert [t for t, _ in orders] == [0.48, 1.18] and not events
    (_, up), (_, down) = orders
    assert (up.contact, up.direction, up.target, up.planned_start, up.planned_end) == (0, 1, 0.01, 0.5, 1.0)
    assert (down.direction, down.target, down.planned_end) == (-1, 0.0, 1.7)
    for when in (0.5, 0.55, 0.75, 0.99, 1.0):  # the order's reference is the slide's profile
        x, v, a = (float(c[0]) for c in UP.profile(np.array([when])))
        assert up.reference(when) == pytest.approx((x, v, a), abs=1e-15)


def test_a_periodic_schedule_repeats_its_slides_every_period():
    policy = ScheduledPolicy(schedule([UP, DOWN]), NAMES, settings=ScheduledSettings(prime_lead=0.0))
    orders, _ = run_until(policy, 6.0)
    assert [t for t, _ in orders] == [0.5, 1.2, 2.5, 3.2, 4.5, 5.2]
    assert orders[2][1].reference(2.75) == pytest.approx(orders[0][1].reference(0.75))
    assert np.allclose(policy.planned_xi(2.75), policy.planned_xi(0.75))


@pytest.mark.parametrize("lead", [0.0, 0.02])
def test_a_decision_period_issues_the_same_orders_at_the_same_steps(lead):
    """Deciding every 50 ms (and at slide starts and phase changes) orders what deciding every 1 ms orders,
    at the same steps: a due slide is never late; a phase change is acted on at the next step."""
    results = []
    for period in (0.0, 0.05):
        policy = ScheduledPolicy(schedule([UP, DOWN]), NAMES, settings=ScheduledSettings(prime_lead=lead,
                                                                                         decision_period=period))
        orders = []
        for j in range(6000):
            t = round(0.001 * j, 9)
            phases = (ContactPhase.SETTLING, ContactPhase.FIXED) if 2.47 <= t < 2.53 else FIXED
            orders += [(t, o.planned_start) for o in policy.propose(meas(t), reading(t), phases, [])]
        results.append(orders)
    assert results[0] == results[1] and len(results[0]) == 6
    assert results[0][2][0] == 2.53  # the third slide waited for its contact


def test_a_decision_period_must_be_shorter_than_the_schedule():
    with pytest.raises(InvalidParameterError, match="decision_period"):
        ScheduledPolicy(schedule([UP, DOWN]), NAMES, settings=ScheduledSettings(decision_period=2.0))
    with pytest.raises(InvalidParameterError):
        ScheduledSettings(decision_period=-0.1)


def test_a_slide_waits_for_its_contact_to_be_fixed():
    policy = ScheduledPolicy(schedule([UP]), NAMES, settings=ScheduledSettings(prime_lead=0.0))
    busy = (ContactPhase.SETTLING, ContactPhase.FIXED)
    assert policy.propose(meas(0.5), reading(0.5), busy, []) == []
    assert len(policy.propose(meas(0.51), reading(0.51), FIXED, [])) == 1


def late_end(order, by):
    return SlideEnd(order, EventKind.ARRIVED, order.planned_end + by, order.target)


def test_a_late_slide_triggers_one_logged_replan_once_every_contact_is_fixed():
    calls = []

    def replan(t, xi):
        calls.append((t, xi.copy()))
        return schedule([], periodic=False, t_start=t, t_end=4.0, xi_start=tuple(xi))

    policy = ScheduledPolicy(schedule([UP, DOWN]), NAMES, replan=replan,
                             settings=ScheduledSettings(prime_lead=0.0, time_tolerance=0.05))
    (order,) = policy.propose(meas(0.5), reading(0.5), FIXED, [])
    events = []
    policy.notify([late_end(order, 0.04)], meas(1.04), events)  # within the tolerance: nothing
    assert policy.propose(meas(1.05), reading(1.05), FIXED, events) == [] and not calls
    policy.notify([late_end(order, 0.08)], meas(1.08), events)
    busy = (ContactPhase.SETTLING, ContactPhase.FIXED)
    policy.propose(meas(1.08), reading(1.08), busy, events)
    assert not calls  # waits while a contact settles
    policy.propose(meas(1.09, (0.0098, 0.01)), reading(1.09), FIXED, events)
    assert len(calls) == 1 and calls[0][0] == 1.09 and calls[0][1].tolist() == [0.0098, 0.01]
    (replanned,) = [e for e in events if e.kind is EventKind.REPLAN]
    assert "ended arrived at t = 1.080 s" in replanned.detail and replanned.values["slides"] == 0
    assert policy.replans == 1 and not policy.schedule.periodic
    assert policy.propose(meas(1.2), reading(1.2), FIXED, []) == []  # the old DOWN slide is gone


def test_a_margin_below_half_the_planned_one_triggers_a_replan_and_a_failed_one_keeps_the_schedule():
    def replan(t, xi):
        raise RegraspError("no schedule from here")

    policy = ScheduledPolicy(schedule([UP, DOWN], margin=0.004), NAMES, replan=replan,
                             settings=ScheduledSettings(prime_lead=0.0, replan_cooldown=0.1))
    events = []
    policy.propose(meas(0.1), reading(0.1, (0.0021, 0.004)), FIXED, events)  # above half: nothing
    assert not events
    policy.propose(meas(0.2), reading(0.2, (0.0019, 0.004)), FIXED, events)
    (failed,) = events
    assert failed.kind is EventKind.REPLAN_FAILED and "a's envelope margin 1.90 mm" in failed.detail
    assert "no schedule from here" in failed.detail
    policy.propose(meas(0.25), reading(0.25, (0.0019, 0.004)), FIXED, events)
    assert len(events) == 1  # the cooldown
    assert len(policy.propose(meas(0.5), reading(0.5), FIXED, events)) == 1  # the old schedule still runs


def test_the_scheduled_policy_checks_its_arguments():
    with pytest.raises(InvalidParameterError):
        ScheduledPolicy("a schedule", NAMES)
    with pytest.raises(InvalidParameterError):
        ScheduledPolicy(schedule([UP]), ("a", "b", "c"))
    for bad in (dict(prime_lead=-1.0), dict(margin_fraction=1.0), dict(max_replans=1.5), dict(time_tolerance=math.nan)):
        with pytest.raises(InvalidParameterError):
            ScheduledSettings(**bad)


def test_no_regrasp_never_orders_and_plans_nothing():
    policy = NoRegraspPolicy(2)
    assert policy.propose(meas(0.0), reading(0.0, (-1.0, -1.0)), FIXED, []) == []
    assert np.isnan(policy.planned_xi(0.3)).all()


def test_ordered_slides_start_at_their_times_once_their_contacts_are_fixed():
    first, second = SlideOrder(0, 1, 0.01, planned_start=0.3), SlideOrder(1, -1, 0.0, planned_start=0.1)
    policy = OrderedSlidesPolicy([first, second], 2)
    busy = (ContactPhase.FIXED, ContactPhase.SLIDING)
    orders = [(round(float(t), 6), o) for t in np.arange(0.0, 0.5, 0.05)
              for o in policy.propose(meas(t), reading(t), busy if t < 0.2 else FIXED, [])]
    assert orders == [(0.2, second), (0.3, first)]  # the second waited for its contact
    assert np.isnan(policy.planned_xi(0.3)).all()
    with pytest.raises(InvalidParameterError):
        OrderedSlidesPolicy([SlideOrder(0, 1, 0.01)], 2)  # no planned start


def test_a_slide_order_checks_itself():
    with pytest.raises(InvalidParameterError):
        SlideOrder(0, 0, 0.01)
    with pytest.raises(InvalidParameterError):
        SlideOrder(0, 1, math.inf)


def test_quiet_until_is_the_next_decision_while_the_phases_stay():
    """Until quiet_until(phases) propose() returns nothing (compiled stretches run up to it); a phase change
    makes the next step a decision."""
    policy = ScheduledPolicy(schedule([UP, DOWN]), NAMES, settings=ScheduledSettings(decision_period=0.01))
    assert policy.quiet_until(FIXED) == -math.inf  # (nothing decided yet)
    assert policy.propose(meas(0.1), reading(0.1), FIXED, []) == []
    quiet = policy.quiet_until(FIXED)
    assert 0.11 - 2e-9 < quiet < 0.11  # (a period on, less the 1e-9 s that keeps t + k dt from missing it)
    assert policy.quiet_until((ContactPhase.SLIDING, ContactPhase.FIXED)) == -math.inf
    for t in np.arange(0.101, quiet, 0.001):
        assert policy.propose(meas(t), reading(t), FIXED, []) == [] and policy.quiet_until(FIXED) == quiet


def test_stretch_view_say_when_the_next_slide_is_due_and_end_with_the_period():
    policy = ScheduledPolicy(schedule([UP, DOWN]), NAMES, replan=lambda t, xi: schedule([UP]),
                             settings=ScheduledSettings(decision_period=0.01, prime_lead=0.02))
    terms = policy.stretch_view(0.1)
    assert terms["slide_due"] == pytest.approx(0.5 - 0.02 - 1e-9, abs=1e-12) and terms["end"] == 2.0
    assert terms["replan"] and terms["periodic"] and terms["margins"].shape == (101, 2)
    orders = run_until(policy, 0.6)[0]
    assert len(orders) == 1 and policy.stretch_view(0.6)["slide_due"] == pytest.approx(1.2 - 0.02 - 1e-9)
    assert policy.stretch_view(2.1)["end"] == 4.0 and policy.stretch_view(2.1)["slide_due"] == pytest.approx(
        2.5 - 0.02 - 1e-9)
    late = SlideEnd(orders[0][1], EventKind.ARRIVED, 1.2, 0.01)  # (0.2 s late: a re-plan is pending)
    policy.notify([late], meas(1.2), [])
    assert policy.stretch_view(1.2) is None


def test_planned_xi_series_uses_the_schedule_in_force_at_each_time():
    policy = ScheduledPolicy(schedule([UP, DOWN]), NAMES, replan=lambda t, xi: schedule([], xi_start=(0.005, 0.01)))
    times = np.linspace(0.0, 3.0, 31)
    before = policy.planned_xi_series(times)
    assert np.array_equal(before, np.array([policy.planned_xi(float(t)) for t in times]))
    policy.adopt(schedule([], xi_start=(0.005, 0.01)), 1.5)  # (a re-plan adopted at 1.5 s)
    after = policy.planned_xi_series(times)
    assert np.array_equal(after[times < 1.5], before[times < 1.5])
    assert np.all(after[times >= 1.5, 0] == 0.005)

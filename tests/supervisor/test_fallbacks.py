"""The order in which a step's law gives up its preferences (regrasp.supervisor.fallbacks)."""

import pytest

from regrasp.core.exceptions import InvalidParameterError
from regrasp.supervisor.fallbacks import (
    FEEDBACK_FRACTIONS,
    FLOOR_BISECTIONS,
    FLOOR_FRACTIONS,
    Fallback,
    fallbacks,
    first_feasible,
    largest_fraction,
)


class Infeasible(Exception):
    pass


def _solver(limit: float, calls: list, strict_limit: float | None = None):
    """A solve whose floors leave forces up to ``limit`` of them (with the whole feedback and the edges), and up to
    ``strict_limit`` (None: ``limit``) with the whole friction margin."""
    def solve(fraction, gain=1.0, edges=True, relaxed=True):
        calls.append((fraction, gain, edges, relaxed))
        if fraction > (limit if relaxed or strict_limit is None else strict_limit):
            raise Infeasible(fraction)
        return (fraction, gain, edges, relaxed)
    return solve


def test_floors_go_first_then_the_friction_margin_then_the_feedback_then_the_settling_edges():
    order = fallbacks(floored=True, relaxable=True, settling=True)
    n = len(FLOOR_FRACTIONS)
    assert order[0] == Fallback(1.0, 1.0, True, False)
    assert order[-1] == Fallback(FLOOR_FRACTIONS[-1], FEEDBACK_FRACTIONS[-1], False, True)
    assert [f.floors for f in order[:n]] == list(FLOOR_FRACTIONS) == [f.floors for f in order[n:2 * n]]
    assert not any(f.relaxed for f in order[:n]) and all(f.relaxed for f in order[n:])  # the margin before the floors
    assert all(f.feedback == 1.0 for f in order[:2 * n])  # the whole feedback while floors remain
    assert all(f.floors == 0.0 for f in order[2 * n:])
    assert len(set(order)) == len(order)
    assert all(f.edges for f in fallbacks(True, True, settling=False))  # no settling contact: its edges stay
    # without a fallback friction margin there is nothing to relax: the same law, not tried twice
    assert [f[:3] for f in fallbacks(True, False, True)] == [f[:3] for f in order[n:]]


def test_a_law_without_floors_gives_up_only_the_margin_and_the_feedback():
    for relaxable in (False, True):
        order = fallbacks(floored=False, relaxable=relaxable, settling=False)
        assert [(f.floors, f.edges) for f in order] == [(1.0, True)] * (len(FEEDBACK_FRACTIONS) + relaxable)
        assert [f.feedback for f in order] == [1.0] * relaxable + list(FEEDBACK_FRACTIONS)


@pytest.mark.parametrize("limit", [0.0, 0.03, 0.3, 0.5, 0.74, 0.99])
def test_the_largest_fraction_is_found_within_one_bisection_step_and_never_above_what_leaves_forces(limit):
    calls = []
    found = largest_fraction(_solver(limit, calls), 0.0, 1.0, (0.0, 1.0, True, True), errors=(Infeasible,))
    assert found[0] <= limit and limit - found[0] < 0.5**FLOOR_BISECTIONS
    assert len(calls) == FLOOR_BISECTIONS


def test_first_feasible_bisects_the_floors_it_gave_up_and_keeps_the_whole_feedback_and_margin():
    order = fallbacks(floored=True, relaxable=True, settling=True)
    calls = []
    found = first_feasible(order, _solver(0.6, calls), Infeasible)
    assert found[1:] == (1.0, True, False) and 0.6 - 0.5**FLOOR_BISECTIONS < found[0] <= 0.6
    assert calls[:2] == [(1.0, 1.0, True, False), (0.0, 1.0, True, False)] and len(calls) == 2 + FLOOR_BISECTIONS
    calls.clear()  # the whole floors leave forces: one solve
    assert first_feasible(order, _solver(1.0, calls), Infeasible) == (1.0, 1.0, True, False)
    assert len(calls) == 1


def test_more_floors_are_never_bought_with_the_friction_margin():
    """Where the whole margin leaves forces only up to 0.2 of the floors and the fallback margin up to 0.9, the step
    keeps the whole margin and about 0.2 of the floors; only where the whole margin leaves none at f_min does it relax
    (and then bisects the floors with the relaxed margin)."""
    order = fallbacks(floored=True, relaxable=True, settling=False)
    calls = []
    found = first_feasible(order, _solver(0.9, calls, strict_limit=0.2), Infeasible)
    assert found[3] is False
    assert 0.2 - 0.5**FLOOR_BISECTIONS < found[0] <= 0.2
    assert all(not c[3] for c in calls)
    calls.clear()
    found = first_feasible(order, _solver(0.9, calls, strict_limit=-1.0), Infeasible)
    assert found[3] is True and 0.9 - 0.5**FLOOR_BISECTIONS < found[0] <= 0.9


def test_first_feasible_raises_the_last_error_and_refuses_an_empty_order():
    def never(fraction, gain, edges, relaxed):
        raise Infeasible((fraction, gain, edges, relaxed))
    order = fallbacks(floored=True, relaxable=True, settling=False)
    with pytest.raises(Infeasible) as info:
        first_feasible(order, never, Infeasible)
    assert info.value.args[0] == order[-1]
    with pytest.raises(InvalidParameterError):
        first_feasible([], never, Infeasible)

"""The order in which a step's law gives up its preferences (regrasp.supervisor.fallbacks)."""

import pytest

from regrasp.core.exceptions import InvalidParameterError
from regrasp.dynamics.internal_force.settings import InternalForceSettings
from regrasp.supervisor.fallbacks import (
    FEEDBACK_FRACTIONS,
    FLOOR_BISECTIONS,
    FLOOR_FRACTIONS,
    fallbacks,
    first_feasible,
    largest_fraction,
)


class Infeasible(Exception):
    pass


def _solver(limit: float, calls: list):
    """A solve whose floors leave forces up to ``limit`` of them (with the whole feedback and the edges)."""
    def solve(fraction, gain=1.0, edges=True):
        calls.append((fraction, gain, edges))
        if fraction > limit:
            raise Infeasible(fraction)
        return (fraction, gain, edges)
    return solve


def test_floors_go_first_then_the_feedback_then_the_settling_edges_and_the_last_is_f_min_without_feedback():
    floored = InternalForceSettings(f_min=0.2, floors=(0.3, 0.3, 0.3))
    order = fallbacks(floored, settling=True)
    assert order[0] == (1.0, 1.0, True) and order[-1] == (FLOOR_FRACTIONS[-1], FEEDBACK_FRACTIONS[-1], False)
    assert [f for f, g, e in order[:len(FLOOR_FRACTIONS)]] == list(FLOOR_FRACTIONS)
    assert all(g == 1.0 for _, g, _ in order[:len(FLOOR_FRACTIONS)])  # the whole feedback while floors remain
    assert all(f == 0.0 for f, _, _ in order[len(FLOOR_FRACTIONS):])
    assert len(set(order)) == len(order)
    assert all(e for _, _, e in fallbacks(floored, settling=False))  # no settling contact: its edges stay


def test_a_law_without_floors_gives_up_only_feedback():
    for settings in (None, InternalForceSettings(f_min=0.2)):
        order = fallbacks(settings, settling=False)
        assert [(f, e) for f, _, e in order] == [(1.0, True)] * len(FEEDBACK_FRACTIONS)
        assert [g for _, g, _ in order] == list(FEEDBACK_FRACTIONS)


@pytest.mark.parametrize("limit", [0.0, 0.03, 0.3, 0.5, 0.74, 0.99])
def test_the_largest_fraction_is_found_within_one_bisection_step_and_never_above_what_leaves_forces(limit):
    calls = []
    found = largest_fraction(_solver(limit, calls), 0.0, 1.0, (0.0, 1.0, True), errors=(Infeasible,))
    assert found[0] <= limit and limit - found[0] < 0.5**FLOOR_BISECTIONS
    assert len(calls) == FLOOR_BISECTIONS


def test_first_feasible_bisects_the_floors_it_gave_up_and_keeps_the_whole_feedback():
    floored = InternalForceSettings(f_min=0.2, floors=(0.3, 0.3, 0.3))
    calls = []
    found = first_feasible(fallbacks(floored, settling=True), _solver(0.6, calls), Infeasible)
    assert found[1:] == (1.0, True) and 0.6 - 0.5**FLOOR_BISECTIONS < found[0] <= 0.6
    assert calls[:2] == [(1.0, 1.0, True), (0.0, 1.0, True)] and len(calls) == 2 + FLOOR_BISECTIONS
    calls.clear()  # the whole floors leave forces: one solve
    assert first_feasible(fallbacks(floored, settling=True), _solver(1.0, calls), Infeasible) == (1.0, 1.0, True)
    assert len(calls) == 1


def test_first_feasible_raises_the_last_error_and_refuses_an_empty_order():
    def never(fraction, gain, edges):
        raise Infeasible((fraction, gain, edges))
    order = fallbacks(InternalForceSettings(f_min=0.2, floors=(0.3, 0.3, 0.3)), settling=False)
    with pytest.raises(Infeasible) as info:
        first_feasible(order, never, Infeasible)
    assert info.value.args[0] == order[-1]
    with pytest.raises(InvalidParameterError):
        first_feasible([], never, Infeasible)

"""The order in which a step's law gives up its preferences (regrasp.supervisor.fallbacks)."""

from regrasp.dynamics.internal_force.settings import InternalForceSettings
from regrasp.supervisor.fallbacks import FEEDBACK_FRACTIONS, FLOOR_FRACTIONS, fallbacks


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

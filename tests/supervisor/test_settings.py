"""The supervisor's settings (regrasp.supervisor.settings): every field of every settings type checked on
construction (tests/field_checks.py), and issue 25's reproducers."""

import math

import numpy as np
import pytest

from field_checks import field_tests, fields_of, short_id
from regrasp.core.exceptions import InvalidParameterError
from regrasp.supervisor.settings import (
    ExecutorSettings,
    MonitorSettings,
    PaperSettings,
    ScheduledSettings,
    SupervisorSettings,
)

TABLE = [
    *fields_of(ExecutorSettings(), {
        "pos": ("omega_n", "zeta", "prime_time", "prime_overshoot", "prime_overshoot_max", "settle_undershoot",
                "arrive_tolerance", "arrive_speed", "max_slide_time", "friction_filter_time", "friction_min_force",
                "friction_resolution", "control_period", "control_omega", "slide_omega", "hold_resolution",
                "hold_filter_time", "reflex_time", "handover_load_max"),
        "nonneg": ("start_speed", "settle_margin", "integral", "tip_radius", "slider_floor", "holder_preload",
                   "reflex_below", "reflex_floor", "handover_time", "reprime_overshoot_step"),
        "count0": ("max_reprimes", "actuation_delay"), "flag": ("breakaway_estimate",), "type": ("internal_force",)},
        optional=("start_speed", "friction_filter_time", "hold_resolution", "hold_filter_time"),
        good={"start_speed": 1e-3, "friction_filter_time": 0.01, "hold_filter_time": 0.02}),
    *fields_of(MonitorSettings(), {"geometry": ("geometry",), "count1": ("every",), "flag": ("track",)}),
    *fields_of(PaperSettings(), {
        "pos": ("danger_fraction", "reaction_time", "target_horizon", "recheck_time", "enabling_recheck_time"),
        "count1": ("path_checks", "enabling_candidates"), "flag": ("regrasp", "enabling"), "type": ("feasibility",)}),
    *fields_of(ScheduledSettings(), {
        "nonneg": ("prime_lead", "time_tolerance", "xi_tolerance", "margin_fraction", "replan_cooldown",
                   "decision_period"),
        "count0": ("max_replans",), "flag": ("replan",)}),
    *fields_of(SupervisorSettings(), {"type": ("executor", "monitor", "paper", "scheduled")}),
]


test_each_field_refuses_bad_values, test_each_field_refuses_generated_bad_values = field_tests(TABLE)


@pytest.mark.parametrize("name", ["path_checks", "enabling_candidates"])
@pytest.mark.parametrize("value", [math.nan, None, "abc", math.inf, object(), 10**400, 2.0], ids=short_id)
def test_paper_counts_are_bounded_integers(name, value):
    """Issue 25: NaN, None, a string, inf, an object and 10**400 were a ValueError/TypeError/OverflowError from
    ``int()``, or accepted."""
    with pytest.raises(InvalidParameterError, match=name):
        PaperSettings(**{name: value})
    assert getattr(PaperSettings(**{name: np.int64(4)}), name) == 4


@pytest.mark.parametrize("value", [math.nan, None, "abc", math.inf, object(), 10**400, 1.5, True], ids=short_id)
def test_counts_of_the_other_settings_are_bounded_integers(value):
    for make, name in ((ScheduledSettings, "max_replans"), (MonitorSettings, "every"),
                       (ExecutorSettings, "max_reprimes"), (ExecutorSettings, "actuation_delay")):
        with pytest.raises(InvalidParameterError, match=name):
            make(**{name: value})
    assert type(ScheduledSettings(max_replans=np.int64(3)).max_replans) is int


def test_prime_overshoot_max_is_a_finite_number():
    for value in (math.inf, "0.1", None):
        with pytest.raises(InvalidParameterError, match="prime_overshoot_max"):
            ExecutorSettings(prime_overshoot_max=value)

"""The internal-force QP's settings (regrasp.dynamics.internal_force.settings): every field checked on construction
(tests/field_checks.py)."""

import math

import pytest

from field_checks import field_tests, fields_of
from regrasp.core.exceptions import InvalidParameterError
from regrasp.dynamics.internal_force.settings import InternalForceSettings

TABLE = fields_of(InternalForceSettings(), {
    "nonneg": ("f_min", "friction_margin", "target_cone_margin", "fallback_friction_margin"), "pos": ("tolerance",),
    "pos+inf": ("f_max",), "other": ("floors", "last_friction_margin")},
    optional=("fallback_friction_margin", "last_friction_margin"),
    good={"fallback_friction_margin": 0.01, "f_max": 20.0},
    empty_ok=("floors",))

test_each_field_refuses_bad_values, test_each_field_refuses_generated_bad_values = field_tests(TABLE)


def test_f_max_may_be_inf_and_the_floors_are_floats():
    settings = InternalForceSettings(f_max=math.inf, floors=[1, 0.5])
    assert settings.f_max == math.inf and settings.floors == (1.0, 0.5) and type(settings.floors[0]) is float
    with pytest.raises(InvalidParameterError, match="floors"):
        InternalForceSettings(floors=[0.1, True])


def test_the_last_friction_margin_is_below_the_fallback_one():
    settings = InternalForceSettings(friction_margin=0.1, fallback_friction_margin=0.05, last_friction_margin=0.0)
    assert settings.last_friction_margin == 0.0
    for fallback, last in ((None, 0.0), (0.05, 0.05), (0.05, 0.07), (0.05, -0.01), (0.05, math.nan), (0.05, "0")):
        with pytest.raises(InvalidParameterError, match="last_friction_margin"):
            InternalForceSettings(friction_margin=0.1, fallback_friction_margin=fallback, last_friction_margin=last)

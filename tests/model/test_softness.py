"""Contact softness drawn per run (regrasp.model.softness)."""

import math

import numpy as np
import pytest

from field_checks import field_tests, fields_of
from regrasp.core.exceptions import InvalidParameterError
from regrasp.model.softness import ContactSoftness, SoftnessRanges


def test_draws_are_seeded_and_inside_the_ranges():
    ranges = SoftnessRanges()
    a = [ranges.draw(np.random.default_rng(s)) for s in range(200)]
    b = [ranges.draw(np.random.default_rng(s)) for s in range(200)]
    assert a == b
    for name in ("time_constant", "solimp_width", "tip_radius"):
        lo, hi = getattr(ranges, name)
        values = np.array([getattr(x, name) for x in a])
        assert lo <= values.min() and values.max() <= hi
        assert values.max() - values.min() > 0.8 * (hi - lo)  # (spread over the range)
    fixed = SoftnessRanges(tip_radius=(5e-4, 5e-4)).draw(np.random.default_rng(1))
    assert fixed.tip_radius == 5e-4
    assert "solref 0.25-2 ms" in ranges.describe()
    assert a[0].to_json_dict()["tip_radius"] == a[0].tip_radius


@pytest.mark.parametrize("bad", [dict(time_constant=(2e-3, 1e-3)), dict(solimp_width=(0.0, 1e-4)),
                                 dict(tip_radius=1e-3), dict(tip_radius=(1e-4, math.nan)), dict(time_constant="ab")])
def test_ranges_refuse_bad_values(bad):
    with pytest.raises(InvalidParameterError):
        SoftnessRanges(**bad)


def test_a_softness_refuses_bad_values():
    with pytest.raises(InvalidParameterError):
        ContactSoftness(1e-3, -1e-4, 1e-3)


TABLE = [*fields_of(SoftnessRanges(), {"other": ("time_constant", "solimp_width", "tip_radius")}),
         *fields_of(ContactSoftness(1e-3, 1e-4, 5e-4), {"pos": ("time_constant", "solimp_width", "tip_radius")})]

test_each_field_refuses_bad_values, test_each_field_refuses_generated_bad_values = field_tests(TABLE)

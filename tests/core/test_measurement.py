"""Measurement: what a hand senses, and the friction ratio read from it."""

import math

import numpy as np
import pytest

from regrasp.core.measurement import Measurement


def sensed(normal, tangential):
    z = np.zeros(3)
    return Measurement(0.0, z, z, np.zeros(2), np.zeros(2), np.zeros(2, bool), np.array(tangential, float),
                       None if normal is None else np.array(normal, float))


def test_force_ratio_is_the_tangential_over_the_normal_force_of_one_contact():
    m = sensed((0.5, 2.0), (-0.2, 0.3))
    assert m.force_ratio(0) == pytest.approx(0.4) and m.force_ratio(1) == pytest.approx(0.15)


@pytest.mark.parametrize("normal", [None, (0.05, 1.0), (0.0, 1.0), (-0.1, 1.0), (math.nan, 1.0)])
def test_force_ratio_is_nan_without_a_sensed_normal_force_above_the_floor(normal):
    assert math.isnan(sensed(normal, (0.01, 0.0)).force_ratio(0, min_force=0.05))

"""Interval-set helpers against a brute-force membership grid."""

import numpy as np
import pytest

from regrasp.core.intervals import contains, intersect, merge, total_length, widest


def _random_set(rng, n):
    pts = np.sort(rng.uniform(-5, 5, size=2 * n))
    return merge(zip(pts[::2], pts[1::2]))


def _mask(intervals, grid):
    out = np.zeros(grid.shape, bool)
    for lo, hi in intervals:
        out |= (grid >= lo) & (grid <= hi)
    return out


@pytest.mark.parametrize("seed", range(20))
def test_intersect_and_merge_match_pointwise_logic(seed):
    rng = np.random.default_rng(seed)
    a, b = _random_set(rng, rng.integers(0, 5)), _random_set(rng, rng.integers(0, 5))
    grid = np.linspace(-6, 6, 4001)
    ends = np.array([x for iv in (*a, *b) for x in iv])
    away = np.all(np.abs(grid[:, None] - ends[None, :]) > 1e-9, axis=1) if ends.size else np.ones_like(grid, bool)
    np.testing.assert_array_equal(_mask(intersect(a, b), grid)[away], (_mask(a, grid) & _mask(b, grid))[away])
    np.testing.assert_array_equal(_mask(merge([*a, *b]), grid)[away], (_mask(a, grid) | _mask(b, grid))[away])
    for iv in (intersect(a, b), merge([*a, *b])):
        assert all(lo < hi for lo, hi in iv)
        assert all(iv[k][1] < iv[k + 1][0] for k in range(len(iv) - 1))


def test_merge_joins_touching_and_drops_empty():
    assert merge([(0, 1), (1, 2), (3, 3), (5, 4)]) == ((0.0, 2.0),)
    assert merge([(0, 1), (1.05, 2)], gap=0.1) == ((0.0, 2.0),)


def test_contains_total_length_widest():
    s = ((0.0, 1.0), (2.0, 4.5))
    assert contains(s, 1.0) and not contains(s, 1.5) and contains(s, 1.5, tol=0.6)
    assert total_length(s) == pytest.approx(3.5)
    assert widest(s) == (2.0, 4.5)
    assert widest(()) is None

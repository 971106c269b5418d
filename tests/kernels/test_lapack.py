"""The kernels' LAPACK calls (regrasp.kernels.lapack) against numpy's solve and lstsq, which call the same routines."""

import numpy as np
import pytest

from regrasp.kernels.lapack import checked_fortran_copy, gelsd, gesv


def fortran_copy(a: np.ndarray) -> np.ndarray:
    return np.array(a.T, order="C")  # a copy: LAPACK destroys it (ascontiguousarray may return a view of a)


@pytest.mark.parametrize("n", [1, 2, 3, 6, 9])
def test_gesv_is_numpys_solve(n):
    rng = np.random.default_rng(n)
    for _ in range(50):
        a, b = rng.normal(size=(n, n)), rng.normal(size=n)
        x = b.copy()
        assert gesv(fortran_copy(a), x) == 0
        np.testing.assert_allclose(x, np.linalg.solve(a, b), rtol=1e-12, atol=1e-12)
        assert np.allclose(a @ x, b)


def test_gesv_reports_a_singular_matrix():
    a = np.array([[1.0, 2.0], [2.0, 4.0]])
    assert gesv(fortran_copy(a), np.ones(2)) > 0


@pytest.mark.parametrize("rows, cols", [(1, 3), (2, 5), (3, 3), (4, 7), (6, 2)])
def test_gelsd_is_numpys_lstsq(rows, cols):
    rng = np.random.default_rng(10 * rows + cols)
    for rank_deficient in (False, True):
        a, b = rng.normal(size=(rows, cols)), rng.normal(size=rows)
        if rank_deficient and min(rows, cols) > 1:
            a[-1] = a[0]  # a repeated row: rank one less
        rhs = np.zeros(max(rows, cols))
        rhs[:rows] = b
        singular = np.empty(min(rows, cols))
        info, rank = gelsd(fortran_copy(a), rows, cols, rhs, singular)
        x, _, expected_rank, expected_singular = np.linalg.lstsq(a, b, rcond=None)
        assert info == 0 and rank == expected_rank
        np.testing.assert_allclose(rhs[:cols], x, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(singular, expected_singular, rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("where", ["a", "b"])
def test_a_non_finite_entry_is_numpys_error(where):
    a, b = np.eye(2), np.ones(2)
    (a if where == "a" else b)[1, ...] = np.nan
    fortran, rhs = np.empty((2, 2)), np.empty(2)
    with pytest.raises(np.linalg.LinAlgError, match="infs or NaNs"):
        checked_fortran_copy(a, b, fortran, rhs)

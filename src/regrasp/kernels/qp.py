r"""A small dense QP solver, compiled: the internal-force QP's few variables, solved exactly.

The internal-force QP (:mod:`regrasp.dynamics.internal_force.solver`) has k <= 2m - 3 variables (plus the margin
variable s) and a dozen rows; OSQP solves it iteratively to a tolerance in ~10 µs, most of it set-up and the Python
around it. Its objective has a diagonal Hessian, so it is a *least-distance problem* (Lawson & Hanson,
*Solving Least Squares Problems*, 1974, ch. 23):

.. math:: \min_v \tfrac12 v^T D v + q^T v \ \text{ s.t. } \ a_r^T v \ge b_r\ (r < n_{ineq}),\ a_r^T v = b_r

with :math:`D = \mathrm{diag}(d) \succ 0`. Substituting :math:`z = D^{1/2} v` and :math:`w = z - z_0`,
:math:`z_0 = -D^{-1/2} q`, gives :math:`\min \tfrac12\|w\|^2` s.t. :math:`g_r^T w \ge h_r` with
:math:`g_r = D^{-1/2} a_r` and :math:`h_r = b_r - g_r^T z_0` (an equality as two opposite inequalities).
Its solution comes from one non-negative least-squares problem: with :math:`E = [G^T; h^T]` and
:math:`f = e_{n+1}`, :math:`u = \arg\min_{u \ge 0}\|E u - f\|` (Lawson–Hanson active set) and
:math:`r = E u - f`; the constraints are inconsistent iff :math:`r = 0`, else :math:`w = -r_{1..n}/r_{n+1}`.
At the NNLS optimum :math:`E^T r \ge 0` and :math:`u^T E^T r = 0`, so :math:`\|r\|^2 = -r_{n+1}` and a
feasible problem with solution norm :math:`\|w\|` has :math:`\|r\|^2 = 1/(1 + \|w\|^2)`: the test
:math:`\|r\|^2 \le 10^{-14}` calls infeasible only what would need :math:`\|w\| > 10^7` (N, here).

The active set terminates in finitely many steps (each passive set is visited once); the answer is exact to
round-off, where OSQP's is within its tolerance. ``tests/kernels/test_qp.py`` checks both against each other
and the KKT conditions on random problems.
"""

from __future__ import annotations

import numba
import numpy as np

from .lapack import checked_fortran_copy, gelsd

__all__ = ["INFEASIBLE", "NOT_CONVERGED", "SOLVED", "back_substitute", "diagonal_qp", "householder_into",
           "least_distance", "matmul", "matvec", "nnls"]

#: statuses of :func:`diagonal_qp` and :func:`least_distance`
SOLVED, INFEASIBLE, NOT_CONVERGED = 0, 1, 2

_EPS = np.finfo(np.float64).eps

@numba.njit(cache=True)
def matvec(a: np.ndarray, x: np.ndarray, transpose: bool = False) -> np.ndarray:
    """a x (or aᵀ x) in loops: on these few rows and columns a BLAS call's set-up costs more than the work."""
    rows, cols = a.shape
    if transpose:
        out = np.zeros(cols)
        for i in range(rows):
            xi = x[i]
            for j in range(cols):
                out[j] += a[i, j] * xi
        return out
    out = np.zeros(rows)
    for i in range(rows):
        acc = 0.0
        for j in range(cols):
            acc += a[i, j] * x[j]
        out[i] = acc
    return out


@numba.njit(cache=True)
def matmul(a: np.ndarray, b: np.ndarray, transpose_a: bool = False) -> np.ndarray:
    """a b (or aᵀ b) in loops (see :func:`matvec`)."""
    if transpose_a:
        inner, rows = a.shape
    else:
        rows, inner = a.shape
    cols = b.shape[1]
    out = np.zeros((rows, cols))
    for i in range(rows):
        for k in range(inner):
            aik = a[k, i] if transpose_a else a[i, k]
            if aik != 0.0:
                for j in range(cols):
                    out[i, j] += aik * b[k, j]
    return out


@numba.njit(cache=True)
def _reflect(r: np.ndarray, j: int, first: int, scale: float, target: np.ndarray) -> None:
    """Apply the reflection I - scale v vᵀ (v: column j of r from row j down) to target's columns from
    ``first`` on, rows j and below."""
    for col in range(first, target.shape[1]):
        dot = 0.0
        for i in range(j, r.shape[0]):
            dot += r[i, j] * target[i, col]
        dot *= scale
        for i in range(j, r.shape[0]):
            target[i, col] -= dot * r[i, j]


@numba.njit(cache=True)
def householder_into(r: np.ndarray, y: np.ndarray) -> float:
    r"""Householder QR in place, in loops (a few rows and columns, where LAPACK's set-up costs more than the
    work): ``r`` (rows, cols), rows >= cols, becomes R (its upper triangle; below it, scratch) and ``y``
    (rows, k) becomes :math:`Q^T y`. Returns :math:`\min|R_{jj}| / \max|R_{jj}|` (0 for a zero column)."""
    rows, cols = r.shape
    largest, smallest = 0.0, np.inf
    for j in range(cols):
        norm = 0.0
        for i in range(j, rows):
            norm += r[i, j] * r[i, j]
        norm = np.sqrt(norm)
        if norm == 0.0:
            return 0.0
        alpha = -norm if r[j, j] >= 0.0 else norm
        v0 = r[j, j] - alpha
        vnorm = v0 * v0 + norm * norm - r[j, j] * r[j, j]  # ‖v‖² with v = x - alpha e_1
        r[j, j] = v0  # (column j below the diagonal is v's tail already)
        if vnorm > 0.0:
            _reflect(r, j, j + 1, 2.0 / vnorm, r)
            _reflect(r, j, np.int64(0), 2.0 / vnorm, y)  # (not the literal 0: one compile of _reflect)
        r[j, j] = alpha
        largest = max(largest, abs(alpha))
        smallest = min(smallest, abs(alpha))
    return smallest / largest if cols else 1.0


@numba.njit(cache=True)
def back_substitute(upper: np.ndarray, y: np.ndarray) -> np.ndarray:
    """x with upper x = y for the upper triangle of ``upper`` (its first n = y.size rows and columns)."""
    n = y.size
    x = np.empty(n)
    for j in range(n - 1, -1, -1):
        acc = y[j]
        for col in range(j + 1, n):
            acc -= upper[j, col] * x[col]
        x[j] = acc / upper[j, j]
    return x


@numba.njit(cache=True)
def _lstsq(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.linalg.lstsq(a, b)[0]`` for a (rows, cols) and b (rows,): the minimum-norm least-squares solution by
    LAPACK's ``dgelsd`` (:func:`~regrasp.kernels.lapack.gelsd`, called as numba's ``np.linalg.lstsq`` calls it, without
    compiling numba's general ``lstsq``: about 3.5 s of a cold compile)."""
    rows, cols = a.shape
    if rows == 0 or cols == 0:
        raise np.linalg.LinAlgError("Arrays cannot be empty")
    size = max(rows, cols)
    fortran = np.empty((cols, rows))  # (a's copy in Fortran order: fortran.T; dgelsd destroys it)
    rhs = np.zeros(size)
    checked_fortran_copy(a, b, fortran, rhs)
    singular = np.empty(min(rows, cols))
    info, _ = gelsd(fortran, rows, cols, rhs, singular)
    if info != 0:  # (numba's errors: < 0 cannot happen here)
        raise ValueError("Internal algorithm failed to converge.")
    return rhs[:cols].copy()


@numba.njit(cache=True)
def _least_squares(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """argmin ‖a x - b‖ for a (rows, cols) by :func:`householder_into`; a rank-deficient or wide a goes to
    LAPACK's minimum-norm solution (:func:`_lstsq`, ``np.linalg.lstsq``'s)."""
    rows, cols = a.shape
    if cols > rows:
        return _lstsq(a, b)
    r = a.copy()
    y = b.copy().reshape(rows, 1)
    if not householder_into(r, y) > max(rows, cols) * _EPS * 10.0:
        return _lstsq(a, b)
    return back_substitute(r, y[:cols, 0].copy())


@numba.njit(cache=True)
def nnls(E: np.ndarray, f: np.ndarray, u: np.ndarray, max_iterations: int) -> bool:
    r"""Lawson–Hanson NNLS: :math:`u = \arg\min_{u \ge 0}\|E u - f\|` written into ``u`` (r,); E (n, r).
    False if it did not terminate within ``max_iterations`` inner steps."""
    n, r = E.shape
    passive = np.zeros(r, dtype=np.bool_)
    skip = np.zeros(r, dtype=np.bool_)  # entered with a non-positive solution (round-off): not tried again
    u[:] = 0.0
    scale = 0.0
    for i in range(n):
        for j in range(r):
            scale = max(scale, abs(E[i, j]))
    tol = 10.0 * _EPS * max(n, r) * max(scale, 1.0)
    residual = f - matvec(E, u)
    w = matvec(E, residual, True)
    z = np.zeros(r)
    iterations = 0
    while True:
        t, best = -1, tol
        for j in range(r):
            if not passive[j] and not skip[j] and w[j] > best:
                t, best = j, w[j]
        if t < 0:
            return True
        passive[t] = True
        while True:
            iterations += 1
            if iterations > max_iterations:
                return False
            cols = np.nonzero(passive)[0]
            sub = np.empty((n, cols.size))
            for c in range(cols.size):
                for i in range(n):
                    sub[i, c] = E[i, cols[c]]
            sol = _least_squares(sub, f)
            z[:] = 0.0
            positive = True
            for c in range(cols.size):
                z[cols[c]] = sol[c]
                if sol[c] <= 0.0:
                    positive = False
            if positive:
                for j in range(r):
                    u[j] = z[j]
                break
            if z[t] <= 0.0 and u[t] == 0.0 and passive[t]:  # the entering column itself (only round-off)
                passive[t] = False
                skip[t] = True
                continue
            alpha, leaving = 1.0, -1
            for j in cols:
                if z[j] <= 0.0:
                    step = u[j] / (u[j] - z[j])
                    if step < alpha or leaving < 0:
                        alpha, leaving = step, j
            for j in cols:
                u[j] += alpha * (z[j] - u[j])
                if j == leaving or u[j] <= tol:  # (the one that set alpha is 0 up to round-off)
                    u[j] = 0.0
                    passive[j] = False
        residual = f - matvec(E, u)
        w = matvec(E, residual, True)


@numba.njit(cache=True)
def least_distance(G: np.ndarray, h: np.ndarray, w: np.ndarray, max_iterations: int) -> int:
    r""":math:`w = \arg\min \|w\|` s.t. :math:`G w \ge h` (G (rows, n)), written into ``w`` (n,); the status
    (:data:`SOLVED`, :data:`INFEASIBLE` or :data:`NOT_CONVERGED`); the module docstring."""
    rows, n = G.shape
    E = np.empty((n + 1, rows))
    for r in range(rows):
        for i in range(n):
            E[i, r] = G[r, i]
        E[n, r] = h[r]
    f = np.zeros(n + 1)
    f[n] = 1.0
    u = np.empty(rows)
    if not nnls(E, f, u, max_iterations):
        return NOT_CONVERGED
    res = matvec(E, u) - f
    norm2 = 0.0
    for i in range(n + 1):
        norm2 += res[i] * res[i]
    if norm2 <= 1e-14:
        return INFEASIBLE
    for i in range(n):
        w[i] = -res[i] / res[n]
    return SOLVED


@numba.njit(cache=True)
def diagonal_qp(d: np.ndarray, q: np.ndarray, a: np.ndarray, b: np.ndarray, n_ineq: int, v: np.ndarray) -> int:
    r""":math:`\min \tfrac12 v^T \mathrm{diag}(d) v + q^T v` s.t. :math:`a_r^T v \ge b_r` for the first
    ``n_ineq`` rows of a (rows, n), :math:`= b_r` for the others; the solution into ``v`` (n,), the status
    (:data:`SOLVED`, :data:`INFEASIBLE`, :data:`NOT_CONVERGED`). ``d`` > 0 (the caller's)."""
    rows, n = a.shape
    n_eq = rows - n_ineq
    scale = np.sqrt(d)
    z0 = -q / scale
    G = np.empty((n_ineq + 2 * n_eq, n))
    h = np.empty(n_ineq + 2 * n_eq)
    for r in range(rows):
        gz = 0.0
        for i in range(n):
            g = a[r, i] / scale[i]
            G[r, i] = g
            gz += g * z0[i]
        h[r] = b[r] - gz
        if r >= n_ineq:  # the equality's other side, -g w >= -h
            for i in range(n):
                G[r + n_eq, i] = -G[r, i]
            h[r + n_eq] = -h[r]
    w = np.empty(n)
    status = least_distance(G, h, w, 50 * (G.shape[0] + n + 1))
    if status == SOLVED:
        for i in range(n):
            v[i] = (w[i] + z0[i]) / scale[i]
    return status

r"""The internal-force QP of :class:`regrasp.dynamics.internal_force.solver.InternalForceSolver`, compiled in one call.

What :meth:`InternalForceSolver.solve <regrasp.dynamics.internal_force.solver.InternalForceSolver.solve>` does around
OSQP, with the dense solver of :mod:`.qp` in its place: an orthonormal basis :math:`N_c` of
:math:`\mathrm{null}(A^T)` (Householder QR of A, the last 2m - c columns of Q; a rank-deficient A is reported,
and the caller takes the reference path's SVD), the rows :math:`C f \ge lo` at the contacts' surface frames
(``regrasp.dynamics.internal_force.rows``: row r is :math:`\alpha_r n_i^T f_i + \beta_r t_i^T f_i - \sigma_r s`), the QP
in :math:`y` (or :math:`(y, s)` with a target cone margin: weight W on :math:`(s - \text{target} - \delta)^2`,
:math:`0 \le s \le` target), :math:`f_c = N_c y`, and the same check of the predicted forces
:math:`f_m + f_c` as the reference path (every row to a slack of :math:`10^{-6}\max(1, |f_m|_\infty)` N, or
:math:`10^{-9}` of it when nothing is chosen, k = 0), with the cone margin: the least residual of the
static-cone rows. Joint torque limits add rows :math:`|w_j + J_j^T f_i| \le e_j` where the answer without them
exceeds one (:func:`internal_force_into`). ``f_c`` is basis-independent (the objective is
:math:`\tfrac12\|N_c y\|^2 = \tfrac12\|y\|^2`),
so the answer is the reference's, exact where OSQP's is within its tolerance.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .qp import SOLVED, diagonal_qp, householder_into, matmul, matvec

__all__ = ["FORCE_CHECK_FAILED", "FORCE_INFEASIBLE", "FORCE_NOT_APPLICABLE", "FORCE_NOT_CONVERGED", "FORCE_SOLVED",
           "exceeds_effort", "internal_force_into", "null_basis"]

#: statuses of :func:`internal_force_into`: NOT_APPLICABLE is a rank-deficient A or a non-finite input (the
#: caller takes the reference path); CHECK_FAILED a solution whose forces miss a row by more than the slack
FORCE_SOLVED, FORCE_INFEASIBLE, FORCE_NOT_CONVERGED, FORCE_NOT_APPLICABLE, FORCE_CHECK_FAILED = 0, 1, 2, 3, 4

_EPS = np.finfo(np.float64).eps


@numba.njit(cache=True)
def null_basis(A: np.ndarray, out: np.ndarray) -> int:
    r"""An orthonormal basis of :math:`\mathrm{null}(A^T)` for A (rows, c), rows >= c, into ``out``
    (rows, rows - c): Q's last columns in a Householder QR :math:`A = QR` (:func:`.qp.householder_into` on
    :math:`[A \mid I]` gives :math:`Q^T`). Returns rows - c, or -1 when A is not of full column rank (the
    reference path's test: :math:`\min|R_{jj}| \le \max|R_{jj}|\,\max(rows, c)\,\epsilon`)."""
    rows, c = A.shape
    qt = np.eye(rows)
    if not householder_into(A.copy(), qt) > max(rows, c) * _EPS:
        return -1
    for i in range(rows):
        for j in range(rows - c):
            out[i, j] = qt[c + j, i]
    return rows - c


@numba.njit(cache=True)
def _solve_rows(A, f_m, C, lower, n_ineq, is_cone, target, margin_column, weight, aim, f_c, forces):
    """The QP of the module docstring on rows given in the hand frame, ``C`` (rows, 2m) f >= ``lower`` (the first
    ``n_ineq`` inequalities, then equalities); (status, k, cone margin) as :func:`internal_force_into`."""
    m2, c = A.shape
    rows = lower.size
    scale = 1.0
    for i in range(m2):
        scale = max(scale, abs(f_m[i]))
    basis = np.empty((m2, max(m2 - c, 0)))
    k = null_basis(A, basis) if m2 >= c else -1
    if k < 0:
        return FORCE_NOT_APPLICABLE, 0, math.nan
    slack = 1e-9 * scale
    f_c[:] = 0.0
    if k > 0:
        slack = 1e-6 * scale
        margin_var = target > 0.0
        n = k + 1 if margin_var else k
        extra = 1 if margin_var else 0
        a = np.zeros((rows + extra, n))
        b = np.empty(rows + extra)
        cn = matmul(C, basis)
        cf = matvec(C, f_m)
        for r in range(rows):
            out_r = r if r < n_ineq else r + extra  # (s <= target goes after the inequalities)
            for j in range(k):
                a[out_r, j] = cn[r, j]
            if margin_var:
                a[out_r, k] = margin_column[r]
            b[out_r] = lower[r] - cf[r]
        d = np.ones(n)
        q = np.zeros(n)
        if margin_var:
            d[k] = weight
            q[k] = -weight * (target + aim)
            a[n_ineq, k] = -1.0  # -s >= -target
            b[n_ineq] = -target
        v = np.empty(n)
        status = diagonal_qp(d, q, a, b, n_ineq + extra, v)
        if status != SOLVED:
            return status, k, math.nan  # (INFEASIBLE, NOT_CONVERGED: the same codes)
        for i in range(m2):
            acc = 0.0
            for j in range(k):
                acc += basis[i, j] * v[j]
            f_c[i] = acc
    for i in range(m2):
        forces[i] = f_m[i] + f_c[i]
    # (the reference path's check, ``regrasp.dynamics.internal_force.rows.ConstraintRows.check_at``, compiled)
    ok = True
    margin = math.inf
    for r in range(rows):
        residual = -lower[r]
        for i in range(m2):
            residual += C[r, i] * forces[i]
        if r < n_ineq:
            if not residual >= -slack:
                ok = False
            if is_cone[r] and residual < margin:
                margin = residual
        elif not abs(residual) <= slack:
            ok = False
    return (FORCE_SOLVED if ok else FORCE_CHECK_FAILED), k, margin


@numba.njit(cache=True)
def exceeds_effort(jac: np.ndarray, wrench: np.ndarray, effort: np.ndarray, forces: np.ndarray) -> bool:
    r"""Whether some joint torque :math:`\tau = w + J^T f` (per finger, J_i row-major (a, b, c, d) in ``jac``
    (m, 4), ``wrench`` w = M q̈ + N (2m) [N m]) exceeds its limit: :math:`|\tau_j| > e_j` (``effort`` (2m) [N m],
    inf: none)."""
    for i in range(jac.shape[0]):
        f0, f1 = forces[2 * i], forces[2 * i + 1]
        t0 = wrench[2 * i] + jac[i, 0] * f0 + jac[i, 2] * f1
        t1 = wrench[2 * i + 1] + jac[i, 1] * f0 + jac[i, 3] * f1
        if abs(t0) > effort[2 * i] or abs(t1) > effort[2 * i + 1]:
            return True
    return False


@numba.njit(cache=True)
def internal_force_into(A: np.ndarray, f_m: np.ndarray, frames: np.ndarray, coefficients: np.ndarray,
                        lower: np.ndarray, n_ineq: int, is_cone: np.ndarray, target: float,
                        margin_column: np.ndarray, weight: float, aim: float, jac: np.ndarray, wrench: np.ndarray,
                        effort: np.ndarray, f_c: np.ndarray, forces: np.ndarray) -> tuple[int, int, float]:
    r"""The internal force of the module docstring into ``f_c`` and ``forces`` (2m,), hand frame.

    Args:
        A: :math:`[G^T \mid R_f B_v]` or the law's own equations (2m, c); f_c spans null(Aᵀ).
        f_m: The motion forces (2m,) [N].
        frames: Per contact (n_x, n_y, t_x, t_y), hand frame (m, 4).
        coefficients: The rows in surface coordinates (rows, 2m): (α_r, β_r) in contact i's columns.
        lower: lo_r (rows,); the first ``n_ineq`` rows are inequalities, the rest equalities.
        is_cone: Whether each row is a static-cone row (rows,).
        target: The target cone margin [N]; > 0 adds the variable s (``margin_column`` its σ_r, ``weight``
            W and ``aim`` δ [N] the objective's, :data:`regrasp.dynamics.internal_force.rows.MARGIN_WEIGHT` and
            ``MARGIN_AIM``).
        jac: For the joint torque limits (:mod:`regrasp.dynamics.internal_force.torque`), per finger its tip
            Jacobian J_i row-major (m, 4) [m/rad].
        wrench: w = M q̈ + N (2m) [N m].
        effort: The limits e (2m) [N m] (inf: none), so that :math:`\tau = w + J^T f` and
            :math:`|\tau_j| \le e_j`. They are rows of the QP only where the answer without them exceeds a limit
            (its optimum is then not the constrained one); otherwise that answer is the constrained problem's
            optimum already, bit for bit the same as without limits.

    Returns:
        (status, k, cone margin [N]): ``FORCE_*``; k the null space's dimension; the least static-cone
        residual at the forces (inf without such rows).
    """
    m2, c = A.shape
    rows = lower.size
    if not (np.isfinite(A).all() and np.isfinite(f_m).all() and np.isfinite(frames).all()):
        return FORCE_NOT_APPLICABLE, 0, math.nan
    # C f: the rows in the hand frame
    C = np.zeros((rows, m2))
    for r in range(rows):
        for i in range(m2 // 2):
            alpha, beta = coefficients[r, 2 * i], coefficients[r, 2 * i + 1]
            if alpha != 0.0 or beta != 0.0:
                C[r, 2 * i] = alpha * frames[i, 0] + beta * frames[i, 2]
                C[r, 2 * i + 1] = alpha * frames[i, 1] + beta * frames[i, 3]
    status, k, margin = _solve_rows(A, f_m, C, lower, n_ineq, is_cone, target, margin_column, weight, aim, f_c,
                                    forces)
    if status != FORCE_SOLVED or not exceeds_effort(jac, wrench, effort, forces):
        return status, k, margin
    # the limits bind: the same problem with the torque rows among the inequalities, w_j + J_jᵀ f_i >= -e_j and
    # -w_j - J_jᵀ f_i >= -e_j (J_j: column j of J_i)
    n_torque = 0
    for j in range(m2):
        if np.isfinite(effort[j]):
            n_torque += 2
    C2 = np.zeros((rows + n_torque, m2))
    lower2 = np.empty(rows + n_torque)
    is_cone2 = np.zeros(rows + n_torque, np.bool_)
    margin2 = np.zeros(rows + n_torque)
    for r in range(rows):
        out_r = r if r < n_ineq else r + n_torque
        for j in range(m2):  # (a loop: a row assignment compiles a formatted shape check)
            C2[out_r, j] = C[r, j]
        lower2[out_r] = lower[r]
        is_cone2[out_r] = is_cone[r]
        if target > 0.0:
            margin2[out_r] = margin_column[r]
    r = n_ineq
    for i in range(m2 // 2):
        for j in range(2):
            e = effort[2 * i + j]
            if not np.isfinite(e):
                continue
            cx, cy = jac[i, j], jac[i, 2 + j]  # column j of J_i
            w = wrench[2 * i + j]
            C2[r, 2 * i], C2[r, 2 * i + 1], lower2[r] = cx, cy, -e - w
            C2[r + 1, 2 * i], C2[r + 1, 2 * i + 1], lower2[r + 1] = -cx, -cy, w - e
            r += 2
    return _solve_rows(A, f_m, C2, lower2, n_ineq + n_torque, is_cone2, target, margin2, weight, aim, f_c, forces)

r"""The internal (squeezing) force, chosen by a QP (paper §3.3, eq. 3.3.7).

A torque :math:`\tau_{Ic} = J^T f_c` with :math:`f_c` in the null space of
:math:`A^T = [G;\ B_v^T R_f^T]` changes no object motion and no sliding motion
(:math:`H^T \tau_{Ic} = A^T f_c = 0`): it only redistributes the contact forces. With
:math:`f_m` the contact forces the motion part of the torque produces, the predicted force
is :math:`f = f_m + f_c`, :math:`f_c = N_c y` (:math:`N_c` an orthonormal basis of the null
space, :math:`\dim = 2m - 3 - p`). The QP

.. math:: \min_y \tfrac12 \|f_c\|^2 = \tfrac12 y^T y \quad \text{s.t.}\quad
          f_{min} \le n_i^T f_i\ (\le f_{max})\ \forall i,\qquad
          |t_i^T f_i| \le (\mu_i - \text{margin})\, n_i^T f_i\ \text{for fixed } i

keeps every contact pushing and every fixed contact inside a linearized friction cone with
a margin, with the least squeeze. Optionally one contact is put exactly on its cone edge in
a given direction, :math:`t_j^T f_j = s \mu_j n_j^T f_j` (the transition before it slides, §4).

:func:`build_internal_force_qp` returns the ``qpsolvers.Problem`` (and the data to read its
solution); :func:`solve_internal_force_qp` solves it with OSQP and raises
:class:`InternalForceInfeasibleError` (carrying the problem and the solver status) when it
cannot. With an empty null space (m = 2, p = 1) there is nothing to choose: the result says
so and only reports whether the predicted forces satisfy the constraints.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass

import numpy as np
import osqp
import qpsolvers
import scipy.linalg
import scipy.sparse as sp

from .exceptions import InvalidParameterError, RegraspError

__all__ = [
    "ConeEdge",
    "InternalForceInfeasibleError",
    "InternalForceQP",
    "InternalForceResult",
    "InternalForceSettings",
    "InternalForceSolver",
    "build_internal_force_qp",
    "solve_internal_force_qp",
]


@dataclass(frozen=True)
class InternalForceSettings:
    """Margins of the internal-force QP.

    Attributes:
        f_min: Minimum normal force [N] at every contact.
        margin: Friction margin [-]: fixed contacts keep |f_t| <= (μ - margin) f_n.
        tolerance: OSQP absolute and relative tolerance.
        f_max: Maximum normal force [N] at every contact (what the fingers can push), or inf.
    """

    f_min: float = 0.5
    margin: float = 0.05
    tolerance: float = 1e-9
    f_max: float = float("inf")


@dataclass(frozen=True)
class ConeEdge:
    """Put contact ``contact`` on the edge of its friction cone, sliding direction ``sign`` (±1)."""

    contact: int
    sign: float


@dataclass(frozen=True)
class InternalForceQP:
    """A built internal-force QP and what is needed to read its solution.

    Attributes:
        problem: The ``qpsolvers.Problem`` in y (f_c = N_c y); None when the null space is empty.
        null_basis: N_c, (2m, k), orthonormal columns.
        motion_forces: f_m, (2m,), hand frame.
        settings: The margins used.
    """

    problem: qpsolvers.Problem | None
    null_basis: np.ndarray
    motion_forces: np.ndarray
    settings: InternalForceSettings


@dataclass(frozen=True)
class InternalForceResult:
    """The chosen internal force.

    Attributes:
        f_c: Internal contact forces (2m,) [N], hand frame.
        forces: Predicted contact forces f_m + f_c, (m, 2) [N], hand frame.
        null_space_dim: k = 2m - 3 - p (0: nothing to choose, forces only checked).
        feasible: Whether the predicted forces satisfy the QP's constraints.
        status: Solver status (``"solved"``, ``"empty null space"``...).
        seconds: Wall time of building and solving [s].
    """

    f_c: np.ndarray
    forces: np.ndarray
    null_space_dim: int
    feasible: bool
    status: str
    seconds: float


class InternalForceInfeasibleError(RegraspError):
    """No internal force keeps every contact inside its cone with the requested margins.

    Attributes:
        qp: The :class:`InternalForceQP` (its ``problem`` is the qpsolvers problem).
        status: The solver's status string.
    """

    def __init__(self, qp: InternalForceQP, status: str):
        self.qp = qp
        self.status = status
        super().__init__(
            f"internal-force QP infeasible (solver status: {status}): no squeeze keeps every contact "
            f"pushing with >= {qp.settings.f_min} N and every fixed contact inside its friction cone "
            f"with margin {qp.settings.margin}"
        )


def _constraint_rows(frames, fixed, mu, settings, cone_edge):
    """Rows (a, lo) meaning a . f_i >= lo on the predicted force of contact i (plus equalities)."""
    ineq, eq = [], []
    for i, frame in enumerate(frames):
        n, t = frame[:, 0], frame[:, 1]
        ineq.append((i, n, settings.f_min))
        if np.isfinite(settings.f_max):
            ineq.append((i, -n, -settings.f_max))
        if fixed[i] and (cone_edge is None or cone_edge.contact != i):
            slope = mu[i] - settings.margin
            ineq.append((i, slope * n - t, 0.0))
            ineq.append((i, slope * n + t, 0.0))
    if cone_edge is not None:
        j = cone_edge.contact
        n, t = frames[j][:, 0], frames[j][:, 1]
        eq.append((j, t - cone_edge.sign * mu[j] * n, 0.0))
    return ineq, eq


def build_internal_force_qp(
    constraint_matrix: np.ndarray,
    motion_forces: np.ndarray,
    surface_frames: np.ndarray,
    fixed: np.ndarray,
    mu: np.ndarray,
    settings: InternalForceSettings = InternalForceSettings(),
    cone_edge: ConeEdge | None = None,
) -> InternalForceQP:
    r"""Build the QP of the module docstring.

    Args:
        constraint_matrix: :math:`A = [G^T \mid R_f B_v]` (2m, 3 + p); f_c spans null(Aᵀ).
        motion_forces: f_m, (2m,) [N].
        surface_frames: (m, 2, 2), columns (normal, tangent) in the hand frame.
        fixed: (m,) bool, which contacts are fixed.
        mu: (m,) friction coefficients.
        settings: Margins.
        cone_edge: Optional contact to put on its cone edge.
    """
    m = len(surface_frames)
    if cone_edge is not None and not 0 <= cone_edge.contact < m:
        raise InvalidParameterError("cone_edge", cone_edge, f"a contact index in 0..{m - 1}")
    null = scipy.linalg.null_space(constraint_matrix.T)
    k = null.shape[1]
    if k == 0:
        return InternalForceQP(None, null, motion_forces, settings)
    ineq, eq = _constraint_rows(surface_frames, fixed, mu, settings, cone_edge)

    def rows(items):
        a = np.array([coef @ null[2 * i:2 * i + 2] for i, coef, _ in items])
        rhs = np.array([lo - coef @ motion_forces[2 * i:2 * i + 2] for i, coef, lo in items])
        return a, rhs

    a_in, lo_in = rows(ineq)  # a y >= lo  ->  -a y <= -lo
    problem_args = dict(P=sp.csc_matrix(np.eye(k)), q=np.zeros(k), G=sp.csc_matrix(-a_in), h=-lo_in)
    if eq:
        a_eq, b_eq = rows(eq)
        problem_args.update(A=sp.csc_matrix(a_eq), b=b_eq)
    return InternalForceQP(qpsolvers.Problem(**problem_args), null, motion_forces, settings)


def _satisfied(qp: InternalForceQP, forces, frames, fixed, mu, cone_edge, slack) -> bool:
    ineq, eq = _constraint_rows(frames, fixed, mu, qp.settings, cone_edge)
    ok = all(coef @ forces[i] >= lo - slack for i, coef, lo in ineq)
    return ok and all(abs(coef @ forces[i]) <= slack for i, coef, _ in eq)


def solve_internal_force_qp(
    qp: InternalForceQP,
    surface_frames: np.ndarray,
    fixed: np.ndarray,
    mu: np.ndarray,
    cone_edge: ConeEdge | None = None,
) -> InternalForceResult:
    """Solve a built QP with OSQP; raises InternalForceInfeasibleError when it has no solution."""
    start = time.perf_counter()
    m = len(surface_frames)
    tol = qp.settings.tolerance
    scale = max(1.0, float(np.abs(qp.motion_forces).max(initial=0.0)))
    if qp.problem is None:
        forces = qp.motion_forces.reshape(m, 2)
        ok = _satisfied(qp, forces, surface_frames, fixed, mu, cone_edge, 1e-9 * scale)
        return InternalForceResult(np.zeros(2 * m), forces, 0, ok, "empty null space",
                                   time.perf_counter() - start)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # OSQP warns on infeasibility; we raise a typed error instead
        solution = qpsolvers.solve_problem(qp.problem, solver="osqp", eps_abs=tol, eps_rel=tol,
                                           polishing=True, verbose=False, max_iter=20000)
    info = solution.extras.get("info") if isinstance(solution.extras, dict) else None
    status = getattr(info, "status", "unknown")
    if not solution.found or solution.x is None:
        raise InternalForceInfeasibleError(qp, status)
    f_c = qp.null_basis @ solution.x
    forces = (qp.motion_forces + f_c).reshape(m, 2)
    ok = _satisfied(qp, forces, surface_frames, fixed, mu, cone_edge, 1e-6 * scale)
    if not ok:
        raise InternalForceInfeasibleError(qp, f"{status} (solution violates the constraints)")
    return InternalForceResult(f_c, forces, qp.null_basis.shape[1], True, status, time.perf_counter() - start)


class InternalForceSolver:
    """The same QP as :func:`build_internal_force_qp` + :func:`solve_internal_force_qp`, on a
    persistent ``osqp.OSQP`` object per problem shape (warm-started, only the numbers updated),
    for controllers that solve it every control step.

    On failure it builds the ``qpsolvers`` problem so the raised
    :class:`InternalForceInfeasibleError` carries it, as the one-shot path does.
    """

    def __init__(self, settings: InternalForceSettings = InternalForceSettings()):
        self.settings = settings
        self._solvers: dict[tuple[int, int, int], tuple[osqp.OSQP, np.ndarray, np.ndarray]] = {}

    def _osqp(self, k: int, rows: int, n_eq: int, a: np.ndarray, lower: np.ndarray, upper: np.ndarray):
        key = (k, rows, n_eq)
        if key not in self._solvers:
            # a dense pattern, so that later updates keep the sparsity structure
            indptr = np.arange(0, rows * k + 1, rows)
            indices = np.tile(np.arange(rows), k)
            a_csc = sp.csc_matrix((a.T.reshape(-1), indices, indptr), shape=(rows, k))
            solver = osqp.OSQP()
            tol = self.settings.tolerance
            solver.setup(P=sp.csc_matrix(np.eye(k)), q=np.zeros(k), A=a_csc, l=lower, u=upper, eps_abs=tol,
                         eps_rel=tol, polishing=True, verbose=False, max_iter=20000)
            self._solvers[key] = solver
        else:
            self._solvers[key].update(Ax=a.T.reshape(-1), l=lower, u=upper)
        return self._solvers[key]

    def solve(self, constraint_matrix, motion_forces, surface_frames, fixed, mu,
              cone_edge: ConeEdge | None = None) -> InternalForceResult:
        """Solve the QP of the module docstring; see :func:`build_internal_force_qp` for the arguments."""
        start = time.perf_counter()
        m = len(surface_frames)
        null = scipy.linalg.null_space(np.asarray(constraint_matrix).T)
        k = null.shape[1]
        qp_shell = InternalForceQP(None, null, motion_forces, self.settings)
        scale = max(1.0, float(np.abs(motion_forces).max(initial=0.0)))
        if k == 0:
            forces = motion_forces.reshape(m, 2)
            ok = _satisfied(qp_shell, forces, surface_frames, fixed, mu, cone_edge, 1e-9 * scale)
            return InternalForceResult(np.zeros(2 * m), forces, 0, ok, "empty null space",
                                       time.perf_counter() - start)
        ineq, eq = _constraint_rows(surface_frames, fixed, mu, self.settings, cone_edge)
        items = ineq + eq
        a = np.array([coef @ null[2 * i:2 * i + 2] for i, coef, _ in items])
        bound = np.array([lo - coef @ motion_forces[2 * i:2 * i + 2] for i, coef, lo in items])
        upper = np.concatenate([np.full(len(ineq), np.inf), bound[len(ineq):]])
        solver = self._osqp(k, len(items), len(eq), a, bound, upper)
        result = solver.solve(raise_error=False)
        status = str(result.info.status)
        x = result.x
        solved = status in ("solved", "solved inaccurate") and x is not None and np.all(np.isfinite(x))
        if solved:
            f_c = null @ x
            forces = (motion_forces + f_c).reshape(m, 2)
            if _satisfied(qp_shell, forces, surface_frames, fixed, mu, cone_edge, 1e-6 * scale):
                return InternalForceResult(f_c, forces, k, True, status, time.perf_counter() - start)
            status = f"{status} (solution violates the constraints)"
        qp = build_internal_force_qp(constraint_matrix, motion_forces, surface_frames, fixed, mu, self.settings,
                                     cone_edge)
        raise InternalForceInfeasibleError(qp, status)

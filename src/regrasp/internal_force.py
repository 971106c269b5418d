r"""The internal (squeezing) force, chosen by a QP (paper §3.3, eq. 3.3.7).

A torque :math:`\tau_{Ic} = J^T f_c` with :math:`f_c` in the null space of
:math:`A^T = [G;\ B_v^T R_f^T]` changes no object motion and no sliding motion
(:math:`H^T \tau_{Ic} = A^T f_c = 0`): it only redistributes the contact forces. With
:math:`f_m` the contact forces the motion part of the torque produces, the predicted force
is :math:`f = f_m + f_c`, :math:`f_c = N_c y` (:math:`N_c` an orthonormal basis of the null
space, :math:`\dim = 2m - 3 - p`). The QP

.. math:: \min_y \tfrac12 \|f_c\|^2 = \tfrac12 y^T y \quad \text{s.t.}\quad
          f_{min} \le n_i^T f_i\ (\le f_{max})\ \forall i,\qquad
          |t_i^T f_i| \le (\mu_{s,i} - \text{margin})\, n_i^T f_i\ \text{for fixed } i

keeps every contact pushing and every fixed contact inside its static friction cone
(:math:`\mu_{s,i}`, :class:`~regrasp.contact.Friction`) with a margin, with the least squeeze; a
sliding contact gets no cone row (its friction is part of the motion). Optionally one contact is
put exactly on a cone edge in a given direction, :math:`t_j^T f_j = s \mu n_j^T f_j` with the
coefficient :math:`\mu` the :class:`ConeEdge` carries (the caller's choice: the kinetic
coefficient for a slider, :math:`\mu_s` + an overshoot for the transition before a slide, §4).

The contacts' modes are a sequence of :class:`~regrasp.contact.ContactMode` (or their strings), the
friction anything :func:`~regrasp.contact.as_frictions` takes.

:func:`build_internal_force_qp` returns the ``qpsolvers.Problem`` (and the data to read its
solution); :func:`solve_internal_force_qp` solves it with OSQP and raises
:class:`InternalForceInfeasibleError` (carrying the problem and the solver status) when it
cannot. With an empty null space (m = 2, p = 1) there is nothing to choose: the result says
so and only reports whether the predicted forces satisfy the constraints.
"""

from __future__ import annotations

import functools
import math
import time
import warnings
from dataclasses import dataclass

import numpy as np
import osqp
import qpsolvers
import scipy.linalg
import scipy.sparse as sp
from scipy.linalg import lapack

from .contact import ContactMode, as_frictions, as_modes
from .exceptions import InvalidParameterError, RegraspError
from .hand import block_diagonal

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
        margin: Friction margin [-]: fixed contacts keep |f_t| <= (μ_s - margin) f_n.
        tolerance: OSQP absolute and relative tolerance.
        f_max: Maximum normal force [N] at every contact (what the fingers can push), or inf.
    """

    f_min: float = 0.5
    margin: float = 0.05
    tolerance: float = 1e-9
    f_max: float = float("inf")


@dataclass(frozen=True)
class ConeEdge:
    r"""Put contact ``contact`` on a cone edge: :math:`t \cdot f = \text{sign}\,\mu\, n \cdot f` there.

    Attributes:
        contact: The contact's index.
        sign: The sliding direction, ±1 (the friction on the object points along sign · t).
        mu: The edge's coefficient [-], >= 0, chosen by the caller: the kinetic one for a sliding
            contact, the static one plus an overshoot to make a fixed contact break away, the kinetic
            one minus an undershoot to let a sliding contact slow down and stick.
    """

    contact: int
    sign: float
    mu: float

    def __post_init__(self):
        if self.sign not in (-1, 1, -1.0, 1.0):
            raise InvalidParameterError("cone_edge.sign", self.sign, "+1 or -1")
        if isinstance(self.mu, bool) or not isinstance(self.mu, (int, float, np.floating, np.integer)) \
                or not math.isfinite(self.mu) or self.mu < 0.0:
            raise InvalidParameterError("cone_edge.mu", self.mu, "a finite friction coefficient >= 0")
        object.__setattr__(self, "sign", float(self.sign))
        object.__setattr__(self, "mu", float(self.mu))


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


def _constraint_rows(frames, modes, frictions, settings, cone_edge):
    """Rows (a, lo) meaning a . f_i >= lo on the predicted force of contact i (plus equalities):
    every contact pushes, every fixed one (but the cone edge's) stays inside its static cone."""
    ineq, eq = [], []
    for i, frame in enumerate(frames):
        n, t = frame[:, 0], frame[:, 1]
        ineq.append((i, n, settings.f_min))
        if np.isfinite(settings.f_max):
            ineq.append((i, -n, -settings.f_max))
        if modes[i] is ContactMode.FIXED and (cone_edge is None or cone_edge.contact != i):
            slope = frictions[i].static - settings.margin
            ineq.append((i, slope * n - t, 0.0))
            ineq.append((i, slope * n + t, 0.0))
    if cone_edge is not None:
        j = cone_edge.contact
        n, t = frames[j][:, 0], frames[j][:, 1]
        eq.append((j, t - cone_edge.sign * cone_edge.mu * n, 0.0))
    return ineq, eq


def _contacts(m: int, modes, friction) -> tuple[tuple[ContactMode, ...], tuple]:
    """The modes and the frictions of ``m`` contacts, validated."""
    return as_modes(modes, m), as_frictions(friction, m)


class _Rows:
    r"""The constraint rows of :func:`_constraint_rows` for one (modes, frictions, settings, cone edge),
    as matrices: row r reads :math:`\alpha_r n_i^T f_i + \beta_r t_i^T f_i \ge lo_r` (equalities last,
    = lo_r), so that for given surface frames all rows are one product :math:`C f` (:meth:`matrix`)."""

    def __init__(self, m: int, modes, friction, settings: InternalForceSettings, cone_edge: ConeEdge | None):
        if cone_edge is not None and not 0 <= cone_edge.contact < m:
            raise InvalidParameterError("cone_edge", cone_edge, f"a contact index in 0..{m - 1}")
        modes, frictions = _contacts(m, modes, friction)
        # in surface coordinates (n = e_x, t = e_y) each row's coefficients are (α_r, β_r)
        ineq, eq = _constraint_rows(np.broadcast_to(np.eye(2), (m, 2, 2)), modes, frictions, settings, cone_edge)
        self.coefficients = np.zeros((len(ineq) + len(eq), 2 * m))
        for r, (i, coef, _) in enumerate(ineq + eq):
            self.coefficients[r, 2 * i:2 * i + 2] = coef
        self.lower = np.array([lo for _, _, lo in ineq + eq])
        self.n_ineq, self.n_eq = len(ineq), len(eq)
        self.upper = np.full(self.n_ineq + self.n_eq, _OSQP_INFTY)  # equalities' bounds set per problem
        #: per row (2i, α_r, β_r, lo_r) as floats (hot paths)
        self.terms = [(2 * i, *(float(v) for v in coef), float(lo)) for i, coef, lo in ineq + eq]

    def matrix(self, frames_bd: np.ndarray) -> np.ndarray:
        """C (rows, 2m): the rows' left-hand sides are C f for contact forces f (2m,) in the hand frame;
        ``frames_bd``: blockdiag(R_fi) (2m, 2m) of the surface frames."""
        return self.coefficients.dot(frames_bd.T)  # (ndarray.dot: cheaper than matmul on small arrays)

    def satisfied(self, C: np.ndarray, forces: np.ndarray, slack: float) -> bool:
        """Whether forces (2m,) satisfy every row to ``slack`` [N]."""
        return self._within((C.dot(forces) - self.lower).tolist(), slack)

    def _within(self, residual: list, slack: float) -> bool:
        n = self.n_ineq
        return min(residual[:n], default=0.0) >= -slack and all(abs(r) <= slack for r in residual[n:])

    def rows_at(self, frames: list) -> list:
        """The rows of :meth:`matrix` as floats: per row (2i, c_x, c_y, lo), row r of C being (c_x, c_y)
        in the columns of contact i; ``frames``: per contact (n_x, n_y, t_x, t_y), hand frame."""
        out = []
        for i2, alpha, beta, lo in self.terms:
            nx, ny, tx, ty = frames[i2 >> 1]
            out.append((i2, alpha * nx + beta * tx, alpha * ny + beta * ty, lo))
        return out

    def satisfied_at(self, rows: list, forces: list, slack: float) -> bool:
        """:meth:`satisfied` with the rows of :meth:`rows_at` and forces (2m) as floats."""
        n = self.n_ineq
        for r, (i2, cx, cy, lo) in enumerate(rows):
            residual = cx * forces[i2] + cy * forces[i2 + 1] - lo
            if not (residual >= -slack if r < n else abs(residual) <= slack):
                return False
        return True


_EPS = float(np.finfo(float).eps)
_OSQP_INFTY = 1e30  # OSQP's infinity (osqp.OSQP().constant("OSQP_INFTY"))


def _null_basis(constraint_matrix) -> np.ndarray:
    r"""An orthonormal basis of :math:`\mathrm{null}(A^T)`, (rows, k).

    For a full-column-rank A (the usual case) the last k columns of Q in A = QR (Householder,
    LAPACK), without forming Q; otherwise ``scipy.linalg.null_space`` (SVD, numerical rank).
    """
    a = np.asarray(constraint_matrix, dtype=float)
    rows, cols = a.shape
    if rows >= cols > 0:
        qr, tau, _, info = lapack.dgeqrf(a)
        diagonal = list(map(abs, qr.diagonal().tolist()))
        if info == 0 and min(diagonal) > max(diagonal) * max(rows, cols) * _EPS:
            if rows == cols:
                return np.zeros((rows, 0))
            basis, _, info = lapack.dormqr("L", "N", qr, tau, _unit_tail(rows, rows - cols), max(64, rows))
            if info == 0:
                return basis
    return scipy.linalg.null_space(a.T)


@functools.cache
def _unit_tail(rows: int, k: int) -> np.ndarray:
    """[0; I_k] (rows, k): Q times it is Q's last k columns (read-only: LAPACK gets a copy)."""
    tail = np.zeros((rows, k))
    tail[rows - k:] = np.eye(k)
    tail.flags.writeable = False
    return tail


def build_internal_force_qp(
    constraint_matrix: np.ndarray,
    motion_forces: np.ndarray,
    surface_frames: np.ndarray,
    modes,
    friction,
    settings: InternalForceSettings = InternalForceSettings(),
    cone_edge: ConeEdge | None = None,
) -> InternalForceQP:
    r"""Build the QP of the module docstring.

    Args:
        constraint_matrix: :math:`A = [G^T \mid R_f B_v]` (2m, 3 + p); f_c spans null(Aᵀ).
        motion_forces: f_m, (2m,) [N].
        surface_frames: (m, 2, 2), columns (normal, tangent) in the hand frame.
        modes: Each contact's :class:`~regrasp.contact.ContactMode`: the fixed ones get static cones.
        friction: The contacts' :class:`~regrasp.contact.Friction` (one for all, a coefficient [-], or
            one per contact).
        settings: Margins.
        cone_edge: Optional contact to put on a cone edge (its coefficient is the ConeEdge's).
    """
    rows = _Rows(len(surface_frames), modes, friction, settings, cone_edge)
    null = _null_basis(constraint_matrix)
    k = null.shape[1]
    if k == 0:
        return InternalForceQP(None, null, motion_forces, settings)
    C = rows.matrix(block_diagonal(np.asarray(surface_frames, dtype=float)))
    a = C @ null
    rhs = rows.lower - C @ motion_forces  # a y >= rhs (inequalities), a y = rhs (equalities)
    ineq = slice(0, rows.n_ineq)
    problem_args = dict(P=sp.csc_matrix(np.eye(k)), q=np.zeros(k), G=sp.csc_matrix(-a[ineq]), h=-rhs[ineq])
    if rows.n_eq:
        problem_args.update(A=sp.csc_matrix(a[rows.n_ineq:]), b=rhs[rows.n_ineq:])
    return InternalForceQP(qpsolvers.Problem(**problem_args), null, motion_forces, settings)


def _satisfied(qp: InternalForceQP, forces, frames, modes, friction, cone_edge, slack) -> bool:
    rows = _Rows(len(frames), modes, friction, qp.settings, cone_edge)
    C = rows.matrix(block_diagonal(np.asarray(frames, dtype=float)))
    return rows.satisfied(C, np.asarray(forces).reshape(-1), slack)


def solve_internal_force_qp(
    qp: InternalForceQP,
    surface_frames: np.ndarray,
    modes,
    friction,
    cone_edge: ConeEdge | None = None,
) -> InternalForceResult:
    """Solve a built QP with OSQP (the contacts' ``modes``, ``friction`` and ``cone_edge`` as it was built
    with, to check the solution); raises InternalForceInfeasibleError when it has no solution."""
    start = time.perf_counter()
    m = len(surface_frames)
    tol = qp.settings.tolerance
    scale = max(1.0, float(np.abs(qp.motion_forces).max(initial=0.0)))
    if qp.problem is None:
        forces = qp.motion_forces.reshape(m, 2)
        ok = _satisfied(qp, forces, surface_frames, modes, friction, cone_edge, 1e-9 * scale)
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
    ok = _satisfied(qp, forces, surface_frames, modes, friction, cone_edge, 1e-6 * scale)
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
        self._solvers: dict[tuple[int, int, int], osqp.OSQP] = {}
        self._rows: dict[tuple, _Rows] = {}
        self._rows_settings = settings
        self._last_contacts = None  # (modes, friction) as last passed (tuples), and validated

    def _rows_for(self, m: int, modes, friction, cone_edge: ConeEdge | None) -> _Rows:
        """The rows of these modes, frictions and cone edge (cached: the key holds all three)."""
        if self._rows_settings is not self.settings:
            self._rows.clear()
            self._rows_settings = self.settings
        last = self._last_contacts
        if last is not None and modes is last[0] and friction is last[1] and len(last[2][0]) == m:
            contacts = last[2]
        else:
            contacts = _contacts(m, modes, friction)
            if type(modes) is tuple and type(friction) is tuple:  # immutable: the same objects, the same values
                self._last_contacts = (modes, friction, contacts)
        key = (m, *contacts, cone_edge)
        rows = self._rows.get(key)
        if rows is None:
            rows = self._rows[key] = _Rows(m, *contacts, self.settings, cone_edge)
        return rows

    def _osqp(self, k: int, rows: _Rows, a_t: np.ndarray, lower: np.ndarray) -> osqp.OSQP:
        """The persistent solver of this shape, set up or updated with the numbers of this problem
        (``a_t``: the constraint matrix's column-major data, k * rows)."""
        key = (k, len(lower), rows.n_eq)
        upper = rows.upper
        if rows.n_eq:
            upper = upper.copy()
            upper[rows.n_ineq:] = lower[rows.n_ineq:]
        solver = self._solvers.get(key)
        if solver is None:
            # a dense pattern, so that later updates keep the sparsity structure
            n_rows = len(lower)
            indptr = np.arange(0, n_rows * k + 1, n_rows)
            indices = np.tile(np.arange(n_rows), k)
            a_csc = sp.csc_matrix((a_t.reshape(-1), indices, indptr), shape=(n_rows, k))
            solver = osqp.OSQP()
            tol = self.settings.tolerance
            solver.setup(P=sp.csc_matrix(np.eye(k)), q=np.zeros(k), A=a_csc, l=lower, u=upper, eps_abs=tol,
                         eps_rel=tol, polishing=True, verbose=False, max_iter=20000)
            self._solvers[key] = solver
        else:
            # what ``solver.update(Ax=..., l=..., u=...)`` does, without its bookkeeping for derivatives
            # (the upper bounds of the inequalities are OSQP's infinity in every problem of this shape;
            # the lower bounds are at least minus it)
            solver._solver.update_data_vec(q=None, l=lower, u=upper if rows.n_eq else None)
            solver._solver.update_data_mat(P_x=None, P_i=None, A_x=a_t.reshape(-1), A_i=None)
        return solver

    def solve(self, constraint_matrix, motion_forces, surface_frames, modes, friction,
              cone_edge: ConeEdge | None = None) -> InternalForceResult:
        """Solve the QP of the module docstring; see :func:`build_internal_force_qp` for the arguments."""
        frames = [(n_x, n_y, t_x, t_y) for (n_x, t_x), (n_y, t_y) in np.asarray(surface_frames, dtype=float).tolist()]
        return self._solve(constraint_matrix, np.asarray(motion_forces, dtype=float).reshape(-1).tolist(), frames,
                           modes, friction, cone_edge, time.perf_counter())

    def _solve(self, constraint_matrix, motion_forces: list, frames: list, modes, friction, cone_edge, start: float):
        """:meth:`solve` with f_m (2m) and the surface frames, per contact (n_x, n_y, t_x, t_y), as floats
        (hot paths)."""
        m = len(frames)
        rows = self._rows_for(m, modes, friction, cone_edge)
        null = _null_basis(constraint_matrix)
        k = null.shape[1]
        C = rows.rows_at(frames)
        f_m = motion_forces
        scale = max(1.0, max(map(abs, f_m), default=0.0))
        if k == 0:
            ok = rows.satisfied_at(C, f_m, 1e-9 * scale)
            return InternalForceResult(np.zeros(2 * m), np.array(f_m).reshape(m, 2), 0, ok, "empty null space",
                                       time.perf_counter() - start)
        # a y >= lo - C f_m, with a = C N_c; OSQP takes a column by column, i.e. a^T's rows
        lower = [v if (v := lo - (cx * f_m[i2] + cy * f_m[i2 + 1])) >= -_OSQP_INFTY else -_OSQP_INFTY
                 for i2, cx, cy, lo in C]  # (NaN stays NaN)
        a_t = [cx * b[i2] + cy * b[i2 + 1] for b in null.T.tolist() for i2, cx, cy, _ in C]
        solver = self._osqp(k, rows, np.array(a_t), np.array(lower))
        solver._solver.solve()
        status = str(solver._solver.info.status)
        x = solver._solver.solution.x
        if status in ("solved", "solved inaccurate") and x is not None and all(map(math.isfinite, x.tolist())):
            f_c = null.dot(x)
            forces = [a + b for a, b in zip(f_m, f_c.tolist())]
            if rows.satisfied_at(C, forces, 1e-6 * scale):
                return InternalForceResult(f_c, np.array(forces).reshape(m, 2), k, True, status,
                                           time.perf_counter() - start)
            status = f"{status} (solution violates the constraints)"
        surface_frames = np.array([((n_x, t_x), (n_y, t_y)) for n_x, n_y, t_x, t_y in frames])
        qp = build_internal_force_qp(constraint_matrix, np.array(f_m), surface_frames, modes, friction, self.settings,
                                     cone_edge)
        raise InternalForceInfeasibleError(qp, status)

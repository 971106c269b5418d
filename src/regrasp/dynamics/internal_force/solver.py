r"""The internal (squeezing) force, chosen by a QP (paper §3.3, eq. 3.3.7).

A torque :math:`\tau_{Ic} = J^T f_c` with :math:`f_c` in the null space of
:math:`A^T = [G;\ B_v^T R_f^T]` changes no object motion and no sliding motion
(:math:`H^T \tau_{Ic} = A^T f_c = 0`): it only redistributes the contact forces. With
:math:`f_m` the contact forces the motion part of the torque produces, the predicted force
is :math:`f = f_m + f_c`, :math:`f_c = N_c y` (:math:`N_c` an orthonormal basis of the null
space, :math:`\dim = 2m - 3 - p`). The QP

.. math:: \min_y \tfrac12 \|f_c\|^2 = \tfrac12 y^T y \quad \text{s.t.}\quad
          f_{min} \le n_i^T f_i\ (\le f_{max})\ \forall i,\qquad
          |t_i^T f_i| \le (\mu_{s,i} - \text{friction\_margin})\, n_i^T f_i\ \text{for fixed } i

keeps every contact pushing and every fixed contact inside its static friction cone
(:math:`\mu_{s,i}`, :class:`~regrasp.core.contact.Friction`) with a margin, with the least squeeze; a
sliding contact gets no cone row (its friction is part of the motion). Optionally some contacts
(a :class:`ConeEdge` or a tuple of them, on distinct contacts) are put exactly on a cone edge in
a given direction, :math:`t_j^T f_j = s_j \mu_j n_j^T f_j` with the coefficient :math:`\mu_j` the
ConeEdge carries (the caller's choice: the kinetic coefficient for a slider, :math:`\mu_s` + an
overshoot for the transition before a slide, §4); such a contact gets no static-cone rows.

**A margin instead of the least squeeze** (the paper's "γ large"). With
``settings.target_cone_margin`` = :math:`\bar s > 0` [N] the QP gains one variable s [N]:

.. math:: \min_{y, s} \tfrac12 \|f_c\|^2 + \tfrac12 W (s - \bar s - \delta)^2 \quad \text{s.t.}\quad
          (\mu_{s,i} - \text{friction\_margin})\, n_i^T f_i - |t_i^T f_i| \ge s\ \text{for fixed } i
          \text{ not on a cone edge},\qquad 0 \le s \le \bar s,

plus the same normal-force and cone-edge rows. It is feasible exactly when the least-squeeze QP is
(s = 0 is allowed). W = 1e4 and δ = 1 N (``MARGIN_WEIGHT``, ``MARGIN_AIM`` of
:mod:`regrasp.dynamics.internal_force.rows`) make the margin term dominate: at :math:`s = \bar s` it still pulls with
:math:`W\delta` = 1e4 N, more than the marginal cost :math:`\|f_c\|\,\|\partial f_c/\partial s\|` of
any squeeze below ~100 N, so s reaches min(:math:`\bar s`, the largest achievable smallest margin)
to the solver's tolerance, and among such forces the squeeze is the least. (With δ = 0, s would
fall short by that cost over W: 1e-3 N for a 20 N squeeze.) The result's ``cone_margin`` is the
reached smallest margin, with either setting.

The contacts' modes are a sequence of :class:`~regrasp.core.contact.ContactMode` (or their strings), the
friction anything :func:`~regrasp.core.contact.as_frictions` takes.

:func:`build_internal_force_qp` returns the ``qpsolvers.Problem`` (and the data to read its
solution); :func:`solve_internal_force_qp` solves it with OSQP and raises
:class:`InternalForceInfeasibleError` (carrying the problem and the solver status) when it
cannot. With an empty null space (m = 2, p = 1) there is nothing to choose: the result says
so and only reports whether the predicted forces satisfy the constraints.
"""

from __future__ import annotations

import ctypes
import functools
import math
import signal
import time
import warnings
from collections.abc import Callable, Iterable
from dataclasses import dataclass, replace

import numpy as np
import osqp
import qpsolvers
import scipy.sparse as sp
from numpy.typing import ArrayLike

from ...core.contact import FrictionLike, ModesLike
from ...core.exceptions import InvalidParameterError, RegraspError
from ...core.validation import as_finite_float
from ...kernels.force import (
    FORCE_CHECK_FAILED,
    FORCE_INFEASIBLE,
    FORCE_NOT_APPLICABLE,
    FORCE_NOT_CONVERGED,
    FORCE_SOLVED,
    internal_force_into,
)
from ...model.hand import block_diagonal
from .rows import (
    _OSQP_INFTY,
    MARGIN_AIM,
    MARGIN_WEIGHT,
    _contacts,
    _null_basis,
    _Rows,
)

__all__ = [
    "ConeEdge",
    "InternalForceInfeasibleError",
    "InternalForceQP",
    "InternalForceResult",
    "InternalForceSettings",
    "InternalForceSolver",
    "as_cone_edges",
    "build_internal_force_qp",
    "solve_internal_force_qp",
]


@dataclass(frozen=True)
class InternalForceSettings:
    """Margins of the internal-force QP.

    Attributes:
        f_min: Minimum normal force [N] at every contact, >= 0.
        friction_margin: A ratio [-], >= 0: fixed contacts keep |f_t| <= (μ_s - friction_margin) f_n.
        tolerance: OSQP absolute and relative tolerance, > 0.
        f_max: Maximum normal force [N] at every contact (what the fingers can push), > f_min, or inf.
        target_cone_margin: The smallest cone margin (μ_s - margin) f_n - |f_t| [N] to reach at the fixed
            contacts, >= 0 (the module docstring); 0: the least squeeze only.
        fallback_friction_margin: Where no internal force keeps the fixed contacts ``friction_margin`` inside their
            cones, the solver answers with this smaller friction margin [-] instead of failing (None: it fails). A margin
            that covers an uncertain μ is a preference; the cone of the model's μ is the limit.
    """

    f_min: float = 0.5
    friction_margin: float = 0.05
    tolerance: float = 1e-9
    f_max: float = float("inf")
    target_cone_margin: float = 0.0
    fallback_friction_margin: float | None = None

    def __post_init__(self):
        for name, low, strict in (("f_min", 0.0, False), ("friction_margin", 0.0, False), ("tolerance", 0.0, True),
                                  ("target_cone_margin", 0.0, False)):
            value = as_finite_float(name, getattr(self, name))
            if value < low or (strict and value == low):
                raise InvalidParameterError(name, value, f"a finite value {'>' if strict else '>='} {low:g}")
        f_max = self.f_max
        if not (isinstance(f_max, float) and f_max == math.inf):  # inf: no upper bound
            try:
                f_max = as_finite_float("f_max", f_max)
            except InvalidParameterError:
                f_max = math.nan  # (the error below says what f_max may be)
        if not f_max > self.f_min:
            raise InvalidParameterError("f_max", self.f_max, f"a maximum normal force > f_min ({self.f_min}) or inf")
        fallback = self.fallback_friction_margin
        if fallback is not None and not 0.0 <= as_finite_float("fallback_friction_margin", fallback) \
                < self.friction_margin:
            raise InvalidParameterError("fallback_friction_margin", fallback,
                                        f"None or a friction margin in [0, friction_margin = {self.friction_margin:g})")


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
        if not as_finite_float("cone_edge.mu", self.mu) >= 0.0:
            raise InvalidParameterError("cone_edge.mu", self.mu, "a finite friction coefficient >= 0")
        object.__setattr__(self, "sign", float(self.sign))
        object.__setattr__(self, "mu", float(self.mu))


@dataclass(frozen=True)
class InternalForceQP:
    """A built internal-force QP and what is needed to read its solution.

    Attributes:
        problem: The ``qpsolvers.Problem`` in y (f_c = N_c y), or in (y, s) with a target cone margin
            (s the smallest cone margin [N], the last variable); None when the null space is empty.
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
        cone_margin: The smallest (μ_s - margin) f_n - |f_t| [N] of the fixed contacts not on a cone edge,
            at ``forces`` (math.inf when there is none).
    """

    f_c: np.ndarray
    forces: np.ndarray
    null_space_dim: int
    feasible: bool
    status: str
    seconds: float
    cone_margin: float


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
            f"with friction margin {qp.settings.friction_margin}"
        )


def as_cone_edges(cone_edge: ConeEdge | Iterable[ConeEdge] | None, m: int) -> tuple[ConeEdge, ...]:
    """``cone_edge`` (None, a :class:`ConeEdge`, or a sequence of them on distinct contacts) as a tuple,
    validated against ``m`` contacts."""
    if cone_edge is None:
        return ()
    edges = (cone_edge,) if isinstance(cone_edge, ConeEdge) else cone_edge
    if isinstance(edges, (str, bytes)) or not hasattr(edges, "__iter__"):
        raise InvalidParameterError("cone_edge", cone_edge, "None, a ConeEdge or a tuple of them")
    edges = tuple(edges)
    if not all(isinstance(edge, ConeEdge) for edge in edges):
        raise InvalidParameterError("cone_edge", cone_edge, "None, a ConeEdge or a tuple of them")
    contacts = [edge.contact for edge in edges]
    if not all(isinstance(j, (int, np.integer)) and 0 <= j < m for j in contacts):
        raise InvalidParameterError("cone_edge", cone_edge, f"contact indices in 0..{m - 1}")
    if len(set(contacts)) != len(contacts):
        raise InvalidParameterError("cone_edge", cone_edge, "cone edges on distinct contacts")
    return edges


def _rows(m: int, modes, friction, settings: InternalForceSettings, cone_edge) -> _Rows:
    return _Rows(m, modes, friction, settings, as_cone_edges(cone_edge, m))


def build_internal_force_qp(
    constraint_matrix: np.ndarray,
    motion_forces: np.ndarray,
    surface_frames: np.ndarray,
    modes: ModesLike,
    friction: FrictionLike,
    settings: InternalForceSettings = InternalForceSettings(),
    cone_edge: ConeEdge | tuple[ConeEdge, ...] | None = None,
) -> InternalForceQP:
    r"""Build the QP of the module docstring.

    Args:
        constraint_matrix: :math:`A = [G^T \mid R_f B_v]` (2m, 3 + p); f_c spans null(Aᵀ).
        motion_forces: f_m, (2m,) [N].
        surface_frames: (m, 2, 2), columns (normal, tangent) in the hand frame.
        modes: Each contact's :class:`~regrasp.core.contact.ContactMode`: the fixed ones get static cones.
        friction: The contacts' :class:`~regrasp.core.contact.Friction` (one for all, a coefficient [-], or
            one per contact).
        settings: Margins (and the target cone margin: then the problem is in (y, s)).
        cone_edge: Optional contacts to put on a cone edge (each at its ConeEdge's coefficient): a
            :class:`ConeEdge` or a tuple of them on distinct contacts.
    """
    rows = _rows(len(surface_frames), modes, friction, settings, cone_edge)
    null = _null_basis(constraint_matrix)
    k = null.shape[1]
    if k == 0:
        return InternalForceQP(None, null, motion_forces, settings)
    C = rows.matrix(block_diagonal(np.asarray(surface_frames, dtype=float)))
    a = C @ null
    rhs = rows.lower - C @ motion_forces  # a y >= rhs (inequalities), a y = rhs (equalities)
    ineq = slice(0, rows.n_ineq)
    P, q = np.eye(k), np.zeros(k)
    if rows.target > 0.0:  # the variables (y, s): a y + σ s >= rhs, σ the margin column
        a = np.hstack([a, np.array(rows.margin_column)[:, None]])
        P = np.diag([1.0] * k + [MARGIN_WEIGHT])
        q = np.append(q, -MARGIN_WEIGHT * (rows.target + MARGIN_AIM))
        G, h = -a[ineq], -rhs[ineq]
        G, h = np.vstack([G, a[rows.n_ineq - 1]]), np.append(h, rows.target)  # s <= target
    else:
        G, h = -a[ineq], -rhs[ineq]
    problem_args = dict(P=sp.csc_matrix(P), q=q, G=sp.csc_matrix(G), h=h)
    if rows.n_eq:
        problem_args.update(A=sp.csc_matrix(a[rows.n_ineq:]), b=rhs[rows.n_ineq:])
    return InternalForceQP(qpsolvers.Problem(**problem_args), null, motion_forces, settings)


def _check(qp: InternalForceQP, forces, frames, modes, friction, cone_edge, slack) -> tuple[bool, float]:
    rows = _rows(len(frames), modes, friction, qp.settings, cone_edge)
    C = rows.matrix(block_diagonal(np.asarray(frames, dtype=float)))
    return rows.check(C, np.asarray(forces).reshape(-1), slack)


_OSQP_INTERRUPTED = "interrupted"
#: the compiled path's failures, as statuses (the reference path's are OSQP's)
_COMPILED_STATUS = {FORCE_INFEASIBLE: "infeasible (dense solver)", FORCE_NOT_CONVERGED: "not converged (dense solver)",
                    FORCE_CHECK_FAILED: "solved (dense solver; the solution violates the constraints)"}


@functools.cache
def _osqp_interrupt_flag() -> Callable[[], int] | None:
    """OSQP's own record of a Ctrl-C during its last solve (``osqp_is_interrupted`` in its C library, which
    keeps the flag until the next solve starts), or None where the library does not export it."""
    try:
        from osqp import ext_builtin

        flag = ctypes.CDLL(ext_builtin.__file__).osqp_is_interrupted
    except (ImportError, OSError, AttributeError):
        return None
    flag.restype, flag.argtypes = ctypes.c_int, []
    return flag


def _hand_on_ctrl_c(status: str) -> bool:
    r"""OSQP's C library listens for Ctrl-C while it solves: it takes the SIGINT (Python never sees it) and
    either ends the solve early (status ``interrupted``) or, when the signal comes after its last check (while
    it polishes), finishes and forgets it. Either way, hand the signal on to Python's handler (a
    :class:`KeyboardInterrupt`, or a loop's deferred request, :class:`~regrasp.plants.simulation.InterruptAtStepEnd`)
    and return whether the caller must solve again (the solve was cut short)."""
    flag = _osqp_interrupt_flag()
    if status != _OSQP_INTERRUPTED and (flag is None or not flag()):
        return False
    signal.raise_signal(signal.SIGINT)
    return status == _OSQP_INTERRUPTED


def solve_internal_force_qp(
    qp: InternalForceQP,
    surface_frames: np.ndarray,
    modes: ModesLike,
    friction: FrictionLike,
    cone_edge: ConeEdge | tuple[ConeEdge, ...] | None = None,
) -> InternalForceResult:
    """Solve a built QP with OSQP (the contacts' ``modes``, ``friction`` and ``cone_edge`` as it was built
    with, to check the solution); raises InternalForceInfeasibleError when it has no solution."""
    start = time.perf_counter()
    m = len(surface_frames)
    tol = qp.settings.tolerance
    scale = max(1.0, float(np.abs(qp.motion_forces).max(initial=0.0)))
    if qp.problem is None:
        forces = qp.motion_forces.reshape(m, 2)
        ok, margin = _check(qp, forces, surface_frames, modes, friction, cone_edge, 1e-9 * scale)
        return InternalForceResult(np.zeros(2 * m), forces, 0, ok, "empty null space",
                                   time.perf_counter() - start, margin)
    while True:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # OSQP warns on infeasibility; we raise a typed error instead
            solution = qpsolvers.solve_problem(qp.problem, solver="osqp", eps_abs=tol, eps_rel=tol,
                                               polishing=True, verbose=False, max_iter=20000)
        info = solution.extras.get("info") if isinstance(solution.extras, dict) else None
        status = getattr(info, "status", "unknown")
        if not _hand_on_ctrl_c(status):
            break
    if not solution.found or solution.x is None:
        raise InternalForceInfeasibleError(qp, status)
    k = qp.null_basis.shape[1]
    f_c = qp.null_basis @ solution.x[:k]
    forces = (qp.motion_forces + f_c).reshape(m, 2)
    ok, margin = _check(qp, forces, surface_frames, modes, friction, cone_edge, 1e-6 * scale)
    if not ok:
        raise InternalForceInfeasibleError(qp, f"{status} (solution violates the constraints)")
    return InternalForceResult(f_c, forces, k, True, status, time.perf_counter() - start, margin)


class InternalForceSolver:
    """The same QP as :func:`build_internal_force_qp` + :func:`solve_internal_force_qp`, on a
    persistent ``osqp.OSQP`` object per problem shape (warm-started, only the numbers updated),
    for controllers that solve it every control step.

    On failure it builds the ``qpsolvers`` problem so the raised
    :class:`InternalForceInfeasibleError` carries it, as the one-shot path does.
    """

    def __init__(self, settings: InternalForceSettings = InternalForceSettings(), *, compiled: bool | None = None):
        self.settings = settings
        #: whether the compiled dense solver (:mod:`regrasp.kernels.force`) answers (None: yes); False: OSQP
        self.compiled = True if compiled is None else bool(compiled)
        self._solvers: dict[tuple[int, int, int, float], osqp.OSQP] = {}
        self._rows: dict[tuple, _Rows] = {}
        self._rows_settings = settings
        self._last_contacts = None  # (modes, friction) as last passed (tuples), and validated
        self._plain: InternalForceSolver | None = None  # the least-squeeze fallback of a target margin
        self._relaxed: InternalForceSolver | None = None  # the fallback_friction_margin's solver
        #: how often a target-margin problem fell back to the least squeeze (its QP did not converge)
        self.fallbacks = 0
        #: how often the friction margin was relaxed to ``fallback_friction_margin`` (no force kept ``friction_margin``)
        self.relaxations = 0

    def _rows_for(self, m: int, modes, friction, cone_edge) -> _Rows:
        """The rows of these modes, frictions and cone edges (cached: the key holds all three; a list of
        cone edges is taken as the tuple)."""
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
        if type(cone_edge) is list:
            cone_edge = tuple(cone_edge)
        key = (m, *contacts, cone_edge)
        rows = self._rows.get(key)
        if rows is None:
            rows = self._rows[key] = _Rows(m, *contacts, self.settings, as_cone_edges(cone_edge, m))
        return rows

    def rows_arrays(self, m: int, modes: ModesLike, friction: FrictionLike,
                    cone_edge: ConeEdge | tuple[ConeEdge, ...] | None = None) -> tuple:
        """The QP's rows for these contacts, as :func:`regrasp.kernels.force.internal_force_into` takes them
        (after its first three arguments: coefficients, lower, n_ineq, is_cone, target, σ, W, δ)."""
        return self._rows_for(m, modes, friction, cone_edge).arrays()

    def _osqp(self, k: int, rows: _Rows, a_t: np.ndarray, lower: np.ndarray) -> osqp.OSQP:
        """The persistent solver of this shape, set up or updated with the numbers of this problem
        (``a_t``: the constraint matrix's column-major data, rows * k, or rows * (k + 1) with the
        margin variable s)."""
        key = (k, len(lower), rows.n_eq, rows.target)
        upper = rows.upper
        if rows.n_eq:
            upper = upper.copy()
            upper[rows.n_ineq:] = lower[rows.n_ineq:]
        solver = self._solvers.get(key)
        if solver is None:
            # a dense pattern, so that later updates keep the sparsity structure
            n_rows, n_vars = len(lower), k + (rows.target > 0.0)
            indptr = np.arange(0, n_rows * n_vars + 1, n_rows)
            indices = np.tile(np.arange(n_rows), n_vars)
            a_csc = sp.csc_matrix((a_t.reshape(-1), indices, indptr), shape=(n_rows, n_vars))
            P, q = sp.csc_matrix(np.eye(k)), np.zeros(k)
            if rows.target > 0.0:
                P = sp.csc_matrix(np.diag([1.0] * k + [MARGIN_WEIGHT]))
                q = np.append(q, -MARGIN_WEIGHT * (rows.target + MARGIN_AIM))
            solver = osqp.OSQP()
            tol = self.settings.tolerance
            solver.setup(P=P, q=q, A=a_csc, l=lower, u=upper, eps_abs=tol,
                         eps_rel=tol, polishing=True, verbose=False, max_iter=20000)
            self._solvers[key] = solver
        else:
            # what ``solver.update(Ax=..., l=..., u=...)`` does, without its bookkeeping for derivatives
            # (the upper bounds of the inequalities are OSQP's infinity, or the target for s's row, in
            # every problem of this shape; the lower bounds are at least minus it)
            solver._solver.update_data_vec(q=None, l=lower, u=upper if rows.n_eq else None)
            solver._solver.update_data_mat(P_x=None, P_i=None, A_x=a_t.reshape(-1), A_i=None)
        return solver

    def solve(self, constraint_matrix: ArrayLike, motion_forces: ArrayLike, surface_frames: ArrayLike,
              modes: ModesLike, friction: FrictionLike,
              cone_edge: ConeEdge | tuple[ConeEdge, ...] | None = None) -> InternalForceResult:
        """Solve the QP of the module docstring; see :func:`build_internal_force_qp` for the arguments."""
        frames = [(n_x, n_y, t_x, t_y) for (n_x, t_x), (n_y, t_y) in np.asarray(surface_frames, dtype=float).tolist()]
        return self._solve(constraint_matrix, np.asarray(motion_forces, dtype=float).reshape(-1).tolist(), frames,
                           modes, friction, cone_edge, time.perf_counter())

    def _solve(self, constraint_matrix, motion_forces: list, frames: list, modes, friction, cone_edge, start: float):
        """:meth:`solve` with f_m (2m) and the surface frames, per contact (n_x, n_y, t_x, t_y), as floats
        (hot paths)."""
        m = len(frames)
        rows = self._rows_for(m, modes, friction, cone_edge)
        outcome = None
        if self.compiled:
            outcome = self._solve_compiled(constraint_matrix, motion_forces, frames, rows, start)
        if outcome is None:  # (the reference path, or a rank-deficient A)
            outcome = self._solve_osqp(constraint_matrix, motion_forces, frames, rows, start)
        if isinstance(outcome, InternalForceResult):
            return outcome
        status = outcome
        if self.settings.fallback_friction_margin is not None:
            # the friction margin is a preference too: the same problem with the smaller one (its own target
            # margin, and its own least-squeeze fallback)
            if self._relaxed is None:
                self._relaxed = InternalForceSolver(
                    replace(self.settings, friction_margin=self.settings.fallback_friction_margin,
                            fallback_friction_margin=None), compiled=self.compiled)
            self.relaxations += 1
            return self._relaxed._solve(constraint_matrix, motion_forces, frames, modes, friction, cone_edge, start)
        if rows.target > 0.0:
            # the margin is a preference: where its QP does not converge, the least squeeze that keeps the
            # constraints (the same feasible set) is the answer
            if self._plain is None:
                self._plain = InternalForceSolver(replace(self.settings, target_cone_margin=0.0), compiled=self.compiled)
            self.fallbacks += 1
            return self._plain._solve(constraint_matrix, motion_forces, frames, modes, friction, cone_edge, start)
        surface_frames = np.array([((n_x, t_x), (n_y, t_y)) for n_x, n_y, t_x, t_y in frames])
        qp = build_internal_force_qp(constraint_matrix, np.array(motion_forces), surface_frames, modes, friction,
                                     self.settings, cone_edge)
        raise InternalForceInfeasibleError(qp, status)

    def _solve_compiled(self, constraint_matrix, motion_forces: list, frames: list, rows: _Rows,
                        start: float) -> InternalForceResult | str | None:
        """The compiled path (:func:`regrasp.kernels.force.internal_force_into`): the result, the failure's
        status, or None where the kernel does not apply (a rank-deficient A, a non-finite input: the reference
        path decides, as it did before the kernel)."""
        m = len(frames)
        f_m = np.array(motion_forces, dtype=float)
        f_c, forces = np.empty(2 * m), np.empty(2 * m)
        arrays = rows.arrays()
        status, k, margin = internal_force_into(np.ascontiguousarray(constraint_matrix, dtype=float), f_m,
                                                np.array(frames, dtype=float), *arrays, f_c, forces)
        if status == FORCE_NOT_APPLICABLE:
            return None
        if k == 0:
            return InternalForceResult(f_c, forces.reshape(m, 2), 0, status == FORCE_SOLVED, "empty null space",
                                       time.perf_counter() - start, margin)
        if status == FORCE_SOLVED:
            return InternalForceResult(f_c, forces.reshape(m, 2), k, True, "solved", time.perf_counter() - start,
                                       margin)
        return _COMPILED_STATUS[status]

    def _solve_osqp(self, constraint_matrix, motion_forces: list, frames: list, rows: _Rows,
                    start: float) -> InternalForceResult | str:
        """The reference path (OSQP, warm-started): the result or the failure's status."""
        m = len(frames)
        null = _null_basis(constraint_matrix)
        k = null.shape[1]
        C = rows.rows_at(frames)
        f_m = motion_forces
        scale = max(1.0, max(map(abs, f_m), default=0.0))
        if k == 0:
            ok, margin = rows.check_at(C, f_m, 1e-9 * scale)
            return InternalForceResult(np.zeros(2 * m), np.array(f_m).reshape(m, 2), 0, ok, "empty null space",
                                       time.perf_counter() - start, margin)
        # a y >= lo - C f_m, with a = C N_c; OSQP takes a column by column, i.e. a^T's rows
        lower = [v if (v := lo - (cx * f_m[i2] + cy * f_m[i2 + 1])) >= -_OSQP_INFTY else -_OSQP_INFTY
                 for i2, cx, cy, lo in C]  # (NaN stays NaN)
        a_t = [cx * b[i2] + cy * b[i2 + 1] for b in null.T.tolist() for i2, cx, cy, _ in C]
        if rows.target > 0.0:
            a_t += rows.margin_column  # s's column
        solver = self._osqp(k, rows, np.array(a_t), np.array(lower))
        solver._solver.solve()
        while _hand_on_ctrl_c(str(solver._solver.info.status)):
            solver._solver.solve()
        status = str(solver._solver.info.status)
        x = solver._solver.solution.x
        if status in ("solved", "solved inaccurate") and x is not None and all(map(math.isfinite, x.tolist())):
            f_c = null.dot(x[:k] if rows.target > 0.0 else x)
            forces = [a + b for a, b in zip(f_m, f_c.tolist())]
            ok, margin = rows.check_at(C, forces, 1e-6 * scale)
            if ok:
                return InternalForceResult(f_c, np.array(forces).reshape(m, 2), k, True, status,
                                           time.perf_counter() - start, margin)
            status = f"{status} (solution violates the constraints)"
        return status

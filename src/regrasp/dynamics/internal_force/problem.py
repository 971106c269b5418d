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
(a :class:`~regrasp.dynamics.internal_force.settings.ConeEdge` or a tuple of them, on distinct contacts) are put
exactly on a cone edge in a given direction, :math:`t_j^T f_j = s_j \mu_j n_j^T f_j` with the coefficient
:math:`\mu_j` the ConeEdge carries (the caller's choice: the kinetic coefficient for a slider, :math:`\mu_s` + an
overshoot for the transition before a slide, §4); such a contact gets no static-cone rows.

**Joint torque limits** (``torques``, :mod:`regrasp.dynamics.internal_force.torque`): with
:math:`\tau_i = w_i + J_i^T f_i`, two more inequalities per limited joint, :math:`|\tau_{ij}| \le e_{ij}`.
Where none keeps them, :class:`InternalForceInfeasibleError` names the joint and the least shortfall.

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
so and only reports whether the predicted forces satisfy the constraints. A controller that solves the QP every
control step keeps an :class:`~regrasp.dynamics.internal_force.solver.InternalForceSolver`; the margins are
:class:`~regrasp.dynamics.internal_force.settings.InternalForceSettings`.
"""

from __future__ import annotations

import ctypes
import functools
import math
import signal
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import qpsolvers
import scipy.sparse as sp

from ...core.contact import FrictionLike, ModesLike
from ...core.exceptions import RegraspError
from ...model.hand import block_diagonal
from .rows import MARGIN_AIM, MARGIN_WEIGHT, ConstraintRows, null_basis
from .settings import ConeEdge, InternalForceSettings, as_cone_edges
from .torque import JointTorques, TorqueShortfall, torque_matrix, torque_shortfall, within_limits

__all__ = [
    "InternalForceInfeasibleError",
    "InternalForceQP",
    "InternalForceResult",
    "build_internal_force_qp",
    "hand_on_ctrl_c",
    "qp_shortfall",
    "solve_internal_force_qp",
]


@dataclass(frozen=True)
class InternalForceQP:
    """A built internal-force QP and what is needed to read its solution.

    Attributes:
        problem: The ``qpsolvers.Problem`` in y (f_c = N_c y), or in (y, s) with a target cone margin
            (s the smallest cone margin [N], the last variable); None when the null space is empty.
        null_basis: N_c, (2m, k), orthonormal columns.
        motion_forces: f_m, (2m,), hand frame.
        settings: The margins used.
        rows: The rows but the torque limits' in the hand frame, (C (r, 2m), lower (r,), n_ineq): C f >= lower in
            the first n_ineq, = lower in the rest (f = f_m + N_c y).
        torques: The joint torque limits (:mod:`regrasp.dynamics.internal_force.torque`; their rows are in
            ``problem``), or None.
    """

    problem: qpsolvers.Problem | None
    null_basis: np.ndarray
    motion_forces: np.ndarray
    settings: InternalForceSettings
    rows: tuple = ()
    torques: JointTorques | None = None


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
    """No internal force keeps every contact inside its cone with the requested margins (and every joint within its
    torque limit).

    Attributes:
        qp: The :class:`InternalForceQP` (its ``problem`` is the qpsolvers problem).
        status: The solver's status string.
        torque: Where the joint torque limits are the reason (a force keeps the other rows, none within the limits):
            the :class:`~regrasp.dynamics.internal_force.torque.TorqueShortfall`, the finger and joint that fall
            short and by how much; else None.
    """

    def __init__(self, qp: InternalForceQP, status: str, torque: TorqueShortfall | None = None):
        self.qp = qp
        self.status = status
        self.torque = torque
        what = (f"no squeeze keeps every contact pushing with >= {qp.settings.f_min} N (or its floor) and every fixed "
                f"contact inside its friction cone with friction margin {qp.settings.friction_margin}")
        if torque is not None:
            what = f"joint torque limit: {torque}, whatever the squeeze ({what} otherwise)"
        super().__init__(f"internal-force QP infeasible (solver status: {status}): {what}")


def _rows(m: int, modes, friction, settings: InternalForceSettings, cone_edge) -> ConstraintRows:
    return ConstraintRows(m, modes, friction, settings, as_cone_edges(cone_edge, m))


def build_internal_force_qp(
    constraint_matrix: np.ndarray,
    motion_forces: np.ndarray,
    surface_frames: np.ndarray,
    modes: ModesLike,
    friction: FrictionLike,
    settings: InternalForceSettings = InternalForceSettings(),
    cone_edge: ConeEdge | tuple[ConeEdge, ...] | None = None,
    torques: JointTorques | None = None,
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
        torques: The joint torque limits, |τ_j| <= e_j with τ = w + Jᵀ f
            (:class:`~regrasp.dynamics.internal_force.torque.JointTorques`), or None: no such rows.
    """
    m = len(surface_frames)
    rows = _rows(m, modes, friction, settings, cone_edge)
    null = null_basis(constraint_matrix)
    k = null.shape[1]
    C = rows.matrix(block_diagonal(np.asarray(surface_frames, dtype=float)))
    plain = (C, rows.lower, rows.n_ineq)
    if k == 0:
        return InternalForceQP(None, null, motion_forces, settings, plain, torques)
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
    if torques is not None:  # the limits' rows: C_τ (f_m + N_c y) >= lo_τ
        C_t, lower_t = torque_matrix(torques, m)
        a_t = C_t @ null
        if rows.target > 0.0:
            a_t = np.hstack([a_t, np.zeros((len(a_t), 1))])
        G, h = np.vstack([G, -a_t]), np.append(h, C_t @ motion_forces - lower_t)
    problem_args = dict(P=sp.csc_matrix(P), q=q, G=sp.csc_matrix(G), h=h)
    if rows.n_eq:
        problem_args.update(A=sp.csc_matrix(a[rows.n_ineq:]), b=rhs[rows.n_ineq:])
    return InternalForceQP(qpsolvers.Problem(**problem_args), null, motion_forces, settings, plain, torques)


def qp_shortfall(qp: InternalForceQP) -> TorqueShortfall | None:
    """How far a built QP's joint torque limits fall short at the least
    (:func:`~regrasp.dynamics.internal_force.torque.torque_shortfall`), or None (no limits, or not the reason)."""
    if qp.torques is None or not any(map(math.isfinite, qp.torques.effort)):
        return None
    return torque_shortfall(qp.null_basis, qp.motion_forces, *qp.rows, qp.torques)


def _check(qp: InternalForceQP, forces, frames, modes, friction, cone_edge, slack) -> tuple[bool, float]:
    rows = _rows(len(frames), modes, friction, qp.settings, cone_edge)
    C = rows.matrix(block_diagonal(np.asarray(frames, dtype=float)))
    ok, margin = rows.check(C, np.asarray(forces).reshape(-1), slack)
    if qp.torques is not None:
        ok = ok and within_limits(qp.torques, np.asarray(forces).reshape(-1).tolist(), slack)
    return ok, margin


_OSQP_INTERRUPTED = "interrupted"


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


def hand_on_ctrl_c(status: str) -> bool:
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
        if not hand_on_ctrl_c(status):
            break
    if not solution.found or solution.x is None:
        raise InternalForceInfeasibleError(qp, status, qp_shortfall(qp))
    k = qp.null_basis.shape[1]
    f_c = qp.null_basis @ solution.x[:k]
    forces = (qp.motion_forces + f_c).reshape(m, 2)
    ok, margin = _check(qp, forces, surface_frames, modes, friction, cone_edge, 1e-6 * scale)
    if not ok:
        raise InternalForceInfeasibleError(qp, f"{status} (solution violates the constraints)", qp_shortfall(qp))
    return InternalForceResult(f_c, forces, k, True, status, time.perf_counter() - start, margin)

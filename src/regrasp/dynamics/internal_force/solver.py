r"""The internal-force QP (:mod:`regrasp.dynamics.internal_force.problem`, paper §3.3, eq. 3.3.7) solved every
control step: :class:`InternalForceSolver` keeps a persistent ``osqp.OSQP`` object per problem shape, or answers with
the compiled dense solver (:mod:`regrasp.kernels.force`).
"""

from __future__ import annotations

import math
import time
from dataclasses import replace

import numpy as np
import osqp
import scipy.sparse as sp
from numpy.typing import ArrayLike

from ...core.contact import FrictionLike, ModesLike
from ...kernels.force import (
    FORCE_CHECK_FAILED,
    FORCE_INFEASIBLE,
    FORCE_NOT_APPLICABLE,
    FORCE_NOT_CONVERGED,
    FORCE_SOLVED,
    internal_force_into,
)
from .problem import (
    InternalForceInfeasibleError,
    InternalForceResult,
    build_internal_force_qp,
    hand_on_ctrl_c,
    qp_shortfall,
)
from .rows import MARGIN_AIM, MARGIN_WEIGHT, OSQP_INFTY, ConstraintRows, as_contacts, null_basis
from .settings import ConeEdge, InternalForceSettings, as_cone_edges
from .torque import JointTorques, torque_rows, within_limits

__all__ = ["InternalForceSolver"]

#: the compiled path's failures, as statuses (the reference path's are OSQP's)
_COMPILED_STATUS = {FORCE_INFEASIBLE: "infeasible (dense solver)", FORCE_NOT_CONVERGED: "not converged (dense solver)",
                    FORCE_CHECK_FAILED: "solved (dense solver; the solution violates the constraints)"}


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
        self._solvers: dict[tuple[int, int, int, float, int], osqp.OSQP] = {}
        self._rows: dict[tuple, ConstraintRows] = {}
        self._rows_settings = settings
        self._last_contacts = None  # (modes, friction) as last passed (tuples), and validated
        self._plain: InternalForceSolver | None = None  # the least-squeeze fallback of a target margin
        self._relaxed: InternalForceSolver | None = None  # the fallback_friction_margin's solver
        #: how often a target-margin problem fell back to the least squeeze (its QP did not converge)
        self.fallbacks = 0
        #: how often the friction margin was relaxed to ``fallback_friction_margin`` (no force kept ``friction_margin``)
        self.relaxations = 0

    def _rows_for(self, m: int, modes, friction, cone_edge) -> ConstraintRows:
        """The rows of these modes, frictions and cone edges (cached: the key holds all three; a list of
        cone edges is taken as the tuple)."""
        if self._rows_settings is not self.settings:
            self._rows.clear()
            self._rows_settings = self.settings
        last = self._last_contacts
        if last is not None and modes is last[0] and friction is last[1] and len(last[2][0]) == m:
            contacts = last[2]
        else:
            contacts = as_contacts(m, modes, friction)
            if type(modes) is tuple and type(friction) is tuple:  # immutable: the same objects, the same values
                self._last_contacts = (modes, friction, contacts)
        if type(cone_edge) is list:
            cone_edge = tuple(cone_edge)
        key = (m, *contacts, cone_edge)
        rows = self._rows.get(key)
        if rows is None:
            rows = self._rows[key] = ConstraintRows(m, *contacts, self.settings, as_cone_edges(cone_edge, m))
        return rows

    def rows_arrays(self, m: int, modes: ModesLike, friction: FrictionLike,
                    cone_edge: ConeEdge | tuple[ConeEdge, ...] | None = None) -> tuple:
        """The QP's rows for these contacts, as :func:`regrasp.kernels.force.internal_force_into` takes them
        (after its first three arguments: coefficients, lower, n_ineq, is_cone, target, σ, W, δ)."""
        return self._rows_for(m, modes, friction, cone_edge).arrays()

    def _osqp(self, k: int, rows: ConstraintRows, a_t: np.ndarray, lower: np.ndarray, n_torque: int = 0) -> osqp.OSQP:
        """The persistent solver of this shape, set up or updated with the numbers of this problem
        (``a_t``: the constraint matrix's column-major data, rows * k, or rows * (k + 1) with the
        margin variable s; ``n_torque``: torque rows after the inequalities of ``rows``, before its equalities)."""
        key = (k, len(lower), rows.n_eq, rows.target, n_torque)  # (the upper bounds' pattern is the key's)
        n_ineq = rows.n_ineq + n_torque
        upper = rows.upper
        if n_torque:
            upper = np.concatenate([upper[:rows.n_ineq], np.full(n_torque, OSQP_INFTY), upper[rows.n_ineq:]])
        if rows.n_eq:
            upper = upper.copy()
            upper[n_ineq:] = lower[n_ineq:]
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
            # only the numbers: the upper bounds of the inequalities are OSQP's infinity, or the target for s's row,
            # in every problem of this shape (the lower bounds are at least minus it: OSQP's clipping keeps them)
            solver.update(l=lower, u=upper if rows.n_eq else None, Ax=a_t.reshape(-1))
        return solver

    @property
    def osqp_solvers(self) -> tuple[osqp.OSQP, ...]:
        """The persistent ``osqp.OSQP`` objects of the reference path set up so far, one per problem shape."""
        return tuple(self._solvers.values())

    def solve(self, constraint_matrix: ArrayLike, motion_forces: ArrayLike, surface_frames: ArrayLike,
              modes: ModesLike, friction: FrictionLike, cone_edge: ConeEdge | tuple[ConeEdge, ...] | None = None,
              torques: JointTorques | None = None) -> InternalForceResult:
        """Solve the QP of :mod:`regrasp.dynamics.internal_force.problem`; see
        :func:`~regrasp.dynamics.internal_force.problem.build_internal_force_qp` for the arguments."""
        frames = [(n_x, n_y, t_x, t_y) for (n_x, t_x), (n_y, t_y) in np.asarray(surface_frames, dtype=float).tolist()]
        return self.solve_floats(constraint_matrix, np.asarray(motion_forces, dtype=float).reshape(-1).tolist(), frames,
                                 modes, friction, cone_edge, time.perf_counter(), torques)

    def solve_floats(self, constraint_matrix: ArrayLike, motion_forces: list[float],
                     frames: list[tuple[float, float, float, float]], modes: ModesLike, friction: FrictionLike,
                     cone_edge: ConeEdge | tuple[ConeEdge, ...] | None, start: float,
                     torques: JointTorques | None = None) -> InternalForceResult:
        """:meth:`solve` with f_m (2m) [N] and the surface frames, per contact (n_x, n_y, t_x, t_y) in the hand frame,
        as floats (hot paths; not validated); ``start``: the ``time.perf_counter()`` the result's ``seconds``
        count from; ``torques``: the joint torque limits (:mod:`regrasp.dynamics.internal_force.torque`), or None."""
        m = len(frames)
        rows = self._rows_for(m, modes, friction, cone_edge)
        outcome = None
        if self.compiled:
            outcome = self._solve_compiled(constraint_matrix, motion_forces, frames, rows, start, torques)
        if outcome is None:  # (the reference path, or a rank-deficient A)
            outcome = self._solve_osqp(constraint_matrix, motion_forces, frames, rows, start, torques)
        if isinstance(outcome, InternalForceResult):
            return outcome
        status = outcome
        if self.settings.fallback_friction_margin is not None:
            # the friction margin is a preference too: the same problem with the smaller one (its own target
            # margin, and its own least-squeeze fallback)
            if self._relaxed is None:
                self._relaxed = InternalForceSolver(
                    replace(self.settings, friction_margin=self.settings.fallback_friction_margin,
                            fallback_friction_margin=self.settings.last_friction_margin, last_friction_margin=None),
                    compiled=self.compiled)
            self.relaxations += 1
            return self._relaxed.solve_floats(constraint_matrix, motion_forces, frames, modes, friction, cone_edge,
                                              start, torques)
        if rows.target > 0.0:
            # the margin is a preference: where its QP does not converge, the least squeeze that keeps the
            # constraints (the same feasible set) is the answer
            if self._plain is None:
                self._plain = InternalForceSolver(replace(self.settings, target_cone_margin=0.0),
                                                  compiled=self.compiled)
            self.fallbacks += 1
            return self._plain.solve_floats(constraint_matrix, motion_forces, frames, modes, friction, cone_edge, start,
                                            torques)
        surface_frames = np.array([((n_x, t_x), (n_y, t_y)) for n_x, n_y, t_x, t_y in frames])
        qp = build_internal_force_qp(constraint_matrix, np.array(motion_forces), surface_frames, modes, friction,
                                     self.settings, cone_edge, torques)
        raise InternalForceInfeasibleError(qp, status, qp_shortfall(qp))

    def _solve_compiled(self, constraint_matrix, motion_forces: list, frames: list, rows: ConstraintRows,
                        start: float, torques: JointTorques | None) -> InternalForceResult | str | None:
        """The compiled path (:func:`regrasp.kernels.force.internal_force_into`): the result, the failure's
        status, or None where the kernel does not apply (a rank-deficient A, a non-finite input: the reference
        path decides, as it did before the kernel)."""
        m = len(frames)
        f_m = np.array(motion_forces, dtype=float)
        f_c, forces = np.empty(2 * m), np.empty(2 * m)
        arrays = rows.arrays()
        if torques is None:
            jac, wrench, effort = np.zeros((m, 4)), np.zeros(2 * m), np.full(2 * m, np.inf)
        else:
            jac, wrench = np.array(torques.jacobians, dtype=float), np.array(torques.wrench, dtype=float)
            effort = np.array(torques.effort, dtype=float)
        status, k, margin = internal_force_into(np.ascontiguousarray(constraint_matrix, dtype=float), f_m,
                                                np.array(frames, dtype=float), *arrays, jac, wrench, effort, f_c,
                                                forces)
        if status == FORCE_NOT_APPLICABLE:
            return None
        if k == 0:
            return InternalForceResult(f_c, forces.reshape(m, 2), 0, status == FORCE_SOLVED, "empty null space",
                                       time.perf_counter() - start, margin)
        if status == FORCE_SOLVED:
            return InternalForceResult(f_c, forces.reshape(m, 2), k, True, "solved", time.perf_counter() - start,
                                       margin)
        return _COMPILED_STATUS[status]

    def _solve_osqp(self, constraint_matrix, motion_forces: list, frames: list, rows: ConstraintRows,
                    start: float, torques: JointTorques | None) -> InternalForceResult | str:
        """The reference path (OSQP, warm-started): the result or the failure's status. With ``torques``, the
        problem is solved again with the torque rows where its answer exceeds a limit (as the compiled path)."""
        m = len(frames)
        null = null_basis(constraint_matrix)
        k = null.shape[1]
        C = rows.rows_at(frames)
        f_m = motion_forces
        scale = max(1.0, max(map(abs, f_m), default=0.0))
        if k == 0:
            ok, margin = rows.check_at(C, f_m, 1e-9 * scale)
            ok = ok and (torques is None or within_limits(torques, f_m, 1e-9 * scale))
            return InternalForceResult(np.zeros(2 * m), np.array(f_m).reshape(m, 2), 0, ok, "empty null space",
                                       time.perf_counter() - start, margin)
        outcome = self._osqp_rows(null, f_m, C, rows, 0, scale, start)
        if torques is None or not isinstance(outcome, InternalForceResult) \
                or within_limits(torques, outcome.forces.reshape(-1).tolist()):
            return outcome
        limits = torque_rows(torques)
        C = C[:rows.n_ineq] + limits + C[rows.n_ineq:]
        return self._osqp_rows(null, f_m, C, rows, len(limits), scale, start)

    def _osqp_rows(self, null: np.ndarray, f_m: list, C: list, rows: ConstraintRows, n_torque: int, scale: float,
                   start: float) -> InternalForceResult | str:
        """OSQP on the rows ``C`` (:meth:`ConstraintRows.rows_at`'s format: those of ``rows``, with ``n_torque``
        torque rows after its inequalities): the result or the failure's status."""
        m, k = len(f_m) // 2, null.shape[1]
        # a y >= lo - C f_m, with a = C N_c; OSQP takes a column by column, i.e. a^T's rows
        lower = [v if (v := lo - (cx * f_m[i2] + cy * f_m[i2 + 1])) >= -OSQP_INFTY else -OSQP_INFTY
                 for i2, cx, cy, lo in C]  # (NaN stays NaN)
        a_t = [cx * b[i2] + cy * b[i2 + 1] for b in null.T.tolist() for i2, cx, cy, _ in C]
        if rows.target > 0.0:  # s's column
            column = rows.margin_column
            a_t += column[:rows.n_ineq] + [0.0] * n_torque + column[rows.n_ineq:] if n_torque else column
        solver = self._osqp(k, rows, np.array(a_t), np.array(lower), n_torque)
        result = solver.solve(raise_error=False)
        while hand_on_ctrl_c(str(result.info.status)):
            result = solver.solve(raise_error=False)
        status = str(result.info.status)
        x = result.x
        if status in ("solved", "solved inaccurate") and x is not None and all(map(math.isfinite, x.tolist())):
            f_c = null.dot(x[:k] if rows.target > 0.0 else x)
            forces = [a + b for a, b in zip(f_m, f_c.tolist())]
            ok, margin = rows.check_at(C[:rows.n_ineq] + C[rows.n_ineq + n_torque:], forces, 1e-6 * scale)
            ok = ok and all(cx * forces[i2] + cy * forces[i2 + 1] - lo >= -1e-6 * scale
                            for i2, cx, cy, lo in C[rows.n_ineq:rows.n_ineq + n_torque])
            if ok:
                return InternalForceResult(f_c, np.array(forces).reshape(m, 2), k, True, status,
                                           time.perf_counter() - start, margin)
            status = f"{status} (solution violates the constraints)"
        return status


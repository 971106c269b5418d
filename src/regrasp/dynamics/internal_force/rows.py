r"""The internal-force QP's constraint rows and null-space basis (the building blocks of
:mod:`regrasp.dynamics.internal_force.problem` and :mod:`regrasp.dynamics.internal_force.solver`).

A row reads :math:`\alpha_r n_i^T f_i + \beta_r t_i^T f_i\ (-\ \sigma_r s) \ge lo_r` on the predicted
force :math:`f_i` of contact i (equalities last, :math:`= lo_r`). With a target cone margin
(``settings.target_cone_margin`` > 0) the QP has one more variable, the smallest cone margin
s [N]: every static-cone row has :math:`\sigma_r = 1`, and one more inequality bounds
:math:`0 \le s \le` target.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike
from scipy.linalg import lapack

from ...core.contact import ContactMode, Friction, FrictionLike, ModesLike, as_frictions, as_modes
from .settings import ConeEdge, InternalForceSettings

__all__ = ["MARGIN_AIM", "MARGIN_WEIGHT", "OSQP_INFTY", "ConstraintRows", "as_contacts", "null_basis"]

_EPS = float(np.finfo(float).eps)
#: OSQP's infinity (``osqp.OSQP().constant("OSQP_INFTY")``): a bound at or beyond it is no bound.
OSQP_INFTY = 1e30
#: the weight W [-] of the margin term ½ W (s - target - δ)² and its aim δ [N] beyond the target
#: (``docs/derivations.md``, "Internal force for a margin"): at s = target the term still pulls with
#: W δ = 1e4 N, more than the squeeze's marginal cost ‖f_c‖ ‖∂f_c/∂s‖ of any squeeze below ~100 N, so s
#: reaches min(target, best margin) to the solver's tolerance (with δ = 0 it would fall short by that
#: cost over W, 1e-3 N at a 20 N squeeze with W = 1e4)
MARGIN_WEIGHT = 1e2
MARGIN_AIM = 1.0


def _constraint_rows(frames, modes, frictions, settings, cone_edges: tuple):
    """Rows (a, lo) meaning a . f_i >= lo on the predicted force of contact i (plus equalities), and
    the indices of the static-cone rows among the inequalities: every contact pushes, every fixed
    one (but those on a cone edge) stays inside its static cone, every cone edge's contact is on it."""
    ineq, eq, cone = [], [], []
    on_edge = {edge.contact for edge in cone_edges}
    for i, frame in enumerate(frames):
        n, t = frame[:, 0], frame[:, 1]
        ineq.append((i, n, settings.floor(i)))
        if np.isfinite(settings.f_max):
            ineq.append((i, -n, -settings.f_max))
        if modes[i] is ContactMode.FIXED and i not in on_edge:
            slope = frictions[i].static - settings.friction_margin
            cone += (len(ineq), len(ineq) + 1)
            ineq.append((i, slope * n - t, 0.0))
            ineq.append((i, slope * n + t, 0.0))
    for edge in cone_edges:
        j = edge.contact
        n, t = frames[j][:, 0], frames[j][:, 1]
        eq.append((j, t - edge.sign * edge.mu * n, 0.0))
    return ineq, eq, cone


def as_contacts(m: int, modes: ModesLike,
                friction: FrictionLike) -> tuple[tuple[ContactMode, ...], tuple[Friction, ...]]:
    """The modes (:func:`~regrasp.core.contact.as_modes`) and the frictions (:func:`~regrasp.core.contact.as_frictions`)
    of ``m`` contacts, validated."""
    return as_modes(modes, m), as_frictions(friction, m)


class ConstraintRows:
    r"""The QP's constraint rows (module docstring) for one (modes, frictions, settings, cone edges) of ``m``
    contacts, as matrices: row r reads :math:`\alpha_r n_i^T f_i + \beta_r t_i^T f_i - \sigma_r s \ge lo_r`
    (equalities last, = lo_r), so that for given surface frames all rows are one product :math:`C f`
    (:meth:`matrix`); ``modes`` and ``friction`` as :func:`as_contacts` takes them; ``cone_edges``: a tuple of
    :class:`~regrasp.dynamics.internal_force.settings.ConeEdge` on distinct contacts, validated by the caller
    (:func:`~regrasp.dynamics.internal_force.settings.as_cone_edges`)."""

    def __init__(self, m: int, modes: ModesLike, friction: FrictionLike, settings: InternalForceSettings,
                 cone_edges: tuple[ConeEdge, ...]):
        modes, frictions = as_contacts(m, modes, friction)
        # in surface coordinates (n = e_x, t = e_y) each row's coefficients are (α_r, β_r)
        ineq, eq, cone = _constraint_rows(np.broadcast_to(np.eye(2), (m, 2, 2)), modes, frictions, settings,
                                          cone_edges)
        #: the target cone margin [N] (0: no margin variable)
        self.target = float(settings.target_cone_margin)
        if self.target > 0.0:
            ineq.append((0, np.zeros(2), 0.0))  # 0 <= s (<= target: its upper bound)
        self.coefficients = np.zeros((len(ineq) + len(eq), 2 * m))
        for r, (i, coef, _) in enumerate(ineq + eq):
            self.coefficients[r, 2 * i:2 * i + 2] = coef
        self.lower = np.array([lo for _, _, lo in ineq + eq])
        self.n_ineq, self.n_eq = len(ineq), len(eq)
        self.upper = np.full(self.n_ineq + self.n_eq, OSQP_INFTY)  # equalities' bounds set per problem
        #: the inequalities' indices of the static-cone rows (their residuals' minimum is the cone margin)
        self.cone = tuple(cone)
        cone_set = set(cone)
        self._is_cone = [r in cone_set for r in range(self.n_ineq)]
        #: σ_r, the margin variable's coefficient in each row (empty without a target)
        self.margin_column: list = []
        if self.target > 0.0:
            self.upper[self.n_ineq - 1] = self.target
            self.margin_column = [0.0] * (self.n_ineq + self.n_eq)
            for r in cone:
                self.margin_column[r] = -1.0
            self.margin_column[self.n_ineq - 1] = 1.0
        self._arrays: tuple | None = None
        #: per row (2i, α_r, β_r, lo_r) as floats (hot paths)
        self.terms = [(2 * i, *(float(v) for v in coef), float(lo)) for i, coef, lo in ineq + eq]

    def arrays(self) -> tuple:
        """The rows as the compiled kernel takes them (:func:`regrasp.kernels.force.internal_force_into`, after
        its first three arguments): coefficients, lower, n_ineq, is_cone, target, margin column, W, δ."""
        if self._arrays is None:
            rows = self.n_ineq + self.n_eq
            is_cone = np.zeros(rows, dtype=np.bool_)
            is_cone[list(self.cone)] = True
            margin = np.array(self.margin_column, dtype=float) if self.margin_column else np.zeros(rows)
            self._arrays = (np.ascontiguousarray(self.coefficients), self.lower.astype(float), self.n_ineq, is_cone,
                            self.target, margin, MARGIN_WEIGHT, MARGIN_AIM)
        return self._arrays

    def matrix(self, frames_bd: np.ndarray) -> np.ndarray:
        """C (rows, 2m): the rows' left-hand sides are C f for contact forces f (2m,) in the hand frame;
        ``frames_bd``: blockdiag(R_fi) (2m, 2m) of the surface frames."""
        return self.coefficients.dot(frames_bd.T)  # (ndarray.dot: cheaper than matmul on small arrays)

    def check(self, C: np.ndarray, forces: np.ndarray, slack: float) -> tuple[bool, float]:
        """(whether forces (2m,) satisfy every row to ``slack`` [N], the cone margin [N]: the least
        residual of the static-cone rows, (μ_s - margin) f_n - |f_t| at the worst fixed contact; inf
        without such rows)."""
        residual = (C.dot(forces) - self.lower).tolist()
        n = self.n_ineq
        ok = min(residual[:n], default=0.0) >= -slack and all(abs(r) <= slack for r in residual[n:])
        return ok, min((residual[r] for r in self.cone), default=math.inf)

    def rows_at(self, frames: list) -> list:
        """The rows of :meth:`matrix` as floats: per row (2i, c_x, c_y, lo), row r of C being (c_x, c_y)
        in the columns of contact i; ``frames``: per contact (n_x, n_y, t_x, t_y), hand frame."""
        out = []
        for i2, alpha, beta, lo in self.terms:
            nx, ny, tx, ty = frames[i2 >> 1]
            out.append((i2, alpha * nx + beta * tx, alpha * ny + beta * ty, lo))
        return out

    def check_at(self, rows: list, forces: list, slack: float) -> tuple[bool, float]:
        """:meth:`check` with the rows of :meth:`rows_at` and forces (2m) as floats."""
        n, is_cone = self.n_ineq, self._is_cone
        ok, margin = True, math.inf
        for r, (i2, cx, cy, lo) in enumerate(rows):
            residual = cx * forces[i2] + cy * forces[i2 + 1] - lo
            if r < n:
                if not residual >= -slack:
                    ok = False
                if is_cone[r] and residual < margin:
                    margin = residual
            elif not abs(residual) <= slack:
                ok = False
        return ok, margin


def null_basis(constraint_matrix: ArrayLike) -> np.ndarray:
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

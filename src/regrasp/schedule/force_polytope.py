r"""The contact forces that can move the object as planned, as a polytope (for the regrasp planner).

Contact i pushes on edge :math:`e_i` with the force :math:`f_i = \lambda_i n_i + \tau_i t_i` (normal
:math:`\lambda_i` and tangential :math:`\tau_i` [N], surface frame of :mod:`regrasp.dynamics.grasp`) at the
point :math:`c_i = o_i + \xi_i t^o_i` of the object frame. Newton–Euler with the trajectory's
acceleration :math:`(a, \alpha)` (paper eq. 3.2.4, :math:`M_o \ddot X = G f + f_g`) reads

.. math:: \sum_i \lambda_i n_i + \tau_i t_i = m_o (a - g), \qquad
          \sum_i \lambda_i A_i + \tau_i B_i - \xi_i \lambda_i = I_o \alpha,

with :math:`A_i = o_i \times n^o_i`, :math:`B_i = o_i \times t^o_i` (object frame) and
:math:`t^o \times n^o = -1`, since :math:`c_i \times f_i = \lambda_i A_i + \tau_i B_i +
\xi_i (t^o_i \times n^o_i) \lambda_i`. **Only the moment depends on the contact positions, and
linearly in ξ for given forces.** So for one time and one contact mode, the forces that satisfy
the force balance and the contact constraints,

* every contact pushes, :math:`f_{min} \le \lambda_i \le f_{max}`;
* a fixed contact stays inside its static cone with a friction margin :math:`\delta` [-] and a margin
  :math:`c` [N]: :math:`(\mu_{s,i} - \delta) \lambda_i - |\tau_i| \ge c` (the executor's internal-force law
  keeps :math:`|\tau_i| \le (\mu_{s,i} - \delta) \lambda_i`,
  :class:`~regrasp.dynamics.internal_force.settings.InternalForceSettings`);
* a contact on a cone edge (sliding with :math:`\mu_k`, or breaking away at :math:`\mu_s`) has
  :math:`\tau_i = r_i \lambda_i` with the signed ratio :math:`r_i = s_i \mu_i`,

form a polytope P that does not depend on ξ, and the positions ξ are feasible iff the linear
function :math:`\varphi(f) = \sum_i \lambda_i \xi_i - q(f)`,
:math:`q(f) = \sum_i \lambda_i A_i + \tau_i B_i - I_o \alpha`, vanishes somewhere on P, i.e. iff
:math:`\min_v \varphi(v) \le 0 \le \max_v \varphi(v)` over P's vertices v. For one contact j, with
the others' positions given, the feasible :math:`\xi_j` form the interval
:math:`[\min_v \rho_v, \max_v \rho_v]`, :math:`\rho_v = (q_v - \sum_{i \ne j} \lambda_{v,i}\xi_i) /
\lambda_{v,j}` (a linear-fractional function with :math:`\lambda_j \ge f_{min} > 0` attains its
extremes over a polytope at vertices).

:func:`force_vertices` enumerates P's vertices (every choice of active inequalities, solved for all
times at once): the planner then classifies whole grids of contact positions with a few products.
:func:`force_system` solves one sample's forces as a linear program instead (the reported forces).

**Joint torque limits** (:mod:`regrasp.schedule.torque`): contact i's joint torques are affine in its own
(λ_i, τ_i), with coefficients that depend on ξ_i: they are not part of P. :func:`force_system` takes them as
rows, and :func:`torque_excess` finds the least excess over them of any force system at given positions (a linear
program: the planner's verification, and its diagnosis).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
import scipy.optimize
from numpy.typing import ArrayLike

from ..core.contact import cone_margin
from ..core.exceptions import InvalidParameterError
from ..core.polygon import ConvexPolygon
from ..core.validation import as_positive_float, check_fields

#: The most floats :func:`force_vertices` holds per block of times (its candidates' solutions and slacks)
_CHUNK_FLOATS = 2e7

__all__ = ["ForceGeometry", "ForceLimits", "ForceVertices", "TorqueExcess", "force_system", "force_vertices",
           "torque_excess", "xi_intervals"]


@dataclass(frozen=True)
class ForceLimits:
    """What a force system must satisfy.

    Attributes:
        f_min: Smallest normal force [N] (> 0).
        f_max: Largest normal force [N] (finite).
        cone_margin: Fixed contacts keep (μ_s - friction_margin) f_n - |f_t| >= this [N].
        slider_floor: A contact on a cone edge (sliding or breaking away) pushes with at least this [N] (0: f_min).
        holder_preload: While any contact is on a cone edge, the fixed ones push with at least this [N] (0: f_min):
            the executor's floors (:class:`~regrasp.supervisor.settings.ExecutorSettings`), planned.
        friction_margin: Fixed contacts keep |f_t| <= (μ_s - this) f_n [-] (a coefficient, as the executor's
            ``InternalForceSettings.friction_margin``), besides ``cone_margin``.
    """

    f_min: float
    f_max: float
    cone_margin: float
    slider_floor: float = 0.0
    holder_preload: float = 0.0
    friction_margin: float = 0.0

    def __post_init__(self):
        check_fields(self, as_positive_float, ("f_min", "f_max"))
        check_fields(self, as_positive_float, ("cone_margin", "slider_floor", "holder_preload", "friction_margin"),
                     allow_zero=True)
        if not self.f_max > self.f_min:
            raise InvalidParameterError("f_max", self.f_max, f"a finite normal force > f_min = {self.f_min} [N]")
        for name in ("slider_floor", "holder_preload"):
            value = getattr(self, name)
            if not value < self.f_max:
                raise InvalidParameterError(name, value, f"a normal force in [0, f_max = {self.f_max}) [N]")

    def floors(self, ratios: Sequence[float | None]) -> list[float]:
        """Each contact's least normal force [N] in a mode given by its ``ratios`` (None: fixed)."""
        moving = any(r is not None for r in ratios)
        return [max(self.f_min, self.slider_floor) if r is not None
                else max(self.f_min, self.holder_preload) if moving else self.f_min for r in ratios]


@dataclass(frozen=True, eq=False)
class ForceGeometry:
    """The object-side constants of the force balance of m contacts (object frame).

    Attributes:
        normals: Inward normals n°_i, (m, 2).
        tangents: ξ directions t°_i, (m, 2).
        moment_normal: A_i = o_i × n°_i [m], (m,).
        moment_tangent: B_i = o_i × t°_i [m], (m,).
        mass: m_o [kg].
        inertia: I_o [kg m²].
        gravity: g [m/s²] in the hand frame, (2,).
    """

    normals: np.ndarray
    tangents: np.ndarray
    moment_normal: np.ndarray
    moment_tangent: np.ndarray
    mass: float
    inertia: float
    gravity: np.ndarray

    @classmethod
    def of(cls, polygon: ConvexPolygon, edges: Sequence[int], *, mass: float, inertia: float,
           gravity: ArrayLike) -> "ForceGeometry":
        """The constants for contacts on ``edges`` of ``polygon``."""
        e = [polygon.edge(k) for k in edges]
        n = np.array([x.inward_normal for x in e])
        t = np.array([x.xi_direction for x in e])
        o = np.array([x.xi_origin for x in e])
        cross = lambda a, b: a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]  # noqa: E731
        return cls(n, t, cross(o, n), cross(o, t), float(mass), float(inertia), np.asarray(gravity, dtype=float))

    @property
    def m(self) -> int:
        return len(self.normals)


@dataclass(frozen=True, eq=False)
class ForceVertices:
    r"""The vertices of the force polytope P at T times for one contact mode.

    Attributes:
        normal: λ per vertex and contact [N], (T, V, m); rows of invalid candidates are NaN (each time's vertices
            first; V: the most vertices any time has).
        tangential: τ per vertex and contact [N], (T, V, m).
        offset: q = Σ λ_i A_i + τ_i B_i - I_o α per vertex [N m], (T, V).
        valid: Which candidates are vertices of P, (T, V) bool (P empty at t: none).
    """

    normal: np.ndarray
    tangential: np.ndarray
    offset: np.ndarray
    valid: np.ndarray

    def at(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """(λ (V_k, m), q (V_k,)) of the valid vertices at time index k."""
        keep = self.valid[k]
        return self.normal[k, keep], self.offset[k, keep]


def _inequalities(m: int, ratios, static_mu, limits: ForceLimits):
    """G x >= h over x = (λ_1..λ_m, τ of the fixed contacts)."""
    fixed = [i for i in range(m) if ratios[i] is None]
    d = m + len(fixed)
    rows, rhs = [], []
    for i, floor in enumerate(limits.floors(ratios)):
        row = np.zeros(d)
        row[i] = 1.0
        rows += [row, -row]
        rhs += [floor, -limits.f_max]
    for k, i in enumerate(fixed):
        for sign in (-1.0, 1.0):  # (μ - δ) λ - τ >= c and (μ - δ) λ + τ >= c
            row = np.zeros(d)
            row[i], row[m + k] = static_mu[i] - limits.friction_margin, sign
            rows.append(row)
            rhs.append(limits.cone_margin)
    return np.array(rows), np.array(rhs), fixed


def _forces(x: np.ndarray, m: int, ratios, fixed) -> tuple[np.ndarray, np.ndarray]:
    """(λ, τ) per contact from x (..., d)."""
    lam = x[..., :m]
    tau = np.zeros_like(lam)
    for i in range(m):
        if ratios[i] is not None:
            tau[..., i] = ratios[i] * lam[..., i]
    for k, i in enumerate(fixed):
        tau[..., i] = x[..., m + k]
    return lam, tau


def _balance(geometry: ForceGeometry, beta: np.ndarray, acceleration: np.ndarray, ratios, fixed):
    """The force balance in the object frame, E_0 x = R(β)^T F(t): E_0 (2, d), rhs (T, 2)."""
    m = geometry.m
    n, t = geometry.normals, geometry.tangents
    cols = [n[i] + (0.0 if ratios[i] is None else ratios[i]) * t[i] for i in range(m)] + [t[i] for i in fixed]
    E = np.stack(cols, -1)
    F = geometry.mass * (acceleration[:, :2] - geometry.gravity)
    c, s = np.cos(beta), np.sin(beta)
    return E, np.stack([c * F[:, 0] + s * F[:, 1], -s * F[:, 0] + c * F[:, 1]], -1)


def _check_mode(m: int, ratios, static_mu) -> tuple[tuple, np.ndarray]:
    if len(ratios) != m or len(static_mu) != m:
        raise InvalidParameterError("ratios", ratios, f"one entry per contact ({m})")
    ratios = tuple(None if r is None else float(r) for r in ratios)
    return ratios, np.asarray(static_mu, dtype=float)


def force_vertices(geometry: ForceGeometry, beta: ArrayLike, acceleration: ArrayLike, ratios: Sequence[float | None],
                   static_mu: Sequence[float] | np.ndarray, limits: ForceLimits) -> ForceVertices:
    r"""P's vertices at each of T times (module docstring).

    Args:
        geometry: The object's constants.
        beta: Object orientation β(t) [rad], (T,).
        acceleration: The object's acceleration (a_x, a_y, α) [m/s², rad/s²], (T, 3).
        ratios: Per contact None (fixed: inside its static cone with the margin) or the signed ratio
            r = τ/λ of a contact on a cone edge (s μ_k sliding, s μ_s breaking away).
        static_mu: μ_s per contact [-].
        limits: Normal force bounds and the cone margin.
    """
    m = geometry.m
    ratios, static_mu = _check_mode(m, ratios, static_mu)
    beta = np.atleast_1d(np.asarray(beta, dtype=float))
    acceleration = np.atleast_2d(np.asarray(acceleration, dtype=float))
    G, h, fixed = _inequalities(m, ratios, static_mu, limits)
    d = G.shape[1]
    E, F = _balance(geometry, beta, acceleration, ratios, fixed)
    T = len(beta)
    combos = np.array(list(itertools.combinations(range(len(G)), d - 2)), dtype=int).reshape(-1, d - 2)
    # every choice of active inequalities gives one matrix [E_0; G_S] for all times (the balance is
    # written in the object frame): invert the regular ones once
    A = np.empty((len(combos), d, d))
    A[:, :2] = E[None]
    A[:, 2:] = G[combos]
    scale_a = np.max(np.abs(A), axis=(1, 2))
    regular = np.abs(np.linalg.det(A)) > 1e-12 * scale_a ** d
    inverse = np.linalg.inv(A[regular])  # (C, d, d)
    scale = max(1.0, limits.f_max)
    # a few times at once (the candidates number C(2m + 2 fixed, d - 2): 126k for five fixed contacts), each time's
    # vertices packed first in candidate order, the rows past the most any time has dropped
    chunk = max(1, int(_CHUNK_FLOATS // max(1, len(inverse) * (d + len(G)))))
    parts = []
    for s in range(0, T, chunk):
        b = np.empty((len(F[s:s + chunk]), len(inverse), d))
        b[:, :, :2] = F[s:s + chunk, None]
        b[:, :, 2:] = h[combos[regular]][None]
        x = np.einsum("cij,tcj->tci", inverse, b)
        slack = np.einsum("rd,tcd->tcr", G, x) - h
        valid = np.all(slack >= -1e-9 * scale, axis=-1)
        order = np.argsort(~valid, axis=1, kind="stable")[:, :max(1, int(valid.sum(axis=1).max(initial=0)))]
        parts.append((np.take_along_axis(x, order[..., None], axis=1), np.take_along_axis(valid, order, axis=1)))
    width = max(p[0].shape[1] for p in parts)
    x = np.concatenate([np.pad(p[0], ((0, 0), (0, width - p[0].shape[1]), (0, 0))) for p in parts])
    valid = np.concatenate([np.pad(p[1], ((0, 0), (0, width - p[1].shape[1]))) for p in parts])
    x[~valid] = np.nan
    lam, tau = _forces(x, m, ratios, fixed)
    offset = lam @ geometry.moment_normal + tau @ geometry.moment_tangent - geometry.inertia * acceleration[:, 2:3]
    return ForceVertices(lam, tau, offset, valid)


def xi_intervals(lam: np.ndarray, offset: np.ndarray, axis: int, others: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r"""The feasible :math:`\xi_j` interval (j = ``axis``) for each row of ``others``.

    Args:
        lam: One time's vertices λ (:meth:`ForceVertices.at`), (V, m).
        offset: Their offsets q, (V,).
        axis: The contact j whose interval is wanted.
        others: Positions ξ [m] of the other contacts (in contact order, j left out), (n, m - 1).

    Returns:
        (lo, hi) [m], each (n,); lo > hi (inf, -inf) where no position of j is feasible.
    """
    n = len(others)
    if len(lam) == 0:
        return np.full(n, np.inf), np.full(n, -np.inf)
    rest = np.delete(lam, axis, axis=1)  # (V, m - 1)
    rho = (offset[:, None] - rest @ others.T) / lam[:, axis:axis + 1]  # (V, n)
    return rho.min(axis=0), rho.max(axis=0)


@dataclass(frozen=True)
class ForceSystem:
    """One sample's contact forces (:func:`force_system`).

    Attributes:
        feasible: Whether a system satisfying every constraint exists.
        normal: λ per contact [N], (m,) (NaN when infeasible).
        tangential: τ per contact [N], (m,).
        cone_margins: μ f_n - |f_t| per contact [N] (μ_s at fixed contacts; 0 on a cone edge).
    """

    feasible: bool
    normal: np.ndarray
    tangential: np.ndarray
    cone_margins: np.ndarray


def _equalities(geometry: ForceGeometry, beta: float, acceleration: ArrayLike, xi: ArrayLike, ratios, fixed, d: int):
    """The force balance at positions ``xi`` as A_eq x = b_eq (3, d): the force in the object frame and the
    moment, Σ λ_i (A_i + r_i B_i - ξ_i) + Σ_fixed τ_i B_i = I α."""
    m = geometry.m
    E, F = _balance(geometry, np.array([beta]), np.atleast_2d(acceleration), ratios, fixed)
    xi = np.asarray(xi, dtype=float)
    moment = np.zeros(d)
    for i in range(m):
        moment[i] = geometry.moment_normal[i] - xi[i] + (0.0 if ratios[i] is None
                                                         else ratios[i] * geometry.moment_tangent[i])
    for k, i in enumerate(fixed):
        moment[m + k] = geometry.moment_tangent[i]
    return np.vstack([E, moment]), np.append(F[0], geometry.inertia * float(np.atleast_2d(acceleration)[0, 2]))


def _torque_rows(torques: np.ndarray, effort: np.ndarray, ratios, fixed, d: int):
    """The torque limits as rows A x <= b: ±(w_j + a_j λ_i + b_j τ_i) <= e_j per limited joint, with τ_i = r_i λ_i
    on a cone edge; ``torques`` (m, 2, 3): per contact and joint (w [N m], a, b [m]); and each row's (i, j)."""
    m = len(ratios)
    col = {i: m + k for k, i in enumerate(fixed)}
    rows, rhs, which = [], [], []
    for i in range(m):
        for j in range(2):
            w, a, b = torques[i, j]
            if not (np.isfinite(effort[i, j]) and np.isfinite(w)):
                continue
            row = np.zeros(d)
            row[i] = a + (0.0 if ratios[i] is None else ratios[i] * b)
            if ratios[i] is None:
                row[col[i]] = b
            for sign in (1.0, -1.0):
                rows.append(sign * row)
                rhs.append(effort[i, j] - sign * w)
                which.append((i, j))
    return np.array(rows).reshape(-1, d), np.array(rhs), which


@dataclass(frozen=True)
class TorqueExcess:
    """The least excess over the joint torque limits of a force system (:func:`torque_excess`).

    Attributes:
        excess: The least t [N m] such that a force system has every |τ_ij| <= e_ij + t (<= 0: one within the
            limits; inf: no force system at all, whatever the torques).
        contact, joint: A joint (0-based contact, joint 0 or 1) at that bound, or -1.
        torque: Its |τ| there [N m].
    """

    excess: float
    contact: int
    joint: int
    torque: float


def torque_excess(geometry: ForceGeometry, beta: float, acceleration: ArrayLike, xi: ArrayLike,
                  ratios: Sequence[float | None], static_mu: Sequence[float] | np.ndarray, limits: ForceLimits,
                  torques: np.ndarray, effort: np.ndarray) -> TorqueExcess:
    r"""The least excess t over the joint torque limits of the force systems at positions ``xi`` [m] (the
    constraints of the module docstring, with ``limits.cone_margin``): the linear program min t s.t.
    :math:`|w_{ij} + a_{ij}\lambda_i + b_{ij}	au_i| \le e_{ij} + t`. ``torques`` (m, 2, 3): per contact and joint
    (w [N m], a [m], b [m]) (:class:`~regrasp.schedule.torque.ContactTorques`); ``effort`` (m, 2) [N m]."""
    m = geometry.m
    ratios, static_mu = _check_mode(m, ratios, static_mu)
    G, h, fixed = _inequalities(m, ratios, static_mu, limits)
    d = G.shape[1]
    A_eq, b_eq = _equalities(geometry, beta, acceleration, xi, ratios, fixed, d)
    T, b_t, which = _torque_rows(np.asarray(torques, dtype=float), np.asarray(effort, dtype=float), ratios, fixed, d)
    if not which:
        return TorqueExcess(-math.inf, -1, -1, math.nan)
    A_ub = np.vstack([np.hstack([-G, np.zeros((len(G), 1))]), np.hstack([T, -np.ones((len(T), 1))])])
    result = scipy.optimize.linprog(np.append(np.zeros(d), 1.0), A_ub=A_ub, b_ub=np.concatenate([-h, b_t]),
                                    A_eq=np.hstack([A_eq, np.zeros((3, 1))]), b_eq=b_eq,
                                    bounds=[(None, None)] * (d + 1), method="highs")
    if result.status != 0:
        return TorqueExcess(math.inf, -1, -1, math.nan)
    x, t = result.x[:d], float(result.x[-1])
    slack = b_t + t - T @ x  # the rows at the bound have no slack
    r = int(np.argmin(slack))
    i, j = which[r]
    return TorqueExcess(t, i, j, float(effort[i, j] + t))


def force_system(geometry: ForceGeometry, beta: float, acceleration: ArrayLike, xi: ArrayLike,
                 ratios: Sequence[float | None], static_mu: Sequence[float] | np.ndarray,
                 limits: ForceLimits, torques: np.ndarray | None = None,
                 effort: np.ndarray | None = None) -> ForceSystem:
    r"""The forces that keep the fixed contacts deepest inside their cones (the largest smallest cone
    margin, at least ``limits.cone_margin``), and among those the least squeeze (smallest Σ λ): two
    linear programs (HiGHS) over the constraints of the module docstring at positions ``xi`` [m], and the joint
    torque limits where ``torques`` (m, 2, 3) and ``effort`` (m, 2) are given (:func:`torque_excess`)."""
    m = geometry.m
    ratios, static_mu = _check_mode(m, ratios, static_mu)
    G, h, fixed = _inequalities(m, ratios, static_mu, replace(limits, cone_margin=0.0))
    d = G.shape[1]
    A_eq, b_eq = _equalities(geometry, beta, acceleration, xi, ratios, fixed, d)
    # variables (x, c): cone rows read μ λ ∓ τ - c >= 0; maximize c
    cone = np.array([r >= 2 * m for r in range(len(G))])
    G_c = np.hstack([G, -cone[:, None].astype(float)])
    h_c = np.where(cone, 0.0, h)
    if torques is not None and effort is not None:  # -T x >= -b_t
        T, b_t, _ = _torque_rows(np.asarray(torques, dtype=float), np.asarray(effort, dtype=float), ratios, fixed, d)
        G_c, h_c = np.vstack([G_c, np.hstack([-T, np.zeros((len(T), 1))])]), np.concatenate([h_c, -b_t])
    A_eq_c = np.hstack([A_eq, np.zeros((3, 1))])
    bounds = [(None, None)] * d + [(None, None) if fixed else (0.0, 0.0)]
    first = scipy.optimize.linprog(np.append(np.zeros(d), -1.0), A_ub=-G_c, b_ub=-h_c, A_eq=A_eq_c, b_eq=b_eq,
                                   bounds=bounds, method="highs")
    nan = np.full(m, np.nan)
    if first.status != 0 or (fixed and -first.fun < limits.cone_margin - 1e-9):
        return ForceSystem(False, nan, nan, nan)
    best = -first.fun if fixed else 0.0
    least = np.append(np.ones(m), np.zeros(d - m + 1))
    bounds[-1] = (best - 1e-9 * max(1.0, abs(best)), None) if fixed else (0.0, 0.0)
    second = scipy.optimize.linprog(least, A_ub=-G_c, b_ub=-h_c, A_eq=A_eq_c, b_eq=b_eq, bounds=bounds,
                                    method="highs")
    x = (second if second.status == 0 else first).x[:d]
    lam, tau = _forces(x, m, ratios, fixed)
    mu = np.array([static_mu[i] if ratios[i] is None else abs(ratios[i]) for i in range(m)])
    return ForceSystem(True, lam, tau, cone_margin(mu, lam, tau))

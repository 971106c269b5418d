r"""The force tables of contacts on a curve: where the force polytope depends on the positions.

On an edge the force balance's only dependence on the positions is the moment's :math:`-\xi_i\lambda_i`, which
makes the force polytope independent of ξ (:mod:`regrasp.schedule.force_polytope`). On a curve the contact's
normal and tangent turn with ξ, so every cell has its own geometry. Contact i's surface-frame force
:math:`q_i = (\lambda_i, \tau_i)` (normal, tangential [N]) exerts on the object, at its point :math:`c_i(\xi_i)`,
the wrench (object frame; force and moment about the centre of mass)

.. math:: A_i(\xi_i)\, q_i, \qquad A_i = \begin{bmatrix} n_i & t_i \\ c_i \times n_i & c_i \times t_i
          \end{bmatrix} \in \mathbb R^{3 \times 2},

and :math:`q_i` ranges over a convex polygon :math:`Q_i` of the mode (a fixed contact: :math:`f_{floor} \le
\lambda_i \le f_{max}`, :math:`|\tau_i| \le (\mu_s - \delta)\lambda_i - c`; on a cone edge the segment
:math:`\tau_i = r_i \lambda_i`). A force system exists iff the required wrench
:math:`w = (R(\beta)^T m_o (a - g),\ I_o\alpha)` lies in the Minkowski sum :math:`\sum_i A_i Q_i`.

**Exact test per cell.** With the other contacts' cells given, their sum :math:`W = \sum_{j \ne a} A_j Q_j` is a
3-D polytope whose facet normals are among: each summand's plane normal :math:`A_j e_1 \times A_j e_2`, the
cross products of two summands' edges, and a summand's edge crossed with its own plane normal (its in-plane
facets when W is flat). So :math:`w - A_a q_a \in W` iff :math:`u \cdot (w - A_a q_a) \le h_W(u)` for each such
u (:math:`h_W` the support function, a sum over the summands' vertices): half-planes in :math:`q_a`. The axis
contact's cell is feasible iff :math:`Q_a` clipped by them is not empty. The compiled kernel
(:func:`feasible_runs`) does this for every layer, cell of the other contacts and cell of the axis contact, and
reports per row the longest run of consecutive feasible cells (the lattice's tables hold one interval per row:
a shorter second run is dropped, so the tables never admit an infeasible cell).

:func:`tangent_geometry` turns positions on a curve into the :class:`~regrasp.schedule.force_polytope.ForceGeometry`
of the contacts' tangent lines there: at those positions its force balance is the curve's exactly (the moment
of :math:`f` at :math:`c = o + \xi t` is :math:`\lambda (o \times n - \xi) + \tau\, o \times t`), so the linear
programs of :mod:`regrasp.schedule.force_polytope` check a schedule's forces on a curve unchanged.
"""

from __future__ import annotations

from collections.abc import Sequence

import numba
import numpy as np
from numpy.typing import ArrayLike

from ..core.curves import CurvedObject
from ..core.exceptions import InvalidParameterError
from ..core.validation import as_finite_array
from .force_polytope import ForceGeometry, ForceLimits

__all__ = ["clip_polygons", "feasible_runs", "mode_polygon", "tangent_geometry", "wrench_maps"]

#: The most vertices of a contact's force polygon (the mode's 4, cut by a few joint torque half-planes).
MAX_POLYGON = 12


def wrench_maps(curve: CurvedObject, xi: ArrayLike) -> np.ndarray:
    r""":math:`A(\xi)` (n, 3, 2) at the positions ``xi`` [m] (module docstring): columns :math:`(n, c \times n)`
    and :math:`(t, c \times t)`, object frame."""
    points, normals, _ = curve.frames(np.atleast_1d(as_finite_array("xi", xi)))
    tangents = np.stack([-normals[:, 1], normals[:, 0]], axis=-1)
    out = np.empty((len(points), 3, 2))
    out[:, :2, 0], out[:, :2, 1] = normals, tangents
    out[:, 2, 0] = points[:, 0] * normals[:, 1] - points[:, 1] * normals[:, 0]
    out[:, 2, 1] = points[:, 0] * tangents[:, 1] - points[:, 1] * tangents[:, 0]
    return out


def tangent_geometry(curve: CurvedObject, xi: ArrayLike, *, mass: float, inertia: float,
                     gravity: ArrayLike) -> ForceGeometry:
    """The :class:`ForceGeometry` of the tangent lines at the contacts' positions ``xi`` [m] (one per contact), each
    with its ξ origin placed so that ``xi`` is the contact's position on it (module docstring)."""
    xi = np.atleast_1d(as_finite_array("xi", xi))
    points, normals, _ = curve.frames(xi)
    tangents = np.stack([-normals[:, 1], normals[:, 0]], axis=-1)
    origins = points - xi[:, None] * tangents

    def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]

    return ForceGeometry(normals, tangents, cross(origins, normals), cross(origins, tangents), float(mass),
                         float(inertia), np.asarray(gravity, dtype=float))


def mode_polygon(ratio: float | None, static_mu: float, floor: float, limits: ForceLimits) -> np.ndarray:
    """A contact's force polygon in (λ, τ) [N], counter-clockwise (k, 2) (k = 0: empty): fixed (``ratio`` None)
    inside its static cone with ``limits``' friction and cone margins, λ in [``floor``, f_max]; on a cone edge the
    segment τ = ``ratio`` λ."""
    if ratio is not None:
        return np.array([[floor, ratio * floor], [limits.f_max, ratio * limits.f_max]])
    slope = static_mu - limits.friction_margin
    if not slope > 0.0:
        return np.empty((0, 2))
    lo = max(floor, limits.cone_margin / slope)
    if lo > limits.f_max:
        return np.empty((0, 2))
    a, b = slope * lo - limits.cone_margin, slope * limits.f_max - limits.cone_margin
    return np.array([[lo, -a], [limits.f_max, -b], [limits.f_max, b], [lo, a]])


@numba.njit(cache=True)
def _cross3(a, b):
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


@numba.njit(cache=True)
def _clip(poly, count, g0, g1, beta):
    """The convex polygon ``poly[:count]`` cut to g·q >= beta (Sutherland–Hodgman); returns (polygon, count)."""
    out = np.empty((2 * count + 2, 2))
    k = 0
    for i in range(count):
        p, q = poly[i], poly[(i + 1) % count]
        sp, sq = g0 * p[0] + g1 * p[1] - beta, g0 * q[0] + g1 * q[1] - beta
        if sp >= 0.0:
            out[k] = p
            k += 1
        if (sp >= 0.0) != (sq >= 0.0):
            s = sp / (sp - sq)
            out[k, 0] = p[0] + s * (q[0] - p[0])
            out[k, 1] = p[1] + s * (q[1] - p[1])
            k += 1
        if count == 2:  # a segment: its one edge, once
            if sq >= 0.0:
                out[k] = q
                k += 1
            break
    return out, k


@numba.njit(cache=True)
def _slack(a, dirs, betas, keep, q):
    """The least slack min_d (A^T u_d)·q - β_d of q over the half-planes (``a``: the axis cell's A); >= 0: q meets
    every one."""
    x, y, z = a[0, 0] * q[0] + a[0, 1] * q[1], a[1, 0] * q[0] + a[1, 1] * q[1], a[2, 0] * q[0] + a[2, 1] * q[1]
    least = np.inf
    for d in range(len(betas)):
        if keep[d]:
            least = min(least, dirs[d, 0] * x + dirs[d, 1] * y + dirs[d, 2] * z - betas[d])
            if least < 0.0:
                return least
    return least


@numba.njit(cache=True)
def _misses(a, u, beta, poly, count):
    """Whether every vertex of the polygon ``poly[:count]`` violates (A^T u)·q >= β (the polygon misses it)."""
    g0 = u[0] * a[0, 0] + u[1] * a[1, 0] + u[2] * a[2, 0]
    g1 = u[0] * a[0, 1] + u[1] * a[1, 1] + u[2] * a[2, 1]
    for v in range(count):
        if g0 * poly[v, 0] + g1 * poly[v, 1] >= beta:
            return False
    return True


@numba.njit(cache=True)
def _inside(poly, q, tol):
    """Whether q lies in the convex CCW polygon (a segment: on it, within ``tol``)."""
    count = len(poly)
    if count == 2:
        dx, dy = poly[1, 0] - poly[0, 0], poly[1, 1] - poly[0, 1]
        cross = dx * (q[1] - poly[0, 1]) - dy * (q[0] - poly[0, 0])
        dot = dx * (q[0] - poly[0, 0]) + dy * (q[1] - poly[0, 1])
        return abs(cross) <= tol * (abs(dx) + abs(dy)) and -tol <= dot <= dx * dx + dy * dy + tol
    for i in range(count):
        p, r = poly[i], poly[(i + 1) % count]
        if (r[0] - p[0]) * (q[1] - p[1]) - (r[1] - p[1]) * (q[0] - p[0]) < -tol:
            return False
    return True


@numba.njit(cache=True)
def _workspace(m):
    """The row test's arrays (reused across rows): vertices, plane normals, directions, supports."""
    n = 4 * m * m * MAX_POLYGON * MAX_POLYGON + 4 * m * MAX_POLYGON + 4 * m
    return np.zeros((m, MAX_POLYGON, 3)), np.zeros((m, 3)), np.zeros((n, 3)), np.zeros(n), np.zeros(n, dtype=np.bool_)


@numba.njit(cache=True)
def _row_run(A, Q, nq, w, env, axis, cells, n_axis, tol, verts, planes, dirs, support, keep):
    """The longest run (first, last) of feasible axis cells for one layer and one cell of each other contact
    (``cells``: per contact its cell, the axis's ignored); (-1, -2) when none. ``verts`` ... ``keep``: the
    workspace (:func:`_workspace`), overwritten."""
    m = A.shape[0]
    # the other contacts' summands: vertices (3-D), plane normals, edges
    n_dirs = 0
    for j in range(m):
        if j == axis:
            continue
        c = cells[j]
        for v in range(nq[j, c]):
            for r in range(3):
                verts[j, v, r] = A[j, c, r, 0] * Q[j, c, v, 0] + A[j, c, r, 1] * Q[j, c, v, 1]
        planes[j] = _cross3(A[j, c, :, 0], A[j, c, :, 1])
        dirs[n_dirs] = planes[j]
        dirs[n_dirs + 1] = -planes[j]
        n_dirs += 2
    for j in range(m):
        if j == axis:
            continue
        nj = nq[j, cells[j]]
        for v in range(nj):
            e = verts[j, (v + 1) % nj] - verts[j, v]
            d = _cross3(e, planes[j])
            dirs[n_dirs], dirs[n_dirs + 1] = d, -d
            n_dirs += 2
            for k in range(j + 1, m):
                if k == axis:
                    continue
                nk = nq[k, cells[k]]
                for u in range(nk):
                    d = _cross3(e, verts[k, (u + 1) % nk] - verts[k, u])
                    dirs[n_dirs], dirs[n_dirs + 1] = d, -d
                    n_dirs += 2
    # normalised, and each direction's support of W
    for d in range(n_dirs):
        keep[d] = False
        norm = np.sqrt(dirs[d, 0] ** 2 + dirs[d, 1] ** 2 + dirs[d, 2] ** 2)
        if norm < 1e-14:
            continue
        dirs[d] /= norm
        keep[d] = True
        h = 0.0
        for j in range(m):
            if j == axis:
                continue
            best = -np.inf
            for v in range(nq[j, cells[j]]):
                s = dirs[d, 0] * verts[j, v, 0] + dirs[d, 1] * verts[j, v, 1] + dirs[d, 2] * verts[j, v, 2]
                if s > best:
                    best = s
            h += best
        support[d] = h
    first, last, best_first, best_last = -1, -2, -1, -2
    witness = np.zeros(2)
    have_witness = False
    killer = -1
    betas = support[:n_dirs]  # u·(w - A q) <= h  <=>  (A^T u)·q >= u·w - h: the offsets depend on the row only
    for d in range(n_dirs):
        betas[d] = dirs[d, 0] * w[0] + dirs[d, 1] * w[1] + dirs[d, 2] * w[2] - support[d] - tol
    for c in range(n_axis):
        ok = env[axis, c] and nq[axis, c] > 0
        if ok:
            a = A[axis, c]
            count = nq[axis, c]
            # cheap verdicts first: the half-plane that emptied the last infeasible cell (likely this one's too)
            if killer >= 0 and _misses(a, dirs[killer], betas[killer], Q[axis, c], count):
                ok = False
        found = False
        if ok and have_witness and _inside(Q[axis, c, :count], witness, 1e-12 * (1.0 + abs(witness[0]))):
            found = _slack(a, dirs, betas, keep, witness) >= 0.0  # (the last feasible cell's witness)
        if ok and not found:
            poly = Q[axis, c, :count].copy()
            for d in range(n_dirs):
                if keep[d]:
                    g0 = dirs[d, 0] * a[0, 0] + dirs[d, 1] * a[1, 0] + dirs[d, 2] * a[2, 0]
                    g1 = dirs[d, 0] * a[0, 1] + dirs[d, 1] * a[1, 1] + dirs[d, 2] * a[2, 1]
                    poly, count = _clip(poly, count, g0, g1, betas[d])
                    if count == 0:
                        ok = False
                        killer = d
                        break
            if ok:
                witness[0], witness[1] = 0.0, 0.0
                for v in range(count):
                    witness[0] += poly[v, 0] / count
                    witness[1] += poly[v, 1] / count
                have_witness = True
        if ok:
            if last == c - 1 and first >= 0:
                last = c
            else:
                first, last = c, c
            if last - first > best_last - best_first:
                best_first, best_last = first, last
        else:
            first, last = -1, -2
    return best_first, best_last


@numba.njit(cache=True, parallel=True)
def _runs_kernel(A, Q, nq, w, env, axis, counts, tol):
    T = w.shape[0]
    m = A.shape[0]
    n_rows = 1
    for j in range(m):
        if j != axis:
            n_rows *= counts[j]
    out = np.full((T, n_rows, 2), -1, dtype=np.int64)
    for k in numba.prange(T):
        cells = np.zeros(m, dtype=np.int64)
        verts, planes, dirs, support, keep = _workspace(m)
        for row in range(n_rows):
            rem = row
            skip = False
            for j in range(m - 1, -1, -1):
                if j == axis:
                    continue
                cells[j] = rem % counts[j]
                rem //= counts[j]
                if not env[k, j, cells[j]] or nq[k, j, cells[j]] == 0:
                    skip = True
            if skip:
                out[k, row, 0], out[k, row, 1] = -1, -2
                continue
            first, last = _row_run(A, Q[k], nq[k], w[k], env[k], axis, cells, counts[axis], tol, verts, planes, dirs,
                                   support, keep)
            out[k, row, 0], out[k, row, 1] = first, last
    return out


def feasible_runs(maps: Sequence[np.ndarray], polygons: np.ndarray, counts: np.ndarray, wrench: np.ndarray,
                  admissible: np.ndarray, axis: int, tol: float) -> np.ndarray:
    """Per layer and cell of the other contacts (in the order of ``itertools.product`` over the other contacts'
    cells), the longest run (first, last) of the axis contact's feasible cells, (T, rows, 2) int (-1, -2: none).

    Args:
        maps: Per contact its cells' wrench maps (n_i, 3, 2) (:func:`wrench_maps`).
        polygons: Per layer, contact and cell its force polygon, (T, m, n_max, MAX_POLYGON, 2) [N] (CCW).
        counts: Their vertex counts, (T, m, n_max) (0: no force allowed there).
        wrench: The required wrench per layer, object frame, (T, 3) [N, N, N m].
        admissible: Per layer, contact and cell whether the cell is worth testing (T, m, n_max) (the others: empty).
        axis: The contact whose runs are wanted.
        tol: Slack of the half-plane tests [N] (rounding).
    """
    m = len(maps)
    if not 0 <= axis < m:
        raise InvalidParameterError("axis", axis, f"a contact index in 0..{m - 1}")
    n_max = max(len(a) for a in maps)
    A = np.zeros((m, n_max, 3, 2))
    for i, a in enumerate(maps):
        A[i, :len(a)] = a
    sizes = np.array([len(a) for a in maps], dtype=np.int64)
    return _runs_kernel(A, np.ascontiguousarray(polygons, dtype=float), np.ascontiguousarray(counts, dtype=np.int64),
                        np.ascontiguousarray(wrench, dtype=float), np.ascontiguousarray(admissible, dtype=np.bool_),
                        int(axis), sizes, float(tol))


@numba.njit(cache=True)
def _clip_all(base, nb, g, beta, valid):
    T, K, H = beta.shape
    out = np.zeros((T, K, MAX_POLYGON, 2))
    counts = np.zeros((T, K), dtype=np.int64)
    for k in range(T):
        for c in range(K):
            if not valid[k, c] or nb == 0:
                continue
            poly = base[:nb].copy()
            count = nb
            for r in range(H):
                if not np.isfinite(beta[k, c, r]):
                    continue
                poly, count = _clip(poly, count, g[k, c, r, 0], g[k, c, r, 1], beta[k, c, r])
                if count == 0:
                    break
            count = min(count, MAX_POLYGON)
            out[k, c, :count] = poly[:count]
            counts[k, c] = count
    return out, counts


def clip_polygons(base: np.ndarray, rows: np.ndarray, offsets: np.ndarray, valid: np.ndarray) -> tuple[np.ndarray,
                                                                                                         np.ndarray]:
    """A contact's force polygon ``base`` (k, 2) cut, per layer and cell, by the half-planes ``rows[..., r, :]·q >=
    offsets[..., r]`` (rows (T, K, H, 2), offsets (T, K, H); a NaN offset: no cut): ((T, K, MAX_POLYGON, 2) polygons,
    (T, K) counts); ``valid`` (T, K) False: no force there (count 0)."""
    base = np.asarray(base, dtype=float).reshape(-1, 2)
    return _clip_all(np.ascontiguousarray(base), len(base), np.ascontiguousarray(rows, dtype=float),
                     np.ascontiguousarray(offsets, dtype=float), np.ascontiguousarray(valid, dtype=np.bool_))

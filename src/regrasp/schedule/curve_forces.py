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
3-D polytope whose facet normals are among: each summand's plane normal :math:`A_j e_1 \times A_j e_2`, the cross
products of two summands' edges, a summand's edge crossed with its own plane normal (its in-plane facets when W is
flat) and a segment summand's own direction (the ends of a W of one dimension). A candidate is kept only if the
summand edges it comes from lie in its face (the others' half-planes repeat the facets'). So :math:`w - A_a q_a \in
W` iff :math:`u \cdot (w - A_a q_a) \le h_W(u)` for each such u (:math:`h_W` the support function, a sum over the
summands' vertices): half-planes in :math:`q_a`. The axis contact's cell is feasible iff :math:`Q_a` clipped by
them is not empty. The compiled kernel (:func:`feasible_runs`) does this for every layer, cell of the other
contacts and cell of the axis contact, and reports per row the longest run of consecutive feasible cells (the
lattice's tables hold one interval per row: a shorter second run is dropped, so the tables never admit an
infeasible cell).

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
def _clip_into(src, count, g0, g1, beta, dst):
    """The convex polygon ``src[:count]`` cut to g·q >= beta (Sutherland–Hodgman) written to ``dst``; returns its
    vertex count (``dst`` holds at least count + 1 rows)."""
    k = 0
    for i in range(count):
        j = i + 1 if i + 1 < count else 0
        px, py, qx, qy = src[i, 0], src[i, 1], src[j, 0], src[j, 1]
        sp, sq = g0 * px + g1 * py - beta, g0 * qx + g1 * qy - beta
        if sp >= 0.0:
            dst[k, 0], dst[k, 1] = px, py
            k += 1
        if (sp >= 0.0) != (sq >= 0.0):
            s = sp / (sp - sq)
            dst[k, 0], dst[k, 1] = px + s * (qx - px), py + s * (qy - py)
            k += 1
        if count == 2:  # a segment: its one edge, once
            if sq >= 0.0:
                dst[k, 0], dst[k, 1] = qx, qy
                k += 1
            break
    return k


@numba.njit(cache=True)
def _clip(poly, count, g0, g1, beta):
    """:func:`_clip_into` to a new array; returns (polygon, count)."""
    out = np.empty((count + 2, 2))
    return out, _clip_into(poly, count, g0, g1, beta, out)


@numba.njit(cache=True)
def _push(dirs, refs, n, x, y, z, j1, v1, j2, v2):
    """Appends ±(x, y, z) to the candidate directions, each with the summand edges (j, v) it comes from (-1: none;
    a candidate is a facet normal only if those edges lie in its face)."""
    dirs[n, 0], dirs[n, 1], dirs[n, 2] = x, y, z
    dirs[n + 1, 0], dirs[n + 1, 1], dirs[n + 1, 2] = -x, -y, -z
    for r in range(2):
        refs[n + r, 0], refs[n + r, 1], refs[n + r, 2], refs[n + r, 3] = j1, v1, j2, v2
    return n + 2


@numba.njit(cache=True)
def _on_face(verts, nj, v, d, best, tol):
    """Whether summand edge (v, v + 1) of the ``nj`` vertices ``verts`` is in its face in direction d (value best)."""
    w = v + 1 if v + 1 < nj else 0
    a = d[0] * verts[v, 0] + d[1] * verts[v, 1] + d[2] * verts[v, 2]
    b = d[0] * verts[w, 0] + d[1] * verts[w, 1] + d[2] * verts[w, 2]
    return a >= best - tol and b >= best - tol


@numba.njit(cache=True)
def _workspace(m):
    """The row test's arrays (reused across rows): vertices, plane normals, directions, their source edges, supports,
    kept flags, per-summand maxima, and two polygon buffers."""
    n = 4 * m * m * MAX_POLYGON * MAX_POLYGON + 6 * m * MAX_POLYGON + 4 * m
    return (np.zeros((m, MAX_POLYGON, 3)), np.zeros((m, 3)), np.zeros((n, 3)), np.zeros((n, 4), dtype=np.int64),
            np.zeros(n), np.zeros(n, dtype=np.int64), np.zeros(m), np.zeros((MAX_POLYGON + n + 2, 2)),
            np.zeros((MAX_POLYGON + n + 2, 2)))


@numba.njit(cache=True)
def _directions(A, Q, nq, axis, cells, verts, planes, dirs, refs):
    """The other contacts' summands A_j Q_j (their vertices in ``verts``, plane normals in ``planes``) and W's
    candidate facet normals (module docstring; a segment's own direction too, for a W of one dimension); returns
    their count."""
    m = A.shape[0]
    n = 0
    for j in range(m):
        if j == axis:
            continue
        c = cells[j]
        for v in range(nq[j, c]):
            for r in range(3):
                verts[j, v, r] = A[j, c, r, 0] * Q[j, c, v, 0] + A[j, c, r, 1] * Q[j, c, v, 1]
        planes[j, 0] = A[j, c, 1, 0] * A[j, c, 2, 1] - A[j, c, 2, 0] * A[j, c, 1, 1]
        planes[j, 1] = A[j, c, 2, 0] * A[j, c, 0, 1] - A[j, c, 0, 0] * A[j, c, 2, 1]
        planes[j, 2] = A[j, c, 0, 0] * A[j, c, 1, 1] - A[j, c, 1, 0] * A[j, c, 0, 1]
        n = _push(dirs, refs, n, planes[j, 0], planes[j, 1], planes[j, 2], -1, -1, -1, -1)
    for j in range(m):
        if j == axis:
            continue
        nj = nq[j, cells[j]]
        px, py, pz = planes[j, 0], planes[j, 1], planes[j, 2]
        for v in range(nj):
            w = v + 1 if v + 1 < nj else 0
            ex, ey = verts[j, w, 0] - verts[j, v, 0], verts[j, w, 1] - verts[j, v, 1]
            ez = verts[j, w, 2] - verts[j, v, 2]
            if nj == 2 and v == 0:
                n = _push(dirs, refs, n, ex, ey, ez, -1, -1, -1, -1)
            n = _push(dirs, refs, n, ey * pz - ez * py, ez * px - ex * pz, ex * py - ey * px, j, v, -1, -1)
            for k in range(j + 1, m):
                if k == axis:
                    continue
                nk = nq[k, cells[k]]
                for u in range(nk):
                    x = u + 1 if u + 1 < nk else 0
                    fx, fy, fz = verts[k, x, 0] - verts[k, u, 0], verts[k, x, 1] - verts[k, u, 1], \
                        verts[k, x, 2] - verts[k, u, 2]
                    n = _push(dirs, refs, n, ey * fz - ez * fy, ez * fx - ex * fz, ex * fy - ey * fx, j, v, k, u)
    return n


@numba.njit(cache=True)
def _facets(nq, axis, cells, verts, dirs, refs, n_dirs, support, keep, best, w, tol):
    """Normalises the candidates, keeps W's facet normals among them (a candidate whose source edges are not in its
    face only repeats the facets' half-planes) and writes the kept ones' offsets (A^T u)·q >= u·w - h_W(u) - tol to
    ``support``; returns the number kept (their indices first in ``keep``)."""
    m = verts.shape[0]
    kept = 0
    for d in range(n_dirs):
        norm = np.sqrt(dirs[d, 0] ** 2 + dirs[d, 1] ** 2 + dirs[d, 2] ** 2)
        if norm < 1e-14:
            continue
        dirs[d, 0], dirs[d, 1], dirs[d, 2] = dirs[d, 0] / norm, dirs[d, 1] / norm, dirs[d, 2] / norm
        h, scale = 0.0, 0.0
        for j in range(m):
            if j == axis:
                continue
            top = -np.inf
            for v in range(nq[j, cells[j]]):
                s = dirs[d, 0] * verts[j, v, 0] + dirs[d, 1] * verts[j, v, 1] + dirs[d, 2] * verts[j, v, 2]
                top = max(top, s)
                scale = max(scale, abs(s))
            best[j] = top
            h += top
        slack = 1e-9 * (1.0 + scale)  # (keeping a redundant half-plane is harmless; dropping a facet is not)
        facet = True
        for r in range(0, 4, 2):
            j = refs[d, r]
            if j >= 0 and not _on_face(verts[j], nq[j, cells[j]], refs[d, r + 1], dirs[d], best[j], slack):
                facet = False
        if facet:
            support[d] = dirs[d, 0] * w[0] + dirs[d, 1] * w[1] + dirs[d, 2] * w[2] - h - tol
            keep[kept] = d
            kept += 1
    return kept


@numba.njit(cache=True)
def _row_run(A, Q, nq, w, env, axis, cells, stretch, tol, work):
    """The longest run (first, last) of feasible axis cells for one layer and one cell of each other contact
    (``cells``: per contact its cell, the axis's ignored); (-1, -2) when none. ``stretch``: per axis cell the number
    of admissible cells from it on without a gap; ``work``: the workspace (:func:`_workspace`), overwritten.

    A cell is feasible iff its polygon Q_a clipped by the half-planes (A_a^T u)·q >= u·w - h_W(u) is not empty; two
    shortcuts first: the half-plane that emptied the last infeasible cell, and the last feasible cell's witness. A
    stretch that cannot hold a run longer than the longest so far is skipped (the same result: the first longest
    run)."""
    verts, planes, dirs, refs, offsets, keep, best, buf0, buf1 = work
    n_dirs = _directions(A, Q, nq, axis, cells, verts, planes, dirs, refs)
    kept = _facets(nq, axis, cells, verts, dirs, refs, n_dirs, offsets, keep, best, w, tol)
    first, last, best_first, best_last = -1, -2, -1, -2
    wx, wy, have_witness, killer = 0.0, 0.0, False, -1
    c = -1
    while c + 1 < len(stretch):
        c += 1
        run = c - first if last == c - 1 and first >= 0 else 0
        if run + stretch[c] <= best_last - best_first + 1:
            c += stretch[c]  # (to the gap that ends this stretch)
            first, last = -1, -2
            continue
        count = nq[axis, c]
        ok = env[axis, c] and count > 0
        a00, a01, a10, a11, a20, a21 = (A[axis, c, 0, 0], A[axis, c, 0, 1], A[axis, c, 1, 0], A[axis, c, 1, 1],
                                        A[axis, c, 2, 0], A[axis, c, 2, 1])
        if ok and killer >= 0:  # (the half-plane that emptied the last infeasible cell: likely this one's too)
            g0 = dirs[killer, 0] * a00 + dirs[killer, 1] * a10 + dirs[killer, 2] * a20
            g1 = dirs[killer, 0] * a01 + dirs[killer, 1] * a11 + dirs[killer, 2] * a21
            ok = False
            for v in range(count):
                if g0 * Q[axis, c, v, 0] + g1 * Q[axis, c, v, 1] >= offsets[killer]:
                    ok = True
                    break
        found = False
        if ok and have_witness and _inside(Q[axis, c], count, wx, wy, 1e-12 * (1.0 + abs(wx))):
            x, y, z = a00 * wx + a01 * wy, a10 * wx + a11 * wy, a20 * wx + a21 * wy
            found = True
            for i in range(kept):
                d = keep[i]
                if dirs[d, 0] * x + dirs[d, 1] * y + dirs[d, 2] * z < offsets[d]:
                    found = False
                    break
        if ok and not found:
            src, dst = buf0, buf1
            for v in range(count):
                src[v, 0], src[v, 1] = Q[axis, c, v, 0], Q[axis, c, v, 1]
            for i in range(kept):
                d = keep[i]
                g0 = dirs[d, 0] * a00 + dirs[d, 1] * a10 + dirs[d, 2] * a20
                g1 = dirs[d, 0] * a01 + dirs[d, 1] * a11 + dirs[d, 2] * a21
                count = _clip_into(src, count, g0, g1, offsets[d], dst)
                src, dst = dst, src
                if count == 0:
                    ok = False
                    killer = d
                    break
            if ok:
                wx, wy = 0.0, 0.0
                for v in range(count):
                    wx += src[v, 0] / count
                    wy += src[v, 1] / count
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


@numba.njit(cache=True)
def _inside(poly, count, qx, qy, tol):
    """Whether q lies in the convex CCW polygon ``poly[:count]`` (a segment: on it, within ``tol``)."""
    if count == 2:
        dx, dy = poly[1, 0] - poly[0, 0], poly[1, 1] - poly[0, 1]
        cross = dx * (qy - poly[0, 1]) - dy * (qx - poly[0, 0])
        dot = dx * (qx - poly[0, 0]) + dy * (qy - poly[0, 1])
        return abs(cross) <= tol * (abs(dx) + abs(dy)) and -tol <= dot <= dx * dx + dy * dy + tol
    for i in range(count):
        j = i + 1 if i + 1 < count else 0
        if (poly[j, 0] - poly[i, 0]) * (qy - poly[i, 1]) - (poly[j, 1] - poly[i, 1]) * (qx - poly[i, 0]) < -tol:
            return False
    return True


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
        work = _workspace(m)
        stretch = np.zeros(counts[axis], dtype=np.int64)
        for c in range(counts[axis] - 1, -1, -1):
            if env[k, axis, c] and nq[k, axis, c] > 0:
                stretch[c] = 1 + (stretch[c + 1] if c + 1 < counts[axis] else 0)
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
            first, last = _row_run(A, Q[k], nq[k], w[k], env[k], axis, cells, stretch, tol, work)
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

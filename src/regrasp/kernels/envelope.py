r"""One ``urdf`` envelope sample, compiled: :meth:`regrasp.envelope.finger_envelope.FingerEnvelope.at` in one call.

The same steps and the same arithmetic as the reference path (:class:`~regrasp.envelope.evaluator.EnvelopeEvaluator`;
:mod:`regrasp.envelope.line` and :mod:`regrasp.envelope.finger_envelope` have the derivations): the edge's line at
the object pose (d, λ, s0), the reachable set on it (Definition 2.1) merged, its intersection with the edge, the
``ideal`` feasible set (link 1 through a vertex, each piece classified at its midpoint), then per piece of
reachable ∩ edge the ``urdf`` cuts: the verdict on the grid of ``grid`` points plus the ``ideal`` ends inside, every
flip bisected to ``tol``, and the free pieces merged. Only the collision verdict differs in kind: the footprints'
closed-form signed distances (:mod:`.footprint`) instead of coal's, so a verdict can differ only within coal's own
tolerance of a contact (``tests/kernels/test_footprint.py`` measures both).

Everything is in line coordinates s [m] (:class:`~regrasp.envelope.line.EdgeLine`; ξ = s - s0). The finger, edge
and sampling constants are one :data:`ENVELOPE_PARAMETERS` record; the polygon is given in its own frame
(vertices and inward edge normals) and the link shapes as :data:`~.footprint.FOOTPRINT` records.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .footprint import links_collide_at, object_in_hand

__all__ = ["ENVELOPE_PARAMETERS", "envelope_sample_into", "feasible_capacity", "tip_is_free", "workspace_size"]

_F8 = np.float64

#: A finger on an edge: joint 1 (o1x, o1y) [m] and the base angle [rad] (hand frame), the link lengths
#: [m] and the squares the reference path uses (l1², l2², l1² - l2², (l1 + l2)², (l1 - l2)² [m²], computed
#: by Python's ``**``, which may differ from a product in the last bit), the configuration's sign σ, the
#: ``ideal`` test's eps [m], the edge's inward normal and ξ origin (object frame) and ξ range [m], the grid
#: size, the bisection tolerance [m] and the prism's half-height [m].
ENVELOPE_PARAMETERS = np.dtype([
    ("o1x", _F8), ("o1y", _F8), ("base_angle", _F8), ("l1", _F8), ("l2", _F8), ("l1sq", _F8), ("l2sq", _F8),
    ("l12", _F8), ("outer_sq", _F8), ("inner_sq", _F8), ("sign", _F8), ("eps", _F8),
    ("n0x", _F8), ("n0y", _F8), ("c0x", _F8), ("c0y", _F8), ("xi_lo", _F8), ("xi_hi", _F8),
    ("grid", np.int64), ("tol", _F8), ("half_thickness", _F8),
], align=True)


def feasible_capacity(grid: int, n_vertices: int) -> int:
    """Rows enough for the feasible pieces (and the cuts) of any sample: four pieces of reachable ∩ edge, each
    with at most ``grid`` points plus two ``ideal`` ends per piece of its vertex cuts."""
    return 4 * (grid + 2 * (2 * n_vertices + 1))


def workspace_size(grid: int, n_vertices: int) -> int:
    """Length of the float64 workspace of :func:`envelope_sample_into` (:func:`_carve`)."""
    n, rows = n_vertices, 4 * (2 * n_vertices + 1)
    return 5 * n + 8 + 2 * rows + 2 * n + 2 * rows + 2 * n + 2 + grid + 2 * rows + 2 * feasible_capacity(grid, n) + 2


@numba.njit(cache=True)
def _carve(work, grid, n):
    """The views of :func:`workspace_size`'s workspace: the polygon in the hand frame (vertices, normals,
    offsets), the reachable pieces before merging, the ``ideal`` pieces (merged, and before), the vertex
    cuts, one piece's cuts, the grid points, the ``urdf`` pieces before merging, the links' distances."""
    rows = 4 * (2 * n + 1)
    urdf_rows = 4 * (grid + 2 * (2 * n + 1))
    a = 2 * n
    b = a + 2 * n
    c = b + n
    d = c + 8
    e = d + 2 * rows
    f = e + 2 * n
    g = f + 2 * rows
    h = g + 2 * n + 2
    i = h + grid + 2 * rows
    j = i + 2 * urdf_rows
    return (work[:a].reshape((n, 2)), work[a:b].reshape((n, 2)), work[b:c], work[c:d].reshape((4, 2)),
            work[d:e].reshape((rows, 2)), work[e:f], work[f:g].reshape((rows, 2)), work[g:h], work[h:i],
            work[i:j].reshape((urdf_rows, 2)), work[j:j + 2])


@numba.njit(cache=True)
def _merge(pieces, count, out):
    """:func:`regrasp.core.intervals.merge` (gap 0) of ``pieces[:count]`` into ``out`` (``pieces`` is sorted in
    place by (lo, hi)); returns the count."""
    for i in range(1, count):  # insertion sort: a few dozen pieces at most
        lo, hi = pieces[i, 0], pieces[i, 1]
        j = i - 1
        while j >= 0 and (pieces[j, 0] > lo or (pieces[j, 0] == lo and pieces[j, 1] > hi)):
            pieces[j + 1, 0], pieces[j + 1, 1] = pieces[j, 0], pieces[j, 1]
            j -= 1
        pieces[j + 1, 0], pieces[j + 1, 1] = lo, hi
    k = 0
    for idx in range(count):
        lo, hi = pieces[idx, 0], pieces[idx, 1]
        if not hi > lo:
            continue
        if k > 0 and lo <= out[k - 1, 1]:
            if hi > out[k - 1, 1]:
                out[k - 1, 1] = hi
        else:
            out[k, 0], out[k, 1] = lo, hi
            k += 1
    return k


@numba.njit(cache=True)
def _reachable(p, d, pieces, out):
    """:func:`regrasp.envelope.line.reachable_on_line` into ``out`` (4, 2) (``pieces``: (4, 2) scratch); returns the
    count."""
    l1, l2 = p.l1, p.l2
    outer2 = p.outer_sq - d * d
    if outer2 <= 0.0 or d < -l1:
        return 0
    big = math.sqrt(outer2)
    if d > l1:
        pieces[0, 0], pieces[0, 1] = -big, big
        k = 1
    else:
        c = math.sqrt(l1 * l1 - d * d)
        if d >= 0.0:
            pieces[0, 0], pieces[0, 1], pieces[1, 0], pieces[1, 1] = c - l2, big, -big, -c - l2
            k = 2
        else:
            pieces[0, 0], pieces[0, 1] = l2 - c, l2 + c
            k = 1
    inner2 = p.inner_sq - d * d
    if inner2 > 0.0:
        hole = math.sqrt(inner2)
        for j in range(k - 1, -1, -1):  # (lo, min(hi, -hole)), (max(lo, hole), hi), in order
            lo, hi = pieces[j, 0], pieces[j, 1]
            pieces[2 * j, 0], pieces[2 * j, 1] = lo, min(hi, -hole)
            pieces[2 * j + 1, 0], pieces[2 * j + 1, 1] = max(lo, hole), hi
        k *= 2
    if p.sign < 0.0:
        for j in range(k):
            lo, hi = pieces[j, 0], pieces[j, 1]
            pieces[j, 0], pieces[j, 1] = -hi, -lo
    return _merge(pieces, k, out)


@numba.njit(cache=True)
def _tip_and_elbow(p, d, nx, ny, s):
    """Tip and elbow (x, y, x, y) [m] relative to joint 1 for the tip at line coordinate s."""
    px = d * nx - s * ny
    py = d * ny + s * nx
    r = math.hypot(px, py)
    ux, uy = px / r, py / r
    a = (p.l12 + r * r) / (2.0 * r)
    h = p.sign * math.sqrt(max(p.l1sq - a * a, 0.0))
    return px, py, a * ux - h * uy, a * uy + h * ux


@numba.njit(cache=True)
def _segment_hits(ax, ay, bx, by, verts, normals, offsets, eps):
    """:func:`regrasp.model.collision.segment_hits_halfplanes` against the polygon
    (:func:`~.footprint.object_in_hand`)."""
    n = verts.shape[0]
    t0, t1 = 0.0, 1.0
    for k in range(n):
        nx, ny, off = normals[k, 0], normals[k, 1], offsets[k]
        fa = nx * ax + ny * ay - off
        fb = nx * bx + ny * by - off
        if fa < 0.0:
            if fb < 0.0:
                return False
            t0 = max(t0, fa / (fa - fb))
        elif fb < 0.0:
            t1 = min(t1, fa / (fa - fb))
        if t1 <= t0:
            return False
    tm = 0.5 * (t0 + t1)
    inside = math.inf
    for k in range(n):
        nx, ny, off = normals[k, 0], normals[k, 1], offsets[k]
        fa = nx * ax + ny * ay - off
        fb = nx * bx + ny * by - off
        inside = min(inside, fa + tm * (fb - fa))
    return inside > eps


@numba.njit(cache=True)
def _sorted_unique(values, count):
    """The distinct values of ``values[:count]``, sorted (in place: a view of ``values``)."""
    ordered = values[:count]
    ordered.sort()
    k = 0
    for j in range(count):
        if k == 0 or ordered[j] != ordered[k - 1]:
            ordered[k] = ordered[j]
            k += 1
    return ordered[:k]


@numba.njit(cache=True)
def _ideal(p, base, nb, d, nx, ny, verts, normals, offsets, extra, cuts, pieces, out):
    """The ``ideal`` feasible pieces of ``base[:nb]`` into ``out``
    (:meth:`~regrasp.envelope.evaluator.EnvelopeEvaluator.ideal_feasible`); scratch: ``extra`` (2n,), ``cuts``
    (2n + 2,), ``pieces`` (4 (2n + 1), 2)."""
    n = verts.shape[0]
    ne = 0
    for k in range(n):  # link 1 through a vertex (EnvelopeEvaluator.vertex_cuts)
        wx, wy = verts[k, 0] - p.o1x, verts[k, 1] - p.o1y
        dist = math.hypot(wx, wy)
        if dist == 0.0 or dist > p.l1:
            continue
        ex, ey = p.l1 * wx / dist, p.l1 * wy / dist
        gap = d - (ex * nx + ey * ny)
        disc = p.l2sq - gap * gap
        if disc >= 0.0:
            et, root = ey * nx - ex * ny, math.sqrt(disc)
            extra[ne], extra[ne + 1] = et - root, et + root
            ne += 2
    count = np.int64(0)  # (not the literal 0: numba would compile _merge for it too)
    for j in range(nb):
        lo, hi = base[j, 0], base[j, 1]
        cuts[0], cuts[1] = lo, hi
        nc = np.int64(2)  # (not a literal: see count)
        for t in extra[:ne]:
            if lo < t < hi:
                cuts[nc] = t
                nc += 1
        ordered = _sorted_unique(cuts, nc)
        for i in range(ordered.shape[0] - 1):
            a, b = ordered[i], ordered[i + 1]
            if b <= a:
                continue
            px, py, ex, ey = _tip_and_elbow(p, d, nx, ny, 0.5 * (a + b))
            if not (_segment_hits(p.o1x, p.o1y, p.o1x + ex, p.o1y + ey, verts, normals, offsets, p.eps)
                    or _segment_hits(p.o1x + ex, p.o1y + ey, p.o1x + px, p.o1y + py, verts, normals, offsets,
                                     p.eps)):
                pieces[count, 0], pieces[count, 1] = a, b
                count += 1
    return _merge(pieces, count, out)


@numba.njit(cache=True)
def _free(p, shapes, d, nx, ny, s, verts, normals, offsets, nearest, exact=False):
    """Whether no footprint penetrates the object with the tip at line coordinate s
    (``EnvelopeEvaluator.free_test``)."""
    px, py, ex, ey = _tip_and_elbow(p, d, nx, ny, s)
    n1 = math.hypot(ex, ey)
    vx, vy = px - ex, py - ey
    n2 = math.hypot(vx, vy)
    return not links_collide_at(shapes, p.o1x, p.o1y, ex / n1, ey / n1, p.o1x + ex, p.o1y + ey, vx / n2, vy / n2,
                                verts, normals, offsets, p.half_thickness, nearest, exact)


@numba.njit(cache=True)
def _line(p, x, y, c, s):
    """(d, λ, s0, n_x, n_y) of the edge's line at the object pose (``EnvelopeEvaluator.edge_line``)."""
    nx, ny = c * p.n0x - s * p.n0y, s * p.n0x + c * p.n0y
    rx = x + (c * p.c0x - s * p.c0y) - p.o1x
    ry = y + (s * p.c0x + c * p.c0y) - p.o1y
    lam = (math.atan2(ny, nx) - p.base_angle + math.pi) % (2.0 * math.pi) - math.pi
    if lam == -math.pi:
        lam = math.pi
    return rx * nx + ry * ny, lam, ry * nx - rx * ny, nx, ny


@numba.njit(cache=True)
def tip_is_free(params, shapes, vertices, normals, x, y, beta, s, nearest):
    """The ``urdf`` verdict at one tip position: whether no footprint penetrates the object at the pose
    (x [m], y [m], beta [rad]) with the tip at line coordinate s [m]; each link's smallest signed distance
    [m] into ``nearest`` (2,). ``params``: one :data:`ENVELOPE_PARAMETERS` record, shape (1,)."""
    p = params[0]
    n = vertices.shape[0]
    verts, norms, offsets = np.empty((n, 2)), np.empty((n, 2)), np.empty(n)
    c, sn = math.cos(beta), math.sin(beta)
    object_in_hand(vertices, normals, x, y, c, sn, verts, norms, offsets)
    d, _, _, nx, ny = _line(p, x, y, c, sn)
    return _free(p, shapes, d, nx, ny, s, verts, norms, offsets, nearest, True)


@numba.njit(cache=True)
def envelope_sample_into(params, shapes, vertices, normals, x, y, beta, scalars, reach, base, starts, flip_counts,
                         flips, feasible, work):
    """One ``urdf`` sample at the object pose (x [m], y [m], beta [rad]) (module docstring). ``params``: one
    :data:`ENVELOPE_PARAMETERS` record, shape (1,); ``shapes``: the :data:`~.footprint.FOOTPRINT` records;
    ``vertices``, ``normals``: the polygon's vertices and inward edge normals (n, 2), object frame.

    Writes (d, λ, s0) into ``scalars`` (3,); the reachable set in ξ = s - s0 into ``reach`` and reachable ∩
    edge into ``base`` (4, 2); per piece of reachable ∩ edge, whether its start is free into ``starts`` (4,) and its
    number of flips into ``flip_counts`` (4,), the free side of every flip, in order, into ``flips``; the
    feasible pieces in ξ into ``feasible`` (rows: :func:`feasible_capacity`). ``work``: a float64 scratch array
    (:func:`workspace_size`). Returns (reachable pieces,
    pieces of reachable ∩ edge, feasible pieces), all in line coordinates s [m]."""
    p = params[0]
    n = vertices.shape[0]
    grid = p.grid
    verts, norms, offsets, reach_scratch, hints, extra, ideal_scratch, cuts, points, pieces, nearest = _carve(
        work, grid, n)
    c, sn = math.cos(beta), math.sin(beta)
    d, lam, s0, nx, ny = _line(p, x, y, c, sn)
    scalars[0], scalars[1], scalars[2] = d, lam, s0
    nr = _reachable(p, d, reach_scratch, reach)
    nb = 0
    edge_lo, edge_hi = p.xi_lo + s0, p.xi_hi + s0
    for j in range(nr):  # intersect(reach, ((lo, hi),))
        lo, hi = max(reach[j, 0], edge_lo), min(reach[j, 1], edge_hi)
        if hi > lo:
            base[nb, 0], base[nb, 1] = lo, hi
            nb += 1
        if not reach[j, 1] < edge_hi:
            break
    if nb == 0:
        _shift(reach, nr, s0)
        return nr, 0, 0
    object_in_hand(vertices, normals, x, y, c, sn, verts, norms, offsets)
    nh = _ideal(p, base, nb, d, nx, ny, verts, norms, offsets, extra, cuts, ideal_scratch, hints)
    count = np.int64(0)  # (not the literal 0: numba would compile _merge for it too)
    nf = 0
    for j in range(nb):
        lo, hi = base[j, 0], base[j, 1]
        delta = hi - lo  # regrasp.envelope.floats.linspace_floats
        div = grid - 1
        step = delta / div
        for k in range(div):
            points[k] = (k / div) * delta + lo if step == 0.0 else k * step + lo
        points[div] = hi
        npts = grid
        for i in range(nh):
            for t in (hints[i, 0], hints[i, 1]):
                if lo < t < hi:
                    points[npts] = t
                    npts += 1
        pts = _sorted_unique(points, npts)
        previous = _free(p, shapes, d, nx, ny, pts[0], verts, norms, offsets, nearest)
        starts[j] = previous
        start = lo if previous else math.nan
        flip_counts[j] = 0
        for k in range(1, pts.shape[0]):
            verdict = _free(p, shapes, d, nx, ny, pts[k], verts, norms, offsets, nearest)
            if verdict == previous:
                continue
            a, b = pts[k - 1], pts[k]  # the verdict flips in (a, b): bisect
            while b - a > p.tol:
                m = 0.5 * (a + b)
                if _free(p, shapes, d, nx, ny, m, verts, norms, offsets, nearest) == previous:
                    a = m
                else:
                    b = m
            end = a if previous else b  # the free side
            flips[nf] = end
            nf += 1
            flip_counts[j] += 1
            if math.isnan(start):  # colliding -> free: open a piece
                start = end
            else:  # free -> colliding: close it
                pieces[count, 0], pieces[count, 1] = start, end
                count += 1
                start = math.nan
            previous = verdict
        if not math.isnan(start):
            pieces[count, 0], pieces[count, 1] = start, hi
            count += 1
    nf = _merge(pieces, count, feasible)
    _shift(reach, nr, s0)
    _shift(feasible, nf, s0)
    return nr, nb, nf


@numba.njit(cache=True)
def _shift(pieces, count, s0):
    """``pieces[:count]`` from line coordinates s to ξ = s - s0 [m], in place."""
    for k in range(count):
        pieces[k, 0] -= s0
        pieces[k, 1] -= s0

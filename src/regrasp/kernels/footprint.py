r"""Signed distances between a planar finger's link shapes and the object prism, in closed form (compiled).

**Why the plane suffices.** The ``urdf`` geometry tests each link shape S against the object's prism
:math:`P = Q \times [-h, h]` (:class:`~regrasp.model.collision.UrdfCollisionChecker`: Q the polygon in the hand
plane z = 0, h the finger's reach). Let :math:`\pi` be the projection onto the plane, and suppose S is
symmetric about z = 0 and :math:`|z| \le h` on S. Then:

* *separated*: every point of S is inside the slab, so its distance to P is the planar distance of its
  projection to Q, and :math:`\operatorname{dist}(S, P) = \operatorname{dist}(\pi S, Q)`;
* *penetrating*: the penetration depth is the distance from the origin to the boundary of
  :math:`K = P - S` (Minkowski difference). S is convex and symmetric, so with (x, y, z) it holds
  (x, y, -z) and their midpoint: its mid-slice :math:`S_0 = S \cap \{z = 0\}` projects onto
  :math:`\pi S`. Hence :math:`(Q - \pi S) \times [-h, h] \subseteq K \subseteq (Q - \pi S) \times
  \mathbb{R}`, and the depth lies in :math:`[\min(p, h), p]` with p the planar depth of
  :math:`\pi S` in Q: it equals p whenever :math:`p \le h`.

So the 3-D signed distance is the planar signed distance of the shape's *footprint* :math:`\pi S` to Q
(exactly, unless a link is deeper than h inside the object, where :func:`footprint_distance` returns -h:
of the right sign, and no larger in magnitude than the true depth, so still a valid certificate radius).
The footprints (:data:`FOOTPRINT`, in the shape's link frame) are a rectangle (half-sides ``hu`` along the
unit axis u, ``hv`` across) dilated by a disc of radius ``rad``: a box turned about z only (``rad`` = 0),
a cylinder whose axis lies in the plane (a ``2 half_length`` by ``2 radius`` rectangle), a capsule so
placed (a stadium: ``hv`` = 0), a sphere centred in the plane (a disc: ``hu`` = ``hv`` = 0).
:meth:`~regrasp.model.collision.UrdfCollisionChecker.footprints` builds them, and returns None for any other
shape or placement (an axis out of the plane, a centre off it, another geometry type): the caller then
keeps coal.

**Planar signed distance** of a rectangle R (possibly degenerate) dilated by ``rad`` to a convex polygon Q
(CCW, inward normals :math:`m_k`, offsets :math:`o_k = m_k \cdot v_k`): it is the signed distance of R
to Q minus ``rad``. The separating-axis gaps over Q's edge normals (:math:`o_k - \max_R m_k \cdot r`) and
R's four normals (:math:`\min_Q w \cdot q - \max_R w \cdot r`, w = ±u, ±v) are each at most the signed
distance, and their largest equals it when R and Q overlap (the edges of Q - R have exactly these
normals; a normal of a degenerate side that is not an edge gives a smaller gap, so it is harmless). When
a gap is positive they are disjoint, and the distance is the smallest vertex–edge distance between them.
"""

from __future__ import annotations

import math

import numba
import numpy as np

__all__ = ["FOOTPRINT", "footprint_distance", "footprint_distances", "links_collide_at", "object_in_hand"]

_F8 = np.float64

#: One link shape's planar footprint in its link frame (origin at the link's joint, x along the link):
#: the link (0 proximal, 1 distal), the centre (cx, cy) [m], the unit axis (ux, uy), the half-sides
#: along (hu) and across (hv) the axis [m], the dilation radius rad [m] and the largest |z| on the shape
#: [m] (for the check against the prism's half-height).
FOOTPRINT = np.dtype([
    ("link", np.int64), ("cx", _F8), ("cy", _F8), ("ux", _F8), ("uy", _F8), ("hu", _F8), ("hv", _F8),
    ("rad", _F8), ("zext", _F8),
], align=True)


@numba.njit(cache=True)
def object_in_hand(vertices, normals, x, y, c, s, verts_out, normals_out, offsets_out):
    """The polygon (vertices (n, 2) [m], inward edge normals (n, 2), object frame; edge k starts at vertex k)
    at the pose (x [m], y [m], cos beta, sin beta) in the hand frame: its vertices and normals into
    ``verts_out`` and ``normals_out`` (n, 2) and the offsets :math:`m_k \\cdot v_k` [m] into ``offsets_out``."""
    for k in range(vertices.shape[0]):
        vx, vy = vertices[k, 0], vertices[k, 1]
        px, py = x + (c * vx - s * vy), y + (s * vx + c * vy)
        mx, my = normals[k, 0], normals[k, 1]
        kx, ky = c * mx - s * my, s * mx + c * my
        verts_out[k, 0], verts_out[k, 1] = px, py
        normals_out[k, 0], normals_out[k, 1] = kx, ky
        offsets_out[k] = kx * px + ky * py


@numba.njit(cache=True)
def _point_segment_sq(px, py, ax, ay, bx, by):
    """Squared distance [m²] from (px, py) to the segment (ax, ay)–(bx, by)."""
    dx, dy = bx - ax, by - ay
    wx, wy = px - ax, py - ay
    len2 = dx * dx + dy * dy
    t = 0.0
    if len2 > 0.0:
        t = min(max((wx * dx + wy * dy) / len2, 0.0), 1.0)
    ex, ey = wx - t * dx, wy - t * dy
    return ex * ex + ey * ey


@numba.njit(cache=True)
def footprint_distance(fp, ox, oy, c, s, verts, normals, offsets, half_thickness, exact):
    """Signed distance [m] of the footprint ``fp`` (:data:`FOOTPRINT`) in the link frame at (ox, oy) [m] with
    direction (c, s) (hand frame) to the polygon (``verts``, ``normals``, ``offsets`` of
    :func:`object_in_hand`), clamped below at -``half_thickness`` [m] (module docstring). Unless ``exact``, a
    separation larger than the dilation radius is returned as a separating-axis gap, a lower bound (the
    sign is the same; the remaining axes and the vertex–edge distances are skipped)."""
    cx = ox + c * fp.cx - s * fp.cy
    cy = oy + s * fp.cx + c * fp.cy
    ux, uy = c * fp.ux - s * fp.uy, s * fp.ux + c * fp.uy
    hu, hv, rad = fp.hu, fp.hv, fp.rad
    n = verts.shape[0]
    gap = -math.inf
    for k in range(n):  # Q's normals: how far R's deepest point is from edge k's line (negated)
        mx, my = normals[k, 0], normals[k, 1]
        deepest = mx * cx + my * cy + hu * abs(mx * ux + my * uy) + hv * abs(my * ux - mx * uy)
        gap = max(gap, offsets[k] - deepest)
        if gap > rad and not exact:
            return gap - rad
    # R's normals ±u, ±v (v = (-uy, ux)): Q's extent along u and v against R's
    lo_u = hi_u = ux * verts[0, 0] + uy * verts[0, 1]
    lo_v = hi_v = ux * verts[0, 1] - uy * verts[0, 0]
    for k in range(1, n):
        pu = ux * verts[k, 0] + uy * verts[k, 1]
        pv = ux * verts[k, 1] - uy * verts[k, 0]
        lo_u, hi_u = min(lo_u, pu), max(hi_u, pu)
        lo_v, hi_v = min(lo_v, pv), max(hi_v, pv)
    cu, cv = ux * cx + uy * cy, ux * cy - uy * cx
    gap = max(gap, lo_u - (cu + hu), (cu - hu) - hi_u, lo_v - (cv + hv), (cv - hv) - hi_v)
    if gap > 0.0 and (exact or gap <= rad):  # disjoint: the smallest vertex-edge distance
        vx, vy = -uy, ux
        best = math.inf
        for a in range(4):
            su = 1.0 if a == 0 or a == 1 else -1.0
            sv = 1.0 if a == 1 or a == 2 else -1.0
            ax, ay = cx + su * hu * ux + sv * hv * vx, cy + su * hu * uy + sv * hv * vy
            b = (a + 1) % 4
            tu = 1.0 if b == 0 or b == 1 else -1.0
            tv = 1.0 if b == 1 or b == 2 else -1.0
            bx, by = cx + tu * hu * ux + tv * hv * vx, cy + tu * hu * uy + tv * hv * vy
            for k in range(n):
                j = k + 1 if k + 1 < n else 0
                best = min(best, _point_segment_sq(ax, ay, verts[k, 0], verts[k, 1], verts[j, 0], verts[j, 1]),
                           _point_segment_sq(verts[k, 0], verts[k, 1], ax, ay, bx, by))
        gap = math.sqrt(best)
    return max(gap - rad, -half_thickness)


@numba.njit(cache=True)
def links_collide_at(shapes, o1x, o1y, c1, s1, x2, y2, c2, s2, verts, normals, offsets, half_thickness, nearest,
                     exact):
    """Whether any footprint has a negative signed distance to the polygon (:func:`object_in_hand`): link 1's
    frame at joint 1 (o1x, o1y) [m] with direction (c1, s1), link 2's at the elbow (x2, y2) [m] with
    direction (c2, s2), hand frame. ``nearest`` (2,) receives each link's smallest signed distance [m]
    (+inf for a link without shapes). Unless ``exact``, a positive one may be a lower bound
    (:func:`footprint_distance`) and the shapes after the first penetrating one are skipped."""
    nearest[0] = math.inf
    nearest[1] = math.inf
    for i in range(shapes.shape[0]):
        fp = shapes[i]
        if fp.link == 0:
            dist = footprint_distance(fp, o1x, o1y, c1, s1, verts, normals, offsets, half_thickness, exact)
        else:
            dist = footprint_distance(fp, x2, y2, c2, s2, verts, normals, offsets, half_thickness, exact)
        if dist < nearest[fp.link]:
            nearest[fp.link] = dist
            if dist < 0.0 and not exact:
                return True
    return nearest[0] < 0.0 or nearest[1] < 0.0


@numba.njit(cache=True)
def footprint_distances(shapes, vertices, normals, half_thickness, pose, posture, out):
    """Signed distance [m] of every footprint to the polygon into ``out`` (len(shapes),). ``vertices`` and
    ``normals`` (n, 2): the polygon in its frame (:func:`object_in_hand`); ``pose``: the object's (x [m],
    y [m], beta [rad]) in the hand frame; ``posture``: (joint 1 x, y [m], cos psi1, sin psi1, elbow x, y [m],
    cos psi2, sin psi2), psi_k the direction of link k (hand frame)."""
    n = vertices.shape[0]
    verts, norms, offsets = np.empty((n, 2)), np.empty((n, 2)), np.empty(n)
    object_in_hand(vertices, normals, pose[0], pose[1], math.cos(pose[2]), math.sin(pose[2]), verts, norms, offsets)
    for i in range(shapes.shape[0]):
        fp = shapes[i]
        k = 4 * fp.link
        out[i] = footprint_distance(fp, posture[k], posture[k + 1], posture[k + 2], posture[k + 3], verts, norms,
                                    offsets, half_thickness, True)

r"""Rounded polygons: a convex polygon whose corners are filleted by arcs of one radius r.

The object is the polygon's inner parallel body grown back by r: each edge line :math:`n_k \cdot x = e_k`
(inward normal :math:`n_k`) moves inwards to :math:`n_k \cdot x = e_k + r`; the moved lines meet at the inner
corners :math:`w_k`; the boundary is each edge's straight part, from :math:`w_{k+1} - r n_k` to
:math:`w_k - r n_k` (on the polygon's edge), joined at corner k by the arc of radius r about :math:`w_k`,
whose inward normal turns from :math:`n_k` to :math:`n_{k-1}` through the exterior angle. The outline stays
inside the polygon and touches each of its edges along the straight part: a 10 cm box with 1 cm corners is
still 10 cm wide. A radius is valid while every straight part keeps a positive length:
:math:`r < L_k / (\cot(\alpha_k/2) + \cot(\alpha_{k+1}/2))` with :math:`\alpha` the interior angles.

ξ (arc length, clockwise; :mod:`regrasp.core.curves.base`) is the polygon's edge-0 ξ on edge 0's straight part
(same origin, the foot of the perpendicular from the centre of mass, same direction); the pieces follow
clockwise: edge 0, arc 0, edge n-1, arc n-1, ..., edge 1, arc 1. Radius 0 is the polygon itself
(:func:`rounded`). Mass properties from Green's theorem over the pieces (Gauss-Legendre, exact to rounding for
segments and arcs).
"""

from __future__ import annotations

import bisect
import math

import numpy as np
from numpy.typing import ArrayLike

from ..exceptions import CurveError, InvalidParameterError
from ..polygon import ConvexPolygon
from ..validation import as_finite_float
from .base import CurvedObject, uniform_mass_properties

__all__ = ["RoundedPolygon", "rounded"]

#: Gauss-Legendre nodes per piece for the second moments (an arc's integrands are trigonometric polynomials of
#: degree <= 4 over less than half a turn: 24 nodes leave an error far below rounding).
_GAUSS = np.polynomial.legendre.leggauss(24)


class RoundedPolygon(CurvedObject):
    r"""The convex polygon ``vertices`` [m] (object frame, any orientation, as for
    :class:`~regrasp.core.polygon.ConvexPolygon`) with every corner rounded to ``radius`` [m] > 0 (module
    docstring). Mass properties as :func:`~regrasp.core.curves.base.uniform_mass_properties`: with a uniform
    density the *rounded* outline's centroid must be the origin.

    Raises:
        PolygonError: the vertices are no strictly convex polygon.
        CurveError: the radius is not positive, or so large that an edge's straight part vanishes
            (``where`` = that edge; the message gives the largest radius).
    """

    def __init__(self, vertices: ArrayLike, radius: float, *, mass: float | None = None,
                 inertia: float | None = None, density: float | None = None):
        self.polygon = ConvexPolygon(vertices, mass=1.0, inertia=1.0)  # validates, normalises to CCW
        radius_f = as_finite_float("radius", radius)
        if not radius_f > 0.0:
            raise CurveError(f"radius = {radius_f:g} m: expected a corner radius > 0 (use rounded() for 0: the "
                             "polygon itself)", parameter="radius", value=radius)
        self.radius = radius_f
        edges = self.polygon.edges
        n = len(edges)
        normals = np.array([e.inward_normal for e in edges])
        offsets = np.array([float(e.inward_normal @ e.start) for e in edges]) + radius_f
        inner = []  # w_k: lines k-1 and k moved inwards meet at corner k
        for k in range(n):
            a = np.array([normals[k - 1], normals[k]])
            inner.append(np.linalg.solve(a, [offsets[k - 1], offsets[k]]))
        self.inner_corners = np.array(inner)
        for k, e in enumerate(edges):
            along = float((self.inner_corners[(k + 1) % n] - self.inner_corners[k]) @ (e.end - e.start)) / e.length
            if not along > 1e-9 * self.polygon.scale:
                largest = min(self._largest_radius(j) for j in range(n))
                raise CurveError(f"radius = {radius_f:g} m: edge {k}'s straight part would vanish (length "
                                 f"{along:.3g} m); the largest corner radius of this polygon is below {largest:.6g} m",
                                 parameter="radius", value=radius, where=k)
        self._pieces = self._build_pieces()
        self._starts = [p[0] for p in self._pieces]
        self._period = self._pieces[-1][0] + self._pieces[-1][1] - self._pieces[0][0]
        self.mass, self.inertia = uniform_mass_properties(
            "rounded polygon", self._moments(), self.polygon.scale, mass=mass, inertia=inertia, density=density,
            centring_hint="rounding moves a polygon's centroid unless it is symmetric: shift the vertices by minus "
                          "the centroid given, or give mass and inertia")

    def __repr__(self) -> str:
        return (f"RoundedPolygon({self.polygon.n_vertices} vertices, radius={self.radius:g}, mass={self.mass:g}, "
                f"inertia={self.inertia:g})")

    @property
    def label(self) -> str:
        """``"4-gon rounded to r = 10 mm"``."""
        return f"{self.polygon.n_vertices}-gon rounded to r = {self.radius * 1e3:.4g} mm"

    def _largest_radius(self, k: int) -> float:
        """Edge k's straight part vanishes at this radius [m]."""
        e = self.polygon.edges
        n = len(e)

        def cot_half_interior(j: int) -> float:  # at vertex j, between edges j-1 and j
            (ax, ay), (bx, by) = e[j - 1].end - e[j - 1].start, e[j].end - e[j].start
            turn = math.atan2(float(ax * by - ay * bx), float(ax * bx + ay * by))
            return 1.0 / math.tan(0.5 * (math.pi - turn))

        return e[k].length / (cot_half_interior(k) + cot_half_interior((k + 1) % n))

    def _build_pieces(self) -> list[tuple]:
        """Clockwise pieces from edge 0's straight part's start: (ξ start [m], length [m], kind, data)."""
        edges, r, w = self.polygon.edges, self.radius, self.inner_corners
        n = len(edges)
        pieces = []
        e0 = edges[0]
        xi = float(e0.xi_of(w[1 % n] - r * e0.inward_normal))
        for k in [0, *range(n - 1, 0, -1)]:
            e = edges[k]
            start = w[(k + 1) % n] - r * e.inward_normal
            length = float(np.linalg.norm(w[k] - w[(k + 1) % n]))
            pieces.append((xi, length, "edge", (k, start, e.xi_direction, e.inward_normal)))
            xi += length
            theta_k = math.atan2(e.inward_normal[1], e.inward_normal[0])
            prev = edges[k - 1].inward_normal
            turn = (theta_k - math.atan2(prev[1], prev[0])) % (2.0 * math.pi)  # exterior angle at corner k
            pieces.append((xi, r * turn, "arc", (k, w[k], theta_k)))
            xi += r * turn
        return pieces

    @property
    def perimeter(self) -> float:
        """The polygon's perimeter less the corners' cuts plus the arcs [m]."""
        return self._period

    def _local_floats(self, xi: float) -> tuple[float, float, float, float, float]:
        x0 = self._starts[0]
        u = x0 + (xi - x0) % self._period
        start, _, kind, data = self._pieces[max(bisect.bisect_right(self._starts, u) - 1, 0)]
        s = u - start
        if kind == "edge":
            _, a, t, n = data
            return float(a[0] + s * t[0]), float(a[1] + s * t[1]), float(n[0]), float(n[1]), 0.0
        _, centre, theta0 = data
        theta = theta0 - s / self.radius
        nx, ny = math.cos(theta), math.sin(theta)
        return float(centre[0] - self.radius * nx), float(centre[1] - self.radius * ny), nx, ny, 1.0 / self.radius

    def piece(self, xi: float) -> tuple[str, int]:
        """Which piece ξ [m] falls on: ``("edge", k)`` (the polygon's edge k's straight part) or ``("arc", k)``
        (corner k's arc)."""
        xi = as_finite_float("xi", xi)
        x0 = self._starts[0]
        _, _, kind, data = self._pieces[max(bisect.bisect_right(self._starts, x0 + (xi - x0) % self._period) - 1, 0)]
        return kind, int(data[0])

    def piece_ranges(self) -> list[tuple[str, int, float, float]]:
        """Every piece as (kind, edge or corner index, ξ start [m], ξ end [m]), clockwise over one period from
        edge 0's straight part."""
        return [(kind, int(data[0]), start, start + length) for start, length, kind, data in self._pieces]

    def pieces_between(self, lo: float, hi: float) -> list[tuple[str, int, float, float]]:
        """The pieces that meet ξ from ``lo`` to ``hi`` [m] (ξ unbounded: every turn round the boundary), in order,
        as (kind, edge or corner index, ξ start [m], ξ end [m]) clipped to that interval."""
        lo, hi = as_finite_float("lo", lo), as_finite_float("hi", hi)
        if not lo <= hi:
            raise InvalidParameterError("hi", hi, f"an interval [lo, hi] [m] with lo <= hi (lo = {lo:g} m)")
        ranges, out = self.piece_ranges(), []
        turn = math.floor((lo - ranges[0][2]) / self._period)
        while ranges[0][2] + turn * self._period <= hi:
            for kind, k, a, b in ranges:
                a, b = a + turn * self._period, b + turn * self._period
                if b > lo and a < hi:
                    out.append((kind, k, max(a, lo), min(b, hi)))
            turn += 1
        return out

    def _moments(self) -> tuple[float, np.ndarray, float]:
        nodes, weights = _GAUSS
        area = mx = my = polar = 0.0
        for start, length, _, _ in self._pieces:
            if length <= 0.0:
                continue
            xi = start + 0.5 * length * (nodes + 1.0)
            pts, normals, _ = self.frames(xi)
            x, y = pts[:, 0], pts[:, 1]
            tx, ty = -normals[:, 1], normals[:, 0]
            w = 0.5 * length * weights
            # Green's theorem, clockwise (hence the signs)
            area -= 0.5 * float(w @ (x * ty - y * tx))
            mx -= 0.5 * float(w @ (x * x * ty))
            my += 0.5 * float(w @ (y * y * tx))
            polar -= float(w @ (x ** 3 * ty - y ** 3 * tx)) / 3.0
        return area, np.array([mx, my]) / area, polar


def rounded(vertices: ArrayLike, radius: float, **mass_properties: float | None) -> ConvexPolygon | RoundedPolygon:
    """The polygon ``vertices`` [m] with corners rounded to ``radius`` [m] >= 0: radius 0 is the
    :class:`~regrasp.core.polygon.ConvexPolygon` itself (``ConvexPolygon.from_vertices``), a positive radius a
    :class:`RoundedPolygon`; ``mass_properties`` (``mass``, ``inertia``, ``density``) as either takes them."""
    radius_f = as_finite_float("radius", radius)
    if radius_f == 0.0:
        return ConvexPolygon.from_vertices(vertices, **mass_properties)
    return RoundedPolygon(vertices, radius_f, **mass_properties)

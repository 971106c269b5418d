r"""Curved objects: a rigid body bounded by a smooth convex closed curve, and its one contact face.

Every quantity is in the **object frame** :math:`C_o` (origin at the centre of mass), lengths in [m].

The boundary as one contact face (the paper's §3.1 "general curve ... with a local parameterization")
---------------------------------------------------------------------------------------------------
A polygon offers one face per edge (:class:`~regrasp.core.polygon.Edge`); a curved object offers **one** face,
its whole boundary, :class:`CurveFace`, so that a contact can slide continuously round it (from a flat part onto
an arc of a rounded polygon, or right round a disc). Its parameter ξ [m] is the **arc length**, growing the way
an edge's ξ grows: along :math:`t = \perp n` with :math:`n` the unit inward normal, i.e. *clockwise* round the
object. The surface frame :math:`C_f(\xi)` has x-axis :math:`n(\xi)` and y-axis :math:`t(\xi)`, as on an edge,
and the curve is parametrised by arc length, so

.. math::

    c'(\xi) = t(\xi), \qquad t'(\xi) = \kappa(\xi)\, n(\xi), \qquad n'(\xi) = -\kappa(\xi)\, t(\xi),

with :math:`\kappa \ge 0` the curvature (convex: the tangent turns towards the inside); the frame's angle
:math:`\theta_f` (of :math:`n`) turns by :math:`d\theta_f / d\xi = -\kappa`. An edge is the case
:math:`\kappa = 0`. ξ is unbounded: the geometry repeats every perimeter P, so a contact's ξ is continuous
however far it slides (``xi_range`` is :math:`(-\infty, \infty)`; ``period`` is P). Each curve puts ξ = 0 where
the inward normal is :math:`(0, -1)` (the top, where :math:`t = (1, 0)`), or, for a rounded polygon, where
its edge 0 has ξ = 0 (the foot of the perpendicular from the centre of mass).

Subclasses give the evaluation :meth:`CurvedObject.local` (point, inward normal, curvature at ξ), the perimeter
and the second moments; the base class derives the rest (projection of a point onto the curve, signed
distance, containment, outline, collision shape).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

import coal
import numpy as np
from numpy.typing import ArrayLike

from ..exceptions import CurveError, InvalidParameterError, PolygonError, UnknownEdgeError
from ..validation import as_finite_array, as_finite_float, as_inertia, as_mass, as_positive_float

__all__ = ["CurveFace", "CurvedObject", "SurfacePoint", "bracketed_root", "uniform_mass_properties"]

#: Relative tolerance (times the diameter) on the centroid's distance from the origin for a uniform density.
CENTROID_RTOL = 1e-9
#: Samples of the boundary per object for the projection's starting guesses and the outline.
TABLE_SAMPLES = 512
#: The collision shape's largest gap [-] (times the diameter) between the curve and its circumscribed polygon.
COLLISION_SAGITTA_RTOL = 1e-5


@dataclass(frozen=True)
class SurfacePoint:
    r"""The curve at one ξ, object frame.

    Attributes:
        xi: ξ [m] (arc length, unbounded).
        point: :math:`c(\xi)` [m].
        normal: Unit inward normal :math:`n(\xi)` (x-axis of :math:`C_f`).
        tangent: :math:`t = \perp n` (y-axis of :math:`C_f`, :math:`c' = t`).
        curvature: :math:`\kappa(\xi) \ge 0` [1/m] (:math:`t' = \kappa n`).
    """

    xi: float
    point: np.ndarray
    normal: np.ndarray
    tangent: np.ndarray
    curvature: float


def bracketed_root(f: Callable[[float], tuple[float, float]], lo: float, hi: float, x0: float, tol: float,
                   max_iter: int = 200) -> float:
    """The root of ``f`` (returning (value, derivative)) in [lo, hi] where f(lo) <= 0 <= f(hi): Newton steps kept
    inside the bracket, bisection when a step leaves it or does not halve the bracket (always converges)."""
    x = min(max(x0, lo), hi)
    for _ in range(max_iter):
        value, slope = f(x)
        if value == 0.0:
            return x
        if value < 0.0:
            lo = x
        else:
            hi = x
        step = value / slope if slope > 0.0 else math.inf
        x_new = x - step
        if abs(step) <= tol:  # converged (a step this small may land on the bracket's end: no bisection then)
            return min(max(x_new, lo), hi)
        if not lo < x_new < hi:
            x_new = 0.5 * (lo + hi)
        if abs(x_new - x) <= tol or hi - lo <= tol:
            return x_new
        x = x_new
    return 0.5 * (lo + hi)


class CurvedObject(ABC):
    r"""A rigid body bounded by a smooth convex closed curve, with its mass properties (module docstring).

    Subclasses set ``mass`` [kg] and ``inertia`` [kg m²] (about the centre of mass, the origin) and implement
    :meth:`_local_floats`, :attr:`perimeter` and :meth:`_moments`. Instances compare by identity.
    """

    mass: float
    inertia: float

    # ------------------------------------------------------------------ subclass interface
    @property
    @abstractmethod
    def perimeter(self) -> float:
        """Perimeter P [m] (the period of ξ)."""

    @property
    @abstractmethod
    def label(self) -> str:
        """A short description for summaries."""

    @abstractmethod
    def _local_floats(self, xi: float) -> tuple[float, float, float, float, float]:
        r"""``(c_x, c_y, n_x, n_y, κ)`` at ξ [m] (any real) as floats: point [m], unit inward normal, curvature."""

    @abstractmethod
    def _moments(self) -> tuple[float, np.ndarray, float]:
        """(area [m²], centroid [m], polar second moment of area about the origin [m⁴]) of the region."""

    # ------------------------------------------------------------------ evaluation
    def local_floats(self, xi: float) -> tuple[float, float, float, float, float]:
        r"""``(c_x, c_y, n_x, n_y, κ)`` at ξ [m] as floats (hot paths; ``xi`` not validated): the point [m], the
        unit inward normal and the curvature [1/m]; the tangent is :math:`(-n_y, n_x)`."""
        return self._local_floats(float(xi))

    def local(self, xi: float) -> SurfacePoint:
        """The curve at ξ [m] (a finite float)."""
        xi = as_finite_float("xi", xi)
        cx, cy, nx, ny, kappa = self._local_floats(xi)
        return SurfacePoint(xi, np.array([cx, cy]), np.array([nx, ny]), np.array([-ny, nx]), kappa)

    def points(self, xi: ArrayLike) -> np.ndarray:
        """Point(s) c(ξ) [m]: shape (2,) for a scalar ξ, (n, 2) for a 1-D array."""
        xi_arr = as_finite_array("xi", xi)
        if xi_arr.ndim > 1:
            raise InvalidParameterError("xi", xi, "a scalar or a 1-D array of ξ [m]")
        out = np.array([self._local_floats(float(x))[:2] for x in np.atleast_1d(xi_arr)])
        return out[0] if xi_arr.ndim == 0 else out

    def frames(self, xi: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(points (n, 2) [m], inward normals (n, 2), curvatures (n,) [1/m]) at a 1-D array of ξ [m]."""
        xi_arr = as_finite_array("xi", xi)
        if xi_arr.ndim != 1:
            raise InvalidParameterError("xi", xi, "a 1-D array of ξ [m]")
        rows = np.array([self._local_floats(float(x)) for x in xi_arr]).reshape(-1, 5)
        return rows[:, :2], rows[:, 2:4], rows[:, 4]

    @cached_property
    def _table(self) -> tuple[np.ndarray, np.ndarray]:
        xi = np.linspace(0.0, self.perimeter, TABLE_SAMPLES, endpoint=False)
        return xi, self.frames(xi)[0]

    # ------------------------------------------------------------------ projection and distance
    def project_floats(self, px: float, py: float, near: float | None = None) -> tuple[float, float]:
        r"""The foot of point (``px``, ``py``) [m] on the curve: (ξ of the closest boundary point [m], signed
        distance δ [m], positive outside). Floats, not validated.

        With ``near``, ξ is the foot's representative within P/2 of ``near`` and the search starts there (a
        contact followed in time); otherwise it starts at the nearest of the table's samples, in [0, P).

        Finds the root of :math:`g(\xi) = (c(\xi) - p) \cdot t(\xi)` in a bracket where g changes sign
        (:math:`g' = 1 + \kappa \delta > 0` near the curve outside it) by Newton steps kept in the bracket and
        bisection otherwise, to 1e-13 × P. Unique for points outside the curve or inside it closer than the
        radius of curvature; a deeper point gets one of its nearest boundary points.
        """
        period = self.perimeter
        if near is None:
            xi_table, pts = self._table
            start = float(xi_table[int(np.argmin((pts[:, 0] - px) ** 2 + (pts[:, 1] - py) ** 2))])
        else:
            start = float(near)

        def g(x: float) -> tuple[float, float]:
            cx, cy, nx, ny, kappa = self._local_floats(x)
            dx, dy = cx - px, cy - py
            return dx * -ny + dy * nx, 1.0 + kappa * (dx * nx + dy * ny)

        step = period / TABLE_SAMPLES
        lo, hi = start - step, start + step
        while (g(lo)[0] > 0.0 or g(hi)[0] < 0.0) and hi - lo < period:
            lo, hi = lo - step, hi + step
            step *= 2.0
        if hi - lo >= period:  # no sign change near the start (deep inside): bracket one whole turn's minimum
            xi_table, pts = self._table
            start = float(xi_table[int(np.argmin((pts[:, 0] - px) ** 2 + (pts[:, 1] - py) ** 2))])
            lo, hi = start - period / TABLE_SAMPLES, start + period / TABLE_SAMPLES
        xi = bracketed_root(g, lo, hi, start, 1e-13 * period)
        cx, cy, nx, ny, _ = self._local_floats(xi)
        if near is not None and math.hypot(cx - px, cy - py) > 0.25 * self.scale:  # (far: check it is the nearest)
            nearest = self.project_floats(px, py)
            if abs(nearest[1]) < math.hypot(cx - px, cy - py) - 1e-12 * self.scale:
                return near + math.remainder(nearest[0] - near, period), nearest[1]
        if near is not None:
            xi = near + math.remainder(xi - near, period)
        else:
            xi = xi % period
        return xi, (cx - px) * nx + (cy - py) * ny

    def project(self, points: ArrayLike, near: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(ξ [m], signed distance [m], positive outside) of the foot of each point (n, 2) [m] (object frame) on
        the curve (:meth:`project_floats`; ``near`` for all of them)."""
        pts = as_finite_array("points", points, (-1, 2))
        near = None if near is None else as_finite_float("near", near)
        out = np.array([self.project_floats(float(x), float(y), near) for x, y in pts]).reshape(-1, 2)
        return out[:, 0], out[:, 1]

    def contains(self, points: ArrayLike, *, strict: bool = True) -> bool | np.ndarray:
        r"""Whether point(s) [m] (object frame) lie inside: signed distance < -ε (``strict``) or <= ε, with
        :math:`\varepsilon = 10^{-12}` × diameter. A bool for shape (2,), a bool array for (n, 2)."""
        pts = as_finite_array("points", points)
        if pts.ndim not in (1, 2) or pts.shape[-1] != 2:
            raise InvalidParameterError("points", points, "an array of shape (2,) or (n, 2)")
        distance = self.project(pts.reshape(-1, 2))[1]
        eps = 1e-12 * self.scale
        inside = distance < -eps if strict else distance <= eps
        return bool(inside[0]) if pts.ndim == 1 else inside

    # ------------------------------------------------------------------ the face
    @cached_property
    def edges(self) -> tuple["CurveFace", ...]:
        """The contact faces: the whole boundary, one :class:`CurveFace` (index 0)."""
        return (CurveFace(self),)

    def edge(self, k: int | np.integer) -> "CurveFace":
        """Face ``k`` (only 0); raises :class:`UnknownEdgeError` otherwise."""
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k != 0:
            raise UnknownEdgeError(k, 1)
        return self.edges[0]

    # ------------------------------------------------------------------ mass and size
    @cached_property
    def _mass_geometry(self) -> tuple[float, np.ndarray, float]:
        return self._moments()

    @property
    def area(self) -> float:
        """Area A [m²]."""
        return self._mass_geometry[0]

    @property
    def centroid(self) -> np.ndarray:
        """Geometric centroid [m] (not necessarily the centre of mass)."""
        return self._mass_geometry[1].copy()

    def outline(self, n: int = 256) -> np.ndarray:
        """``n`` boundary points (n, 2) [m], evenly spaced in ξ from ξ = 0, clockwise (drawing)."""
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 3:
            raise InvalidParameterError("n", n, "an integer number of points >= 3")
        return self.frames(np.linspace(0.0, self.perimeter, int(n), endpoint=False))[0]

    def outline_in(self, pose: ArrayLike, n: int = 256) -> np.ndarray:
        """:meth:`outline` in the parent frame for the object pose ``(x [m], y [m], β [rad])``."""
        pose = as_finite_array("pose", pose, (3,))
        c, s = math.cos(pose[2]), math.sin(pose[2])
        return self.outline(n) @ np.array([[c, s], [-s, c]]) + pose[:2]

    @cached_property
    def scale(self) -> float:
        """Characteristic size [m]: the diameter (largest distance between two boundary points, from the table)."""
        pts = self._table[1]
        return float(np.max(np.linalg.norm(pts[:, None, :] - pts[None, :, :], axis=-1)))

    @cached_property
    def width(self) -> float:
        """Smallest width [m] between two parallel supporting lines (over the table's normals)."""
        xi, _ = self._table
        pts, normals, _ = self.frames(xi)
        return float(min(np.ptp(pts @ n) for n in normals))

    def to_coal(self, half_thickness: float) -> coal.CollisionGeometry:
        """The object extruded to z in ``[-h, h]`` [m] as a coal shape (object frame): the convex hull of the
        polygon circumscribed to the curve (its tangent lines at ξ spaced so that the gap to the curve stays
        below ``COLLISION_SAGITTA_RTOL`` × diameter): it contains the object, so a collision it misses is none."""
        h = as_positive_float("half_thickness", half_thickness)
        corners = self.circumscribed_polygon()
        points = [np.array([x, y, z]) for x, y in corners for z in (-h, h)]
        try:
            # qhull's defaults, not "Qt": a triangulated top face gives a vertex more neighbours than coal stores
            return coal.Convex.convexHull(points, False, "")
        except RuntimeError as exc:
            raise PolygonError(f"coal cannot build the curve's collision shape ({exc})", vertices=corners,
                               index=None) from None

    def circumscribed_polygon(self, rtol: float = COLLISION_SAGITTA_RTOL) -> np.ndarray:
        r"""Vertices (k, 2) [m], CCW, of a polygon containing the curve whose edges are tangent to it, spaced so
        that each corner is at most ``rtol`` × diameter outside the curve: between tangents whose normals turn
        by Δθ on a radius of curvature ρ the corner stands :math:`\rho(1/\cos(\Delta\theta/2) - 1)` off; where the
        normal turns faster than the samples resolve, tangents are added until each corner is that close to its
        chord (which the curve crosses)."""
        rtol = as_positive_float("rtol", rtol)
        xi = np.linspace(0.0, self.perimeter, 4 * TABLE_SAMPLES, endpoint=False)
        pts, normals, kappa = self.frames(xi)
        theta = np.unwrap(np.arctan2(normals[:, 1], normals[:, 0]))
        rho_max = 1.0 / float(np.min(kappa[kappa > 0.0])) if np.any(kappa > 0.0) else 1e3 * self.scale
        step = 2.0 * math.acos(1.0 / (1.0 + rtol * self.scale / min(rho_max, 1e3 * self.scale)))
        # tangents whose normals turn by at most `step` from one to the next (as far as the samples allow), and
        # each straight part's own line (tangents on either side of one would meet far off it)
        chosen, turned = [0], [*theta.tolist(), float(theta[0]) - 2.0 * math.pi]
        for j in range(1, len(turned)):
            if turned[chosen[-1]] - turned[j] > step:
                chosen.append(j - 1 if j - 1 > chosen[-1] else j)
        flat = np.flatnonzero(kappa == 0.0)
        chosen = sorted((set(chosen) | set(flat[np.diff(flat, prepend=-2) > 1].tolist())) - {theta.size})
        bound, two_pi = rtol * self.scale, 2.0 * math.pi

        def between(a: tuple, b: tuple, depth: int = 0) -> list[tuple]:  # tangents (ξ, θ, point, normal) a to b
            if a[1] - b[1] <= step or depth > 60 or (a[1] - b[1] < math.pi and _chord_gap(a, b) <= bound):
                return []
            x = 0.5 * (a[0] + b[0])
            cx, cy, nx, ny, _ = self._local_floats(x)
            m = (x, a[1] - (a[1] - math.atan2(ny, nx)) % two_pi, np.array([cx, cy]), np.array([nx, ny]))
            return [*between(a, m, depth + 1), m, *between(m, b, depth + 1)]

        tangents = [(float(xi[k]), float(theta[k]), pts[k], normals[k]) for k in chosen]
        tangents.append((tangents[0][0] + self.perimeter, tangents[0][1] - two_pi, *tangents[0][2:]))
        tangents = [t for a, b in zip(tangents, tangents[1:]) for t in (a, *between(a, b))]
        lines = [(n, float(n @ p)) for _, _, p, n in tangents]
        corners = [q for (n1, e1), (n2, e2) in zip(lines, lines[1:] + lines[:1])
                   if (q := _corner(n1, e1, n2, e2)) is not None]
        return np.array(corners[::-1])


def _corner(n1: np.ndarray, e1: float, n2: np.ndarray, e2: float) -> np.ndarray | None:
    """Where the lines n1·x = e1 and n2·x = e2 meet (None for parallel lines)."""
    det = n1[0] * n2[1] - n1[1] * n2[0]
    if abs(det) < 1e-12:
        return None
    return np.array([(e1 * n2[1] - e2 * n1[1]) / det, (n1[0] * e2 - n2[0] * e1) / det])


def _chord_gap(a: tuple, b: tuple) -> float:
    """Height over the chord of the corner of the tangents a and b, (ξ, θ, point, normal), turning by < π."""
    q = _corner(a[3], float(a[3] @ a[2]), b[3], float(b[3] @ b[2]))
    chord = b[2] - a[2]
    length = math.hypot(chord[0], chord[1])
    if q is None or length == 0.0:
        return 0.0
    return abs(chord[0] * (q[1] - a[2][1]) - chord[1] * (q[0] - a[2][0])) / length


class CurveFace:
    r"""A curved object's boundary as one contact face (index 0): ξ is the arc length, unbounded (module
    docstring). The counterpart of :class:`~regrasp.core.polygon.Edge` for code that handles both."""

    index = 0
    #: A curve's face is curved (an edge's is not).
    curved = True

    def __init__(self, curve: CurvedObject):
        self.curve = curve
        self.period = curve.perimeter
        self.xi_range = (-math.inf, math.inf)

    def point(self, xi: ArrayLike) -> np.ndarray:
        """Point(s) c(ξ) [m], object frame: (2,) for a scalar, (n, 2) for a 1-D array."""
        return self.curve.points(xi)

    def local(self, xi: float) -> SurfacePoint:
        """Point, inward normal, tangent and curvature at ξ [m]."""
        return self.curve.local(xi)

    def xi_of(self, points: ArrayLike, near: float | None = None) -> float | np.ndarray:
        """ξ [m] of the foot of point(s) on the curve (:meth:`CurvedObject.project`): a float for one point (2,),
        an array for (n, 2)."""
        pts = as_finite_array("points", points)
        if pts.ndim not in (1, 2) or pts.shape[-1] != 2:
            raise InvalidParameterError("points", points, "an array of shape (2,) or (n, 2)")
        xi = self.curve.project(pts.reshape(-1, 2), near)[0]
        return float(xi[0]) if pts.ndim == 1 else xi

    def contains_xi(self, xi: ArrayLike, tol: float = 0.0) -> bool | np.ndarray:
        """Every finite ξ [m] is on the closed curve (a bool, or a bool array for an array)."""
        as_positive_float("tol", tol, allow_zero=True)
        xi_arr = as_finite_array("xi", xi)
        return True if xi_arr.ndim == 0 else np.ones(xi_arr.shape, dtype=bool)


def uniform_mass_properties(curve: str, moments: tuple[float, np.ndarray, float], scale: float, *,
                            mass: float | None, inertia: float | None, density: float | None,
                            centring_hint: str) -> tuple[float, float]:
    r"""(mass [kg], inertia [kg m²] about the centre of mass) from exactly one of: ``mass`` and ``inertia`` (as
    given), ``density`` ρ [kg/m²] (:math:`m = \rho A`, :math:`I = \rho (J_O - A|G|^2)`), or ``mass`` alone
    (uniform density). With a uniform density the centroid G must be the origin (within 1e-9 × ``scale``),
    else :class:`~regrasp.core.exceptions.CurveError` (with ``centring_hint``: how to move it there)."""
    if density is not None and (mass is not None or inertia is not None):
        raise InvalidParameterError("density", density, "either density alone, or mass (and optionally inertia)")
    if inertia is not None and mass is None:
        raise InvalidParameterError("mass", None, "a mass [kg] together with the inertia (or a density alone)")
    if mass is None and density is None:
        raise InvalidParameterError("mass", None, "mass information: mass and inertia [kg, kg m^2], mass alone "
                                    "(uniform density) or density [kg/m^2]")
    if inertia is not None:
        return as_mass("mass", mass), as_inertia("inertia", inertia)
    area, centroid, polar_origin = moments
    if np.linalg.norm(centroid) > CENTROID_RTOL * scale:
        raise CurveError(f"the {curve}'s centroid is at {centroid.tolist()} m, not at the object frame's origin: "
                         f"with a uniform density the origin must be the centre of mass ({centring_hint})",
                         parameter="centroid", value=centroid.tolist())
    rho = as_positive_float("density", density) if density is not None else as_mass("mass", mass) / area
    return rho * area, as_inertia("inertia", rho * (polar_origin - area * float(centroid @ centroid)))

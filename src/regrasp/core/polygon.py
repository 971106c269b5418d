r"""Convex polygon objects in the plane.

Every quantity here is expressed in the **object frame** :math:`C_o`, whose origin is
the object's centre of mass; lengths are in [m], masses in [kg], inertias in [kg m^2].

Vertices are stored counter-clockwise (CCW). Edge ``k`` joins vertex ``k`` (its
``start``) to vertex ``k + 1 mod n`` (its ``end``). Clockwise input is normalised to
CCW by reversing the order while keeping vertex 0 first,
:math:`(v_0, v_{n-1}, \dots, v_1)`, so **edge indices always refer to the normalised
(CCW) order**.

Edge parametrisation (the paper's surface frame :math:`C_f`, Fig 2.2)
-------------------------------------------------------------------
The x-axis of the surface frame of an edge is its unit **inward normal** :math:`n`;
its y-axis is the **ξ direction** :math:`t = \perp n` (``n`` rotated by +90 degrees).
For a CCW edge with unit direction :math:`d = (v_{k+1} - v_k) / L`, the inward normal is
:math:`n = \perp d` and therefore :math:`t = \perp\perp d = -d`: **ξ grows from the
edge's end towards its start**.

The **origin of ξ** is the foot of the perpendicular dropped from the object-frame
origin (the centre of mass) onto the edge's supporting line,

.. math::

    p_0 = v_k - (v_k \cdot t)\, t, \qquad
    \xi(p) = (p - p_0) \cdot t = p \cdot t, \qquad p(\xi) = p_0 + \xi\, t .

ξ is therefore a signed arc length [m] along the edge's line, zero at the point of the
line closest to the centre of mass. The edge itself is the interval
:math:`[\xi(v_{k+1}), \xi(v_k)]`.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass
from functools import cached_property

import coal
import numpy as np
from numpy.typing import ArrayLike

from .exceptions import InvalidParameterError, PolygonError, UnknownEdgeError
from .planar import cross, perp, transform_points
from .validation import as_finite_array, as_inertia, as_mass, as_positive_float

#: Relative tolerance (times the polygon's diameter) for coincident vertices.
REPEATED_VERTEX_RTOL = 1e-12
#: Threshold on |sin(turning angle)| below which three consecutive vertices are collinear.
COLLINEAR_SIN_TOL = 1e-12
#: Relative tolerance (times the polygon's diameter) on |centroid| for uniform density.
CENTROID_RTOL = 1e-9


def _readonly(arr: np.ndarray) -> np.ndarray:
    arr = np.array(arr, dtype=float)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class Edge:
    r"""One edge of a convex polygon, in the object frame.

    Attributes:
        index: Edge index k (in the polygon's CCW order).
        start: Vertex k [m], object frame.
        end: Vertex k+1 mod n [m], object frame.
        length: Edge length L [m].
        inward_normal: Unit normal pointing into the object (x-axis of :math:`C_f`).
        xi_direction: Unit tangent :math:`t = \perp n` (y-axis of :math:`C_f`); equals
            ``-(end - start) / length``, so ξ grows from ``end`` towards ``start``.
        xi_origin: Point [m] of the edge's line closest to the object-frame origin (ξ = 0).
        xi_range: ``(ξ(end), ξ(start))`` [m], the edge as a sorted ξ interval.
    """

    index: int
    start: np.ndarray
    end: np.ndarray
    length: float
    inward_normal: np.ndarray
    xi_direction: np.ndarray
    xi_origin: np.ndarray
    xi_range: tuple[float, float]

    @classmethod
    def _from_vertices(cls, index: int, start: np.ndarray, end: np.ndarray) -> Edge:
        """Edge ``index`` from ``start`` to ``end`` of a CCW polygon."""
        start = np.asarray(start, dtype=float)
        end = np.asarray(end, dtype=float)
        length = float(np.linalg.norm(end - start))
        direction = (end - start) / length
        normal = perp(direction) + 0.0  # "+ 0.0" turns -0.0 into 0.0 (cosmetic)
        tangent = perp(normal) + 0.0
        origin = start - float(start @ tangent) * tangent + 0.0
        xi_end = float((end - origin) @ tangent)
        xi_start = float((start - origin) @ tangent)
        return cls(
            index=int(index),
            start=_readonly(start),
            end=_readonly(end),
            length=length,
            inward_normal=_readonly(normal),
            xi_direction=_readonly(tangent),
            xi_origin=_readonly(origin),
            xi_range=(xi_end, xi_start),
        )

    def point(self, xi: ArrayLike) -> np.ndarray:
        r"""Point(s) :math:`p_0 + \xi t` [m] in the object frame.

        Args:
            xi: Scalar or 1-D array of ξ [m].

        Returns:
            Shape (2,) for a scalar ``xi``, (n, 2) for an array.
        """
        xi_arr = as_finite_array("xi", xi)
        if xi_arr.ndim > 1:
            raise InvalidParameterError("xi", xi, "a scalar or a 1-D array of ξ [m]")
        return self.xi_origin + xi_arr[..., None] * self.xi_direction

    def xi_of(self, points: ArrayLike) -> float | np.ndarray:
        r"""ξ [m] of point(s) in the object frame, :math:`(p - p_0) \cdot t`.

        Points off the edge's line are projected orthogonally onto it.

        Args:
            points: Shape (2,) or (n, 2) [m], object frame.

        Returns:
            A float for one point, shape (n,) for several.
        """
        pts = as_finite_array("points", points)
        if pts.ndim not in (1, 2) or pts.shape[-1] != 2:
            raise InvalidParameterError("points", points, "an array of shape (2,) or (n, 2)")
        xi = (pts - self.xi_origin) @ self.xi_direction
        return float(xi) if pts.ndim == 1 else xi

    def contains_xi(self, xi: ArrayLike, tol: float = 0.0) -> bool | np.ndarray:
        """Whether ξ [m] lies on the edge: ``xi_range[0] - tol <= xi <= xi_range[1] + tol``.

        Args:
            xi: Scalar or array of ξ [m].
            tol: Non-negative slack [m] added at both ends.

        Returns:
            A bool for a scalar ``xi``, a bool array otherwise.
        """
        tol = as_positive_float("tol", tol, allow_zero=True)
        xi_arr = as_finite_array("xi", xi)
        inside = (xi_arr >= self.xi_range[0] - tol) & (xi_arr <= self.xi_range[1] + tol)
        return bool(inside) if xi_arr.ndim == 0 else inside


def _validated_ccw_vertices(vertices) -> np.ndarray:
    """Check that ``vertices`` describe a strictly convex simple polygon; return them CCW.

    Error messages use vertex indices in the order given. CW input is reversed with
    vertex 0 kept first.
    """
    v = as_finite_array("vertices", vertices, (-1, 2))
    n = v.shape[0]
    if n < 3:
        raise PolygonError(
            f"a polygon needs at least 3 vertices, got {n}", vertices=vertices, index=None
        )

    diffs = v[:, None, :] - v[None, :, :]
    dist = np.linalg.norm(diffs, axis=-1)
    diameter = float(dist.max())
    iu, ju = np.triu_indices(n, k=1)
    repeated = dist[iu, ju] <= REPEATED_VERTEX_RTOL * diameter
    if np.any(repeated):
        i, j = int(iu[repeated][0]), int(ju[repeated][0])
        raise PolygonError(
            f"vertex {j} {v[j].tolist()} repeats vertex {i} {v[i].tolist()}: expected "
            f"distinct vertices (tolerance {REPEATED_VERTEX_RTOL:g} x diameter)",
            vertices=vertices,
            index=j,
        )

    incoming = v - np.roll(v, 1, axis=0)  # edge (k-1 -> k)
    outgoing = np.roll(v, -1, axis=0) - v  # edge (k -> k+1)
    turn_cross = cross(incoming, outgoing)
    turn_dot = np.einsum("ij,ij->i", incoming, outgoing)
    lengths = np.linalg.norm(incoming, axis=1) * np.linalg.norm(outgoing, axis=1)
    sin_turn = turn_cross / lengths
    collinear = np.abs(sin_turn) <= COLLINEAR_SIN_TOL
    if np.any(collinear):
        k = int(np.flatnonzero(collinear)[0])
        raise PolygonError(
            f"vertex {k} {v[k].tolist()} is collinear with its neighbours {(k - 1) % n} and "
            f"{(k + 1) % n}: expected a strictly convex polygon (remove the vertex)",
            vertices=vertices,
            index=k,
        )

    total_turn = float(np.sum(np.arctan2(turn_cross, turn_dot)))
    orientation = 1.0 if total_turn > 0.0 else -1.0
    reflex = np.flatnonzero(np.sign(turn_cross) != orientation)
    if reflex.size:
        k = int(reflex[0])
        raise PolygonError(
            f"polygon is not convex at vertex {k} {v[k].tolist()}: the boundary turns the "
            f"other way there; expected every vertex to turn the same way (strictly convex)",
            vertices=vertices,
            index=k,
        )
    windings = total_turn / (2.0 * np.pi)
    if abs(abs(windings) - 1.0) > 1e-6:
        raise PolygonError(
            f"polygon boundary is self-intersecting: it turns {abs(windings):.6g} times around "
            "(e.g. a star); expected a simple convex polygon that turns exactly once",
            vertices=vertices,
            index=None,
        )
    if orientation < 0.0:
        v = np.concatenate([v[:1], v[:0:-1]], axis=0)
    return v


def _area_centroid_polar(v: np.ndarray) -> tuple[float, np.ndarray, float]:
    r"""Signed area, centroid and polar second moment about the origin of a polygon.

    With :math:`c_i = v_i \times v_{i+1}`:

    .. math::

        A = \tfrac12 \sum c_i, \quad
        G = \frac{1}{6A} \sum c_i (v_i + v_{i+1}), \quad
        J_O = \tfrac{1}{12} \sum c_i \left(|v_i|^2 + v_i \cdot v_{i+1} + |v_{i+1}|^2\right).
    """
    w = np.roll(v, -1, axis=0)
    c = cross(v, w)
    area = 0.5 * float(np.sum(c))
    centroid = (c[:, None] * (v + w)).sum(axis=0) / (6.0 * area)
    polar = float(np.sum(c * (np.einsum("ij,ij->i", v, v) + np.einsum("ij,ij->i", v, w)
                              + np.einsum("ij,ij->i", w, w)))) / 12.0
    return area, centroid, polar


@dataclass(frozen=True, eq=False)
class ConvexPolygon:
    r"""A rigid convex polygon with its mass properties.

    Prefer :meth:`from_vertices` or :meth:`rectangle`; direct construction validates the
    vertices too (and normalises CW input to CCW, keeping vertex 0 first) and requires
    ``mass`` > 0 and either ``inertia`` > 0 or, without it, a uniform density (as
    :meth:`from_vertices` with ``mass`` alone: the centroid must then be the origin).

    Attributes:
        vertices: (n, 2) vertices [m], CCW, object frame (origin = centre of mass).
        mass: Mass m [kg].
        inertia: Moment of inertia I [kg m^2] about the centre of mass, z axis.

    Instances compare by identity (``eq=False``: numpy fields have no boolean ``==``).
    """

    vertices: np.ndarray
    mass: float | None = None
    inertia: float | None = None

    def __post_init__(self) -> None:
        if self.mass is None:
            raise InvalidParameterError("mass", None, "a mass [kg] (and optionally an inertia [kg m^2]; "
                                        "ConvexPolygon.from_vertices also takes a density)")
        if self.inertia is None:
            uniform = ConvexPolygon.from_vertices(self.vertices, mass=self.mass)
            object.__setattr__(self, "inertia", uniform.inertia)
        object.__setattr__(self, "vertices", _readonly(_validated_ccw_vertices(self.vertices)))
        object.__setattr__(self, "mass", as_mass("mass", self.mass))
        object.__setattr__(self, "inertia", as_inertia("inertia", self.inertia))

    # ------------------------------------------------------------------ constructors
    @classmethod
    def from_vertices(
        cls,
        vertices: ArrayLike,
        *,
        mass: float | None = None,
        inertia: float | None = None,
        density: float | None = None,
    ) -> ConvexPolygon:
        r"""Validate ``vertices`` [m] (object frame) and attach mass properties.

        Mass properties, exactly one of:

        * ``mass`` [kg] and ``inertia`` [kg m^2] (about the centre of mass): used as given
          (the object need not be uniform, so the centroid is not checked);
        * ``density`` ρ [kg/m^2] (areal): :math:`m = \rho A`, :math:`I = \rho J_G` with
          :math:`J_G = J_O - A |G|^2` the polar second moment of area about the centroid;
        * ``mass`` alone: uniform density :math:`\rho = m / A`, then as above.

        With a uniform density the centroid G must be the object-frame origin
        (:math:`|G| \le 10^{-9}` × diameter), otherwise :class:`PolygonError`.

        Raises:
            InvalidParameterError: bad shape or non-finite vertices; non-positive mass,
                inertia or density; missing or over-determined mass information.
            PolygonError: fewer than 3, repeated or collinear vertices; non-convex or
                self-intersecting boundary; off-centre centroid with uniform density.
        """
        if density is not None and (mass is not None or inertia is not None):
            raise InvalidParameterError(
                "density", density, "either density alone, or mass (and optionally inertia), not both"
            )
        if inertia is not None and mass is None:
            raise InvalidParameterError(
                "mass", None, "a mass [kg] together with the inertia (or a density [kg/m^2] alone)"
            )
        if mass is None and density is None:
            raise InvalidParameterError(
                "mass",
                None,
                "mass information: mass and inertia [kg, kg m^2], mass alone (uniform "
                "density) or density [kg/m^2]",
            )
        if mass is not None:
            mass = as_mass("mass", mass)
        if inertia is not None:
            inertia = as_inertia("inertia", inertia)
        if density is not None:
            density = as_positive_float("density", density)

        size = float(np.abs(as_finite_array("vertices", vertices)).max(initial=0.0))
        if size > MAX_LENGTH:
            raise InvalidParameterError("vertices", vertices, f"coordinates of at most {MAX_LENGTH:g} m "
                                        f"(this one reaches {size:.3g} m)")
        v = _validated_ccw_vertices(vertices)
        if inertia is not None:
            return cls(vertices=v, mass=mass, inertia=inertia)

        area, centroid, polar_origin = _area_centroid_polar(v)
        diameter = float(np.max(np.linalg.norm(v[:, None, :] - v[None, :, :], axis=-1)))
        if np.linalg.norm(centroid) > CENTROID_RTOL * diameter:
            raise PolygonError(
                f"the polygon's centroid is at {centroid.tolist()} m, not at the object frame's "
                "origin: with a uniform density the origin must be the centre of mass (shift "
                "the vertices by minus the centroid)",
                vertices=vertices,
                index=None,
            )
        rho = density if density is not None else mass / area
        polar_centroid = polar_origin - area * float(centroid @ centroid)
        return cls(vertices=v, mass=rho * area, inertia=rho * polar_centroid)

    @classmethod
    def rectangle(
        cls,
        width: float,
        height: float,
        *,
        mass: float | None = None,
        inertia: float | None = None,
        density: float | None = None,
    ) -> ConvexPolygon:
        """A ``width`` x ``height`` [m] rectangle centred on the object-frame origin.

        Vertices (CCW from the top-right corner): (w/2, h/2), (-w/2, h/2), (-w/2, -h/2),
        (w/2, -h/2). Edge 0 is the top, 1 the left side (inward normal +x, ξ along +y),
        2 the bottom, 3 the right side (inward normal -x, ξ along -y).
        Mass properties as in :meth:`from_vertices`.
        """
        w = as_positive_float("width", width)
        h = as_positive_float("height", height)
        for name, value in (("width", w), ("height", h)):
            if not MIN_LENGTH <= value <= MAX_LENGTH:
                raise InvalidParameterError(name, value, f"a length in [{MIN_LENGTH:g}, {MAX_LENGTH:g}] m")
        if max(w, h) > MAX_ASPECT * min(w, h):  # (the thin side is at fault: the other is a length like any object's)
            thin, other = ("height", "width") if h < w else ("width", "height")
            raise InvalidParameterError(thin, min(w, h), f"at least 1/{MAX_ASPECT:g} of the {other} = "
                                        f"{max(w, h):g} m (a rectangle that thin is a segment)")
        verts = 0.5 * np.array([[w, h], [-w, h], [-w, -h], [w, -h]])
        return cls.from_vertices(verts, mass=mass, inertia=inertia, density=density)

    # ------------------------------------------------------------------ geometry
    @property
    def label(self) -> str:
        """A short description for summaries: ``"4-gon"``."""
        return f"{self.n_vertices}-gon"

    @property
    def n_vertices(self) -> int:
        """Number of vertices (= number of edges)."""
        return int(self.vertices.shape[0])

    @cached_property
    def edges(self) -> tuple[Edge, ...]:
        """All edges, edge k from vertex k to vertex k+1 mod n."""
        v = self.vertices
        n = self.n_vertices
        return tuple(Edge._from_vertices(k, v[k], v[(k + 1) % n]) for k in range(n))

    def edge(self, k: int | np.integer) -> Edge:
        """Edge ``k``; raises :class:`UnknownEdgeError` unless ``k`` is an int in 0..n-1."""
        if isinstance(k, bool) or not isinstance(k, numbers.Integral) or not 0 <= k < self.n_vertices:
            raise UnknownEdgeError(k, self.n_vertices)
        return self.edges[int(k)]

    @cached_property
    def _mass_geometry(self) -> tuple[float, np.ndarray, float]:
        area, centroid, polar = _area_centroid_polar(self.vertices)
        return area, _readonly(centroid), polar

    @property
    def area(self) -> float:
        """Area A [m^2]."""
        return self._mass_geometry[0]

    @property
    def centroid(self) -> np.ndarray:
        """Geometric centroid [m] in the object frame (not necessarily the centre of mass)."""
        return self._mass_geometry[1]

    @property
    def perimeter(self) -> float:
        """Perimeter [m]."""
        return float(sum(e.length for e in self.edges))

    @cached_property
    def scale(self) -> float:
        """Characteristic size [m]: the diameter (largest distance between two vertices)."""
        v = self.vertices
        return float(np.max(np.linalg.norm(v[:, None, :] - v[None, :, :], axis=-1)))

    @cached_property
    def width(self) -> float:
        """Smallest width [m]: the least distance between two parallel lines that enclose the polygon
        (for a convex polygon, attained with one line through an edge)."""
        v = self.vertices
        return float(min(np.ptp(v @ e.inward_normal) for e in self.edges))

    def vertices_in(self, pose: ArrayLike) -> np.ndarray:
        """(n, 2) vertices [m] in the parent frame for the object pose ``(x [m], y [m], beta [rad])``."""
        pose = as_finite_array("pose", pose, (3,))
        return transform_points(pose, self.vertices)

    def contains(self, points: ArrayLike, *, strict: bool = True) -> bool | np.ndarray:
        r"""Whether point(s) [m], object frame, lie inside the polygon.

        A point is inside when its distance :math:`(p - v_k) \cdot n_k` to every edge line
        is > ε (``strict``: open polygon) or >= -ε (closed polygon), with
        :math:`\varepsilon = 10^{-12}` × diameter.

        Returns:
            A bool for one point (shape (2,)), a bool array of shape (n,) otherwise.
        """
        pts = as_finite_array("points", points)
        if pts.ndim not in (1, 2) or pts.shape[-1] != 2:
            raise InvalidParameterError("points", points, "an array of shape (2,) or (n, 2)")
        starts = self.vertices
        normals = np.array([e.inward_normal for e in self.edges])
        dist = np.einsum("...kj,kj->...k", pts[..., None, :] - starts, normals)
        eps = 1e-12 * self.scale
        inside = np.all(dist > eps, axis=-1) if strict else np.all(dist >= -eps, axis=-1)
        return bool(inside) if pts.ndim == 1 else inside

    def to_coal(self, half_thickness: float) -> coal.ConvexBase:
        """The polygon extruded to z in ``[-h, h]`` [m] as a coal convex shape (object frame).

        Built with ``coal.Convex.convexHull`` (qhull option ``"Qt"``); coal returns it as
        a ``coal.ConvexBase``.
        """
        h = as_positive_float("half_thickness", half_thickness)
        points = [np.array([x, y, z]) for x, y in self.vertices for z in (-h, h)]
        try:
            return coal.Convex.convexHull(points, False, "Qt")
        except RuntimeError as exc:  # e.g. "Too many neighbors": coal stores a vertex's neighbours in a byte
            reason = str(exc).strip().splitlines()[-1].removeprefix("message: ")
            raise PolygonError(f"coal cannot build the {self.n_vertices}-gon's collision shape ({reason}); the "
                               "urdf geometry takes polygons of up to 252 vertices (measured with coal 3)",
                               vertices=self.vertices, index=None) from None


__all__ = ["Edge", "ConvexPolygon"]

#: The largest object coordinate or side [m] (a hand's object, not a building).
MAX_LENGTH = 1e3
#: A rectangle's shortest side [m] (a micrometre: a foil, not a sheet of atoms; shorter sides round its area, mass
#: and inertia to nothing).
MIN_LENGTH = 1e-6
#: A rectangle's largest side / smallest side [-].
MAX_ASPECT = 1e6

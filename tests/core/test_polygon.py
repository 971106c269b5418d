"""Tests of regrasp.core.polygon: edges and their ξ parametrisation, mass properties, errors, coal."""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import ConvexHull

from regrasp.core.exceptions import InvalidParameterError, PolygonError, UnknownEdgeError
from regrasp.core.polygon import ConvexPolygon, Edge

W, H = 0.2, 0.1  # rectangle width, height [m]


def random_convex_vertices(seed: int, n_points: int = 12) -> np.ndarray:
    """CCW vertices of the convex hull of seeded random points, centroid shifted to the origin."""
    rng = np.random.default_rng(seed)
    pts = rng.uniform(-1.0, 1.0, size=(n_points, 2)) * rng.uniform(0.05, 2.0, size=2)
    hull = ConvexHull(pts)  # 2-D hull vertices are CCW
    verts = pts[hull.vertices]
    return verts - fan_centroid(verts)


def fan_centroid(verts: np.ndarray) -> np.ndarray:
    """Area-weighted centroid of the triangle fan from vertex 0 (independent of the module)."""
    a, b, c = verts[0], verts[1:-1], verts[2:]
    areas = 0.5 * ((b[:, 0] - a[0]) * (c[:, 1] - a[1]) - (b[:, 1] - a[1]) * (c[:, 0] - a[0]))
    centres = (a + b + c) / 3.0
    return (areas[:, None] * centres).sum(axis=0) / areas.sum()


def regular_polygon(n: int, radius: float, phase: float = 0.3) -> np.ndarray:
    angles = phase + 2.0 * np.pi * np.arange(n) / n
    return radius * np.stack([np.cos(angles), np.sin(angles)], axis=1)


# ---------------------------------------------------------------------- rectangle by hand
RECT_EDGES = {
    # index: (start, end, inward normal, xi direction, xi origin, xi range, length)
    0: ((W / 2, H / 2), (-W / 2, H / 2), (0, -1), (1, 0), (0, H / 2), (-W / 2, W / 2), W),
    1: ((-W / 2, H / 2), (-W / 2, -H / 2), (1, 0), (0, 1), (-W / 2, 0), (-H / 2, H / 2), H),
    2: ((-W / 2, -H / 2), (W / 2, -H / 2), (0, 1), (-1, 0), (0, -H / 2), (-W / 2, W / 2), W),
    3: ((W / 2, -H / 2), (W / 2, H / 2), (-1, 0), (0, -1), (W / 2, 0), (-H / 2, H / 2), H),
}


@pytest.mark.parametrize("k", sorted(RECT_EDGES))
def test_rectangle_edges_by_hand(k):
    start, end, normal, tangent, origin, xi_range, length = RECT_EDGES[k]
    edge = ConvexPolygon.rectangle(W, H, density=1.0).edge(k)
    assert isinstance(edge, Edge) and edge.index == k
    np.testing.assert_allclose(edge.start, start, atol=1e-15)
    np.testing.assert_allclose(edge.end, end, atol=1e-15)
    np.testing.assert_allclose(edge.inward_normal, normal, atol=1e-15)
    np.testing.assert_allclose(edge.xi_direction, tangent, atol=1e-15)
    np.testing.assert_allclose(edge.xi_origin, origin, atol=1e-15)
    np.testing.assert_allclose(edge.xi_range, xi_range, atol=1e-15)
    assert edge.length == pytest.approx(length, rel=1e-15)
    # xi grows from end to start
    assert edge.xi_of(edge.end) == pytest.approx(xi_range[0], abs=1e-15)
    assert edge.xi_of(edge.start) == pytest.approx(xi_range[1], abs=1e-15)


def test_rectangle_basic_properties():
    rect = ConvexPolygon.rectangle(W, H, density=3.0)
    assert rect.n_vertices == 4 and len(rect.edges) == 4
    np.testing.assert_allclose(rect.vertices[0], (W / 2, H / 2))
    assert rect.area == pytest.approx(W * H, rel=1e-14)
    assert rect.perimeter == pytest.approx(2 * (W + H), rel=1e-14)
    assert rect.scale == pytest.approx(np.hypot(W, H), rel=1e-14)
    np.testing.assert_allclose(rect.centroid, 0.0, atol=1e-15)


def test_edge_point_shapes_and_contains_xi():
    edge = ConvexPolygon.rectangle(W, H, density=1.0).edge(1)
    assert edge.point(0.01).shape == (2,)
    np.testing.assert_allclose(edge.point(0.01), (-W / 2, 0.01))
    pts = edge.point(np.array([-0.02, 0.0, 0.03]))
    assert pts.shape == (3, 2)
    np.testing.assert_allclose(pts[:, 0], -W / 2)
    np.testing.assert_allclose(pts[:, 1], [-0.02, 0.0, 0.03])
    # xi_of projects off-line points orthogonally
    assert edge.xi_of([0.3, 0.02]) == pytest.approx(0.02)
    assert edge.contains_xi(H / 2) and edge.contains_xi(-H / 2)
    assert not edge.contains_xi(H / 2 + 1e-9)
    assert edge.contains_xi(H / 2 + 1e-9, tol=1e-8)
    np.testing.assert_array_equal(edge.contains_xi([-1.0, 0.0, 1.0]), [False, True, False])
    with pytest.raises(InvalidParameterError, match="xi"):
        edge.point(np.nan)
    with pytest.raises(InvalidParameterError, match="tol"):
        edge.contains_xi(0.0, tol=-1.0)


# ---------------------------------------------------------------------- random polygons
@settings(derandomize=True, max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n_points=st.integers(3, 30))
def test_random_convex_polygon_edges(seed, n_points):
    verts = random_convex_vertices(seed, n_points)
    poly = ConvexPolygon.from_vertices(verts, density=2.0)
    np.testing.assert_allclose(poly.vertices, verts)
    hull_area = ConvexHull(verts).volume
    assert poly.area == pytest.approx(hull_area, rel=1e-10)
    np.testing.assert_allclose(poly.centroid, 0.0, atol=1e-12 * poly.scale)
    rng = np.random.default_rng(seed)
    for edge in poly.edges:
        n = edge.inward_normal
        assert np.linalg.norm(n) == pytest.approx(1.0)
        assert np.linalg.norm(edge.xi_direction) == pytest.approx(1.0)
        assert n @ edge.xi_direction == pytest.approx(0.0, abs=1e-14)
        # xi direction is n rotated by +90 degrees
        np.testing.assert_allclose(edge.xi_direction, (-n[1], n[0]))
        # inward normal points at the centroid side, and every other vertex is on that side
        assert (poly.centroid - edge.start) @ n > 0.0
        assert np.all((poly.vertices - edge.start) @ n > -1e-12)
        # xi origin: on the line, and the foot of the perpendicular from the origin
        assert (edge.xi_origin - edge.start) @ n == pytest.approx(0.0, abs=1e-12)
        assert edge.xi_origin @ edge.xi_direction == pytest.approx(0.0, abs=1e-12)
        # round trip and end points
        xi = rng.uniform(-2.0, 2.0, size=7)
        np.testing.assert_allclose(edge.xi_of(edge.point(xi)), xi, atol=1e-12)
        assert edge.xi_of(edge.end) == pytest.approx(edge.xi_range[0], abs=1e-12)
        assert edge.xi_of(edge.start) == pytest.approx(edge.xi_range[1], abs=1e-12)
        assert edge.xi_range[1] - edge.xi_range[0] == pytest.approx(edge.length)
        np.testing.assert_allclose(edge.point(edge.xi_range[1]), edge.start, atol=1e-12)
        np.testing.assert_allclose(edge.point(edge.xi_range[0]), edge.end, atol=1e-12)
        mid = 0.5 * (edge.start + edge.end)
        assert poly.contains(mid, strict=False) and not poly.contains(mid, strict=True)
        assert not poly.contains(mid - 1e-6 * poly.scale * n, strict=False)


def test_cw_input_is_normalised_keeping_vertex_zero():
    ccw = random_convex_vertices(seed=7)
    cw = np.concatenate([ccw[:1], ccw[:0:-1]])
    poly_cw = ConvexPolygon.from_vertices(cw, density=1.0)
    poly_ccw = ConvexPolygon.from_vertices(ccw, density=1.0)
    np.testing.assert_array_equal(poly_cw.vertices, ccw)
    np.testing.assert_array_equal(poly_cw.vertices[0], cw[0])
    assert poly_cw.area > 0
    assert poly_cw.inertia == pytest.approx(poly_ccw.inertia, rel=1e-14)


def test_vertices_in_pose_and_contains():
    rect = ConvexPolygon.rectangle(W, H, density=1.0)
    x, y, beta = 0.3, -0.2, 0.7
    c, s = np.cos(beta), np.sin(beta)
    expected = rect.vertices @ np.array([[c, -s], [s, c]]).T + (x, y)
    np.testing.assert_allclose(rect.vertices_in((x, y, beta)), expected)
    inside = rect.contains([[0.0, 0.0], [W / 2, 0.0], [W, 0.0], [0.09, 0.049]])
    np.testing.assert_array_equal(inside, [True, False, False, True])
    np.testing.assert_array_equal(rect.contains(rect.vertices, strict=False), True)
    np.testing.assert_array_equal(rect.contains(rect.vertices, strict=True), False)
    with pytest.raises(InvalidParameterError, match="pose"):
        rect.vertices_in((0.0, 0.0))


# ---------------------------------------------------------------------- mass properties
@pytest.mark.parametrize("w, h, rho", [(W, H, 3.0), (1.0, 1.0, 0.5), (0.03, 2.0, 1200.0)])
def test_rectangle_mass_properties_from_density(w, h, rho):
    rect = ConvexPolygon.rectangle(w, h, density=rho)
    assert rect.mass == pytest.approx(rho * w * h, rel=1e-13)
    assert rect.inertia == pytest.approx(rho * w * h * (w**2 + h**2) / 12.0, rel=1e-13)


@pytest.mark.parametrize("w, h, name, expected", [
    (0.1, 1e-300, "height", r"invalid height = 1e-300: expected a length in \[1e-06, 1000\] m"),  # issue 25
    (1e-300, 0.04, "width", r"invalid width = 1e-300: expected a length in \[1e-06, 1000\] m"),
    (1e-150, 1e-150, "width", "a length in"),  # (its area, mass and inertia round to 0)
    (0.1, 1e308, "height", r"a length in \[1e-06, 1000\] m"),
    (1000.0, 1e-4, "height", r"invalid height = 0.0001: expected at least 1/1e\+06 of the width = 1000 m"),
    (1e-4, 1000.0, "width", r"invalid width = 0.0001: expected at least 1/1e\+06 of the height = 1000 m"),
])
def test_a_rectangle_side_out_of_bounds_is_named(w, h, name, expected):
    """The side at fault is named: the one out of [1e-6, 1000] m, or the thin one of a rectangle too thin."""
    with pytest.raises(InvalidParameterError, match=expected) as info:
        ConvexPolygon.rectangle(w, h, mass=0.08)
    assert info.value.name == name


def test_mass_only_gives_uniform_density_inertia():
    mass = 1.7
    rect = ConvexPolygon.rectangle(W, H, mass=mass)
    assert rect.mass == mass
    assert rect.inertia == pytest.approx(mass * (W**2 + H**2) / 12.0, rel=1e-13)
    verts = random_convex_vertices(seed=3)
    from_mass = ConvexPolygon.from_vertices(verts, mass=mass)
    from_density = ConvexPolygon.from_vertices(verts, density=mass / from_mass.area)
    assert from_density.mass == pytest.approx(mass, rel=1e-13)
    assert from_mass.inertia == pytest.approx(from_density.inertia, rel=1e-13)


def test_explicit_mass_and_inertia_are_kept_even_off_centre():
    verts = regular_polygon(5, 0.1) + (0.5, 0.0)
    poly = ConvexPolygon.from_vertices(verts, mass=2.0, inertia=0.01)
    assert (poly.mass, poly.inertia) == (2.0, 0.01)


@pytest.mark.parametrize("n", [3, 5, 6, 11])
def test_regular_polygon_inertia_vs_grid_and_closed_form(n):
    radius, rho = 0.15, 2.5
    poly = ConvexPolygon.from_vertices(regular_polygon(n, radius), density=rho)
    # closed form: J = n R^4 sin(2 pi / n) (2 + cos(2 pi / n)) / 12
    closed = rho * n * radius**4 * np.sin(2 * np.pi / n) * (2 + np.cos(2 * np.pi / n)) / 12.0
    assert poly.inertia == pytest.approx(closed, rel=1e-12)
    # independent midpoint-grid integration with half-plane tests written here
    m = 1200
    step = 2.0 * radius / m
    g = -radius + step * (np.arange(m) + 0.5)
    gx, gy = np.meshgrid(g, g)
    pts = np.stack([gx.ravel(), gy.ravel()], axis=1)
    verts = regular_polygon(n, radius)
    inside = np.ones(len(pts), dtype=bool)
    for k in range(n):
        a, b = verts[k], verts[(k + 1) % n]
        inside &= (b[0] - a[0]) * (pts[:, 1] - a[1]) - (b[1] - a[1]) * (pts[:, 0] - a[0]) >= 0
    cell = step**2
    area_grid = inside.sum() * cell
    inertia_grid = rho * cell * np.sum(np.einsum("ij,ij->i", pts[inside], pts[inside]))
    assert poly.area == pytest.approx(area_grid, rel=2e-3)
    assert poly.mass == pytest.approx(rho * area_grid, rel=2e-3)
    assert poly.inertia == pytest.approx(inertia_grid, rel=2e-3)


# ---------------------------------------------------------------------- errors
def test_too_few_vertices():
    with pytest.raises(PolygonError, match=r"at least 3 vertices, got 2"):
        ConvexPolygon.from_vertices([[0, 0], [1, 0]], density=1.0)


def test_repeated_vertex_non_consecutive():
    verts = regular_polygon(6, 1.0)
    verts[4] = verts[1]
    with pytest.raises(PolygonError, match=r"vertex 4 .* repeats vertex 1") as info:
        ConvexPolygon.from_vertices(verts, mass=1.0, inertia=1.0)
    assert info.value.index == 4


def test_repeated_vertex_consecutive():
    verts = np.array([[1.0, 0.0], [1.0, 0.0], [0.0, 1.0], [-1.0, -1.0]])
    with pytest.raises(PolygonError, match=r"vertex 1 .* repeats vertex 0"):
        ConvexPolygon.from_vertices(verts, mass=1.0, inertia=1.0)


def test_collinear_vertex_named():
    verts = [[1.0, 1.0], [0.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]]
    with pytest.raises(PolygonError, match=r"vertex 1 .*collinear.* 0 and 2") as info:
        ConvexPolygon.from_vertices(verts, density=1.0)
    assert info.value.index == 1


def test_non_convex_dart():
    dart = [[0.0, 1.0], [-1.0, -1.0], [0.0, -0.2], [1.0, -1.0]]
    with pytest.raises(PolygonError, match=r"not convex at vertex 2") as info:
        ConvexPolygon.from_vertices(dart, mass=1.0, inertia=1.0)
    assert info.value.index == 2
    with pytest.raises(PolygonError, match=r"not convex at vertex 2"):  # CW dart too
        ConvexPolygon.from_vertices(dart[:1] + dart[:0:-1], mass=1.0, inertia=1.0)


def test_self_intersecting_star():
    star = regular_polygon(5, 1.0)[[0, 2, 4, 1, 3]]
    with pytest.raises(PolygonError, match=r"self-intersecting.*turns 2 times"):
        ConvexPolygon.from_vertices(star, mass=1.0, inertia=1.0)


@pytest.mark.parametrize(
    "verts, expected",
    [
        ([[0.0, 0.0], [1.0, np.nan], [0.0, 1.0]], "finite"),
        ([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], r"shape \(nx2\)"),
        ([0.0, 1.0, 2.0], r"shape \(nx2\)"),
        ([["a", "b"], ["c", "d"], ["e", "f"]], "numbers"),
    ],
)
def test_bad_vertex_arrays(verts, expected):
    with pytest.raises(InvalidParameterError, match=expected) as info:
        ConvexPolygon.from_vertices(verts, density=1.0)
    assert info.value.name == "vertices"


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"mass": -1.0}, "mass"),
        ({"mass": 0.0}, "mass"),
        ({"density": -2.0}, "density"),
        ({"mass": 1.0, "inertia": -0.1}, "inertia"),
        ({"mass": 1.0, "inertia": np.nan}, "inertia"),
        ({}, "mass"),
        ({"inertia": 0.1}, "mass"),
        ({"density": 1.0, "mass": 1.0}, "density"),
    ],
)
def test_bad_mass_information(kwargs, name):
    with pytest.raises(InvalidParameterError, match=name) as info:
        ConvexPolygon.rectangle(W, H, **kwargs)
    assert info.value.name == name


def test_missing_mass_message_lists_options():
    with pytest.raises(InvalidParameterError, match=r"mass and inertia.*density"):
        ConvexPolygon.rectangle(W, H)


def test_direct_construction_validates():
    with pytest.raises(InvalidParameterError, match="inertia"):
        ConvexPolygon(vertices=regular_polygon(4, 1.0), mass=1.0, inertia=0.0)
    with pytest.raises(PolygonError, match="collinear"):
        ConvexPolygon(vertices=[[0, 0], [1, 0], [2, 0]], mass=1.0, inertia=1.0)
    with pytest.raises(InvalidParameterError, match="a mass"):
        ConvexPolygon(regular_polygon(4, 1.0))
    with pytest.raises(InvalidParameterError, match="mass"):
        ConvexPolygon(regular_polygon(4, 1.0), mass=-1.0)
    with pytest.raises(PolygonError, match="centroid"):  # mass alone: a uniform density about the origin
        ConvexPolygon(regular_polygon(4, 1.0) + 1.0, mass=1.0)


def test_direct_construction_with_mass_alone_is_uniform_density():
    square = np.array([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]])
    assert ConvexPolygon(square, mass=2.0).inertia == pytest.approx(2.0 / 6.0, rel=1e-14)  # m (w² + h²) / 12
    assert ConvexPolygon(square, mass=2.0, inertia=0.5).inertia == 0.5


@pytest.mark.parametrize("kwargs", [{"density": 1.0}, {"mass": 2.0}])
def test_off_centre_centroid_with_uniform_density(kwargs):
    verts = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]])
    with pytest.raises(PolygonError, match=r"centroid is at \[1\.0, 0\.5\].*origin.*centre of mass"):
        ConvexPolygon.from_vertices(verts, **kwargs)
    # shifted by minus the centroid it is accepted
    ConvexPolygon.from_vertices(verts - (1.0, 0.5), **kwargs)


@pytest.mark.parametrize("k", [-1, 4, 1.5, True, "0", None, np.float64(1.0)])
def test_unknown_edge(k):
    rect = ConvexPolygon.rectangle(W, H, density=1.0)
    with pytest.raises(UnknownEdgeError, match=r"edges 0\.\.3") as info:
        rect.edge(k)
    assert info.value.n_edges == 4 and info.value.edge is k


def test_numpy_integer_edge_index_accepted():
    rect = ConvexPolygon.rectangle(W, H, density=1.0)
    assert rect.edge(np.int64(2)) is rect.edges[2]


def test_polygon_is_frozen():
    rect = ConvexPolygon.rectangle(W, H, density=1.0)
    with pytest.raises(AttributeError):
        rect.mass = 2.0
    with pytest.raises(ValueError):
        rect.vertices[0, 0] = 5.0
    with pytest.raises(ValueError):
        rect.edge(0).inward_normal[0] = 5.0


# ---------------------------------------------------------------------- coal
def _coal_distance(shape_a, pose_a: pin.SE3, shape_b, pose_b: pin.SE3) -> float:
    return coal.distance(shape_a, pose_a, shape_b, pose_b, coal.DistanceRequest(), coal.DistanceResult())


@pytest.mark.parametrize(
    "centre, expected",
    [
        ((0.0, H / 2 + 0.03, 0.0), 0.03 - 0.01),  # above the top edge
        ((-W / 2 - 0.04, 0.01, 0.0), 0.04 - 0.01),  # left of the left edge
        ((W / 2 + 0.03, H / 2 + 0.04, 0.0), 0.05 - 0.01),  # off the top-right corner
        ((0.0, 0.0, 0.05 + 0.02), 0.02 - 0.01),  # above the extrusion's top face
    ],
)
def test_to_coal_rectangle_distance(centre, expected):
    prism = ConvexPolygon.rectangle(W, H, density=1.0).to_coal(0.05)
    assert isinstance(prism, coal.ConvexBase)
    sphere = coal.Sphere(0.01)
    placement = pin.SE3(np.eye(3), np.array(centre))
    assert _coal_distance(prism, pin.SE3.Identity(), sphere, placement) == pytest.approx(expected, abs=1e-8)


def test_to_coal_random_polygon_edge_distances():
    poly = ConvexPolygon.from_vertices(random_convex_vertices(seed=11), density=1.0)
    prism = poly.to_coal(0.02)
    sphere = coal.Sphere(0.005)
    rng = np.random.default_rng(11)
    for edge in poly.edges:
        gap = rng.uniform(0.01, 0.1)
        centre = 0.5 * (edge.start + edge.end) - (gap + 0.005) * edge.inward_normal
        placement = pin.SE3(np.eye(3), np.array([centre[0], centre[1], 0.0]))
        assert _coal_distance(prism, pin.SE3.Identity(), sphere, placement) == pytest.approx(gap, abs=1e-7)


def test_to_coal_rejects_bad_thickness():
    with pytest.raises(InvalidParameterError, match="half_thickness"):
        ConvexPolygon.rectangle(W, H, density=1.0).to_coal(0.0)


def test_width_is_the_least_distance_between_enclosing_parallel_lines():
    assert ConvexPolygon.rectangle(0.1, 0.04, mass=0.08).width == pytest.approx(0.04)
    triangle = ConvexPolygon.from_vertices(np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]) - 1.0 / 3.0, mass=1.0)
    # brute force over directions: the width in direction n is the spread of the vertices along n
    angles = np.linspace(0.0, np.pi, 200001)
    spread = np.ptp(triangle.vertices @ np.c_[np.cos(angles), np.sin(angles)].T, axis=0)
    assert triangle.width == pytest.approx(spread.min(), abs=1e-9) and triangle.width == pytest.approx(np.sqrt(0.5))

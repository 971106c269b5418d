"""Tests of regrasp.core.curves (discs, ellipses, rounded polygons, support-function curves) against independent
references: finite differences, closed forms, dense polylines, brute-force distances, the implicit equations.

Every random draw is seeded; the whole file runs in a few seconds.
"""

from __future__ import annotations

import functools
import math
import re

import coal
import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad
from scipy.optimize import minimize_scalar

from regrasp.core.curves import CurveFace, Disc, Ellipse, RoundedPolygon, SupportCurve, rounded
from regrasp.core.exceptions import CurveError, InvalidParameterError, UnknownEdgeError
from regrasp.core.polygon import ConvexPolygon

# ---------------------------------------------------------------------- the objects
R_DISC = 0.05
A_WIDE, B_WIDE = 0.08, 0.03  # an ellipse wider than tall (b < a)
A_TALL, B_TALL = 0.02, 0.06  # and one taller than wide
W, H, R_RECT = 0.2, 0.1, 0.01  # rounded rectangle
RECT = 0.5 * np.array([[W, H], [-W, H], [-W, -H], [W, -H]])
PENTAGON = np.array([[0.06, -0.02], [0.05, 0.04], [-0.01, 0.06], [-0.07, 0.01], [-0.03, -0.05]])  # CCW, no symmetry
R_PENTAGON = 0.008
SUPPORT_COS, SUPPORT_SIN = [0.05, 0.0, 0.004, 0.002, 0.0005], [0.0, 0.003, -0.001, 0.0004]
OFF_COS, OFF_SIN = [0.04, 0.01, 0.003, 0.0, 0.001], [-0.005, 0.0, 0.0008, 0.0]  # not centred: mass and inertia given
MASS = 0.3

NAMES = ["disc", "ellipse_wide", "ellipse_tall", "rounded_rect", "rounded_pentagon", "support", "support_off"]


@functools.cache
def curve(name: str):
    return {
        "disc": lambda: Disc(R_DISC, mass=MASS),
        "ellipse_wide": lambda: Ellipse(A_WIDE, B_WIDE, mass=MASS),
        "ellipse_tall": lambda: Ellipse(A_TALL, B_TALL, mass=MASS),
        "rounded_rect": lambda: RoundedPolygon(RECT, R_RECT, mass=MASS),
        "rounded_pentagon": lambda: RoundedPolygon(PENTAGON, R_PENTAGON, mass=MASS, inertia=2e-4),
        "support": lambda: SupportCurve.centred(SUPPORT_COS, SUPPORT_SIN, mass=MASS),
        "support_off": lambda: SupportCurve(OFF_COS, OFF_SIN, mass=MASS, inertia=1e-4),
    }[name]()


@functools.cache
def dense(name: str, n: int = 16000):
    """(ξ, points, normals, curvatures) at n ξ evenly spaced over [0, P)."""
    c = curve(name)
    xi = np.linspace(0.0, c.perimeter, n, endpoint=False)
    return (xi, *c.frames(xi))


def point(c, xi: float) -> np.ndarray:
    return np.array(c.local_floats(xi)[:2])


def normal(c, xi: float) -> np.ndarray:
    return np.array(c.local_floats(xi)[2:4])


def tangent(c, xi: float) -> np.ndarray:
    nx, ny = c.local_floats(xi)[2:4]
    return np.array([-ny, nx])


def fd5(f, x: float, h: float) -> np.ndarray:
    """5-point central difference of f at x."""
    return (f(x - 2.0 * h) - 8.0 * f(x - h) + 8.0 * f(x + h) - f(x + 2.0 * h)) / (12.0 * h)


def smooth_xis(c, rng: np.random.Generator, n: int, margin: float) -> np.ndarray:
    """ξ (over several periods) whose ±margin neighbourhood stays on one smooth piece of the curve."""
    period = c.perimeter
    if isinstance(c, RoundedPolygon):
        pieces = c.piece_ranges()
        xi = np.concatenate([rng.uniform(a + margin, b - margin, max(n // len(pieces), 2)) for _, _, a, b in pieces])
        return xi + period * rng.integers(-2, 3, xi.size)
    return rng.uniform(-2.0 * period, 3.0 * period, n)


def polyline_moments(pts: np.ndarray) -> tuple[float, np.ndarray, float]:
    """(area, centroid, polar second moment about the origin) of the polygon with these vertices (either sense):
    the shoelace formulas."""
    x, y = pts[:, 0], pts[:, 1]
    x1, y1 = np.roll(x, -1), np.roll(y, -1)
    cross = x * y1 - x1 * y
    area = 0.5 * cross.sum()
    centroid = np.array([((x + x1) * cross).sum(), ((y + y1) * cross).sum()]) / (6.0 * area)
    polar = (cross * (x * x + x * x1 + x1 * x1 + y * y + y * y1 + y1 * y1)).sum() / 12.0
    sign = math.copysign(1.0, area)
    return sign * area, centroid, sign * polar


def richardson_moments(name: str) -> tuple[float, np.ndarray, float]:
    """polyline_moments of the inscribed polyline with n and 2n points, extrapolated (the error goes as 1/n²)."""
    coarse = polyline_moments(dense(name, 8000)[1])
    fine = polyline_moments(dense(name, 16000)[1])
    return tuple((4.0 * f - c) / 3.0 for c, f in zip(coarse, fine))


def support_series(cosines, sines, theta: float) -> tuple[float, float, float]:
    """(h, h', h'') of the support function, evaluated here from the coefficients."""
    h = dh = ddh = 0.0
    for k, a in enumerate(cosines):
        b = 0.0 if k == 0 else sines[k - 1]
        c, s = math.cos(k * theta), math.sin(k * theta)
        h += a * c + b * s
        dh += k * (b * c - a * s)
        ddh -= k * k * (a * c + b * s)
    return h, dh, ddh


def exterior_angles(vertices: np.ndarray) -> np.ndarray:
    """The turning angle at each vertex of a CCW polygon."""
    d = np.roll(vertices, -1, axis=0) - vertices
    d_prev = np.roll(d, 1, axis=0)
    return np.arctan2(d_prev[:, 0] * d[:, 1] - d_prev[:, 1] * d[:, 0], (d_prev * d).sum(axis=1))


def largest_corner_radius(vertices: np.ndarray) -> float:
    """min over edges k of L_k / (cot(α_k / 2) + cot(α_{k+1} / 2)), α the interior angles (edge k: vertex k to k+1)."""
    lengths = np.linalg.norm(np.roll(vertices, -1, axis=0) - vertices, axis=1)
    cot_half = 1.0 / np.tan(0.5 * (math.pi - exterior_angles(vertices)))
    return float(np.min(lengths / (cot_half + np.roll(cot_half, -1))))


def fan_centroid(vertices: np.ndarray) -> np.ndarray:
    a, b, c = vertices[0], vertices[1:-1], vertices[2:]
    areas = 0.5 * ((b[:, 0] - a[0]) * (c[:, 1] - a[1]) - (b[:, 1] - a[1]) * (c[:, 0] - a[0]))
    return (areas[:, None] * (a + b + c) / 3.0).sum(axis=0) / areas.sum()


def curve_distance(c, q: np.ndarray, name: str) -> float:
    """Distance from q to the curve: nearest dense sample, refined by a bounded 1-D minimisation (not c.project)."""
    xi, pts, _, _ = dense(name)
    qx, qy = float(q[0]), float(q[1])
    j = int(np.argmin((pts[:, 0] - qx) ** 2 + (pts[:, 1] - qy) ** 2))
    ds = xi[1] - xi[0]

    def dist(x: float) -> float:
        cx, cy = c.local_floats(x)[:2]
        return math.hypot(cx - qx, cy - qy)

    res = minimize_scalar(dist, bounds=(xi[j] - 2 * ds, xi[j] + 2 * ds), method="bounded", options={"xatol": 1e-14})
    return min(float(res.fun), dist(xi[j]))


def inside_ccw(corners: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Signed distance of pts inside the CCW convex polygon `corners` (min over its edges, positive inside)."""
    d = np.roll(corners, -1, axis=0) - corners
    d = d / np.linalg.norm(d, axis=1)[:, None]
    out = np.full(len(pts), np.inf)
    for start in range(0, len(corners), 64):
        a, u = corners[start:start + 64], d[start:start + 64]
        rel_x, rel_y = pts[:, 0, None] - a[None, :, 0], pts[:, 1, None] - a[None, :, 1]
        out = np.minimum(out, np.min(u[None, :, 0] * rel_y - u[None, :, 1] * rel_x, axis=1))
    return out


# ---------------------------------------------------------------------- 1. arc length and the frame
@pytest.mark.parametrize("name", NAMES)
def test_frenet_frame_by_finite_differences(name):
    c = curve(name)
    h = 1e-4 * c.scale
    rng = np.random.default_rng(1)
    worst = 0.0
    for xi in smooth_xis(c, rng, 40, 3.0 * h):
        cx, cy, nx, ny, kappa = c.local_floats(xi)
        n, t = np.array([nx, ny]), np.array([-ny, nx])
        assert abs(math.hypot(nx, ny) - 1.0) <= 4e-16
        assert kappa >= 0.0
        worst = max(worst,
                    np.max(np.abs(fd5(lambda x: point(c, x), xi, h) - t)),  # c' = t
                    np.max(np.abs(fd5(lambda x: tangent(c, x), xi, h) - kappa * n)),  # t' = κ n
                    np.max(np.abs(fd5(lambda x: normal(c, x), xi, h) + kappa * t)))  # n' = -κ t
    assert worst <= 1e-7


@pytest.mark.parametrize("name", NAMES)
def test_periodic_in_the_perimeter(name):
    c = curve(name)
    period, size = c.perimeter, c.scale
    rng = np.random.default_rng(2)
    for xi in rng.uniform(-period, period, 20):
        ref = np.array(c.local_floats(xi))
        for k in (-3, -1, 1, 4):
            other = np.array(c.local_floats(xi + k * period))
            np.testing.assert_allclose(other[:2], ref[:2], rtol=0, atol=1e-12 * size)
            np.testing.assert_allclose(other[2:4], ref[2:4], rtol=0, atol=1e-12)
            assert other[4] == pytest.approx(ref[4], rel=1e-11, abs=1e-12 / size)


@pytest.mark.parametrize("name", ["disc", "ellipse_wide", "ellipse_tall", "support", "support_off"])
def test_xi_zero_at_the_top_clockwise(name):
    c = curve(name)
    cx, cy, nx, ny, _ = c.local_floats(0.0)
    np.testing.assert_allclose([nx, ny], [0.0, -1.0], atol=1e-15)
    pts = dense(name)[1]
    assert cy >= pts[:, 1].max() - 1e-15  # the topmost point
    assert point(c, 1e-3 * c.perimeter)[0] > cx  # clockwise: rightwards from the top
    if isinstance(c, SupportCurve):  # x(π/2) = h u + h' u⊥ with u = (0, 1), u⊥ = (-1, 0)
        h, dh, _ = support_series(c.cosines, c.sines[1:], 0.5 * math.pi)
        np.testing.assert_allclose([cx, cy], [-dh, h], atol=1e-15)
    elif isinstance(c, Ellipse):
        np.testing.assert_allclose([cx, cy], [0.0, c.b], atol=1e-15)
        np.testing.assert_allclose(point(c, 0.25 * c.perimeter), [c.a, 0.0], atol=1e-15)  # a quarter turn on
        np.testing.assert_allclose(point(c, 0.5 * c.perimeter), [0.0, -c.b], atol=1e-15)
    else:
        np.testing.assert_allclose([cx, cy], [0.0, R_DISC], atol=1e-15)
        np.testing.assert_allclose(point(c, 0.25 * c.perimeter), [R_DISC, 0.0], atol=1e-15)


@pytest.mark.parametrize("name, vertices", [("rounded_rect", RECT), ("rounded_pentagon", PENTAGON)])
def test_rounded_polygon_xi_is_the_polygon_edge_xi_and_pieces_sit_on_the_polygon(name, vertices):
    c = curve(name)
    polygon = ConvexPolygon.from_vertices(vertices, mass=1.0, inertia=1.0)
    edge0 = polygon.edge(0)
    pieces = c.piece_ranges()
    n = polygon.n_vertices
    assert [(kind, k) for kind, k, _, _ in pieces] == [
        (kind, k) for k in [0, *range(n - 1, 0, -1)] for kind in ("edge", "arc")]
    assert pieces[-1][3] - pieces[0][2] == pytest.approx(c.perimeter, rel=1e-15)
    for (_, _, _, end), (_, _, start, _) in zip(pieces, pieces[1:]):
        assert end == start
    rng = np.random.default_rng(3)
    for kind, k, a, b in pieces:
        for xi in rng.uniform(a, b, 8):
            p, nrm = point(c, xi), normal(c, xi)
            assert c.piece(xi) == (kind, k)
            if kind == "edge":
                e = polygon.edge(k)
                np.testing.assert_allclose(nrm, e.inward_normal, atol=1e-15)
                assert float((p - e.start) @ e.inward_normal) == pytest.approx(0.0, abs=1e-15)  # on edge k's line
                assert e.contains_xi(e.xi_of(p))
                if k == 0:  # the polygon's own edge-0 ξ
                    assert edge0.xi_of(p) == pytest.approx(xi, abs=1e-15)
            else:  # arc about a point at distance r from edge lines k-1 and k
                centre = p + c.radius * nrm
                for e in (polygon.edge(k - 1 if k else n - 1), polygon.edge(k)):
                    assert float((centre - e.start) @ e.inward_normal) == pytest.approx(c.radius, abs=1e-15)
    # edge 0's ξ = 0 is the foot of the perpendicular from the origin, as on the polygon
    a0, b0 = pieces[0][2], pieces[0][3]
    if a0 < 0.0 < b0:
        np.testing.assert_allclose(point(c, 0.0), edge0.xi_origin, atol=1e-15)


@pytest.mark.parametrize("name", ["rounded_rect", "rounded_pentagon"])
def test_pieces_between_tile_any_interval_with_the_pieces_piece_reports(name):
    """Over several turns round the boundary (ξ unbounded, negative too): the clipped pieces tile [lo, hi] without
    gaps, and each one's middle is on the piece that ``piece`` names."""
    c, rng = curve(name), np.random.default_rng(5)
    for _ in range(20):
        lo = float(rng.uniform(-2.0, 2.0) * c.perimeter)
        hi = lo + float(rng.uniform(0.0, 3.0) * c.perimeter)
        pieces = c.pieces_between(lo, hi)
        assert pieces[0][2] == lo and pieces[-1][3] == hi
        for (_, _, _, end), (_, _, start, _) in zip(pieces, pieces[1:]):
            assert end == pytest.approx(start, abs=1e-15)
        for kind, k, a, b in pieces:
            assert a <= b and c.piece(0.5 * (a + b)) == (kind, k)
    with pytest.raises(InvalidParameterError, match="lo <= hi"):
        c.pieces_between(0.1, 0.0)


# ---------------------------------------------------------------------- 2. perimeter
def closed_form_perimeter(name: str) -> float:
    if name == "disc":
        return 2.0 * math.pi * R_DISC
    if name.startswith("ellipse"):
        a, b = (A_WIDE, B_WIDE) if name == "ellipse_wide" else (A_TALL, B_TALL)
        return quad(lambda u: math.hypot(a * math.sin(u), b * math.cos(u)), 0.0, 2.0 * math.pi,
                    epsabs=0.0, epsrel=1e-13, limit=200)[0]
    if name == "rounded_rect":
        return 2.0 * (W + H) - 8.0 * R_RECT + 2.0 * math.pi * R_RECT
    if name == "rounded_pentagon":  # each corner cuts 2 r tan(φ/2) and adds the arc r φ
        turn = exterior_angles(PENTAGON)
        lengths = np.linalg.norm(np.roll(PENTAGON, -1, axis=0) - PENTAGON, axis=1)
        return float(lengths.sum() - 2.0 * R_PENTAGON * np.tan(0.5 * turn).sum() + 2.0 * math.pi * R_PENTAGON)
    cosines = SUPPORT_COS if name == "support" else OFF_COS
    return 2.0 * math.pi * cosines[0]  # Cauchy: P = ∫ h dθ


@pytest.mark.parametrize("name", NAMES)
def test_perimeter(name):
    c = curve(name)
    expected = closed_form_perimeter(name)
    assert c.perimeter == pytest.approx(expected, rel=1e-13)
    chords = [float(np.linalg.norm(np.diff(dense(name, n)[1], axis=0, append=dense(name, n)[1][:1]), axis=1).sum())
              for n in (8000, 16000)]
    errors = [abs(s - c.perimeter) for s in chords]
    assert errors[1] < errors[0] and all(s < c.perimeter for s in chords)  # inscribed: shorter, converging
    assert (4.0 * chords[1] - chords[0]) / 3.0 == pytest.approx(expected, rel=1e-9)
    assert c.edge(0).period == c.perimeter


# ---------------------------------------------------------------------- 3. mass properties
def closed_form_area(name: str) -> float | None:
    if name == "disc":
        return math.pi * R_DISC ** 2
    if name == "ellipse_wide":
        return math.pi * A_WIDE * B_WIDE
    if name == "ellipse_tall":
        return math.pi * A_TALL * B_TALL
    if name == "rounded_rect":
        return W * H - (4.0 - math.pi) * R_RECT ** 2
    if name == "rounded_pentagon":  # each corner loses its kite r² tan(φ/2) less the sector r² φ / 2
        poly = ConvexPolygon.from_vertices(PENTAGON, mass=1.0, inertia=1.0)
        return poly.area - R_PENTAGON ** 2 * (np.tan(0.5 * exterior_angles(PENTAGON)).sum() - math.pi)
    cosines, sines = (SUPPORT_COS, SUPPORT_SIN) if name == "support" else (OFF_COS, OFF_SIN)
    # A = ½∫(h² - h'²) dθ = π a_0² + (π/2) Σ_k (1 - k²)(a_k² + b_k²)
    return math.pi * cosines[0] ** 2 + 0.5 * math.pi * sum(
        (1 - k * k) * (cosines[k] ** 2 + sines[k - 1] ** 2) for k in range(1, len(cosines)))


def closed_form_inertia(name: str) -> float | None:
    if name == "disc":
        return 0.5 * MASS * R_DISC ** 2
    if name.startswith("ellipse"):
        a, b = (A_WIDE, B_WIDE) if name == "ellipse_wide" else (A_TALL, B_TALL)
        return 0.25 * MASS * (a * a + b * b)
    if name == "rounded_rect":  # a cross of two rectangles and four quarter discs
        r = R_RECT
        core = W * (H - 2 * r)
        polar = core * (W ** 2 + (H - 2 * r) ** 2) / 12.0
        strip = (W - 2 * r) * r
        polar += 2.0 * (strip * ((W - 2 * r) ** 2 + r ** 2) / 12.0 + strip * (0.5 * (H - r)) ** 2)
        cx, cy = 0.5 * W - r, 0.5 * H - r
        quarter = 0.25 * math.pi * r * r
        polar += 4.0 * (math.pi * r ** 4 / 8.0 + 2.0 * quarter * 4.0 * r / (3.0 * math.pi) * (cx + cy)
                        + quarter * (cx * cx + cy * cy))
        return MASS / closed_form_area(name) * polar
    return None


@pytest.mark.parametrize("name", NAMES)
def test_mass_properties(name):
    c = curve(name)
    area, centroid, polar = richardson_moments(name)
    exact_area = closed_form_area(name)
    assert c.area == pytest.approx(exact_area, rel=1e-13)
    assert area == pytest.approx(exact_area, rel=1e-9)
    np.testing.assert_allclose(c.centroid, centroid, rtol=0, atol=1e-9 * c.scale)
    if name not in ("rounded_pentagon", "support_off"):  # uniform density: centroid at the origin
        np.testing.assert_allclose(c.centroid, 0.0, atol=1e-15)
        assert c.mass == pytest.approx(MASS, rel=1e-15)
        inertia = MASS / area * (polar - area * float(centroid @ centroid))
        assert c.inertia == pytest.approx(inertia, rel=1e-9)
    exact_inertia = closed_form_inertia(name)
    if exact_inertia is not None:
        assert c.inertia == pytest.approx(exact_inertia, rel=1e-13)


def test_polyline_moments_converge_as_the_outline_refines():
    """The reference itself: the inscribed polyline's area error falls as 1/n² (to the ellipse's πab)."""
    errors = [abs(polyline_moments(dense("ellipse_wide", n)[1])[0] - math.pi * A_WIDE * B_WIDE) for n in
              (2000, 4000, 8000, 16000)]
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    np.testing.assert_allclose(ratios, 4.0, rtol=0.01)


def test_explicit_mass_and_inertia_skip_the_centroid_check():
    c = curve("rounded_pentagon")
    assert c.mass == MASS and c.inertia == 2e-4
    assert np.linalg.norm(c.centroid) > 1e-3  # off-centre, accepted


@pytest.mark.parametrize("name", ["rounded_pentagon", "support_off"])
def test_inertia_of_a_non_symmetric_shape_centred(name):
    """Shift the non-symmetric shape so that its centroid is the origin (a wrong centroid would make the uniform
    density raise) and compare its inertia with the polyline's."""
    c = curve(name)
    density = 700.0
    if name == "rounded_pentagon":
        centred = RoundedPolygon(PENTAGON - c.centroid, R_PENTAGON, density=density)
    else:
        centred = SupportCurve.centred(OFF_COS, OFF_SIN, density=density)
    pts = centred.outline(16000)
    area, centroid, polar = polyline_moments(pts)
    coarse = polyline_moments(centred.outline(8000))
    area, polar = (4 * area - coarse[0]) / 3, (4 * polar - coarse[2]) / 3
    np.testing.assert_allclose(centroid, 0.0, atol=1e-9 * c.scale)
    assert centred.mass == pytest.approx(density * area, rel=1e-9)
    assert centred.inertia == pytest.approx(density * polar, rel=1e-9)
    assert centred.area == pytest.approx(c.area, rel=1e-12)


# ---------------------------------------------------------------------- 4. curvature
@pytest.mark.parametrize("name", ["ellipse_wide", "ellipse_tall"])
def test_ellipse_curvature(name):
    c = curve(name)
    a, b = c.a, c.b
    assert c.local_floats(0.25 * c.perimeter)[4] == pytest.approx(a / b ** 2, rel=1e-12)  # at (a, 0)
    assert c.local_floats(0.0)[4] == pytest.approx(b / a ** 2, rel=1e-12)  # at (0, b)
    _, pts, _, kappa = dense(name, 8000)
    x, y = pts[:, 0], pts[:, 1]
    np.testing.assert_allclose(x ** 2 / a ** 2 + y ** 2 / b ** 2, 1.0, atol=1e-14)  # on the ellipse
    np.testing.assert_allclose(kappa, 1.0 / (a * a * b * b * (x * x / a ** 4 + y * y / b ** 4) ** 1.5), rtol=1e-12)


def test_disc_and_rounded_polygon_curvature():
    assert np.all(dense("disc", 8000)[3] == 1.0 / R_DISC)
    for name, r in (("rounded_rect", R_RECT), ("rounded_pentagon", R_PENTAGON)):
        c = curve(name)
        for kind, _, a, b in c.piece_ranges():
            kappa = c.frames(np.linspace(a, b, 7)[1:-1])[2]
            assert np.all(kappa == (0.0 if kind == "edge" else 1.0 / r))


@pytest.mark.parametrize("name", ["support", "support_off"])
def test_support_curve_against_its_series(name):
    """Point and curvature against h u + h' u⊥ and 1 / (h + h'') at the normal's angle, evaluated here."""
    c = curve(name)
    cosines, sines = c.cosines, c.sines[1:]
    _, pts, normals, kappa = dense(name, 4000)
    for p, n, k in zip(pts[::10], normals[::10], kappa[::10]):
        theta = math.atan2(-n[1], -n[0])
        h, dh, ddh = support_series(cosines, sines, theta)
        np.testing.assert_allclose(p, [h * math.cos(theta) - dh * math.sin(theta),
                                       h * math.sin(theta) + dh * math.cos(theta)], atol=1e-15)
        assert k == pytest.approx(1.0 / (h + ddh), rel=1e-12)


@pytest.mark.parametrize("name", NAMES)
def test_curvature_of_the_osculating_circle(name):
    """κ against the circle through c(ξ - h), c(ξ), c(ξ + h) (2 |cross| / product of the sides), extrapolated from
    h and 2h (its error goes as h²)."""
    c = curve(name)
    h = 3e-4 * c.scale

    def circle(xi: float, step: float) -> float:
        p = point(c, xi)
        u, v = point(c, xi - step) - p, point(c, xi + step) - p
        return 2.0 * abs(u[0] * v[1] - u[1] * v[0]) / (np.linalg.norm(u) * np.linalg.norm(v) * np.linalg.norm(u - v))

    worst = 0.0
    for xi in smooth_xis(c, np.random.default_rng(4), 30, 3.0 * h):
        kappa = c.local_floats(xi)[4]
        estimate = (4.0 * circle(xi, h) - circle(xi, 2.0 * h)) / 3.0
        worst = max(worst, abs(estimate - kappa) / max(kappa, 1.0 / c.scale))
    assert worst <= 1e-7


# ---------------------------------------------------------------------- 5. projection and containment
def rolling_radius(name: str) -> float:
    """1 / max κ: a disc of this radius rolls inside (Blaschke), so a point that deep on a normal projects back."""
    return 1.0 / float(dense(name)[3].max())


@pytest.mark.parametrize("name", NAMES)
def test_projection_recovers_xi_and_offset(name):
    c = curve(name)
    period, size = c.perimeter, c.scale
    rng = np.random.default_rng(5)
    xi_dense, pts_dense, _, _ = dense(name)
    ds = xi_dense[1]
    worst_xi = worst_delta = 0.0
    for _ in range(40):
        xi = rng.uniform(-3.0 * period, 3.0 * period)
        delta = rng.uniform(-0.3 * rolling_radius(name), 0.005)
        cx, cy, nx, ny, _ = c.local_floats(xi)
        p = np.array([cx - delta * nx, cy - delta * ny])
        xi_p, delta_p = c.project_floats(*p)
        assert 0.0 <= xi_p < period
        worst_xi = max(worst_xi, abs(math.remainder(xi_p - xi, period)) / period)
        worst_delta = max(worst_delta, abs(delta_p - delta) / size)
        near = xi + rng.uniform(-0.02, 0.02) * period + period * rng.integers(-2, 3)
        xi_n, delta_n = c.project_floats(*p, near=near)
        assert abs(xi_n - near) <= 0.5 * period
        worst_xi = max(worst_xi, abs(math.remainder(xi_n - xi, period)) / period)
        worst_delta = max(worst_delta, abs(delta_n - delta) / size)
        # brute force over the dense sample: its closest point is within its resolution
        dist = np.linalg.norm(pts_dense - p, axis=1)
        j = int(np.argmin(dist))
        assert -1e-15 <= dist[j] - abs(delta) <= 0.5 * ds
        assert abs(math.remainder(xi_dense[j] - xi, period)) <= 2.0 * ds
        assert c.contains(p) == (delta < 0.0)
    assert worst_xi <= 1e-12 and worst_delta <= 1e-12


@pytest.mark.parametrize("name", NAMES)
def test_projection_on_the_curve_is_exact_to_rounding(name):
    """A point on the curve projects to its own ξ to rounding (the root finder stops on converged Newton steps)."""
    c = curve(name)
    period = c.perimeter
    worst = 0.0
    for xi in np.random.default_rng(6).uniform(0.0, period, 30):
        for delta in (0.0, 1e-3, -0.1 * rolling_radius(name)):
            cx, cy, nx, ny, _ = c.local_floats(xi)
            worst = max(worst, abs(math.remainder(c.project_floats(cx - delta * nx, cy - delta * ny)[0] - xi,
                                                  period)) / period)
    assert worst <= 1e-14


@settings(derandomize=True, database=None, max_examples=30, deadline=None)
@given(name=st.sampled_from(NAMES), fraction=st.floats(-2.0, 2.0), depth=st.floats(-0.3, 1.0),
       turns=st.integers(-3, 3), lag=st.floats(-0.01, 0.01))
def test_projection_property(name, fraction, depth, turns, lag):
    c = curve(name)
    period = c.perimeter
    xi = fraction * period
    delta = depth * (rolling_radius(name) if depth < 0.0 else 0.005)
    cx, cy, nx, ny, _ = c.local_floats(xi)
    px, py = cx - delta * nx, cy - delta * ny
    near = xi + turns * period + lag * period
    xi_n, delta_n = c.project_floats(px, py, near=near)
    assert abs(xi_n - near) <= 0.5 * period
    assert abs(xi_n - (xi + turns * period)) <= 1e-12 * period
    assert delta_n == pytest.approx(delta, abs=1e-12 * c.scale)
    xi_v, delta_v = c.project([[px, py]], near=near)
    assert xi_v[0] == xi_n and delta_v[0] == delta_n


@pytest.mark.parametrize("name", NAMES)
def test_contains_against_the_implicit_equation_and_a_dense_polygon(name):
    c = curve(name)
    rng = np.random.default_rng(7)
    pts = rng.uniform(-0.6, 0.6, (150, 2)) * c.scale
    inside = c.contains(pts)
    inside_closed = c.contains(pts, strict=False)
    assert inside.dtype == bool and inside.shape == (150,)
    _, delta = c.project(pts)
    clear = np.abs(delta) > 1e-9 * c.scale
    assert clear.sum() >= 140
    np.testing.assert_array_equal(inside[clear], delta[clear] < 0.0)
    np.testing.assert_array_equal(inside_closed[clear], inside[clear])
    # the dense inscribed polygon (CCW): a point inside it is inside the curve; one outside it is within its sagitta
    polygon = dense(name)[1][::-1]
    depth = inside_ccw(polygon, pts)
    np.testing.assert_array_equal(inside[np.abs(depth) > 1e-8], depth[np.abs(depth) > 1e-8] > 0.0)
    if name == "disc":
        np.testing.assert_array_equal(inside, np.hypot(pts[:, 0], pts[:, 1]) < R_DISC)
    elif name.startswith("ellipse"):
        np.testing.assert_array_equal(inside, (pts[:, 0] / c.a) ** 2 + (pts[:, 1] / c.b) ** 2 < 1.0)
    boundary = c.points(np.array([0.1, 1.3]) * c.perimeter)
    assert not c.contains(boundary).any() and c.contains(boundary, strict=False).all()
    assert c.contains(np.zeros(2)) is True


def test_disc_projection_closed_form_and_its_centre():
    c = curve("disc")
    xi, delta = c.project_floats(0.03, -0.04)
    assert xi == pytest.approx(R_DISC * (0.5 * math.pi + math.atan2(0.04, 0.03)), rel=1e-15)
    assert delta == pytest.approx(0.0, abs=1e-17)
    assert c.project_floats(0.0, 0.0) == (0.0, -R_DISC)
    assert c.project_floats(0.0, 0.0, near=7.0) == (7.0, -R_DISC)


def test_curve_face():
    c = curve("ellipse_wide")
    face = c.edge(0)
    assert isinstance(face, CurveFace) and c.edges == (face,) and c.edge(np.int64(0)) is face
    assert face.curved and face.index == 0 and face.xi_range == (-math.inf, math.inf)
    xi = np.array([0.01, 0.2, 0.33])
    np.testing.assert_allclose(face.xi_of(face.point(xi)), xi, rtol=1e-13)
    assert face.xi_of(face.point(0.05 + c.perimeter), near=c.perimeter) == pytest.approx(0.05 + c.perimeter)
    assert face.contains_xi(1e6) is True and face.contains_xi(xi).all()
    sp = face.local(0.1)
    np.testing.assert_allclose(sp.tangent, [-sp.normal[1], sp.normal[0]])
    np.testing.assert_allclose(sp.point, point(c, 0.1))
    for k in (1, -1, True, 0.0, "0"):
        with pytest.raises(UnknownEdgeError):
            c.edge(k)


# ---------------------------------------------------------------------- 6. radius 0 and small radii
CENTRED_PENTAGON = PENTAGON - fan_centroid(PENTAGON)
HEXAGON = np.array([[0.07, 0.0], [0.04, 0.05], [-0.03, 0.04], [-0.07, 0.0], [-0.04, -0.05], [0.03, -0.04]])  # C2


@pytest.mark.parametrize("mass_properties", [dict(mass=0.7), dict(mass=0.7, inertia=3e-4), dict(density=500.0)])
def test_radius_zero_is_the_polygon(mass_properties):
    shape = rounded(CENTRED_PENTAGON, 0.0, **mass_properties)
    polygon = ConvexPolygon.from_vertices(CENTRED_PENTAGON, **mass_properties)
    assert type(shape) is ConvexPolygon
    assert np.array_equal(shape.vertices, polygon.vertices)
    assert shape.mass == polygon.mass and shape.inertia == polygon.inertia
    assert isinstance(rounded(HEXAGON, 1e-3, **mass_properties), RoundedPolygon)


def test_small_radii_converge_to_the_polygon():
    polygon = ConvexPolygon.from_vertices(PENTAGON, mass=1.0, inertia=1.0)
    size = polygon.scale
    turn = exterior_angles(PENTAGON)
    cut = 2.0 * np.tan(0.5 * turn).sum() - 2.0 * math.pi  # P_poly - P = cut r, A_poly - A = cut r² / 2
    perimeter_errors, area_errors = [], []
    for rel in (1e-3, 1e-5, 1e-7):
        r = rel * size
        shape = RoundedPolygon(PENTAGON, r, mass=1.0, inertia=1.0)
        perimeter_errors.append(polygon.perimeter - shape.perimeter)
        area_errors.append(polygon.area - shape.area)
        assert perimeter_errors[-1] == pytest.approx(cut * r, rel=1e-6)
        assert area_errors[-1] == pytest.approx(0.5 * cut * r * r, abs=1e-15 * polygon.area)
    assert 0.0 < perimeter_errors[2] < perimeter_errors[1] < perimeter_errors[0]
    assert abs(area_errors[2]) < area_errors[1] < area_errors[0]
    polygon = ConvexPolygon.from_vertices(HEXAGON, density=1.0)  # centrally symmetric: uniform density allowed
    inertia_errors = []
    for rel in (1e-3, 1e-5, 1e-7):
        shape = RoundedPolygon(HEXAGON, rel * size, density=1.0)
        inertia_errors.append(abs(polygon.inertia - shape.inertia) / polygon.inertia)
        assert shape.mass == pytest.approx(polygon.mass, rel=rel)
    assert inertia_errors[2] < inertia_errors[1] < inertia_errors[0] < 1e-5


# ---------------------------------------------------------------------- 7. collision shape
@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("rtol", [1e-5, 1e-3])
def test_circumscribed_polygon(name, rtol):
    c = curve(name)
    corners = c.circumscribed_polygon(rtol)
    if name == "disc":  # not wasteful: about 2π / Δθ corners, ρ (1 / cos(Δθ / 2) - 1) = rtol × diameter
        turn = 2.0 * math.acos(1.0 / (1.0 + 2.0 * rtol))
        assert 2.0 * math.pi / turn <= len(corners) <= 1.1 * 2.0 * math.pi / turn + 2
    assert (corners[:, 0] * np.roll(corners[:, 1], -1) - np.roll(corners[:, 0], -1) * corners[:, 1]).sum() > 0.0
    assert inside_ccw(corners, dense(name)[1]).min() >= -1e-12 * c.scale  # contains the curve (CCW), to rounding
    bound = rtol * c.scale
    gaps = np.array([curve_distance(c, q, name) for q in corners])
    assert gaps.max() <= bound * (1.0 + 1e-6)
    assert np.all(c.project(corners)[1] >= -1e-15)  # outside or on the curve


def ellipse_distances(a: float, b: float, points: np.ndarray) -> np.ndarray:
    """Distances from points to the ellipse (a cos u, b sin u): a dense u grid refined by a bounded minimisation."""
    u = np.linspace(0.0, 2.0 * math.pi, 40000, endpoint=False)
    grid = np.stack([a * np.cos(u), b * np.sin(u)], axis=1)
    out = []
    for qx, qy in points.tolist():
        j = int(np.argmin((grid[:, 0] - qx) ** 2 + (grid[:, 1] - qy) ** 2))
        res = minimize_scalar(lambda x: math.hypot(a * math.cos(x) - qx, b * math.sin(x) - qy),
                              bounds=(u[j] - 2 * u[1], u[j] + 2 * u[1]), method="bounded", options={"xatol": 1e-15})
        out.append(min(float(res.fun), math.hypot(grid[j, 0] - qx, grid[j, 1] - qy)))
    return np.array(out)


def rounded_polygon_distance(vertices: np.ndarray, r: float, q: np.ndarray) -> float:
    """Distance from q (outside) to the polygon rounded by r: to the polygon of the edge lines moved in by r, less r."""
    d = np.roll(vertices, -1, axis=0) - vertices
    n = np.stack([-d[:, 1], d[:, 0]], axis=1) / np.linalg.norm(d, axis=1)[:, None]  # inward (CCW)
    e = (n * vertices).sum(axis=1) + r
    inner = np.array([np.linalg.solve([n[k - 1], n[k]], [e[k - 1], e[k]]) for k in range(len(vertices))])
    dist = []
    for a, b in zip(inner, np.roll(inner, -1, axis=0)):
        s = np.clip((q - a) @ (b - a) / ((b - a) @ (b - a)), 0.0, 1.0)
        dist.append(np.linalg.norm(q - a - s * (b - a)))
    return min(dist) - r


@pytest.mark.parametrize("shape", ["ellipse 30:1", "ellipse 1000:1", "pentagon r = 1e-6"])
def test_circumscribed_polygon_round_tight_bends(shape):
    """Where the normal turns faster than the curve's samples (an elongated ellipse's ends, tiny fillets) the
    corners still stand within the bound (the ξ-spaced tangents alone left them up to 11 × off)."""
    if shape.startswith("ellipse"):
        a = 0.1
        c = Ellipse(a, a / float(shape.split()[1][:-2]), mass=1.0)
        u = np.linspace(0.0, 2.0 * math.pi, 40000, endpoint=False)
        outline = np.stack([c.a * np.cos(u), c.b * np.sin(u)], axis=1)  # dense at the ends too
        corners = c.circumscribed_polygon()
        gaps = ellipse_distances(c.a, c.b, corners)
    else:
        c = RoundedPolygon(PENTAGON, 1e-6, mass=1.0, inertia=1.0)
        outline = c.outline(20000)
        corners = c.circumscribed_polygon()
        gaps = np.array([rounded_polygon_distance(PENTAGON, 1e-6, q) for q in corners])
    assert inside_ccw(corners, outline).min() >= -1e-12 * c.scale
    assert gaps.min() >= -1e-12 * c.scale and gaps.max() <= 1e-5 * c.scale * (1.0 + 1e-6)


@pytest.mark.parametrize("name", NAMES)
def test_to_coal(name):
    c = curve(name)
    half = 0.02
    shape = c.to_coal(half)
    if name == "disc":
        assert isinstance(shape, coal.Cylinder)
        assert shape.radius == R_DISC and shape.halfLength == half
    else:
        assert isinstance(shape, coal.ConvexBase)
        zs = np.array(shape.points())[:, 2]
        assert set(np.round(zs / half, 12)) == {-1.0, 1.0}
        assert shape.num_points == 2 * len(c.circumscribed_polygon())  # (coal takes hulls of over 252 corners)
    sphere = coal.Sphere(0.005)
    request = coal.DistanceRequest()
    request.gjk_tolerance = 1e-10  # (coal's default 1e-6 leaves errors of a few 1e-7 m)
    rng = np.random.default_rng(8)
    for xi in rng.uniform(0.0, c.perimeter, 5):
        gap = rng.uniform(0.002, 0.02)
        cx, cy, nx, ny, _ = c.local_floats(xi)
        placement = pin.SE3(np.eye(3), np.array([cx - (gap + 0.005) * nx, cy - (gap + 0.005) * ny, 0.0]))
        distance = coal.distance(shape, pin.SE3.Identity(), sphere, placement, request, coal.DistanceResult())
        assert gap - 1e-5 * c.scale - 1e-9 <= distance <= gap + 1e-9
        for offset, hit in ((-0.001, True), (0.001, False)):  # the sphere's surface 1 mm into / off the curve
            placement = pin.SE3(np.eye(3), np.array([cx - (offset + 0.005) * nx, cy - (offset + 0.005) * ny, 0.0]))
            result = coal.CollisionResult()
            coal.collide(shape, pin.SE3.Identity(), sphere, placement, coal.CollisionRequest(), result)
            assert result.isCollision() is hit
    with pytest.raises(InvalidParameterError):
        c.to_coal(0.0)


# ---------------------------------------------------------------------- 8. errors
@pytest.mark.parametrize("value", [0.0, -0.01, math.nan, math.inf, "0.1", None])
def test_disc_and_ellipse_reject_bad_lengths(value):
    with pytest.raises(InvalidParameterError):
        Disc(value, mass=1.0)
    with pytest.raises(InvalidParameterError):
        Ellipse(0.05, value, mass=1.0)
    with pytest.raises(InvalidParameterError):
        Ellipse(value, 0.05, mass=1.0)


@pytest.mark.parametrize("make, parameter", [
    (lambda: Disc(2e3, mass=1.0), "radius"), (lambda: Disc(1e-7, mass=1.0), "radius"),
    (lambda: Ellipse(1.5e3, 1.0, mass=1.0), "a"), (lambda: Ellipse(0.05, 1e-7, mass=1.0), "b"),
    (lambda: Ellipse(1.0, 1e-4, mass=1.0), "b"),  # aspect 1e4 > 1e3
])
def test_out_of_range_lengths_are_curve_errors(make, parameter):
    with pytest.raises(CurveError) as info:
        make()
    assert info.value.parameter == parameter and info.value.where is None


def test_mass_information_is_required_and_exclusive():
    with pytest.raises(InvalidParameterError):
        Disc(0.05)
    with pytest.raises(InvalidParameterError):
        Disc(0.05, mass=1.0, density=2.0)
    with pytest.raises(InvalidParameterError):
        Disc(0.05, inertia=1.0)
    assert Disc(0.05, density=2.0).mass == pytest.approx(2.0 * math.pi * 0.05 ** 2, rel=1e-15)


@pytest.mark.parametrize("a0", [0.0, -0.05])
def test_support_curve_needs_a_positive_mean_radius(a0):
    with pytest.raises(CurveError) as info:
        SupportCurve([a0, 0.0, 0.001], [0.0, 0.0], mass=1.0, inertia=1.0)
    assert info.value.parameter == "cosines"


@pytest.mark.parametrize("cosines, sines", [
    ([0.05, 0.0, 0.02], [0.0, 0.0]),  # ρ = a_0 - 3 a_2 cos 2θ < 0 about θ = 0 and π
    ([0.05, 0.0, 0.01667], [0.0, 0.0]),  # barely: min ρ = -1e-5
    # ρ = a_0 - 48 R cos(7θ - π/256) < 0 on seven arcs narrower than the certificate's first 256 samples' spacing,
    # all of them between samples (min ρ there +1.3e-6 m): found by its refinement (512 samples: -2.5e-6 m)
    ([0.05, 0, 0, 0, 0, 0, 0, 0.0500025 / 48 * math.cos(math.pi / 256)],
     [0, 0, 0, 0, 0, 0, 0.0500025 / 48 * math.sin(math.pi / 256)]),
])
def test_non_convex_support_curve_names_where(cosines, sines):
    with pytest.raises(CurveError) as info:
        SupportCurve(cosines, sines, mass=1.0, inertia=1.0)
    theta = info.value.where
    assert isinstance(theta, float) and 0.0 <= theta < 2.0 * math.pi
    h, _, ddh = support_series(cosines, sines, theta)
    assert h + ddh <= 0.0
    assert info.value.parameter == "cosines"


def test_barely_convex_support_curve_is_accepted():
    c = SupportCurve([0.05, 0.0, 0.0166], [0.0, 0.0], mass=1.0)  # min ρ = 0.05 - 3 × 0.0166 = 2e-4 at θ = 0
    assert c.local_floats(0.25 * c.perimeter)[4] == pytest.approx(1.0 / (0.05 - 3 * 0.0166), rel=1e-9)


@pytest.mark.parametrize("cosines, sines", [([0.05, 0.0, 0.01], [0.0]), ([0.05, 0.0], [0.0, 0.0]), ([], [])])
def test_support_curve_coefficient_counts(cosines, sines):
    with pytest.raises(CurveError):
        SupportCurve(cosines, sines, mass=1.0, inertia=1.0)


def test_support_curve_rejects_non_finite_coefficients():
    with pytest.raises(InvalidParameterError):
        SupportCurve([0.05, math.nan], [0.0], mass=1.0, inertia=1.0)


@pytest.mark.parametrize("radius, error", [(0.0, CurveError), (-0.01, CurveError), (math.nan, InvalidParameterError),
                                           (math.inf, InvalidParameterError)])
def test_rounded_polygon_rejects_bad_radius(radius, error):
    with pytest.raises(error):
        RoundedPolygon(RECT, radius, mass=1.0)


@pytest.mark.parametrize("vertices", [RECT, PENTAGON, HEXAGON])
def test_rounded_polygon_largest_radius(vertices):
    largest = largest_corner_radius(vertices)
    RoundedPolygon(vertices, largest * (1.0 - 1e-6), mass=1.0, inertia=1.0)  # slightly below: accepted
    for radius in (largest * (1.0 + 1e-6), largest, 2.0 * largest):
        with pytest.raises(CurveError) as info:
            RoundedPolygon(vertices, radius, mass=1.0, inertia=1.0)
        err = info.value
        assert err.parameter == "radius" and err.value == radius
        named = float(re.search(r"largest corner radius of this polygon is below ([0-9.e+-]+) m", str(err)).group(1))
        assert named == pytest.approx(largest, rel=1e-5)
        # `where` is an edge whose own limit the radius reaches
        k = err.where
        assert isinstance(k, int) and 0 <= k < len(vertices)
        lengths = np.linalg.norm(np.roll(vertices, -1, axis=0) - vertices, axis=1)
        cot_half = 1.0 / np.tan(0.5 * (math.pi - exterior_angles(vertices)))
        assert radius >= lengths[k] / (cot_half[k] + cot_half[(k + 1) % len(vertices)]) * (1.0 - 1e-9)
    assert largest_corner_radius(RECT) == pytest.approx(0.5 * H, rel=1e-15)


def test_off_centre_uniform_density_is_a_curve_error():
    ConvexPolygon.from_vertices(CENTRED_PENTAGON, mass=1.0)  # the polygon is centred...
    with pytest.raises(CurveError) as info:  # ...but rounding moves its centroid
        RoundedPolygon(CENTRED_PENTAGON, R_PENTAGON, mass=1.0)
    assert info.value.parameter == "centroid"
    with pytest.raises(CurveError):
        RoundedPolygon(RECT + 0.01, R_RECT, density=1.0)
    with pytest.raises(CurveError) as info:
        SupportCurve(OFF_COS, OFF_SIN, mass=1.0)
    assert "centred()" in str(info.value)
    RoundedPolygon(CENTRED_PENTAGON, R_PENTAGON, mass=1.0, inertia=1e-4)  # explicit: fine


def test_projection_with_a_far_near_still_finds_the_nearest_point():
    """``near`` only picks the representative: started half a perimeter away, the projection still returns the
    nearest boundary point (the root it first converges to may be another one, e.g. inside a rounded box)."""
    box = RoundedPolygon(0.5 * np.array([[0.1, 0.06], [-0.1, 0.06], [-0.1, -0.06], [0.1, -0.06]]), 0.012, mass=0.1)
    rng = np.random.default_rng(11)
    P = box.perimeter
    for xi in rng.uniform(0, P, 40):
        sp = box.local(xi)
        p = sp.point - 0.002 * sp.normal  # 2 mm outside
        found, delta = box.project_floats(*p, near=xi + 0.5 * P - 1e-3)
        assert abs(delta - 0.002) < 1e-12 and abs(math.remainder(found - xi, P)) < 1e-10
        assert abs(found - (xi + 0.5 * P - 1e-3)) <= 0.5 * P + 1e-12

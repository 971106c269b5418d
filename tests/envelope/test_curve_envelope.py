"""The envelope on curved objects (paper §2.2 and Definition 2.2 on discs, ellipses, rounded polygons and support-
function curves), checked against an independent brute-force sampler.

The sampler re-derives everything from the definitions, from the curve's own parametrisation (``curve.frames``:
point and inward normal at ξ) and its defining data only:

* the tip at ξ in the hand frame is ``pose[:2] + R(beta) c(ξ)``, the tangent line's inward normal ``R(beta) n(ξ)``;
* inverse kinematics with ``acos``/``atan2`` (left: θ2 = -acos(...), elbow left of the ray joint 1 -> tip);
* reachable (Definition 2.1): inside the annulus and the elbow not in the *open* interior half-plane of the tangent
  line at the tip;
* feasible (Definition 2.2, ``ideal``): reachable and link 1 (joint 1 -> elbow) does not meet the open interior,
  tested on the object's implicit description: a disc's ``|x| < R`` and an ellipse's ``(x/a)^2 + (y/b)^2 < 1``
  (the segment's closest point, exact), a rounded polygon's "closer than r to its inner polygon" (exact), and a
  support curve's own dense inscribed polygon built from its Fourier coefficients (separating axes).

ξ is sampled on a uniform grid of one period over the sample's window; every sampled verdict must agree with the
library's intervals except within two grid steps of an interval end.
"""

from __future__ import annotations

import functools
import math
import time
from pathlib import Path

import numpy as np
import pytest

from factories import make_finger, perp2, random_polygon, rot
from regrasp import Finger
from regrasp.core.curves import Disc, Ellipse, RoundedPolygon, SupportCurve
from regrasp.core.exceptions import InvalidParameterError, UnknownEdgeError
from regrasp.core.trajectory import WaypointTrajectory
from regrasp.envelope.curve import CurveGeometry
from regrasp.envelope.finger_envelope import FingerEnvelope
from regrasp.envelope.planner import plan
from regrasp.envelope.tracker import EnvelopeTracker
from regrasp.model import FingerContact
from regrasp.model.collision import UrdfCollisionChecker

ROOT = Path(__file__).resolve().parents[2]
URDF = ROOT / "urdf" / "planar_2r_finger.urdf"

N_GRID = 4096  # sampler points per period
END_STEPS = 2  # verdicts within this many grid steps of a library end are not compared
N_SEEDS = 104  # random geometries and poses per kind of curve (two curves each; left and right alternately)


# --------------------------------------------------------------------------- the objects
def _support(cosines, sines):
    return SupportCurve.centred(cosines, sines, mass=1.0)


CURVES = {
    "disc": [lambda: Disc(0.04, mass=1.0), lambda: Disc(0.075, mass=1.0)],
    "ellipse": [lambda: Ellipse(0.07, 0.03, mass=1.0), lambda: Ellipse(0.035, 0.06, mass=1.0)],
    "rounded": [lambda: RoundedPolygon([[-0.05, -0.025], [0.05, -0.025], [0.05, 0.025], [-0.05, 0.025]], 0.01,
                                       mass=1.0),
                lambda: RoundedPolygon([[-0.04, -0.03], [0.06, -0.02], [0.01, 0.05]], 0.004, mass=1.0, inertia=1.0)],
    "support": [lambda: _support([0.05, 0.0, 0.006, 0.002], [0.0, 0.003, -0.001]),
                lambda: _support([0.045, 0.0, -0.003, 0.0, 0.0008], [0.0, 0.0, 0.0015, 0.0])],
}
KINDS = list(CURVES)


@functools.lru_cache(maxsize=None)
def curve_data(kind: str, index: int) -> dict:
    """The curve and its sampled frames over one period (the sampler's grid, offset by half a step)."""
    curve = CURVES[kind][index]()
    period = curve.perimeter
    xi = (np.arange(N_GRID) + 0.5) * period / N_GRID
    points, normals, _ = curve.frames(xi)
    data = dict(curve=curve, kind=kind, period=period, xi=xi, points=points, normals=normals)
    if kind == "support":  # its own dense inscribed polygon, from the support function h(θ)
        theta = np.linspace(0.0, 2.0 * math.pi, 1024, endpoint=False)
        k = np.arange(curve.cosines.size)
        h = np.cos(np.outer(theta, k)) @ curve.cosines + np.sin(np.outer(theta, k)) @ curve.sines
        dh = np.cos(np.outer(theta, k)) @ (k * curve.sines) - np.sin(np.outer(theta, k)) @ (k * curve.cosines)
        u = np.stack([np.cos(theta), np.sin(theta)], axis=1)
        verts = h[:, None] * u + dh[:, None] * perp2(u)
        edges = np.roll(verts, -1, axis=0) - verts
        normals = perp2(edges / np.linalg.norm(edges, axis=1)[:, None])
        data["polygon"] = (verts, normals, (verts @ normals.T).min(axis=0), (verts @ normals.T).max(axis=0))
    return data


# --------------------------------------------------------------------------- the sampler
def ik_elbow(o1, tips, l1, l2, sign):
    """Elbow of the closed-form IK (own implementation) and the annulus membership."""
    v = tips - o1
    r2 = np.einsum("ij,ij->i", v, v)
    in_annulus = (r2 >= (l1 - l2) ** 2) & (r2 <= (l1 + l2) ** 2)
    cos2 = np.clip((r2 - l1 * l1 - l2 * l2) / (2.0 * l1 * l2), -1.0, 1.0)
    theta2 = -sign * np.arccos(cos2)
    psi1 = np.arctan2(v[:, 1], v[:, 0]) - np.arctan2(l2 * np.sin(theta2), l1 + l2 * np.cos(theta2))
    return o1 + l1 * np.stack([np.cos(psi1), np.sin(psi1)], axis=1), in_annulus


def point_segment_distance(p, a, b):
    ab = b - a
    t = np.clip(np.einsum("...i,...i->...", p - a, ab) / np.maximum(np.einsum("...i,...i->...", ab, ab), 1e-300),
                0.0, 1.0)
    return np.linalg.norm(a + t[..., None] * ab - p, axis=-1)


def segment_to_polygon_distance(a, b, verts):
    """Distance from segments a[i]->b[i] to a filled convex polygon (CCW ``verts``); 0 when they meet."""
    q0, q1 = verts[None, :, :], np.roll(verts, -1, axis=0)[None, :, :]
    a3, b3 = a[:, None, :], b[:, None, :]

    def cross(u, w):
        return u[..., 0] * w[..., 1] - u[..., 1] * w[..., 0]

    d1, d2 = cross(q1 - q0, a3 - q0), cross(q1 - q0, b3 - q0)
    d3, d4 = cross(b3 - a3, q0 - a3), cross(b3 - a3, q1 - a3)
    crossing = np.any((d1 * d2 < 0) & (d3 * d4 < 0), axis=1)
    inside = np.all(d1 > 0, axis=1) | np.all(d2 > 0, axis=1)
    dist = np.minimum.reduce([point_segment_distance(a3, q0, q1).min(axis=1),
                              point_segment_distance(b3, q0, q1).min(axis=1),
                              point_segment_distance(q0, a3, b3).min(axis=1)])
    return np.where(crossing | inside, 0.0, dist)


def segment_penetration(a, b, polygon):
    """Separating-axis depth of segments a[i]->b[i] into a convex polygon (its vertices, edge normals and their
    extents along them): > 0 iff they meet its open interior."""
    verts, normals, pmin, pmax = polygon
    pa, pb = a @ normals.T, b @ normals.T
    pen = np.minimum(np.maximum(pa, pb) - pmin, pmax - np.minimum(pa, pb)).min(axis=1)
    m = perp2(b - a)
    m = m / np.linalg.norm(m, axis=1)[:, None]
    qv = m @ verts.T
    sv = np.einsum("ij,ij->i", a, m)
    return np.minimum(pen, np.minimum(sv - qv.min(axis=1), qv.max(axis=1) - sv))


def link1_hits(data, o, e):
    """Whether segments o -> e[i] (object frame) meet the object's open interior."""
    curve, kind = data["curve"], data["kind"]
    a = np.broadcast_to(o, e.shape)
    if kind == "disc":
        return point_segment_distance(np.zeros(2), a, e) < curve.radius * (1.0 - 1e-12)
    if kind == "ellipse":
        scale = np.array([1.0 / curve.a, 1.0 / curve.b])
        return point_segment_distance(np.zeros(2), a * scale, e * scale) < 1.0 - 1e-12
    if kind == "rounded":
        return segment_to_polygon_distance(a, e, curve.inner_corners) < curve.radius * (1.0 - 1e-13)
    return segment_penetration(a, e, data["polygon"]) > 1e-12


def brute_force(data, pose, o1, l1, l2, sign, xi):
    """(reachable, feasible) at the ξ values ``xi`` (Definitions 2.1, 2.2, ``ideal``; link 1 tested where
    reachable)."""
    if np.array_equal(xi, data.get("window_xi")):
        points, normals = data["window_points"], data["window_normals"]
    else:
        points, normals, _ = data["curve"].frames(np.asarray(xi, dtype=float))
    R = rot(pose[2])
    tips, n_hand = pose[:2] + points @ R.T, normals @ R.T
    elbow, in_annulus = ik_elbow(np.asarray(o1, float), tips, l1, l2, sign)
    reachable = in_annulus & ~(np.einsum("ij,ij->i", elbow - tips, n_hand) > 0.0)
    o_obj = R.T @ (np.asarray(o1, float) - pose[:2])
    feasible = reachable.copy()
    feasible[reachable] = ~link1_hits(data, o_obj, (elbow[reachable] - pose[:2]) @ R)
    return reachable, feasible


def window_grid(data, window):
    """The sampler's points as representatives in the window, sorted, with their frames."""
    lo = window[0]
    period = data["period"]
    xi = lo + (data["xi"] - lo) % period
    order = np.argsort(xi)
    data["window_xi"], data["window_points"], data["window_normals"] = (
        xi[order], data["points"][order], data["normals"][order])
    return xi[order]


def member(intervals, xi):
    out = np.zeros(xi.size, dtype=bool)
    for lo, hi in intervals:
        out |= (xi >= lo) & (xi <= hi)
    return out


def disagreements(intervals, verdicts, xi, step):
    ends = np.array([x for iv in intervals for x in iv])
    far = np.ones(xi.size, dtype=bool) if not ends.size else \
        np.min(np.abs(xi[:, None] - ends[None, :]), axis=1) > END_STEPS * step
    return np.flatnonzero(far & (member(intervals, xi) != verdicts))


# --------------------------------------------------------------------------- the cases
def make_case(kind: str, seed: int) -> dict:
    """A seeded random finger (links, joint 1 at a random signed distance from the curve) and object pose."""
    rng = np.random.default_rng(1000 * KINDS.index(kind) + seed)
    index = seed % len(CURVES[kind])
    data = curve_data(kind, index)
    curve = data["curve"]
    l1 = rng.uniform(0.03, 0.15)
    l2 = [l1, l1 * rng.uniform(0.6, 1.6), l1 * rng.uniform(0.25, 0.45), l1 * rng.uniform(2.2, 3.0)][(seed // 4) % 4]
    pose = np.array([rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1), rng.uniform(-math.pi, math.pi)])
    xi0 = rng.uniform(0.0, curve.perimeter)
    u = rng.random()
    delta = (-rng.uniform(0.0, 0.5) * l1 if u < 0.12 else rng.uniform(0.0, 0.6) * l1 if u < 0.65
             else rng.uniform(0.6 * l1, 1.1 * (l1 + l2)))
    p = curve.local(xi0)
    o1 = pose[:2] + rot(pose[2]) @ (p.point - delta * p.normal)
    base = np.array([o1[0], o1[1], rng.uniform(-math.pi, math.pi)])
    return dict(kind=kind, seed=seed, data=data, l1=l1, l2=l2, pose=pose, base=base, delta=delta)


def configuration(seed: int) -> str:
    return "left" if (seed // 2) % 2 == 0 else "right"


@functools.lru_cache(maxsize=None)
def evaluate(kind: str, seed: int, configuration: str) -> dict:
    case = make_case(kind, seed)
    finger = make_finger(case["l1"], case["l2"], case["base"], configuration)
    sign = 1 if configuration == "left" else -1
    sample = FingerEnvelope(finger, case["data"]["curve"], 0).at(case["pose"], 0.25)
    xi = window_grid(case["data"], sample.edge_range)
    reachable, feasible = brute_force(case["data"], case["pose"], finger.joint1_in_hand, case["l1"], case["l2"],
                                      sign, xi)
    return dict(case=case, finger=finger, sign=sign, sample=sample, xi=xi, reachable=reachable, feasible=feasible,
                step=case["data"]["period"] / N_GRID)


@pytest.mark.parametrize("kind", KINDS)
def test_curve_envelope_matches_the_brute_force_sampler(kind):
    """≥ 100 random geometries and poses per kind of curve (left and right alternately): every sampled verdict
    agrees away from the library's interval ends."""
    problems, ends, compared = [], 0, 0
    for seed in range(N_SEEDS):
        ev = evaluate(kind, seed, configuration(seed))
        s, case = ev["sample"], ev["case"]
        lo, hi = s.edge_range
        assert hi - lo == pytest.approx(case["data"]["period"], rel=1e-12)
        assert lo < s.xi_foot < hi
        for name in ("reachable", "feasible"):
            intervals = getattr(s, name)
            assert all(a < b for a, b in intervals) and all(b < c for (_, b), (c, _) in
                                                            zip(intervals, intervals[1:])), intervals
            assert all(lo <= a and b <= hi for a, b in intervals)
            bad = disagreements(intervals, ev[name], ev["xi"], ev["step"])
            ends += 2 * len(intervals)
            compared += ev["xi"].size
            if bad.size:
                k = bad[0]
                problems.append(f"{kind} seed {seed} {name}: {bad.size} samples disagree, e.g. xi={ev['xi'][k]!r} "
                                f"(brute force {bool(ev[name][k])}); library {intervals}")
        assert all(any(a <= x <= b for a, b in s.reachable) for iv in s.feasible for x in iv)
    print(f"{kind}: {compared} sampled verdicts, {ends} interval ends, {len(problems)} disagreements")
    assert not problems, "; ".join(problems[:5])
    assert ends > 100


@pytest.mark.parametrize("kind", ["disc", "ellipse", "rounded"])
def test_interval_ends_are_the_brute_force_transitions(kind):
    """Where the sampler's predicate is exact, its transitions bisected to 1e-13 P agree with the library's ends."""
    worst, checked = 0.0, 0
    for seed in range(0, N_SEEDS, 3):
        ev = evaluate(kind, seed, configuration(seed))
        s, case, step = ev["sample"], ev["case"], ev["step"]
        period = case["data"]["period"]

        def verdicts(x, name):
            r, f = brute_force(case["data"], case["pose"], ev["finger"].joint1_in_hand, case["l1"], case["l2"],
                               ev["sign"], np.array([x]))
            return bool((r if name == "reachable" else f)[0])

        for name in ("reachable", "feasible"):
            for x in (x for iv in getattr(s, name) for x in iv if s.edge_range[0] < x < s.edge_range[1]):
                a, b = x - 0.5 * step, x + 0.5 * step
                va, vb = verdicts(a, name), verdicts(b, name)
                if va == vb:  # (a thin piece or gap: not a single transition at this scale)
                    continue
                while b - a > 1e-13 * period:
                    m = 0.5 * (a + b)
                    if verdicts(m, name) == va:
                        a = m
                    else:
                        b = m
                worst = max(worst, abs(0.5 * (a + b) - x) / period)
                checked += 1
    print(f"{kind}: {checked} interval ends, worst vs the bisected brute-force transition {worst:.2e} x P")
    assert checked > 20 and worst < 1e-10


def test_brute_force_case_coverage():
    """The cases include: joint 1 inside, empty and non-empty sets, link-1 collision cuts, two reachable pieces, a
    feasible contact past the finger's tangent points (link 1 wrapping round the object) and sets cut at the
    window's ends."""
    inside = cut = split = far_side = at_window_end = feasible_at_window_end = feasible = 0
    for kind, seed in [(k, s) for k in KINDS for s in range(N_SEEDS)]:
        ev = evaluate(kind, seed, configuration(seed))
        s = ev["sample"]
        inside += s.d < 0.0
        feasible += bool(s.feasible)
        cut += bool(s.feasible) and sum(b - a for a, b in s.feasible) < sum(b - a for a, b in s.reachable) - 1e-6
        split += len(s.reachable) >= 2
        at_window_end += any(a == s.edge_range[0] or b == s.edge_range[1] for a, b in s.reachable)
        feasible_at_window_end += any(a == s.edge_range[0] or b == s.edge_range[1] for a, b in s.feasible)
        # past the tangent points: the joint on the interior side of the tangent line at a feasible tip
        data, R = ev["case"]["data"], rot(ev["case"]["pose"][2])
        o = R.T @ (ev["finger"].joint1_in_hand - ev["case"]["pose"][:2])
        tips = [x for x, f in zip(ev["xi"], ev["feasible"]) if f]
        if tips:
            p = data["curve"].local(float(tips[len(tips) // 2]))
            d = float(p.normal @ (p.point - o))
            far_side += d < 0.0
    counts = dict(inside=inside, feasible=feasible, cut=cut, split=split, far_side=far_side,
                  at_window_end=at_window_end, feasible_at_window_end=feasible_at_window_end)
    print(counts)
    assert inside >= 20 and feasible >= 200 and cut >= 30 and split >= 20 and far_side >= 30, counts
    assert at_window_end >= 5 and feasible_at_window_end >= 1, counts


# --------------------------------------------------------------------------- the disc's closed form
def test_disc_closed_form_equals_the_certified_bracketing():
    rng = np.random.default_rng(7)
    worst = 0.0
    for k in range(300):
        disc = Disc(rng.uniform(0.01, 0.1), mass=1.0)
        l1, l2 = rng.uniform(0.02, 0.15, 2)
        sign = int(rng.choice([-1, 1]))
        angle, dist = rng.uniform(-math.pi, math.pi), rng.uniform(0.0, disc.radius + 1.1 * (l1 + l2))
        ox, oy = dist * math.cos(angle), dist * math.sin(angle)
        near = rng.uniform(-1.0, 1.0)
        closed = CurveGeometry(disc, l1, l2, sign).solve(ox, oy, near)
        bracketed = CurveGeometry(disc, l1, l2, sign, closed_form=False).solve(ox, oy, near)
        assert CurveGeometry(disc, l1, l2, sign).closed_form and not CurveGeometry(disc, l1, l2, sign,
                                                                                   closed_form=False).closed_form
        assert closed.window == bracketed.window
        for name in ("reachable", "ideal"):
            a, b = getattr(closed, name), getattr(bracketed, name)
            assert len(a) == len(b), (k, name, a, b)
            worst = max([worst] + [abs(x - y) for u, w in zip(a, b) for x, y in zip(u, w)])
        for x in bracketed.breakpoints:  # every certified sign change is a closed-form breakpoint
            worst = max(worst, min(abs(x - y) for y in closed.breakpoints))
    print(f"disc: closed form vs certified bracketing, worst {worst:.2e} m")
    assert worst < 1e-10


def test_closed_form_needs_a_disc():
    with pytest.raises(InvalidParameterError):
        CurveGeometry(Ellipse(0.05, 0.03, mass=1.0), 0.1, 0.05, 1, closed_form=True)


# --------------------------------------------------------------------------- a rounded polygon of tiny radius
def test_tiny_rounded_polygon_matches_the_polygon_on_its_straight_parts():
    rng = np.random.default_rng(11)
    worst, compared = 0.0, 0
    for k in range(12):
        polygon = random_polygon(rng, rng.uniform(0.06, 0.15))
        rounded = RoundedPolygon(polygon.vertices, 1e-6 * polygon.scale, mass=1.0, inertia=1.0)
        period = rounded.perimeter
        straight = [(j, a, b) for kind, j, a, b in rounded.piece_ranges() if kind == "edge"]
        offsets = {}
        for j, a, b in straight:  # curve ξ - polygon edge-j ξ on edge j's straight part
            mid = 0.5 * (a + b)
            offsets[j] = mid - float(polygon.edge(j).xi_of(rounded.points(mid)))
        for _ in range(3):
            l1 = rng.uniform(0.04, 0.14)
            l2 = l1 * rng.uniform(0.3, 1.5)
            centre = rng.uniform(-0.5, 0.5, 2) * polygon.scale
            angle = rng.uniform(-math.pi, math.pi)
            o1 = centre + rng.uniform(0.6, 1.2) * polygon.scale * np.array([math.cos(angle), math.sin(angle)])
            pose = np.array([*centre, rng.uniform(-math.pi, math.pi)])
            finger = make_finger(l1, l2, (*o1, rng.uniform(-math.pi, math.pi)), str(rng.choice(["left", "right"])))
            s = FingerEnvelope(finger, rounded, 0).at(pose)
            for j, a, b in straight:
                e = FingerEnvelope(finger, polygon, j).at(pose)
                for name in ("reachable", "feasible"):
                    curve_part = [(max(lo + m * period, a), min(hi + m * period, b)) for lo, hi in getattr(s, name)
                                  for m in (-1, 0, 1)]
                    curve_part = merge_pieces(curve_part)
                    poly_part = merge_pieces([(max(lo + offsets[j], a), min(hi + offsets[j], b))
                                              for lo, hi in getattr(e, name)])
                    assert len(curve_part) == len(poly_part), (k, j, name, curve_part, poly_part)
                    for u, w in zip(curve_part, poly_part):
                        worst = max(worst, abs(u[0] - w[0]), abs(u[1] - w[1]))
                        compared += 1
    print(f"tiny rounded polygon vs polygon on {compared} straight-part intervals: worst {worst:.2e} m")
    assert compared > 50
    assert worst < 1e-5


def merge_pieces(pieces, min_length=1e-9):
    out = []
    for lo, hi in sorted(p for p in pieces if p[1] - p[0] > min_length):
        if out and lo <= out[-1][1] + min_length:
            out[-1] = (out[-1][0], max(out[-1][1], hi))
        else:
            out.append((lo, hi))
    return out


# --------------------------------------------------------------------------- urdf on a disc
def test_urdf_on_a_disc_agrees_with_a_brute_force_coal_sampler():
    disc = Disc(0.04, mass=1.0)
    period = disc.perimeter
    finger = Finger.from_urdf(URDF, base_in_hand=(-0.05, 0.0, math.pi / 2), configuration="left")
    l1, l2 = finger.link_lengths
    env = FingerEnvelope(finger, disc, 0, geometry="urdf")
    checker = UrdfCollisionChecker(finger, disc, env.tip_clearance)
    step, worst, checked = 1e-4 * period, 0.0, 0
    for pose in ([0.0, 0.07, 0.3], [0.03, 0.05, -1.0], [-0.02, 0.1, 2.0], [0.06, 0.03, 0.0], [-0.08, 0.06, 0.5]):
        pose = np.array(pose)
        s = env.at(pose)
        lo, hi = s.edge_range
        xi = lo + step * (np.arange(int(period / step)) + 0.5)
        points, normals, _ = disc.frames(xi)
        R = rot(pose[2])
        tips, n_hand = pose[:2] + points @ R.T, normals @ R.T
        elbow, in_annulus = ik_elbow(finger.joint1_in_hand, tips, l1, l2, 1)
        reachable = in_annulus & ~(np.einsum("ij,ij->i", elbow - tips, n_hand) > 0.0)
        free = np.zeros(xi.size, dtype=bool)
        for k in np.flatnonzero(reachable):
            q = finger.inverse_kinematics(tips[k])
            assert np.allclose(finger.joint_positions_in_hand(q)[1], elbow[k], atol=1e-9)
            free[k] = not checker.collides(q, pose)
        bad = disagreements(s.feasible, free, xi, step)
        assert bad.size == 0, (pose, s.feasible, xi[bad[:3]])
        checked += int(reachable.sum())
        assert s.feasible and total(s.feasible) < total(s.reachable)  # the shapes cut the ideal set
        transitions = 0.5 * (xi[:-1] + xi[1:])[free[:-1] != free[1:]]
        for x in (x for iv in s.feasible for x in iv if lo < x < hi):
            worst = max(worst, float(np.min(np.abs(transitions - x))) / period)
    print(f"urdf on a disc: {checked} coal-sampled tips; worst end vs the sampled transition {worst:.2e} x P")
    assert checked > 1000 and worst <= 1e-4


def total(intervals):
    return sum(b - a for a, b in intervals)


def test_urdf_on_an_ellipse_is_within_its_reachable_set_and_near_the_ideal_one():
    ellipse = Ellipse(0.06, 0.03, mass=1.0)
    finger = Finger.from_urdf(URDF, base_in_hand=(-0.05, 0.0, math.pi / 2), configuration="left")
    pose = np.array([0.02, 0.06, 1.2])
    urdf, ideal = (FingerEnvelope(finger, ellipse, 0, geometry=g).at(pose) for g in ("urdf", "ideal"))
    assert urdf.reachable == ideal.reachable and urdf.feasible
    assert all(any(a <= x <= b for a, b in urdf.reachable) for iv in urdf.feasible for x in iv)
    assert 0.3 * total(ideal.feasible) < total(urdf.feasible) < total(ideal.feasible)


# --------------------------------------------------------------------------- FingerEnvelope and the planner
def test_a_curve_has_no_compiled_path_and_the_tracker_follows_at():
    disc = Disc(0.04, mass=1.0)
    finger = Finger.from_urdf(URDF, base_in_hand=(-0.05, 0.0, math.pi / 2), configuration="left")
    with pytest.raises(InvalidParameterError, match="compiled"):
        FingerEnvelope(finger, disc, 0, geometry="urdf", compiled=True)
    with pytest.raises(UnknownEdgeError):
        FingerEnvelope(finger, disc, 1)
    env = FingerEnvelope(finger, disc, 0, geometry="urdf", compiled=None)
    assert not env.compiled and env.curved and env.compiled_arguments is None
    tracker = EnvelopeTracker(env)
    near = None
    for beta in np.linspace(0.0, 4.0 * math.pi, 41):  # two turns: ξ unwraps
        pose = np.array([0.0, 0.07, beta])
        tracked, fresh = tracker.update(pose, float(beta)), env.at(pose, float(beta), near=near)
        assert tracked.feasible == fresh.feasible and tracked.xi_foot == fresh.xi_foot
        near = fresh.xi_foot
    assert abs(near - (FingerEnvelope(finger, disc, 0).at(np.array([0.0, 0.07, 0.0])).xi_foot
                       + 2.0 * disc.perimeter)) < 1e-9
    assert tracker.counts["curve"] == 41


def test_the_sample_of_a_curve_reports_the_tangent_line_at_the_foot():
    ellipse = Ellipse(0.06, 0.03, mass=1.0)
    finger = Finger.from_urdf(URDF, base_in_hand=(-0.05, 0.0, math.pi / 2), configuration="right")
    pose = np.array([0.01, 0.08, 0.7])
    env = FingerEnvelope(finger, ellipse, 0)
    s, line = env.at(pose), env.line(pose)
    foot = ellipse.local(s.xi_foot)
    normal = rot(pose[2]) @ foot.normal
    o1 = finger.joint1_in_hand
    assert s.d == pytest.approx(float(normal @ (pose[:2] + rot(pose[2]) @ foot.point - o1)), abs=1e-12)
    assert s.d == pytest.approx(line.d) and s.lam == pytest.approx(line.lam)
    assert np.allclose(env.tip_in_hand(line, 0.0), pose[:2] + rot(pose[2]) @ foot.point, atol=1e-12)
    assert np.allclose(env.tip_at(pose, s.xi_foot), pose[:2] + rot(pose[2]) @ foot.point, atol=1e-12)
    assert abs(math.remainder(s.lam - (math.atan2(normal[1], normal[0]) - math.pi / 2), 2 * math.pi)) < 1e-12
    assert s.reason is None and s.condition.value in ("II", "III")


def _disc_contacts():
    left = Finger.from_urdf(URDF, base_in_hand=(-0.05, 0.0, math.pi / 2), configuration="left", name="f1")
    right = Finger.from_urdf(URDF, base_in_hand=(0.05, 0.0, math.pi / 2), configuration="right", name="f2")
    return [FingerContact(left, 0), FingerContact(right, 0)]


def test_plan_runs_on_a_turning_disc():
    """A disc turning a full turn about a fixed centre: every sample is feasible, ξ unwraps continuously, and the
    feasible sets are the same material arc moving with the disc (ξ - R β is constant)."""
    disc = Disc(0.04, mass=0.05)
    trajectory = WaypointTrajectory([0.0, 1.0, 2.0], [[0.0, 0.08, 0.0], [0.0, 0.08, math.pi],
                                                      [0.0, 0.08, 2.0 * math.pi]], unwrap_angle=True)
    result = plan(_disc_contacts(), disc, trajectory, samples=81)
    assert result.feasible and result.polygon is disc
    for f in result.fingers:
        assert f.initial_xi is not None and f.fixed_grasp == ()  # a full turn: no contact lasts
        feet = np.array([s.xi_foot for s in f.samples])
        assert np.max(np.abs(np.diff(feet))) < 0.1 * disc.perimeter
        shifted = [tuple((a - disc.radius * p[2], b - disc.radius * p[2]) for a, b in s.feasible)
                   for s, p in zip(f.samples, result.poses)]
        assert all(len(x) == len(shifted[0]) for x in shifted)
        assert np.max(np.abs(np.array(shifted) - np.array(shifted[0]))) < 1e-9
        assert f.samples[0].feasible and any(a <= f.initial_xi <= b for a, b in f.samples[0].feasible)
        assert abs(feet[-1] - feet[0]) == pytest.approx(disc.perimeter, rel=1e-9)
    doc = result.to_json_dict()
    assert len(doc["object"]["vertices_in_object"]) == 256 and np.isfinite(doc["fingers"][0]["edge_range"]).all()


def test_plan_on_a_turning_ellipse_unwraps_its_feet():
    ellipse = Ellipse(0.05, 0.03, mass=0.05)
    trajectory = WaypointTrajectory([0.0, 1.0, 2.0], [[0.0, 0.085, 0.0], [0.01, 0.09, math.pi],
                                                      [0.0, 0.085, 2.0 * math.pi]], unwrap_angle=True)
    result = plan(_disc_contacts(), ellipse, trajectory, samples=41)
    for f in result.fingers:
        feet = np.array([s.xi_foot for s in f.samples])
        assert np.max(np.abs(np.diff(feet))) < 0.1 * ellipse.perimeter
        assert abs(feet[-1] - feet[0]) == pytest.approx(ellipse.perimeter, rel=1e-9)
        assert any(s.feasible for s in f.samples) and f.fixed_grasp == ()


def test_plan_on_a_moving_disc_in_urdf_geometry_keeps_a_grasp():
    disc = Disc(0.04, mass=0.05)
    trajectory = WaypointTrajectory([0.0, 1.0], [[0.0, 0.08, 0.0], [0.01, 0.085, 0.2]])
    ideal = plan(_disc_contacts(), disc, trajectory, samples=21)
    urdf = plan(_disc_contacts(), disc, trajectory, samples=21, geometry="urdf")
    assert ideal.feasible and urdf.feasible
    for fi, fu in zip(ideal.fingers, urdf.fingers):
        assert fu.fixed_grasp and fi.fixed_grasp  # a small turn: one contact lasts
        assert all(any(a <= x <= b for a, b in si.feasible) for si, su in zip(fi.samples, fu.samples)
                   for iv in su.feasible for x in iv)


def test_one_sample_is_fast():
    """The cost of one sample (printed; loose bounds against a slow path slipping in)."""
    finger = Finger.from_urdf(URDF, base_in_hand=(-0.05, 0.0, math.pi / 2), configuration="left")
    pose = np.array([0.0, 0.075, 0.4])
    timings = {}
    for curve in (Disc(0.04, mass=1.0), Ellipse(0.06, 0.03, mass=1.0),
                  RoundedPolygon([[-0.05, -0.025], [0.05, -0.025], [0.05, 0.025], [-0.05, 0.025]], 0.01, mass=1.0),
                  _support([0.05, 0.0, 0.006, 0.002], [0.0, 0.003, -0.001])):
        for geometry in ("ideal", "urdf"):
            env = FingerEnvelope(finger, curve, 0, geometry=geometry)
            env.at(pose)
            start = time.perf_counter()
            for _ in range(5):
                env.at(pose)
            timings[f"{type(curve).__name__} {geometry}"] = (time.perf_counter() - start) / 5
    print({k: f"{v * 1e3:.2f} ms" for k, v in timings.items()})
    assert max(timings.values()) < 0.2

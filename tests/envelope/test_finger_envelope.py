"""Independent verification of the feasible-contact envelope (paper §2.2, Definitions 2.1, 2.2).

The oracle here re-derives everything from the definitions, without calling the library's
envelope internals, ``reachable_on_line``, ``segment_hits_polygon`` or
``Finger.inverse_kinematics``:

* the contact line in the hand frame is ``pose[:2] + R(beta) @ edge.point(xi)`` (the
  sanctioned ξ parametrisation); its inward normal is the unit normal pointing towards the
  polygon's vertices; ``d``, the foot of the perpendicular from joint 1 and the edge's ξ
  range are computed from the hand-frame vertices;
* inverse kinematics with ``acos``/``atan2`` (left: θ2 = -acos(...) ∈ (-π, 0), elbow left of
  the ray joint 1 → tip; right: the mirror);
* reachable (Def. 2.1): inside the annulus and the elbow not in the *open* interior half-plane;
* feasible (Def. 2.2): reachable, on the edge, and neither segment joint1→elbow nor
  elbow→tip meets the open interior of the polygon.  The segment test is a separating-axis
  penetration depth (axes: the polygon's edge normals and the segment's normal), i.e. the
  depth of the origin inside the Minkowski difference ``P - segment``; it is > 0 exactly
  when the segment meets the open interior.

The brute force samples ξ on a uniform grid covering the whole annulus and compares with
the library's closed-form intervals within a few grid steps; a second test refines the
transitions by bisection to 1e-12 and checks the library's ideal-mode ends to 1e-9 × edge
length.
"""

from __future__ import annotations

import functools
import math
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from factories import make_case, make_finger, perp2, rot
from regrasp import load_scenario
from regrasp.core.exceptions import InvalidParameterError
from regrasp.core.polygon import ConvexPolygon
from regrasp.envelope.finger_envelope import FingerEnvelope
from regrasp.envelope.line import Condition
from regrasp.envelope.tracker import EnvelopeTracker

N_CASES = 200
N_GRID = 40001  # grid points over the whole annulus window
CLEAN_STEPS = 4  # pieces / gaps shorter than this many grid steps are ignored when counting
END_STEPS = 2  # library ends must be within this many grid steps of a brute-force transition


# --------------------------------------------------------------------------- the oracle
def line_frame(polygon: ConvexPolygon, k: int, pose: np.ndarray, o1: np.ndarray) -> dict:
    """The contact line in the hand frame, from the ξ parametrisation and the vertices only."""
    R = rot(pose[2])
    p0 = pose[:2] + R @ polygon.edge(k).point(0.0)
    t = pose[:2] + R @ polygon.edge(k).point(1.0) - p0
    assert abs(np.linalg.norm(t) - 1.0) < 1e-12  # ξ is an arc length
    verts = pose[:2] + polygon.vertices @ R.T
    n = perp2(t)
    if n @ (verts.mean(axis=0) - p0) < 0.0:
        n = -n
    nv = len(verts)
    ends = verts[[k, (k + 1) % nv]]
    assert np.all(np.abs((ends - p0) @ n) < 1e-12 * (1 + np.abs(verts).max()))  # edge k is on the line
    assert np.all((verts - p0) @ n > -1e-12)  # and it is a supporting line
    xi_ends = np.sort((ends - p0) @ t)
    coord_scale = 1.0 + np.abs(verts).max() + np.abs(o1).max()
    return dict(
        p0=p0, t=t, n=n, o1=np.asarray(o1, float), verts=verts,
        d=float(n @ (p0 - o1)), xi_foot=float(-(t @ (p0 - o1))),
        edge_range=(float(xi_ends[0]), float(xi_ends[1])),
        eps=1e-13 * coord_scale,
    )


def ik_elbow(o1, tips, l1, l2, sign):
    """Elbow of the closed-form IK (own implementation) and the annulus membership."""
    v = tips - o1
    r2 = np.einsum("ij,ij->i", v, v)
    in_annulus = (r2 >= (l1 - l2) ** 2) & (r2 <= (l1 + l2) ** 2)
    cos2 = np.clip((r2 - l1 * l1 - l2 * l2) / (2.0 * l1 * l2), -1.0, 1.0)
    theta2 = -sign * np.arccos(cos2)  # left (sign +1): theta2 in (-pi, 0)
    psi1 = np.arctan2(v[:, 1], v[:, 0]) - np.arctan2(l2 * np.sin(theta2), l1 + l2 * np.cos(theta2))
    elbow = o1 + l1 * np.stack([np.cos(psi1), np.sin(psi1)], axis=1)
    # self-check of the IK on the annulus: link 2 has length l2 and the elbow is on the
    # configuration's side of the ray joint 1 -> tip (left: cross > 0)
    if np.any(in_annulus):
        ok = in_annulus
        assert np.allclose(np.linalg.norm(tips[ok] - elbow[ok], axis=1), l2, rtol=0, atol=1e-9 * (l1 + l2))
        cr = v[:, 0] * (elbow[:, 1] - o1[1]) - v[:, 1] * (elbow[:, 0] - o1[0])
        clear = ok & (np.abs(np.sin(theta2)) > 1e-6)
        assert np.all(np.sign(cr[clear]) == sign)
    return elbow, in_annulus


def segment_penetration(a: np.ndarray, b: np.ndarray, verts: np.ndarray) -> np.ndarray:
    """Separating-axis penetration depth of segments a[i]→b[i] into a convex polygon.

    > 0 iff the segment meets the polygon's open interior; <= 0 when it is outside or only
    touches the boundary. Axes: the polygon's edge normals and the segment's normal.
    """
    a = np.atleast_2d(a)
    b = np.atleast_2d(b)
    edges = np.roll(verts, -1, axis=0) - verts
    normals = perp2(edges / np.linalg.norm(edges, axis=1)[:, None])
    pv = verts @ normals.T  # (K vertices, K axes)
    pmin, pmax = pv.min(axis=0), pv.max(axis=0)
    pa, pb = a @ normals.T, b @ normals.T  # (M, K)
    smin, smax = np.minimum(pa, pb), np.maximum(pa, pb)
    pen = np.minimum(smax - pmin, pmax - smin).min(axis=1)
    m = perp2(b - a)
    m = m / np.linalg.norm(m, axis=1)[:, None]
    qv = m @ verts.T  # (M, K)
    sv = np.einsum("ij,ij->i", a, m)
    pen_seg = np.minimum(sv - qv.min(axis=1), qv.max(axis=1) - sv)
    return np.minimum(pen, pen_seg)


def oracle(frame: dict, xi: np.ndarray, l1: float, l2: float, sign: int):
    """(reachable, feasible) boolean arrays at the ξ values ``xi`` (Definitions 2.1, 2.2)."""
    xi = np.atleast_1d(np.asarray(xi, dtype=float))
    tips = frame["p0"] + xi[:, None] * frame["t"]
    elbow, in_annulus = ik_elbow(frame["o1"], tips, l1, l2, sign)
    elbow_inside = (elbow - tips) @ frame["n"] > 0.0  # open interior half-plane
    reachable = in_annulus & ~elbow_inside
    lo, hi = frame["edge_range"]
    feasible = reachable & (xi >= lo) & (xi <= hi)
    idx = np.flatnonzero(feasible)
    if idx.size:
        o1 = np.broadcast_to(frame["o1"], (idx.size, 2))
        pen1 = segment_penetration(o1, elbow[idx], frame["verts"])
        pen2 = segment_penetration(elbow[idx], tips[idx], frame["verts"])
        feasible[idx] = (pen1 <= frame["eps"]) & (pen2 <= frame["eps"])
    return reachable, feasible


# --------------------------------------------------------------------------- interval helpers
def clean(pieces, min_len: float):
    """Drop pieces shorter than min_len, merge gaps shorter than min_len, drop again."""
    pieces = [(lo, hi) for lo, hi in pieces if hi - lo >= min_len]
    out = []
    for lo, hi in pieces:
        if out and lo - out[-1][1] < min_len:
            out[-1] = (out[-1][0], max(out[-1][1], hi))
        else:
            out.append((lo, hi))
    return [(lo, hi) for lo, hi in out if hi - lo >= min_len]


def runs(member: np.ndarray, grid: np.ndarray, h: float):
    """Runs of True as intervals whose ends are half-way between grid points."""
    m = np.concatenate([[False], member, [False]]).astype(np.int8)
    starts = np.flatnonzero(np.diff(m) == 1)
    stops = np.flatnonzero(np.diff(m) == -1) - 1
    return [(grid[a] - 0.5 * h, grid[b] + 0.5 * h) for a, b in zip(starts, stops)]


def total(pieces) -> float:
    return float(sum(hi - lo for lo, hi in pieces))


def intersect_range(pieces, rng):
    out = []
    for lo, hi in pieces:
        a, b = max(lo, rng[0]), min(hi, rng[1])
        if b > a:
            out.append((a, b))
    return out


def compare(name: str, lib, member: np.ndarray, grid: np.ndarray, h: float) -> list[str]:
    """Discrepancies between library intervals ``lib`` and brute-force membership on ``grid``."""
    problems = []
    lib = [(float(lo), float(hi)) for lo, hi in lib]
    for lo, hi in lib:
        if not hi > lo:
            problems.append(f"{name}: degenerate interval {(lo, hi)}")
    for (_, h0), (l1_, _) in zip(lib[:-1], lib[1:]):
        if not l1_ > h0:
            problems.append(f"{name}: intervals not sorted/disjoint {lib}")
    lib_member = np.zeros(grid.size, dtype=bool)
    for lo, hi in lib:
        lib_member |= (grid >= lo) & (grid <= hi)
    ends = np.array([x for iv in lib for x in iv])
    far = np.ones(grid.size, dtype=bool)
    if ends.size:
        far = np.min(np.abs(grid[:, None] - ends[None, :]), axis=1) > END_STEPS * h
    bad = np.flatnonzero(far & (lib_member != member))
    if bad.size:
        problems.append(
            f"{name}: {bad.size} grid points disagree away from the library ends, e.g. xi={grid[bad[0]]!r} "
            f"(brute force {bool(member[bad[0]])}, library {bool(lib_member[bad[0]])}); library {lib}"
        )
    # every library end is within a few grid steps of a brute-force transition, unless its
    # interval or the adjacent gap is shorter than the sampling can resolve
    trans = 0.5 * (grid[:-1] + grid[1:])[member[:-1] != member[1:]]
    bounds = [-math.inf] + [x for iv in lib for x in iv] + [math.inf]
    for j in range(1, len(bounds) - 1):
        x = bounds[j]
        if min(x - bounds[j - 1], bounds[j + 1] - x) < CLEAN_STEPS * h:
            continue
        if trans.size == 0 or np.min(np.abs(trans - x)) > END_STEPS * h:
            problems.append(f"{name}: library end {x!r} has no brute-force transition within {END_STEPS} grid steps")
    lib_c = clean(lib, CLEAN_STEPS * h)
    bf_c = clean(runs(member, grid, h), CLEAN_STEPS * h)
    if len(lib_c) != len(bf_c):
        problems.append(f"{name}: {len(lib_c)} library intervals vs {len(bf_c)} brute force: {lib_c} vs {bf_c}")
    else:
        for (a, b), (c, e) in zip(lib_c, bf_c):
            if abs(a - c) > END_STEPS * h or abs(b - e) > END_STEPS * h:
                problems.append(f"{name}: library interval {(a, b)} vs brute force {(c, e)} (grid step {h:.3g})")
    return problems


# --------------------------------------------------------------------------- evaluation of one case
@functools.lru_cache(maxsize=None)
def evaluate(seed: int, configuration: str) -> dict:
    case = make_case(seed)
    finger = make_finger(case["l1"], case["l2"], case["base"], configuration)
    sign = 1 if configuration == "left" else -1
    frame = line_frame(case["polygon"], case["edge"], case["pose"], finger.joint1_in_hand)
    sample = FingerEnvelope(finger, case["polygon"], case["edge"]).at(case["pose"], time=0.5)
    reach = case["l1"] + case["l2"]
    grid = np.linspace(frame["xi_foot"] - 1.02 * reach, frame["xi_foot"] + 1.02 * reach, N_GRID)
    h = float(grid[1] - grid[0])
    reachable, feasible = oracle(frame, grid, case["l1"], case["l2"], sign)
    reach_bf = clean(runs(reachable, grid, h), CLEAN_STEPS * h)
    on_edge_bf = clean(intersect_range(runs(reachable, grid, h), frame["edge_range"]), CLEAN_STEPS * h)
    feas_bf = clean(runs(feasible, grid, h), CLEAN_STEPS * h)
    return dict(case=case, finger=finger, sign=sign, frame=frame, sample=sample, grid=grid, h=h,
                reachable=reachable, feasible=feasible, reach_bf=reach_bf, on_edge_bf=on_edge_bf,
                feas_bf=feas_bf)


def expected_condition(d: float, l1: float) -> Condition:
    if d < -l1:
        return Condition.I
    if d > l1:
        return Condition.II
    return Condition.III if d >= 0.0 else Condition.IV


CASES = [(seed, conf) for seed in range(N_CASES) for conf in ("left", "right")]


# --------------------------------------------------------------------------- 1. brute force
@pytest.mark.parametrize("seed,configuration", CASES)
def test_envelope_matches_brute_force(seed, configuration):
    ev = evaluate(seed, configuration)
    s, fr, case = ev["sample"], ev["frame"], ev["case"]
    scale = case["l1"] + case["l2"]
    assert s.time == 0.5
    assert s.d == pytest.approx(fr["d"], abs=1e-12 * scale)
    assert s.condition is expected_condition(fr["d"], case["l1"])
    lam = math.atan2(fr["n"][1], fr["n"][0]) - case["base"][2]
    assert abs(math.remainder(s.lam - lam, 2 * math.pi)) < 1e-12
    assert s.edge_range == pytest.approx(fr["edge_range"], abs=1e-12 * scale)
    problems = compare("reachable", s.reachable, ev["reachable"], ev["grid"], ev["h"])
    problems += compare("feasible", s.feasible, ev["feasible"], ev["grid"], ev["h"])
    assert not problems, f"seed {seed} {configuration} ({case['lclass']}, {case['dclass']}): " + "; ".join(problems)


def test_brute_force_case_coverage():
    """The random cases exercise every condition, 0/1/2-interval reachable sets and collisions."""
    cond = {c: 0 for c in Condition}
    shapes = {0: 0, 1: 0, 2: 0}
    split_by_length = {}  # reachable sets of >= 2 pieces, per length class
    cut, blocked = 0, 0
    for seed, conf in CASES:
        ev = evaluate(seed, conf)
        cond[expected_condition(ev["frame"]["d"], ev["case"]["l1"])] += 1
        shapes[min(len(ev["reach_bf"]), 2)] += 1
        lclass = ev["case"]["lclass"]
        split_by_length[lclass] = split_by_length.get(lclass, 0) + (len(ev["reach_bf"]) >= 2)
        missing = total(ev["on_edge_bf"]) - total(ev["feas_bf"])
        if missing > 10 * ev["h"]:
            if ev["feas_bf"]:
                cut += 1
            else:
                blocked += 1
    print(f"conditions {dict((c.value, n) for c, n in cond.items())}, reachable pieces {shapes}, "
          f"split reachable sets per length class {split_by_length}, collision cuts {cut}, fully blocked {blocked}")
    assert all(n >= 20 for n in cond.values()), cond
    assert all(n >= 20 for n in shapes.values()), shapes
    # two pieces from the thin near-stretch piece (l1 = l2, III) and from the inner disc (l1 != l2)
    assert all(n >= 5 for n in split_by_length.values()) and len(split_by_length) == 4, split_by_length
    assert cut >= 20, cut
    assert blocked >= 5, blocked


# --------------------------------------------------------------------------- 2. structural properties
@pytest.mark.parametrize("seed", range(N_CASES))
def test_configuration_symmetry(seed):
    left, right = evaluate(seed, "left"), evaluate(seed, "right")
    sl, sr, fr = left["sample"], right["sample"], left["frame"]
    case = left["case"]
    tol = 1e-12 * (case["l1"] + case["l2"] + abs(fr["xi_foot"]))
    assert sl.condition is sr.condition
    assert sl.d == sr.d
    if sl.condition is Condition.I:
        assert sl.reachable == () and sr.reachable == ()
        assert sl.feasible == () and sr.feasible == ()
        assert sl.reason == sr.reason == "condition I"
        return
    if sl.condition is Condition.II:
        assert len(sl.reachable) == len(sr.reachable)
        if sl.reachable:
            assert np.allclose(np.array(sl.reachable), np.array(sr.reachable), rtol=0, atol=tol)
        return
    # III / IV: the right set is the left set mirrored about the foot of the perpendicular
    mirrored = sorted((2 * fr["xi_foot"] - hi, 2 * fr["xi_foot"] - lo) for lo, hi in sl.reachable)
    assert len(mirrored) == len(sr.reachable), (sl.reachable, sr.reachable)
    if mirrored:
        assert np.allclose(np.array(mirrored), np.array(sr.reachable), rtol=0, atol=tol)


@pytest.mark.parametrize("seed,configuration", CASES)
def test_no_collision_outside_condition_iv_and_reason(seed, configuration):
    """In II and III both links stay in the closed outer half-plane: feasible = reachable ∩ edge.

    ``reason`` names why the feasible set is empty (checked against the brute force where the
    answer is not within a few grid steps of a change).
    """
    ev = evaluate(seed, configuration)
    s = ev["sample"]
    if s.condition in (Condition.II, Condition.III):
        expected = intersect_range(s.reachable, s.edge_range)
        assert len(expected) == len(s.feasible)
        if expected:
            tol = 1e-12 * (ev["case"]["l1"] + ev["case"]["l2"] + abs(ev["frame"]["xi_foot"]))
            assert np.allclose(np.array(expected), np.array(s.feasible), rtol=0, atol=tol)
    if s.feasible:
        assert s.reason is None
        return
    small = CLEAN_STEPS * ev["h"]
    if s.condition is Condition.I:
        assert s.reason == "condition I"
    elif not ev["reach_bf"] and not np.any(ev["reachable"]):
        assert s.reason == "out of reach"
    elif ev["reach_bf"] and not ev["on_edge_bf"] and total(intersect_range(s.reachable, s.edge_range)) == 0.0:
        assert s.reason == "off the edge"
    elif total(ev["on_edge_bf"]) > small:
        assert s.reason == "collision"


# --------------------------------------------------------------------------- 3. hand-checkable case
def vertical_line_case(d: float, configuration: str):
    """Base at the origin, l1 = l2 = 1, contact line x = d (a tall rectangle's left side)."""
    finger = make_finger(1.0, 1.0, (0.0, 0.0, 0.0), configuration)
    rect = ConvexPolygon.rectangle(1.0, 10.0, mass=1.0, inertia=1.0)
    pose = np.array([d + 0.5, 0.3, 0.0])
    edge = 1  # left side: inward normal +x, ξ along +y
    frame = line_frame(rect, edge, pose, finger.joint1_in_hand)
    assert frame["d"] == pytest.approx(d, abs=1e-15)
    assert frame["xi_foot"] == pytest.approx(-0.3, abs=1e-15)  # s = y = ξ + 0.3
    return finger, rect, pose, edge, frame


@pytest.mark.parametrize("configuration", ["left", "right"])
def test_hand_checkable_condition_iii(configuration):
    l1 = l2 = 1.0
    d = 0.5
    c, S = math.sqrt(l1**2 - d**2), math.sqrt((l1 + l2) ** 2 - d**2)
    finger, rect, pose, edge, frame = vertical_line_case(d, configuration)
    sign = 1 if configuration == "left" else -1
    thin = (-S, -c - l2)  # near full stretch the other way: thin but real
    main = (c - l2, S)
    if sign < 0:
        thin, main = (-main[1], -main[0]), (-thin[1], -thin[0])
    expected_s = sorted([thin, main])
    # the oracle confirms the thin piece: reachable at its midpoint, not just beyond its inner end
    s_probe = np.array([0.5 * (thin[0] + thin[1]), (thin[1] + 0.01) if sign > 0 else (thin[0] - 0.01),
                        0.5 * (main[0] + main[1]), (main[0] - 0.01) if sign > 0 else (main[1] + 0.01)])
    reach, _ = oracle(frame, s_probe + frame["xi_foot"], l1, l2, sign)
    assert reach.tolist() == [True, False, True, False]
    sample = FingerEnvelope(finger, rect, edge).at(pose)
    assert sample.condition is Condition.III
    expected_xi = [(lo + frame["xi_foot"], hi + frame["xi_foot"]) for lo, hi in expected_s]
    assert np.allclose(np.array(sample.reachable), np.array(expected_xi), rtol=0, atol=1e-12)
    # joint 1 is outside the object, so nothing collides and the tall edge covers the reach
    assert np.allclose(np.array(sample.feasible), np.array(expected_xi), rtol=0, atol=1e-12)
    assert sample.reason is None


@pytest.mark.parametrize("configuration", ["left", "right"])
def test_hand_checkable_condition_iv(configuration):
    l1 = l2 = 1.0
    d = -0.5
    c = math.sqrt(l1**2 - d**2)
    finger, rect, pose, edge, frame = vertical_line_case(d, configuration)
    sign = 1 if configuration == "left" else -1
    expected_s = (l2 - c, l2 + c) if sign > 0 else (-l2 - c, -l2 + c)
    s_probe = np.array([0.5 * sum(expected_s), expected_s[0] - 0.01, expected_s[1] + 0.01])
    reach, feas = oracle(frame, s_probe + frame["xi_foot"], l1, l2, sign)
    assert reach.tolist() == [True, False, False]
    assert not feas.any()  # joint 1 is inside the rectangle: link 1 always collides
    sample = FingerEnvelope(finger, rect, edge).at(pose)
    assert sample.condition is Condition.IV
    expected_xi = (expected_s[0] + frame["xi_foot"], expected_s[1] + frame["xi_foot"])
    assert len(sample.reachable) == 1
    assert sample.reachable[0] == pytest.approx(expected_xi, abs=1e-12)
    assert sample.feasible == ()
    assert sample.reason == "collision"


# --------------------------------------------------------------------------- 4. exactness
def bisect_transition(pred, a: float, b: float, tol: float = 1e-12) -> float:
    fa = pred(a)
    assert pred(b) != fa
    while b - a > tol:
        m = 0.5 * (a + b)
        if pred(m) == fa:
            a = m
        else:
            b = m
    return 0.5 * (a + b)


def exactness_seeds() -> list[tuple[int, str]]:
    """A few cases with collision cuts and a few with two-piece reachable sets."""
    cut, two = [], []
    for seed, conf in CASES[:160]:
        ev = evaluate(seed, conf)
        if ev["feas_bf"] and total(ev["on_edge_bf"]) - total(ev["feas_bf"]) > 10 * ev["h"]:
            cut.append((seed, conf))
        elif len(ev["reach_bf"]) >= 2:
            two.append((seed, conf))
    return cut[:6] + two[:4]


@pytest.mark.parametrize("seed,configuration", exactness_seeds())
def test_ideal_ends_are_exact(seed, configuration):
    ev = evaluate(seed, configuration)
    s, fr, case, h = ev["sample"], ev["frame"], ev["case"], ev["h"]
    l1, l2, sign = case["l1"], case["l2"], ev["sign"]
    edge_len = case["polygon"].edge(case["edge"]).length
    checked = collision_ends = 0
    other_ends = np.array([*s.edge_range, *(x for iv in s.reachable for x in iv)])
    for which, intervals in ((0, s.reachable), (1, s.feasible)):
        def pred(x, which=which):
            return bool(oracle(fr, np.array([x]), l1, l2, sign)[which][0])

        for lo, hi in intervals:
            if hi - lo < 4 * h:
                continue
            for end, inside in ((lo, lo + 2 * h), (hi, hi - 2 * h)):
                outside = 2 * end - inside
                if not pred(inside) or pred(outside):
                    continue  # another transition within two grid steps: not a clean bracket
                ref = bisect_transition(pred, min(inside, outside), max(inside, outside))
                assert abs(end - ref) <= 1e-9 * edge_len, (
                    f"{'feasible' if which else 'reachable'} end {end!r} vs bisection {ref!r} "
                    f"(diff {abs(end - ref):.3g}, edge length {edge_len:.3g})"
                )
                checked += 1
                if which == 1 and np.min(np.abs(other_ends - end)) > 1e-9:
                    collision_ends += 1  # set by link 1 passing a vertex
    assert checked >= 2
    cut = ev["feas_bf"] and total(ev["on_edge_bf"]) - total(ev["feas_bf"]) > 10 * h
    if cut:
        assert collision_ends >= 1


def test_closed_form_reachable_set_matches_the_elbow_margin_classifier():
    """reachable_on_line's per-condition formulas against the sign of g(s) (docs/derivations.md):
    between consecutive candidate ends (annulus radii and second-link-on-line points) the set
    membership must equal g(midpoint) >= 0, and the ends must be candidates."""
    import math

    from regrasp.envelope.line import elbow_margin, reachable_on_line

    rng = np.random.default_rng(20261121)
    for _ in range(20000):
        l1, l2 = rng.uniform(0.2, 2.0, size=2)
        d = rng.uniform(-1.1 * (l1 + l2), 1.1 * (l1 + l2))
        sign = int(rng.choice([-1, 1]))
        got = reachable_on_line(d, l1, l2, sign)
        outer2 = (l1 + l2) ** 2 - d * d
        if outer2 <= 0:
            assert got == ()
            continue
        big = math.sqrt(outer2)
        cuts = [-big, big]
        if (l1 - l2) ** 2 > d * d:
            cuts += [-math.sqrt((l1 - l2) ** 2 - d * d), math.sqrt((l1 - l2) ** 2 - d * d)]
        if abs(d) <= l1:
            c = math.sqrt(l1 * l1 - d * d)
            cuts += [c + l2, c - l2, -c + l2, -c - l2]
        cuts = sorted(x for x in cuts if -big <= x <= big)
        for lo, hi in zip(cuts[:-1], cuts[1:]):
            if hi - lo < 1e-9:
                continue
            mid = 0.5 * (lo + hi)
            inside = any(a <= mid <= b for a, b in got)
            assert inside == (elbow_margin(mid, d, l1, l2, sign) >= 0.0), (l1, l2, d, sign, got)
        for a, b in got:
            assert min(abs(a - x) for x in cuts) < 1e-12 and min(abs(b - x) for x in cuts) < 1e-12


# --------------------------------------------------------------------------- float fast paths
def test_float_helpers_match_numpy():
    """The envelope's float helpers reproduce numpy's linspace bit for bit, and wrap_angle's float path its numpy
    path."""
    from regrasp.core.planar import wrap_angle
    from regrasp.envelope.floats import linspace_floats

    rng = np.random.default_rng(7)
    for _ in range(2000):
        lo = rng.normal(0.0, 0.1)
        hi = lo + abs(rng.normal(0.0, 0.1)) * 10.0 ** rng.integers(-8, 1)
        num = int(rng.integers(2, 60))
        assert linspace_floats(lo, hi, num) == np.linspace(lo, hi, num).tolist()
    angles = np.concatenate([rng.uniform(-20.0, 20.0, 2000), np.pi * np.arange(-6, 7), [1e-300, -0.0]])
    for angle in angles.tolist():
        assert wrap_angle(angle) == float(wrap_angle(np.array([angle]))[0])


@pytest.mark.parametrize("bad", [[0.0, 0.1], [0.0, np.nan, 0.0], np.array([0.0, 0.1, np.inf]), "abc",
                                 np.zeros((1, 3))])
def test_pose_is_validated(bad):
    from regrasp.core.exceptions import InvalidParameterError

    case = make_case(0)
    finger = make_finger(case["l1"], case["l2"], case["base"], "left")
    env = FingerEnvelope(finger, case["polygon"], case["edge"])
    with pytest.raises(InvalidParameterError, match="pose_object_in_hand"):
        env.at(bad)
    # lists, tuples and float32 arrays are accepted like float64 arrays
    pose = case["pose"]
    ref = env.at(pose)
    for same in (pose.tolist(), tuple(pose.tolist())):
        assert env.at(same).feasible == ref.feasible
    assert env.at(pose.astype(np.float32)).condition is env.at(pose.astype(np.float32).astype(float)).condition


# --------------------------------------------------------------------------- the step-to-step tracker
THREE = Path(__file__).resolve().parents[2] / "examples" / "scenarios" / "paper_trajectory_2_three_fingers.toml"


@functools.lru_cache(maxsize=None)
def _three_fingers():
    return load_scenario(THREE)


def _urdf_envelopes(sc):
    return [FingerEnvelope(c.finger, sc.polygon, c.edge, geometry="urdf", tip_clearance=c.tip_clearance)
            for c in sc.contacts]


def _assert_same_envelope(tracker: EnvelopeTracker, tracked, fresh, fallback: bool):
    """Tracked vs fresh: the same pieces, ends within the bisection tolerance; a fallback is bitwise at()."""
    tol = tracker.envelope.urdf_tolerance * tracker.envelope.edge.length
    assert len(tracked.feasible) == len(fresh.feasible), (tracked.time, tracked.feasible, fresh.feasible)
    for (a, b), (c, e) in zip(tracked.feasible, fresh.feasible):
        assert abs(a - c) <= tol and abs(b - e) <= tol, (tracked.time, tracked.feasible, fresh.feasible)
    assert (tracked.reachable, tracked.reason, tracked.condition, tracked.d) == \
        (fresh.reachable, fresh.reason, fresh.condition, fresh.d)
    if fallback:
        assert tracked.feasible == fresh.feasible


def _follow(trackers, fresh_envelopes, poses, times) -> list[float]:
    """Update every tracker along the poses, compare with fresh at() at every step; the largest
    end deviation per finger as a fraction of its tolerance."""
    worst = [0.0] * len(trackers)
    for pose, t in zip(poses, times):
        for i, (tracker, env) in enumerate(zip(trackers, fresh_envelopes)):
            before = tracker.fallbacks
            tracked, fresh = tracker.update(pose, t), env.at(pose, t)
            _assert_same_envelope(tracker, tracked, fresh, tracker.fallbacks > before)
            tol = env.urdf_tolerance * env.edge.length
            for (a, b), (c, e) in zip(tracked.feasible, fresh.feasible):
                worst[i] = max(worst[i], abs(a - c) / tol, abs(b - e) / tol)
    return worst


def test_tracker_matches_fresh_envelopes_along_the_three_finger_trajectory():
    """One period of paper trajectory 2 at 1 kHz: every tracked sample has at()'s pieces, ends within
    the bisection tolerance, and the structure changes on the way force fallbacks."""
    sc = _three_fingers()
    traj = sc.trajectory
    times = np.arange(traj.t_start, traj.t_start + np.pi, 1e-3)
    trackers = [EnvelopeTracker(env) for env in _urdf_envelopes(sc)]
    worst = _follow(trackers, _urdf_envelopes(sc), [traj.pose(t) for t in times], times)
    assert max(worst) <= 1.0
    counts = sum((t.counts for t in trackers), Counter())
    assert counts["tracked"] >= 0.95 * 3 * times.size  # the fast path is what was tested
    assert counts["structure"] + counts["piece end"] > 0  # pieces changed on the way: fallbacks


@pytest.mark.parametrize("seed", range(6))
def test_tracker_matches_fresh_envelopes_on_random_pose_sequences(seed):
    """Seeded random walks of the object around the trajectory, with occasional jumps: the same
    equality at every step; jumps force fallbacks."""
    rng = np.random.default_rng(seed)
    sc = _three_fingers()
    trackers = [EnvelopeTracker(env) for env in _urdf_envelopes(sc)]
    X = sc.trajectory.pose(rng.uniform(0.0, np.pi))
    v = rng.normal(size=3) * np.array([2e-4, 2e-4, 2e-3])
    poses = []
    for k in range(200):
        if k in (60, 140):
            X = X + rng.normal(size=3) * np.array([3e-3, 3e-3, 3e-2])  # a jump
        v = 0.95 * v + rng.normal(size=3) * np.array([4e-5, 4e-5, 4e-4])
        X = X + v
        poses.append(X)
    worst = _follow(trackers, _urdf_envelopes(sc), poses, 1e-3 * np.arange(len(poses)))
    assert max(worst) <= 1.0
    counts = sum((t.counts for t in trackers), Counter())
    assert counts["tracked"] > counts["closed form"]
    assert counts["pose jump"] > 0  # the jumps fell back


def test_tracker_falls_back_on_a_pose_jump_a_reset_and_the_first_call():
    sc = _three_fingers()
    env = _urdf_envelopes(sc)[0]
    tracker = EnvelopeTracker(_urdf_envelopes(sc)[0], max_pose_step=1e-3)
    X = sc.trajectory.pose(0.3)
    for pose, reason in ((X, "first call"), (X + [1e-4, 0.0, 0.0], "tracked"), (X + [2e-3, 0.0, 0.0], "pose jump"),
                         (X + [2e-3, 0.0, 0.0], "tracked"), (X + [2e-3, 0.0, 0.02], "pose jump")):
        before = tracker.counts[reason]
        sample = tracker.update(pose, 0.1)
        assert tracker.counts[reason] == before + 1
        _assert_same_envelope(tracker, sample, env.at(pose, 0.1), reason != "tracked")
        assert tracker.last is sample
    tracker.reset()
    assert tracker.last is None
    tracker.update(X, 0.2)
    assert tracker.counts["first call"] == 2
    assert tracker.fallbacks == 4


def test_tracker_of_an_ideal_envelope_is_at():
    sc = _three_fingers()
    c = sc.contacts[0]
    env = FingerEnvelope(c.finger, sc.polygon, c.edge)
    tracker = EnvelopeTracker(FingerEnvelope(c.finger, sc.polygon, c.edge))
    for t in np.linspace(0.0, 3.0, 7):
        fresh, tracked = env.at(sc.trajectory.pose(t), t), tracker.update(sc.trajectory.pose(t), t)
        assert (tracked.feasible, tracked.reachable, tracked.reason) == (fresh.feasible, fresh.reachable, fresh.reason)
    assert tracker.counts == Counter({"closed form": 7})


@pytest.mark.parametrize("kwargs", [{"envelope": "not an envelope"}, {"max_pose_step": 0.0},
                                    {"max_pose_step": np.nan}])
def test_tracker_rejects_bad_arguments(kwargs):
    sc = _three_fingers()
    args = {"envelope": _urdf_envelopes(sc)[0], **kwargs}
    with pytest.raises(InvalidParameterError):
        EnvelopeTracker(args.pop("envelope"), **args)


@pytest.mark.parametrize("pose, time", [([0.0, np.nan, 0.0], 0.0), ([0.0, 0.17], 0.0), ([0.0, 0.17, 0.0], np.inf)])
def test_tracker_rejects_bad_poses_and_times(pose, time):
    tracker = EnvelopeTracker(_urdf_envelopes(_three_fingers())[0])
    with pytest.raises(InvalidParameterError):
        tracker.update(pose, time)

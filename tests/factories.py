"""Shared test factories: seeded random fingers, convex polygons and envelope cases, and an
independent force oracle.

Used by tests/envelope/test_finger_envelope.py (brute-force oracle), tests/model/test_collision.py, and (``force_lp``,
the contact-force LP written from scratch) tests/schedule/test_force_polytope.py, tests/schedule/test_problem.py
and tests/schedule/test_planner.py.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import scipy.optimize
from scipy.spatial import ConvexHull

from regrasp.core.exceptions import PolygonError
from regrasp.core.polygon import ConvexPolygon
from regrasp.model.finger import Finger
from regrasp.model.finger_urdf import planar_2r_urdf


def rot(beta: float) -> np.ndarray:
    c, s = math.cos(beta), math.sin(beta)
    return np.array([[c, -s], [s, c]])


def perp2(v: np.ndarray) -> np.ndarray:
    return np.stack([-v[..., 1], v[..., 0]], axis=-1)


@functools.lru_cache(maxsize=None)
def _urdf(l1: float, l2: float, radius: float) -> str:
    return planar_2r_urdf(l1, l2, radius1=radius, radius2=radius)


def make_finger(l1: float, l2: float, base, configuration: str, radius: float | None = None) -> Finger:
    """A generated 2R finger; link radius ``radius`` [m] (default 0.1 × the shorter link)."""
    radius = 0.1 * min(l1, l2) if radius is None else radius
    return Finger.from_urdf_string(_urdf(l1, l2, radius), base_in_hand=tuple(base), configuration=configuration)


def random_polygon(rng: np.random.Generator, size: float) -> ConvexPolygon:
    """A random convex polygon of diameter ``size`` whose object origin is not its centroid."""
    while True:
        if rng.random() < 0.5:  # hull of random points
            pts = rng.uniform(-1.0, 1.0, size=(int(rng.integers(3, 13)), 2)) * rng.uniform(0.3, 1.0, size=2)
        else:  # jittered regular polygon
            n = int(rng.integers(3, 9))
            ang = rng.uniform(0, 2 * np.pi) + 2 * np.pi * np.arange(n) / n + rng.uniform(-0.3, 0.3, n) * np.pi / n
            pts = rng.uniform(0.7, 1.0, n)[:, None] * np.stack([np.cos(ang), np.sin(ang)], axis=1)
        try:
            verts = pts[ConvexHull(pts).vertices]
        except Exception:  # degenerate point set
            continue
        diam = np.max(np.linalg.norm(verts[:, None] - verts[None], axis=-1))
        verts = verts / diam * size
        verts = verts - verts.mean(axis=0) + rng.uniform(-0.25, 0.25, size=2) * size
        try:
            return ConvexPolygon.from_vertices(verts, mass=1.0, inertia=1.0)
        except PolygonError:
            continue


LENGTH_CLASSES = ("equal", "equal", "mild", "l2>2l1", "l1>2l2")
D_CLASSES = ("IV", "III", "II", "IV", "I", "IV", "II-far", "III", "IV", "II")


def make_case(seed: int) -> dict:
    """A seeded random (polygon, edge, object pose, finger base, l1, l2) with a target condition."""
    rng = np.random.default_rng(seed)
    lclass = LENGTH_CLASSES[seed % len(LENGTH_CLASSES)]
    dclass = D_CLASSES[(seed // len(LENGTH_CLASSES)) % len(D_CLASSES)]
    l1 = 0.1 * rng.uniform(0.5, 1.5)
    if lclass == "equal":
        l2 = l1
    elif lclass == "mild":
        l2 = l1 * rng.uniform(0.6, 1.6)
    elif lclass == "l2>2l1":
        l2 = l1 * rng.uniform(2.2, 3.5)
    else:
        l2, l1 = l1, l1 * rng.uniform(2.2, 3.5)
    reach = l1 + l2
    d = {
        "I": -l1 - rng.uniform(0.02, 1.3) * l2,
        "II": l1 + rng.uniform(0.02, 0.98) * l2,
        "II-far": reach * rng.uniform(1.01, 1.3),
        "III": rng.uniform(0.02, 0.98) * l1,
        "IV": -rng.uniform(0.02, 0.98) * l1,
    }[dclass]
    base = np.array([rng.uniform(-0.2, 0.2), rng.uniform(-0.2, 0.2), rng.uniform(-np.pi, np.pi)])
    o1 = base[:2]  # the generated URDF has an identity first joint origin
    targeted = dclass == "IV" and rng.random() < 0.8
    for _ in range(50):
        polygon = random_polygon(rng, reach * rng.uniform(0.4, 2.0))
        k = int(rng.integers(polygon.n_vertices))
        edge = polygon.edge(k)
        phi = rng.uniform(-np.pi, np.pi)  # hand-frame angle of the inward normal
        beta = phi - math.atan2(edge.inward_normal[1], edge.inward_normal[0])
        n_h = np.array([math.cos(phi), math.sin(phi)])
        t_h = perp2(n_h)
        if targeted:
            # in IV link 1 crosses the line at s in (-c, c) (c = sqrt(l1² - d²)); put the edge's
            # near end there, on one side, so that link 1 passes near its vertex (collision cuts)
            c = math.sqrt(l1 * l1 - d * d)
            s_mid = rng.choice([-1.0, 1.0]) * (0.5 * edge.length + rng.uniform(0.0, 0.9) * c)
        else:
            s_mid = rng.uniform(-0.8, 0.8) * reach
        mid_obj = 0.5 * (edge.start + edge.end)
        xy = o1 + d * n_h + s_mid * t_h - rot(beta) @ mid_obj
        pose = np.array([xy[0], xy[1], beta])
        verts = xy + polygon.vertices @ rot(beta).T
        edges = np.roll(verts, -1, axis=0) - verts
        o1_inside = np.all(edges[:, 0] * (o1[1] - verts[:, 1]) - edges[:, 1] * (o1[0] - verts[:, 0]) > 0)
        if not (targeted and o1_inside):  # targeted cases keep joint 1 outside the object
            break
    return dict(seed=seed, l1=l1, l2=l2, lclass=lclass, dclass=dclass, polygon=polygon, edge=k,
                pose=pose, base=base)


def force_lp(polygon, edges, pose, acc, xi, ratios, mu_s, limits, gravity, *, maximise_margin=False):
    """Whether contact forces hold the object at ``pose`` with acceleration ``acc`` [m/s², rad/s²]
    and contacts at ``xi`` [m] on ``edges``: an LP in the hand-frame forces f = (f_1x, f_1y, ...),
    Newton-Euler written here, every normal force in [f_min, f_max] (``limits``), a contact with
    ``ratios[i]`` = r on its cone edge t.f = r n.f, the others inside their static cones
    (``mu_s`` less ``limits.friction_margin``) by ``limits.cone_margin``. With ``maximise_margin``: the largest
    smallest such cone margin [N] (None when infeasible)."""
    m = len(edges)
    R = rot(pose[2])
    rows_eq, rhs_eq, rows_ub, rhs_ub = [], [], [], []
    mass, inertia = polygon.mass, polygon.inertia
    wrench = [mass * (acc[0] - gravity[0]), mass * (acc[1] - gravity[1]), inertia * acc[2]]
    lever, normal, tangent = [], [], []
    # the least normal forces: a contact on a cone edge pushes with slider_floor, and while one is, the fixed ones
    # with holder_preload (each at least f_min)
    moving = any(r is not None for r in ratios)
    floors = [max(limits.f_min, limits.slider_floor if r is not None else
                  (limits.holder_preload if moving else 0.0)) for r in ratios]
    for k, x in zip(edges, xi):
        e = polygon.edge(k)
        point, inward = (e.local(x).point, e.local(x).normal) if getattr(e, "curved", False) else \
            (e.point(x), e.inward_normal)  # (on a curve: the point and normal at ξ)
        lever.append(R @ point)
        normal.append(R @ inward)
        tangent.append(R @ np.array([-inward[1], inward[0]]))
    for axis in range(2):  # Σ f_i = m (a - g)
        row = np.zeros(2 * m + 1)
        row[axis:2 * m:2] = 1.0
        rows_eq.append(row)
    row = np.zeros(2 * m + 1)  # Σ r_i × f_i = I α
    for i, r in enumerate(lever):
        row[2 * i], row[2 * i + 1] = -r[1], r[0]
    rows_eq.append(row)
    rhs_eq += wrench
    for i in range(m):
        n_row, t_row = np.zeros(2 * m + 1), np.zeros(2 * m + 1)
        n_row[2 * i:2 * i + 2], t_row[2 * i:2 * i + 2] = normal[i], tangent[i]
        rows_ub += [-n_row, n_row]  # floor <= n.f <= f_max
        rhs_ub += [-floors[i], limits.f_max]
        if ratios[i] is None:  # |t.f| <= mu n.f - c  (c the margin variable when maximising)
            for sign in (1.0, -1.0):
                row = sign * t_row - (mu_s[i] - getattr(limits, "friction_margin", 0.0)) * n_row
                row[-1] = 1.0 if maximise_margin else 0.0
                rows_ub.append(row)
                rhs_ub.append(0.0 if maximise_margin else -limits.cone_margin)
        else:
            row = t_row - ratios[i] * n_row
            rows_eq.append(row)
            rhs_eq.append(0.0)
    cost = np.zeros(2 * m + 1)
    bounds = [(None, None)] * (2 * m) + [(None, None) if maximise_margin else (0.0, 0.0)]
    if maximise_margin:
        cost[-1] = -1.0
    res = scipy.optimize.linprog(cost, A_ub=np.array(rows_ub), b_ub=rhs_ub, A_eq=np.array(rows_eq), b_eq=rhs_eq,
                                 bounds=bounds, method="highs")
    if maximise_margin:
        return -res.fun if res.status == 0 else None
    return res.status == 0


#: A start of the three-finger scenario (``paper_trajectory_2_three_fingers``) with finger 1 0.2 mm from its feasible
#: set's upper bound (-5 mm at t = 0), in its danger zone, so the paper's policy slides it at once (the §2 planner
#: suggests starts outside the danger zones): finger1, finger2, palm [m].
DANGER_START_THREE = (-0.0052, 0.00975, 0.00031)

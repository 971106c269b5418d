"""Independent checks of the ``urdf`` collision geometry of the envelope (paper Definition 2.2).

* ``urdf`` (coal, cylinders of radius r) converges to ``ideal`` (segments) as r → 0 at a fixed
  tip clearance ρ, linearly in r; the urdf feasible set is inside the ideal one (also on the
  random cases of tests/factories.py, where it is also compared pointwise with own coal).
* The library's urdf interval ends agree with an own bisection that builds the link
  cylinders directly in coal from the joint positions of an own inverse kinematics.
* The tip clearance is what makes contact possible at all; a finger without collision
  geometry is rejected in ``urdf`` mode.
"""

from __future__ import annotations

import math

import coal
import numpy as np
import pinocchio as pin
import pytest

from factories import make_case
from factories import make_finger as make_random_finger
from regrasp.core.exceptions import FingerModelError
from regrasp.core.planar import se3_from_planar
from regrasp.core.polygon import ConvexPolygon
from regrasp.envelope.finger_envelope import Condition, FingerEnvelope
from regrasp.model.finger import Finger
from regrasp.model.finger_urdf import planar_2r_urdf

RHO = 0.01  # fixed tip clearance [m]
RADII = (4e-3, 1e-3, 2.5e-4)  # link radii [m], links ~0.1 m
URDF_TOL = 1e-4  # documented urdf bisection tolerance, times the edge length
SEEDS = range(8)


# --------------------------------------------------------------------------- scenario
def rot(beta: float) -> np.ndarray:
    c, s = math.cos(beta), math.sin(beta)
    return np.array([[c, -s], [s, c]])


def scenario(seed: int) -> dict:
    """A rectangle above two fingers, each touching the near side from below (condition IV).

    Left finger: base (-b, 0), left configuration, edge 1 (the left side); right finger:
    base (+b, 0), right configuration, edge 3. The sides are outside the bases (d < 0), so
    link 1 must pass below the lower vertex: contacts high on the side make it hit the object.
    """
    rng = np.random.default_rng(1000 + seed)
    l1, l2 = 0.1 * rng.uniform(0.9, 1.1), 0.1 * rng.uniform(0.9, 1.1)
    b = 0.05 * rng.uniform(0.8, 1.2)
    width = 2.0 * (b + rng.uniform(0.02, 0.04))
    height = rng.uniform(0.15, 0.19)
    bottom = rng.uniform(0.01, 0.04)
    rect = ConvexPolygon.rectangle(width, height, mass=0.2, inertia=1e-3)
    pose = np.array([rng.uniform(-0.005, 0.005), bottom + 0.5 * height, rng.uniform(-0.1, 0.1)])
    theta = rng.uniform(-np.pi, np.pi, size=2)  # base orientations: irrelevant to the geometry
    return dict(l1=l1, l2=l2, b=b, rect=rect, pose=pose,
                fingers={"left": ((-b, 0.0, theta[0]), 1), "right": ((b, 0.0, theta[1]), 3)})


def make_finger(sc: dict, side: str, radius: float) -> Finger:
    base, _ = sc["fingers"][side]
    urdf = planar_2r_urdf(sc["l1"], sc["l2"], radius1=radius, radius2=radius)
    return Finger.from_urdf_string(urdf, base_in_hand=base, configuration=side)


def envelope(sc: dict, side: str, radius: float, geometry: str, tip_clearance=RHO):
    finger = make_finger(sc, side, radius)
    edge = sc["fingers"][side][1]
    kwargs = {"tip_clearance": tip_clearance} if geometry == "urdf" else {}
    return FingerEnvelope(finger, sc["rect"], edge, geometry=geometry, **kwargs).at(sc["pose"])


# --------------------------------------------------------------------------- own kinematics
def tip_of(sc: dict, side: str, xi: float) -> np.ndarray:
    """Hand-frame point of parameter ξ on the contact edge (the sanctioned parametrisation)."""
    edge = sc["rect"].edge(sc["fingers"][side][1])
    return sc["pose"][:2] + rot(sc["pose"][2]) @ edge.point(xi)


def own_ik(o1: np.ndarray, tip: np.ndarray, l1: float, l2: float, sign: int) -> np.ndarray:
    """Elbow position by acos/atan2 (left: θ2 = -acos(...) ∈ (-π, 0))."""
    v = tip - o1
    r2 = float(v @ v)
    assert (l1 - l2) ** 2 <= r2 * (1 + 1e-12) and r2 <= (l1 + l2) ** 2 * (1 + 1e-12)
    theta2 = -sign * math.acos(max(-1.0, min(1.0, (r2 - l1 * l1 - l2 * l2) / (2 * l1 * l2))))
    psi1 = math.atan2(v[1], v[0]) - math.atan2(l2 * math.sin(theta2), l1 + l2 * math.cos(theta2))
    return o1 + l1 * np.array([math.cos(psi1), math.sin(psi1)])


def vertex_offset(sc: dict, side: str, xi: float) -> tuple[float, np.ndarray]:
    """Signed distance of the nearest object vertex within l1 from the line of link 1 at ξ."""
    base, _ = sc["fingers"][side]
    o1 = np.array(base[:2])
    sign = 1 if side == "left" else -1
    elbow = own_ik(o1, tip_of(sc, side, xi), sc["l1"], sc["l2"], sign)
    u = (elbow - o1) / np.linalg.norm(elbow - o1)
    verts = sc["pose"][:2] + sc["rect"].vertices @ rot(sc["pose"][2]).T
    near = [v for v in verts if np.linalg.norm(v - o1) <= sc["l1"]]
    offs = [u[0] * (v - o1)[1] - u[1] * (v - o1)[0] for v in near]
    k = int(np.argmin(np.abs(offs)))
    return offs[k], near[k]


def ends(intervals) -> np.ndarray:
    return np.array([x for iv in intervals for x in iv])


def hausdorff(a, b) -> float:
    ea, eb = ends(a), ends(b)
    if ea.size == 0 or eb.size == 0:
        return 0.0 if ea.size == eb.size else math.inf
    dist = np.abs(ea[:, None] - eb[None, :])
    return float(max(dist.min(axis=1).max(), dist.min(axis=0).max()))


def collision_end(sc: dict, side: str, ideal) -> float:
    """The ideal feasible end set by link 1 passing through a vertex (not an edge/reach end)."""
    s = ideal
    edge_ends = np.array(s.edge_range)
    reach_ends = ends(s.reachable)
    cands = [x for x in ends(s.feasible)
             if np.min(np.abs(edge_ends - x)) > 1e-9 and np.min(np.abs(reach_ends - x)) > 1e-9]
    assert len(cands) == 1, (s.feasible, s.edge_range, s.reachable)
    return cands[0]


# --------------------------------------------------------------------------- 1. convergence
@pytest.mark.parametrize("side", ["left", "right"])
@pytest.mark.parametrize("seed", SEEDS)
def test_urdf_converges_to_ideal(seed, side):
    sc = scenario(seed)
    ideal = envelope(sc, side, RADII[-1], "ideal")
    assert ideal.condition is Condition.IV
    edge_len = sc["rect"].edge(sc["fingers"][side][1]).length
    tol = URDF_TOL * edge_len
    # collisions matter: link 1 passing a vertex cuts the ideal feasible set inside the edge
    xi_star = collision_end(sc, side, ideal)
    on_edge = sum(min(hi, ideal.edge_range[1]) - max(lo, ideal.edge_range[0]) for lo, hi in ideal.reachable
                  if min(hi, ideal.edge_range[1]) > max(lo, ideal.edge_range[0]))
    assert sum(hi - lo for lo, hi in ideal.feasible) < on_edge - 0.05 * edge_len
    # at ξ*, link 1's line passes through a vertex; its distance changes at rate |f'| per unit ξ,
    # so a link of radius r first touches that vertex about r / |f'| away from ξ*
    off, _ = vertex_offset(sc, side, xi_star)
    assert abs(off) < 1e-9
    hstep = 1e-6
    rate = abs(vertex_offset(sc, side, xi_star + hstep)[0] - vertex_offset(sc, side, xi_star - hstep)[0]) / (2 * hstep)
    assert rate > 0.05
    errors = []
    for r in RADII:
        urdf = envelope(sc, side, r, "urdf")
        err = hausdorff(urdf.feasible, ideal.feasible)
        errors.append(err)
        # urdf-feasible ⊂ ideal-feasible: fat links collide wherever segments do
        for lo, hi in urdf.feasible:
            assert any(lo >= a - tol and hi <= b + tol for a, b in ideal.feasible), (urdf.feasible, ideal.feasible)
        if r <= 1e-3:  # in these scenarios the flat-end rim dip (tan α < r/ρ) no longer occurs
            # and only link 1's radius moves the end: bounded by a constant (1.25 / rate) times r
            assert len(urdf.feasible) == len(ideal.feasible), (r, urdf.feasible, ideal.feasible)
            assert err <= 1.25 * r / rate + tol, (r, err, r / rate)
    # the distance between the urdf and ideal ends (Hausdorff) decreases with r (r / 4 each step)
    for big, small in zip(errors[:-1], errors[1:]):
        assert small <= 0.5 * big + tol, errors
    # and the urdf set is genuinely different (fat link), shrinking like r / rate
    assert errors[-1] >= 0.75 * RADII[-1] / rate - tol, (errors, RADII[-1] / rate)


# --------------------------------------------------------------------------- 1b. random cases
@pytest.mark.parametrize("seed", range(0, 200, 2))
def test_urdf_inside_ideal_on_random_cases(seed):
    """Fat links collide wherever the segments do, so urdf-feasible ⊂ ideal-feasible (any case)."""
    case = make_case(seed)
    for conf in ("left", "right"):
        radius = 0.02 * min(case["l1"], case["l2"])
        finger = make_random_finger(case["l1"], case["l2"], case["base"], conf, radius=radius)
        ideal = FingerEnvelope(finger, case["polygon"], case["edge"]).at(case["pose"])
        urdf = FingerEnvelope(finger, case["polygon"], case["edge"], geometry="urdf").at(case["pose"])
        assert urdf.reachable == ideal.reachable and urdf.condition is ideal.condition
        tol = URDF_TOL * case["polygon"].edge(case["edge"]).length
        for lo, hi in urdf.feasible:
            assert any(lo >= a - tol and hi <= b + tol for a, b in ideal.feasible), (
                conf, urdf.feasible, ideal.feasible)


@pytest.mark.parametrize("seed", range(1, 200, 10))
def test_urdf_matches_own_coal_on_random_cases(seed):
    """Pointwise, away from its ends, the urdf feasible set is what an own coal model says."""
    case = make_case(seed)
    for conf in ("left", "right"):
        radius = 0.02 * min(case["l1"], case["l2"])
        finger = make_random_finger(case["l1"], case["l2"], case["base"], conf, radius=radius)
        urdf = FingerEnvelope(finger, case["polygon"], case["edge"], geometry="urdf").at(case["pose"])
        assert urdf.edge_range == case["polygon"].edge(case["edge"]).xi_range
        sc = dict(l1=case["l1"], l2=case["l2"], rect=case["polygon"], pose=case["pose"],
                  fingers={conf: (tuple(case["base"]), case["edge"])})
        tol = URDF_TOL * case["polygon"].edge(case["edge"]).length
        urdf_ends = ends(urdf.feasible)
        for lo, hi in urdf.reachable:
            lo, hi = max(lo, urdf.edge_range[0]), min(hi, urdf.edge_range[1])
            for xi in np.linspace(lo, hi, 25)[1:-1] if hi > lo else ():
                if urdf_ends.size and np.min(np.abs(urdf_ends - xi)) <= 2 * tol:
                    continue
                inside = any(a <= xi <= b for a, b in urdf.feasible)
                assert inside == (not own_coal_collides(sc, conf, radius, 3 * radius, xi)), (conf, xi, urdf.feasible)


# --------------------------------------------------------------------------- 2. urdf accuracy with coal
def z_to(direction: np.ndarray) -> np.ndarray:
    """Rotation taking the local z axis (coal cylinder axis) to the planar unit ``direction``."""
    phi = math.atan2(direction[1], direction[0])
    ry = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])  # R_y(pi/2): z -> x
    rz = np.eye(3)
    rz[:2, :2] = rot(phi)
    return rz @ ry


def own_coal_collides(sc: dict, side: str, radius: float, rho: float, xi: float) -> bool:
    """Link cylinders (link 2 shortened by rho at the tip) vs the object prism, with coal."""
    base, _ = sc["fingers"][side]
    o1 = np.array(base[:2])
    sign = 1 if side == "left" else -1
    tip = tip_of(sc, side, xi)
    elbow = own_ik(o1, tip, sc["l1"], sc["l2"], sign)
    u1 = (elbow - o1) / np.linalg.norm(elbow - o1)
    u2 = (tip - elbow) / np.linalg.norm(tip - elbow)
    cyl1 = coal.Cylinder(radius, sc["l1"])
    c1 = o1 + 0.5 * sc["l1"] * u1
    cyl2 = coal.Cylinder(radius, sc["l2"] - rho)
    c2 = elbow + 0.5 * (sc["l2"] - rho) * u2
    prism = sc["rect"].to_coal(0.5)
    obj_rot = np.eye(3)
    obj_rot[:2, :2] = rot(sc["pose"][2])
    obj = pin.SE3(obj_rot, np.array([sc["pose"][0], sc["pose"][1], 0.0]))
    req = coal.DistanceRequest()
    req.enable_signed_distance = True
    dists = []
    for geom, centre, u in ((cyl1, c1, u1), (cyl2, c2, u2)):
        res = coal.DistanceResult()
        placement = pin.SE3(z_to(u), np.array([centre[0], centre[1], 0.0]))
        dists.append(coal.distance(geom, placement, prism, obj, req, res))
    return min(dists) < 0.0


@pytest.mark.parametrize("side", ["left", "right"])
@pytest.mark.parametrize("seed", SEEDS[:3])
def test_urdf_end_matches_own_coal_bisection(seed, side):
    sc = scenario(seed)
    r = 1e-3
    urdf = envelope(sc, side, r, "urdf")
    ideal = envelope(sc, side, r, "ideal")
    edge_len = sc["rect"].edge(sc["fingers"][side][1]).length
    xi_star = collision_end(sc, side, ideal)
    # the urdf end that corresponds to the ideal collision end
    end = min(ends(urdf.feasible), key=lambda x: abs(x - xi_star))
    assert abs(end - xi_star) > 10 * URDF_TOL * edge_len  # it did move: the radius matters
    free_side = end + (1 if any(lo == end for lo, _ in urdf.feasible) else -1) * 0.02 * edge_len
    hit_side = 2 * end - free_side
    assert not own_coal_collides(sc, side, r, RHO, free_side)
    assert own_coal_collides(sc, side, r, RHO, hit_side)
    a, b = free_side, hit_side
    while abs(b - a) > 1e-10:
        m = 0.5 * (a + b)
        if own_coal_collides(sc, side, r, RHO, m):
            b = m
        else:
            a = m
    assert abs(end - 0.5 * (a + b)) <= URDF_TOL * edge_len, (end, 0.5 * (a + b))
    # the library closes its interval on the free side: its end is itself a feasible contact
    assert not own_coal_collides(sc, side, r, RHO, end)


# --------------------------------------------------------------------------- 3. tip clearance and models
@pytest.mark.parametrize("side", ["left", "right"])
@pytest.mark.parametrize("seed", SEEDS[:3])
def test_tip_clearance_is_needed(seed, side):
    sc = scenario(seed)
    r = 1e-3
    edge_len = sc["rect"].edge(sc["fingers"][side][1]).length
    none = envelope(sc, side, r, "urdf", tip_clearance=0.0)
    some = envelope(sc, side, r, "urdf", tip_clearance=RHO)
    # without clearance the distal link's flat end straddles the edge at every contact
    assert sum(hi - lo for lo, hi in none.feasible) <= 2 * URDF_TOL * edge_len, none.feasible
    if not none.feasible:
        assert none.reason == "collision"
    assert sum(hi - lo for lo, hi in some.feasible) > 0.2 * edge_len
    assert some.reason is None
    # own coal check at a feasible contact: colliding with rho = 0, free with rho
    lo, hi = max(some.feasible, key=lambda iv: iv[1] - iv[0])
    mid = 0.5 * (lo + hi)
    assert own_coal_collides(sc, side, r, 0.0, mid)
    assert not own_coal_collides(sc, side, r, RHO, mid)


def test_default_tip_clearance_is_three_distal_radii():
    sc = scenario(0)
    finger = Finger.from_urdf_string(planar_2r_urdf(sc["l1"], sc["l2"], radius1=0.004, radius2=0.003),
                                     base_in_hand=(-sc["b"], 0.0, 0.0), configuration="left")
    env = FingerEnvelope(finger, sc["rect"], 1, geometry="urdf")
    assert env.tip_clearance == pytest.approx(0.009, abs=1e-15)
    assert FingerEnvelope(finger, sc["rect"], 1).tip_clearance is None


def _urdf_without_collision(with_link1_collision: bool) -> str:
    link1_collision = (
        '<collision><origin xyz="0.05 0 0" rpy="0 1.5707963267948966 0"/>'
        '<geometry><cylinder radius="0.005" length="0.1"/></geometry></collision>'
        if with_link1_collision else ""
    )
    return f"""<?xml version="1.0"?>
<robot name="bare_finger">
  <link name="base"/>
  <joint name="joint1" type="revolute">
    <parent link="base"/><child link="link1"/>
    <origin xyz="0 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3.14" upper="3.14" effort="5" velocity="20"/>
  </joint>
  <link name="link1">
    <inertial><origin xyz="0.05 0 0"/><mass value="0.05"/>
      <inertia ixx="1e-6" ixy="0" ixz="0" iyy="5e-5" iyz="0" izz="5e-5"/></inertial>
    <visual><origin xyz="0.05 0 0" rpy="0 1.5707963267948966 0"/>
      <geometry><cylinder radius="0.005" length="0.1"/></geometry></visual>
    {link1_collision}
  </link>
  <joint name="joint2" type="revolute">
    <parent link="link1"/><child link="link2"/>
    <origin xyz="0.1 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3.14" upper="3.14" effort="5" velocity="20"/>
  </joint>
  <link name="link2">
    <inertial><origin xyz="0.05 0 0"/><mass value="0.05"/>
      <inertia ixx="1e-6" ixy="0" ixz="0" iyy="5e-5" iyz="0" izz="5e-5"/></inertial>
    <visual><origin xyz="0.05 0 0" rpy="0 1.5707963267948966 0"/>
      <geometry><cylinder radius="0.005" length="0.1"/></geometry></visual>
  </link>
  <joint name="tip_joint" type="fixed">
    <parent link="link2"/><child link="tip"/><origin xyz="0.1 0 0" rpy="0 0 0"/>
  </joint>
  <link name="tip"/>
</robot>
"""


@pytest.mark.parametrize("with_link1_collision", [False, True])
def test_urdf_mode_needs_collision_geometry(with_link1_collision):
    sc = scenario(0)
    finger = Finger.from_urdf_string(_urdf_without_collision(with_link1_collision),
                                     base_in_hand=(-sc["b"], 0.0, 0.0), configuration="left")
    assert finger.link_lengths == pytest.approx((0.1, 0.1))
    with pytest.raises(FingerModelError, match="no collision geometry"):
        FingerEnvelope(finger, sc["rect"], 1, geometry="urdf", tip_clearance=RHO)
    # the ideal mode does not need collision shapes
    sample = FingerEnvelope(finger, sc["rect"], 1).at(sc["pose"])
    assert sample.condition is Condition.IV
    assert sample.feasible


def test_default_tip_clearance_for_a_box_distal_link():
    """A box-shaped distal link gets a non-zero default clearance (3 x its middle half-side), so
    its end face does not straddle the edge and the urdf envelope is not empty."""
    from regrasp import ConvexPolygon, Finger, FingerEnvelope
    from regrasp.model.finger_urdf import planar_2r_urdf

    box = '<geometry><box size="0.045 0.010 0.008"/></geometry>'
    text = planar_2r_urdf(0.12, 0.045, radius1=0.006, radius2=0.005)
    head, tail = text.split('<link name="link2">')
    tail = tail.replace('<geometry><cylinder radius="0.005" length="0.045"/></geometry>', box)
    tail = tail.replace('rpy="0 1.5707963267948966 0"', 'rpy="0 0 0"')
    finger = Finger.from_urdf_string(head + '<link name="link2">' + tail, base_in_hand=(-0.05, 0.0, np.pi / 2))
    rect = ConvexPolygon.rectangle(0.10, 0.04, mass=0.08)
    env = FingerEnvelope(finger, rect, 1, geometry="urdf")
    assert env.tip_clearance == pytest.approx(3 * 0.005)
    sample = env.at(np.array([0.03, 0.12, 0.0]))
    ideal = FingerEnvelope(finger, rect, 1).at(np.array([0.03, 0.12, 0.0]))
    assert (sample.feasible
            and sample.feasible[0][1] - sample.feasible[0][0] > 0.5 * (ideal.feasible[0][1] - ideal.feasible[0][0]))


# --------------------------------------------------------------------------- 4. the checker's fast paths
def pinocchio_coal_distances(checker, finger: Finger, q: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """Signed distances with the shapes placed by Pinocchio's forward kinematics (hand frame)."""
    pin.forwardKinematics(finger.model, finger.data, q)
    obj_rot = np.eye(3)
    obj_rot[:2, :2] = rot(pose[2])
    obj = pin.SE3(obj_rot, np.array([pose[0], pose[1], 0.0]))
    req = coal.DistanceRequest()
    req.enable_signed_distance = True
    out = []
    for shape in checker.shapes:
        placement = finger.data.oMi[shape.link + 1] * shape.placement_in_joint
        out.append(coal.distance(shape.geometry, placement, checker.object_geometry, obj, req, coal.DistanceResult()))
    return np.array(out)


def thin_finger_checkers(seed: int):
    """(case, finger, checker, reach l1 + l2 [m]) of seeded case ``seed`` for both configurations, links
    of radius 0.05 l1."""
    case = make_case(seed)
    for conf in ("left", "right"):
        finger = make_random_finger(case["l1"], case["l2"], case["base"], conf, radius=0.05 * case["l1"])
        yield case, finger, FingerEnvelope(finger, case["polygon"], case["edge"], geometry="urdf").checker, \
            case["l1"] + case["l2"]


@pytest.mark.parametrize("seed", range(0, 200, 20))
def test_planar_signed_distances_match_pinocchio_placements(seed):
    """The checker places each shape with the planar link frames (no Pinocchio per query) and
    tests it against the object expressed in that frame; coal's distances agree with shapes
    placed by Pinocchio's forward kinematics (to coal's own tolerance), and so do the verdicts."""
    rng = np.random.default_rng(seed)
    for case, finger, checker, scale in thin_finger_checkers(seed):
        for _ in range(20):
            q = rng.uniform(-np.pi, np.pi, size=2)
            pose = case["pose"] + rng.normal(0.0, 0.3 * scale, size=3)
            ref = pinocchio_coal_distances(checker, finger, q, pose)
            got = checker.signed_distances(q, pose)
            assert np.allclose(got, ref, rtol=0.0, atol=1e-5 * scale), (got, ref)
            if abs(ref.min()) > 1e-5 * scale:  # (each call starts afresh: no stale certificates)
                assert checker.collides(q, pose) == (ref.min() < 0.0)
                far = pose + np.array([10.0 * scale, 0.0, 0.0])
                assert not checker.collides(q, far)  # certifies q free there, which must not carry over
                assert checker.collides(q, se3_from_planar(pose)) == (ref.min() < 0.0)


@pytest.mark.parametrize("seed", range(3, 200, 20))
def test_certified_free_postures_give_coal_verdicts(seed):
    """links_collide skips coal for a link that cannot have reached the object since its last
    coal distance; along sweeps and jumps its verdicts equal fresh coal verdicts."""
    case = make_case(seed)
    rng = np.random.default_rng(seed)
    for conf in ("left", "right"):
        finger = make_random_finger(case["l1"], case["l2"], case["base"], conf, radius=0.05 * case["l1"])
        checker = FingerEnvelope(finger, case["polygon"], case["edge"], geometry="urdf").checker
        pose = case["pose"]
        q, step = rng.uniform(-np.pi, np.pi, size=2), rng.normal(0.0, 0.5, size=2)
        postures = [q + t * step for t in np.linspace(0.0, 1.0, 60)]  # a sweep
        postures += [q + rng.normal(0.0, 0.05, size=2) for _ in range(20)]  # small jumps
        postures += [rng.uniform(-np.pi, np.pi, size=2) for _ in range(20)]  # large jumps
        checker.set_object_pose(*pose)
        stateful = [checker.links_collide(*checker.link_frames(p)[2:].tolist()) for p in postures]
        fresh = [checker.collides(p, pose) for p in postures]  # resets the certificates each time
        assert stateful == fresh


@pytest.mark.parametrize("seed", range(7, 200, 20))
def test_kept_certificates_give_coal_verdicts_while_the_object_moves(seed):
    """links_collide_kept certifies free and colliding links across object poses; along joint sweeps
    with the object drifting and jumping, its verdicts equal fresh coal verdicts."""
    rng = np.random.default_rng(seed)
    for case, _, checker, scale in thin_finger_checkers(seed):
        q, q_step = rng.uniform(-np.pi, np.pi, size=2), rng.normal(0.0, 0.01, size=2)
        pose, pose_step = np.array(case["pose"], float), rng.normal(0.0, 1e-3, size=3) * [scale, scale, 1.0]
        kept = [None, None]
        coal_calls = 0
        for k in range(150):
            if k % 50 == 49:
                pose = pose + rng.normal(0.0, 0.05, size=3) * [scale, scale, 1.0]  # a jump
            q, pose = q + q_step, pose + pose_step
            checker.set_object_pose(*pose)
            before = [c for c in kept]
            verdict = checker.links_collide_kept(kept, *checker.link_frames(q)[2:].tolist())
            coal_calls += sum(a is not b for a, b in zip(before, kept))
            assert verdict == checker.collides(q, pose)  # fresh certificates each time
        assert coal_calls < 2 * 150  # (the certificates were used)


@pytest.mark.parametrize("seed", range(5, 200, 10))
def test_urdf_envelope_without_certificates_is_identical(seed):
    """Disabling the checker's certified-free shortcut (every query calls coal) changes nothing."""
    case = make_case(seed)
    for conf in ("left", "right"):
        finger = make_random_finger(case["l1"], case["l2"], case["base"], conf, radius=0.02 * case["l1"])
        fast = FingerEnvelope(finger, case["polygon"], case["edge"], geometry="urdf")
        slow = FingerEnvelope(finger, case["polygon"], case["edge"], geometry="urdf")
        slow.checker._margin = math.inf  # no certificate ever holds
        for shift in (0.0, 0.1, -0.1):
            pose = case["pose"] + shift * np.array([case["l1"], case["l2"], 1.0])
            a, b = fast.at(pose), slow.at(pose)
            assert (a.feasible, a.reachable, a.reason) == (b.feasible, b.reachable, b.reason)

"""The compiled ``urdf`` envelope (kernels/footprint.py, kernels/envelope.py) against coal and the reference path.

Tolerances. With coal's GJK and EPA tolerances at 1e-13 (``coal_tolerance``) its signed distances and the
closed-form ones agree to 1e-9 m (measured: 5e-11 m on the shipped fingers): both are then exact up to
rounding. At coal's default tolerance (1e-6) coal's own error reaches 1e-6 m (measured 1.0e-6 m), so
there only the verdicts are compared, away from contact (|distance| > 2e-6 m).

Envelope ends are compared with the reference path's (coal at 1e-13) within its documented accuracy, 1e-4
of the edge length (each end is within the bisection tolerance, 5e-5 of it, of its own verdict's flip);
measured on 6000 random samples: equal bitwise. Against the reference at coal's default tolerance the
pieces are the same, but where a link grazes the object (the distance hardly changes along the edge) coal's
1e-6 m moves a flip by up to 14 times that accuracy (measured), so only the pieces are compared there.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from factories import make_case, random_polygon
from factories import make_finger as make_random_finger
from regrasp import load_scenario
from regrasp.core.exceptions import InvalidParameterError
from regrasp.core.polygon import ConvexPolygon
from regrasp.envelope.finger_envelope import FingerEnvelope
from regrasp.kernels.footprint import footprint_distances
from regrasp.model.collision import UrdfCollisionChecker
from regrasp.model.finger import Finger

ROOT = Path(__file__).resolve().parents[2]
#: The shipped polygon scenarios (the compiled envelope takes edges; curved objects run the reference path).
SCENARIOS = sorted(p for p in (ROOT / "examples" / "scenarios").glob("*.toml")
                   if "shape =" not in p.read_text() and "corner_radius" not in p.read_text())
URDFS = sorted((ROOT / "urdf").glob("*.urdf"))
EXACT = 1e-9  # [m], both exact (coal at 1e-13)
COAL_DEFAULT = 2e-6  # [m], coal's error at its default tolerance, with a margin


def closed_form(checker: UrdfCollisionChecker, polygon: ConvexPolygon, q, pose) -> np.ndarray:
    """The footprints' signed distances at joint positions q."""
    normals = np.array([e.inward_normal for e in polygon.edges])
    out = np.empty(len(checker.shapes))
    footprint_distances(checker.footprints, np.ascontiguousarray(polygon.vertices), normals, checker.half_thickness,
                        np.asarray(pose, dtype=float), checker.link_frames(q), out)
    return out


def random_pose_near(rng, finger: Finger, polygon: ConvexPolygon) -> np.ndarray:
    """An object pose whose centre is within the finger's reach of joint 1 (links near or inside the object)."""
    reach = sum(finger.link_lengths)
    centre = finger.joint1_in_hand + rng.uniform(-1.0, 1.0, 2) * reach
    return np.array([*centre, rng.uniform(-np.pi, np.pi)])


def compare_with_coal(finger: Finger, polygon: ConvexPolygon, rng, samples: int, tip_clearance: float):
    """(largest |closed form - coal| [m] at 1e-13, verdict disagreements away from contact at coal's default)."""
    tight = UrdfCollisionChecker(finger, polygon, tip_clearance, coal_tolerance=1e-13)
    default = UrdfCollisionChecker(finger, polygon, tip_clearance)
    assert tight.footprints is not None
    worst, wrong = 0.0, 0
    for _ in range(samples):
        q = rng.uniform(-np.pi, np.pi, 2)
        pose = random_pose_near(rng, finger, polygon)
        mine = closed_form(tight, polygon, q, pose)
        assert np.all(mine > -tight.half_thickness)  # (never deeper than h: the closed form is exact)
        worst = max(worst, float(np.max(np.abs(mine - tight.signed_distances(q, pose)))))
        coal_default = default.signed_distances(q, pose)
        far = np.abs(coal_default) > COAL_DEFAULT
        wrong += int(np.sum((mine[far] < 0.0) != (coal_default[far] < 0.0)))
        assert np.max(np.abs(mine - coal_default)) <= COAL_DEFAULT
    return worst, wrong


@pytest.mark.parametrize("urdf", URDFS, ids=lambda p: p.stem)
def test_shipped_fingers_match_coal(urdf):
    rng = np.random.default_rng(11)
    polygon = ConvexPolygon.rectangle(0.10, 0.04, mass=0.1)
    for configuration in ("left", "right"):
        finger = Finger.from_urdf(urdf, base_in_hand=(0.01, -0.02, 0.4), configuration=configuration)
        for clearance in (0.0, 0.015):
            worst, wrong = compare_with_coal(finger, polygon, rng, 400, clearance)
            assert worst <= EXACT
            assert wrong == 0


# --------------------------------------------------------------------------- random shapes
BARE = ("""<?xml version="1.0"?>
<robot name="shapes">
  <link name="base"/>
  <joint name="joint1" type="revolute"><parent link="base"/><child link="link1"/>
    <origin xyz="0 0 0" rpy="0 0 {yaw1!r}"/><axis xyz="0 0 1"/>"""
        """<limit lower="-3.14" upper="3.14" effort="5" velocity="20"/>
  </joint>
  <link name="link1"><inertial><origin xyz="0.05 0 0"/><mass value="0.05"/>
    <inertia ixx="1e-6" ixy="0" ixz="0" iyy="5e-5" iyz="0" izz="5e-5"/></inertial>{link1}</link>
  <joint name="joint2" type="revolute"><parent link="link1"/><child link="link2"/>
    <origin xyz="{l1!r} 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/>"""
        """<limit lower="-3.14" upper="3.14" effort="5" velocity="20"/>
  </joint>
  <link name="link2"><inertial><origin xyz="0.04 0 0"/><mass value="0.05"/>
    <inertia ixx="1e-6" ixy="0" ixz="0" iyy="5e-5" iyz="0" izz="5e-5"/></inertial>{link2}</link>
  <joint name="tip_joint" type="fixed"><parent link="link2"/><child link="tip"/>"""
        """<origin xyz="{l2!r} 0 0" rpy="0 0 0"/></joint>
  <link name="tip"/>
</robot>
""")


def collision(xyz, rpy, geometry: str) -> str:
    return (f'<collision><origin xyz="{xyz[0]!r} {xyz[1]!r} {xyz[2]!r}" rpy="{rpy[0]!r} {rpy[1]!r} {rpy[2]!r}"/>'
            f'<geometry>{geometry}</geometry></collision>')


def random_shape(rng, length: float) -> str:
    """A box turned about z (or lying on a side), a cylinder with its axis in the plane, or a sphere centred in it."""
    xyz = (float(rng.uniform(0.0, length)), float(rng.uniform(-0.01, 0.01)), 0.0)
    yaw = float(rng.uniform(-np.pi, np.pi))
    kind = rng.integers(3)
    if kind == 0:
        size = rng.uniform(0.004, 0.05, 3).tolist()
        rpy = (0.0, 0.0, yaw) if rng.random() < 0.5 else (float(rng.choice([-1.0, 1.0])) * np.pi / 2, 0.0, yaw)
        return collision(xyz, rpy, f'<box size="{size[0]!r} {size[1]!r} {size[2]!r}"/>')
    if kind == 1:
        rpy = (0.0, np.pi / 2, yaw) if rng.random() < 0.5 else (np.pi / 2, 0.0, yaw)
        radius, length = float(rng.uniform(0.002, 0.012)), float(rng.uniform(0.01, 0.06))
        return collision(xyz, rpy, f'<cylinder radius="{radius!r}" length="{length!r}"/>')
    return collision(xyz, (0.0, 0.0, 0.0), f'<sphere radius="{float(rng.uniform(0.002, 0.015))!r}"/>')


def shapes_finger(rng, link1: str | None = None) -> Finger:
    l1, l2 = float(rng.uniform(0.06, 0.12)), float(rng.uniform(0.04, 0.1))
    if link1 is None:
        link1 = "".join(random_shape(rng, l1) for _ in range(rng.integers(1, 4)))
    link2 = "".join(random_shape(rng, l2) for _ in range(rng.integers(1, 4)))
    text = BARE.format(yaw1=float(rng.uniform(-0.3, 0.3)), l1=l1, l2=l2, link1=link1, link2=link2)
    base = (*rng.uniform(-0.05, 0.05, 2).tolist(), float(rng.uniform(-np.pi, np.pi)))
    return Finger.from_urdf_string(text, base_in_hand=base,
                                   configuration=str(rng.choice(["left", "right"])))


@pytest.mark.parametrize("seed", range(12))
def test_random_boxes_cylinders_and_spheres_match_coal(seed):
    rng = np.random.default_rng(seed)
    finger = shapes_finger(rng)
    polygon = random_polygon(rng, 0.1) if seed % 2 else ConvexPolygon.rectangle(0.08, 0.05, mass=0.1)
    worst, wrong = compare_with_coal(finger, polygon, rng, 150, 0.0)
    assert worst <= EXACT
    assert wrong == 0


@pytest.mark.parametrize("link1", [
    collision((0.05, 0.0, 0.0), (0.0, np.pi / 2 + 0.2, 0.0), '<cylinder radius="0.006" length="0.1"/>'),  # axis tilted
    collision((0.05, 0.0, 0.003), (0.0, np.pi / 2, 0.0), '<cylinder radius="0.006" length="0.1"/>'),  # off the plane
    collision((0.05, 0.0, 0.0), (0.3, 0.0, 0.0), '<box size="0.1 0.01 0.01"/>'),  # rolled
    collision((0.05, 0.0, 0.001), (0.0, 0.0, 0.0), '<sphere radius="0.01"/>'),  # off the plane
], ids=["tilted cylinder", "raised cylinder", "rolled box", "raised sphere"])
def test_unsupported_shapes_fall_back_to_coal(link1):
    rng = np.random.default_rng(3)
    finger = shapes_finger(rng, link1)
    polygon = ConvexPolygon.rectangle(0.08, 0.05, mass=0.1)
    assert UrdfCollisionChecker(finger, polygon, 0.0).footprints is None
    default = FingerEnvelope(finger, polygon, 0, geometry="urdf", tip_clearance=0.0)
    reference = FingerEnvelope(finger, polygon, 0, geometry="urdf", tip_clearance=0.0, compiled=False)
    assert not default.compiled
    with pytest.raises(InvalidParameterError, match="compiled"):
        FingerEnvelope(finger, polygon, 0, geometry="urdf", tip_clearance=0.0, compiled=True)
    for _ in range(20):
        pose = random_pose_near(rng, finger, polygon)
        a, b = default.at(pose), reference.at(pose)
        assert (a.feasible, a.reachable, a.reason) == (b.feasible, b.reachable, b.reason)


def test_compiled_flag_is_checked():
    sc = load_scenario(SCENARIOS[0])
    c = sc.contacts[0]
    with pytest.raises(InvalidParameterError, match="ideal"):
        FingerEnvelope(c.finger, sc.polygon, c.edge, compiled=True)
    with pytest.raises(InvalidParameterError):
        FingerEnvelope(c.finger, sc.polygon, c.edge, geometry="urdf", compiled="yes")
    assert FingerEnvelope(c.finger, sc.polygon, c.edge, geometry="urdf", compiled=True).compiled
    assert not FingerEnvelope(c.finger, sc.polygon, c.edge).compiled


# --------------------------------------------------------------------------- envelopes
def assert_same_envelope(compiled, reference, accuracy: float) -> float:
    """Same structure (bitwise), ends within ``accuracy`` [m]; returns the largest end difference [m]."""
    assert (compiled.d, compiled.lam, compiled.condition, compiled.reachable, compiled.reason) == \
        (reference.d, reference.lam, reference.condition, reference.reachable, reference.reason)
    assert len(compiled.feasible) == len(reference.feasible), (compiled.feasible, reference.feasible)
    worst = 0.0
    for (a, b), (c, e) in zip(compiled.feasible, reference.feasible):
        worst = max(worst, abs(a - c), abs(b - e))
    assert worst <= accuracy, (compiled.feasible, reference.feasible)
    return worst


@pytest.mark.parametrize("path", SCENARIOS, ids=lambda p: p.stem)
def test_compiled_envelopes_match_the_reference_on_the_shipped_scenarios(path):
    sc = load_scenario(path)
    rng = np.random.default_rng(5)
    traj = sc.trajectory
    times = np.linspace(traj.t_start, traj.t_end, 60).tolist()
    for c in sc.contacts:
        args = (c.finger, sc.polygon, c.edge)
        compiled = FingerEnvelope(*args, geometry="urdf", tip_clearance=c.tip_clearance)
        reference = FingerEnvelope(*args, geometry="urdf", tip_clearance=c.tip_clearance, compiled=False,
                                   coal_tolerance=1e-13)
        default = FingerEnvelope(*args, geometry="urdf", tip_clearance=c.tip_clearance, compiled=False)
        assert compiled.compiled and not reference.compiled
        accuracy = 2 * reference.urdf_tolerance * reference.edge.length
        for t in times:
            for pose in (traj.pose(t), traj.pose(t) + rng.normal(size=3) * [3e-3, 3e-3, 3e-2]):
                sample = compiled.at(pose, t)
                assert_same_envelope(sample, reference.at(pose, t), accuracy)
                assert_same_envelope(sample, default.at(pose, t), np.inf)


@pytest.mark.parametrize("seed", range(0, 600, 3))
def test_compiled_envelopes_match_the_reference_on_random_cases(seed):
    """The random fingers, polygons and poses of the envelope tests (thick links grazing the edge)."""
    case = make_case(seed)
    rng = np.random.default_rng(seed)
    for conf in ("left", "right"):
        radius = rng.uniform(0.01, 0.06) * case["l1"]
        finger = make_random_finger(case["l1"], case["l2"], case["base"], conf, radius=radius)
        args = (finger, case["polygon"], case["edge"])
        compiled = FingerEnvelope(*args, geometry="urdf")
        reference = FingerEnvelope(*args, geometry="urdf", compiled=False, coal_tolerance=1e-13)
        default = FingerEnvelope(*args, geometry="urdf", compiled=False)
        assert compiled.compiled
        accuracy = 2 * reference.urdf_tolerance * reference.edge.length
        for shift in (0.0, 0.05, -0.05, 0.1, 0.02):
            pose = case["pose"] + shift * np.array([case["l1"], case["l2"], 1.0])
            sample = compiled.at(pose)
            assert_same_envelope(sample, reference.at(pose), accuracy)
            assert_same_envelope(sample, default.at(pose), np.inf)
            cuts, reference_cuts = compiled.urdf_cuts(pose), reference.urdf_cuts(pose)
            assert [(a, len(flips)) for a, flips in cuts] == [(a, len(flips)) for a, flips in reference_cuts]
            for (_, flips), (_, reference_flips) in zip(cuts, reference_cuts):
                assert np.all(np.abs(np.subtract(flips, reference_flips)) <= accuracy)


def test_tracker_on_the_reference_path_still_matches_fresh_samples():
    """The tracker follows coal's cuts when its envelope runs the reference path (the compiled one is covered by
    tests/envelope/test_finger_envelope.py): at every step the pieces of a fresh reference sample, ends within the
    bisection tolerance, and a fallback is bitwise a fresh sample."""
    from regrasp.envelope.tracker import EnvelopeTracker

    sc = load_scenario(ROOT / "examples" / "scenarios" / "paper_trajectory_2_three_fingers.toml")
    traj = sc.trajectory
    for c in sc.contacts:
        args = (c.finger, sc.polygon, c.edge)
        fresh = FingerEnvelope(*args, geometry="urdf", tip_clearance=c.tip_clearance, compiled=False)
        tracker = EnvelopeTracker(FingerEnvelope(*args, geometry="urdf", tip_clearance=c.tip_clearance, compiled=False))
        tol = fresh.urdf_tolerance * fresh.edge.length
        for t in np.arange(0.5, 0.7, 1e-3).tolist():
            before = tracker.fallbacks
            tracked, sample = tracker.update(traj.pose(t), t), fresh.at(traj.pose(t), t)
            assert_same_envelope(tracked, sample, tol)
            if tracker.fallbacks > before:
                assert tracked.feasible == sample.feasible
        assert tracker.counts["tracked"] > 150


def test_compiled_only_calls_are_checked():
    sc = load_scenario(SCENARIOS[0])
    c = sc.contacts[0]
    reference = FingerEnvelope(c.finger, sc.polygon, c.edge, geometry="urdf", compiled=False)
    with pytest.raises(InvalidParameterError, match="compiled"):
        reference.kernel_arguments(sc.trajectory.pose(0.0))
    with pytest.raises(InvalidParameterError, match="urdf"):
        FingerEnvelope(c.finger, sc.polygon, c.edge).urdf_cuts(sc.trajectory.pose(0.0))


@pytest.mark.parametrize("seed", range(4))
def test_capsules_and_spheres_match_coal(seed):
    """Capsules (urdfdom drops them from URDFs, but a collision model may hold them) and spheres, placed directly:
    the stadium and disc footprints against coal at 1e-13."""
    import coal
    import pinocchio as pin

    from regrasp.kernels.footprint import FOOTPRINT
    from regrasp.model.collision import planar_footprint

    rng = np.random.default_rng(seed)
    polygon = random_polygon(rng, 0.1)
    h = 0.2
    prism = polygon.to_coal(h)
    normals = np.array([e.inward_normal for e in polygon.edges])
    request = coal.DistanceRequest()
    request.enable_signed_distance = True
    request.gjk_tolerance = request.epa_tolerance = 1e-13
    worst = 0.0
    for _ in range(200):
        radius = float(rng.uniform(0.002, 0.02))
        geometry = coal.Capsule(radius, float(rng.uniform(0.01, 0.08))) if rng.random() < 0.7 else coal.Sphere(radius)
        yaw = float(rng.uniform(-np.pi, np.pi))
        roll, pitch = (0.0, np.pi / 2) if rng.random() < 0.5 else (np.pi / 2, 0.0)
        rotation = pin.rpy.rpyToMatrix(roll, pitch, yaw)
        placement = pin.SE3(rotation, np.array([*rng.uniform(-0.08, 0.08, 2), 0.0]))
        shapes = np.array([planar_footprint(geometry, placement, 0.0, h)], dtype=FOOTPRINT)
        pose = np.array([0.0, 0.0, rng.uniform(-np.pi, np.pi)])
        out = np.empty(1)
        footprint_distances(shapes, np.ascontiguousarray(polygon.vertices), normals, h, pose,
                            np.array([0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]), out)
        c, s = np.cos(pose[2]), np.sin(pose[2])
        object_tf = coal.Transform3s(np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]), np.zeros(3))
        result = coal.DistanceResult()
        reference = coal.distance(geometry, coal.Transform3s(placement.rotation, placement.translation), prism,
                                  object_tf, request, result)
        worst = max(worst, abs(out[0] - reference))
    assert worst <= EXACT

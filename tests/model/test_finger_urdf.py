"""Tests of regrasp.model.finger_urdf.planar_2r_urdf: what Pinocchio/coal read from the generated text."""

from __future__ import annotations

import math

import coal
import numpy as np
import pinocchio as pin
import pytest

from regrasp.core.exceptions import InvalidParameterError
from regrasp.model.finger import Finger
from regrasp.model.finger_urdf import planar_2r_urdf

RHO = 0.3 * 2700.0  # default "aluminium tube, 30 % fill" density [kg/m^3]


def cylinder_inertia(mass: float, radius: float, length: float) -> np.ndarray:
    """Solid cylinder along x, about its centre of mass."""
    ixx = mass * radius**2 / 2.0
    iyy = mass * (3.0 * radius**2 + length**2) / 12.0
    return np.diag([ixx, iyy, iyy])


CASES = [
    dict(l1=0.12, l2=0.045, radius1=0.006, radius2=0.005),
    dict(l1=0.09, l2=0.08, radius1=0.007, radius2=0.006, mass1=0.02, mass2=0.004),
    dict(l1=0.3, l2=0.013, radius1=0.02, radius2=0.001, damping=0.05),
]


def random_cases(seed: int, n: int):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        case = dict(
            l1=rng.uniform(0.01, 0.5),
            l2=rng.uniform(0.01, 0.5),
            radius1=rng.uniform(0.001, 0.03),
            radius2=rng.uniform(0.001, 0.03),
            damping=rng.uniform(0.0, 0.1),
        )
        if rng.uniform() < 0.5:
            case.update(mass1=rng.uniform(0.001, 1.0), mass2=rng.uniform(0.001, 1.0))
        yield case


ALL_CASES = CASES + list(random_cases(21, 8))


def expected_links(case: dict):
    """(length, radius, mass) per link from the parameters, with the documented default mass."""
    out = []
    for k in (1, 2):
        length, radius = case[f"l{k}"], case.get(f"radius{k}", 0.008 if k == 1 else 0.007)
        mass = case.get(f"mass{k}")
        if mass is None:
            mass = RHO * math.pi * radius**2 * length
        out.append((length, radius, mass))
    return out


@pytest.mark.parametrize("case", ALL_CASES)
def test_masses_and_inertias_match_solid_cylinders(case):
    model = pin.buildModelFromXML(planar_2r_urdf(**case))
    assert model.njoints == 3
    for jid, (length, radius, mass) in enumerate(expected_links(case), start=1):
        inertia = model.inertias[jid]
        assert inertia.mass == pytest.approx(mass, rel=1e-14)
        np.testing.assert_allclose(inertia.lever, [length / 2.0, 0.0, 0.0], rtol=0, atol=1e-15)
        expected = cylinder_inertia(mass, radius, length)
        np.testing.assert_allclose(inertia.inertia, expected, rtol=1e-13, atol=1e-15 * expected.max())


@pytest.mark.parametrize("case", ALL_CASES)
def test_collision_geometry_is_one_cylinder_per_link_along_the_link(case):
    text = planar_2r_urdf(**case)
    model = pin.buildModelFromXML(text)
    geom = pin.buildGeomFromUrdfString(model, text, pin.GeometryType.COLLISION)
    objects = list(geom.geometryObjects)
    assert sorted(o.parentJoint for o in objects) == [1, 2]
    for obj in objects:
        length, radius, _ = expected_links(case)[obj.parentJoint - 1]
        assert isinstance(obj.geometry, coal.Cylinder)
        assert obj.geometry.radius == pytest.approx(radius, rel=1e-15)
        assert 2.0 * obj.geometry.halfLength == pytest.approx(length, rel=1e-15)
        # the cylinder's axis (local z) lies along the link (joint x) and spans joint -> next joint/tip
        placement = obj.placement
        np.testing.assert_allclose(placement.rotation @ [0.0, 0.0, 1.0], [1.0, 0.0, 0.0], atol=1e-15)
        np.testing.assert_allclose(placement.translation, [length / 2.0, 0.0, 0.0], atol=1e-15)
        ends = sorted(float((placement.act(np.array([0.0, 0.0, s * obj.geometry.halfLength])))[0]) for s in (-1, 1))
        assert ends == pytest.approx([0.0, length], abs=1e-15)
        for s in (-1, 1):
            end = placement.act(np.array([0.0, 0.0, s * obj.geometry.halfLength]))
            assert abs(end[1]) < 1e-15 and abs(end[2]) < 1e-15
    # link 2's cylinder ends exactly at the tip frame
    tip = model.frames[model.getFrameId("tip")]
    assert tip.parentJoint == 2
    np.testing.assert_allclose(tip.placement.translation, [case["l2"], 0.0, 0.0], atol=0)
    np.testing.assert_allclose(model.jointPlacements[2].translation, [case["l1"], 0.0, 0.0], atol=0)


def test_visual_geometry_matches_collision_geometry():
    text = planar_2r_urdf(0.1, 0.05, radius1=0.01, radius2=0.004)
    model = pin.buildModelFromXML(text)
    col = pin.buildGeomFromUrdfString(model, text, pin.GeometryType.COLLISION)
    vis = pin.buildGeomFromUrdfString(model, text, pin.GeometryType.VISUAL)
    assert len(vis.geometryObjects) == len(col.geometryObjects) == 2
    for a, b in zip(vis.geometryObjects, col.geometryObjects):
        assert a.parentJoint == b.parentJoint
        assert a.geometry.radius == b.geometry.radius
        assert a.geometry.halfLength == b.geometry.halfLength
        np.testing.assert_array_equal(a.placement.homogeneous, b.placement.homogeneous)


@pytest.mark.parametrize("damping", [0.0, 0.002, 0.5])
def test_damping_is_read_by_pinocchio(damping):
    model = pin.buildModelFromXML(planar_2r_urdf(0.1, 0.05, damping=damping))
    np.testing.assert_array_equal(np.asarray(model.damping), [damping, damping])
    np.testing.assert_array_equal(np.asarray(model.friction), [0.0, 0.0])


def test_generated_urdf_is_a_valid_finger():
    finger = Finger.from_urdf_string(planar_2r_urdf(0.11, 0.07, radius1=0.009, radius2=0.006), name="gen")
    assert finger.link_lengths == pytest.approx((0.11, 0.07), abs=1e-16)
    shapes = sorted(finger.link_shapes(), key=lambda s: s.link)
    assert [s.link for s in shapes] == [0, 1]
    assert [s.geometry.radius for s in shapes] == pytest.approx([0.009, 0.006])
    assert finger.theta2_offset == 0.0 and finger.psi1_offset == 0.0


def test_equal_links_reach_the_origin():
    finger = Finger.from_urdf_string(planar_2r_urdf(0.08, 0.08), base_in_hand=(0.01, 0.02, 0.3))
    assert finger.reach == pytest.approx((0.0, 0.16), abs=1e-16)
    q = finger.inverse_kinematics(finger.joint1_in_hand)
    np.testing.assert_allclose(finger.forward_kinematics(q), finger.joint1_in_hand, rtol=0, atol=1e-15)


def test_name_is_the_robot_name():
    text = planar_2r_urdf(0.1, 0.05, name="my_finger")
    assert '<robot name="my_finger">' in text
    assert pin.buildModelFromXML(text).name == "my_finger"


@pytest.mark.parametrize(
    ("kwargs", "param"),
    [
        (dict(l1=0.0, l2=0.05), "l1"),
        (dict(l1=-0.1, l2=0.05), "l1"),
        (dict(l1=0.1, l2=0.0), "l2"),
        (dict(l1=0.1, l2=-1e-3), "l2"),
        (dict(l1=math.nan, l2=0.05), "l1"),
        (dict(l1=0.1, l2=math.inf), "l2"),
        (dict(l1=0.1, l2=0.05, radius1=0.0), "radius1"),
        (dict(l1=0.1, l2=0.05, radius1=-0.01), "radius1"),
        (dict(l1=0.1, l2=0.05, radius2=0.0), "radius2"),
        (dict(l1=0.1, l2=0.05, radius2=-0.01), "radius2"),
        (dict(l1=0.1, l2=0.05, mass1=0.0), "mass1"),
        (dict(l1=0.1, l2=0.05, mass2=-1.0), "mass2"),
        (dict(l1=0.1, l2=0.05, damping=-0.001), "damping"),
        (dict(l1=0.1, l2=0.05, damping=math.nan), "damping"),
        (dict(l1="abc", l2=0.05), "l1"),
    ],
)
def test_invalid_parameters_raise(kwargs, param):
    with pytest.raises(InvalidParameterError) as info:
        planar_2r_urdf(**kwargs)
    assert info.value.name == param
    assert param in str(info.value)

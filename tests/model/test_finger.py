"""Tests of regrasp.model.finger: loading and validating planar 2R URDFs, FK, Jacobian, IK, copies.

Every expected value is computed here independently of the module (planar homogeneous
transforms written from the URDF numbers, finite differences, plain geometry).
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from regrasp.core.exceptions import FingerModelError, InvalidParameterError, UnreachableError
from regrasp.model.finger import Configuration, Finger

URDF_DIR = Path(__file__).resolve().parents[2] / "urdf"
SHIPPED = {
    "planar_2r_finger.urdf": (0.12, 0.045),
    "planar_2r_finger_long_distal.urdf": (0.09, 0.08),
}
SHIPPED_NAMES = list(SHIPPED)


# --------------------------------------------------------------------------- helpers
def shipped_path(name: str) -> Path:
    return URDF_DIR / name


def rot2(theta: float) -> np.ndarray:
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, -s], [s, c]])


def homog(x: float, y: float, theta: float) -> np.ndarray:
    """3x3 planar homogeneous transform."""
    t = np.eye(3)
    t[:2, :2] = rot2(theta)
    t[:2, 2] = (x, y)
    return t


def cross2(a, b) -> float:
    return float(a[0] * b[1] - a[1] * b[0])


def random_base(rng: np.random.Generator) -> np.ndarray:
    return np.array([rng.uniform(-0.2, 0.2), rng.uniform(-0.2, 0.2), rng.uniform(-math.pi, math.pi)])


def random_q(rng: np.random.Generator) -> np.ndarray:
    return rng.uniform(-math.pi, math.pi, size=2)


def planar_chain(base, j1, j2, tip, q):
    """Joint 1, joint 2 and tip positions of a planar chain, by composing 3x3 transforms.

    ``j1``/``j2`` are the (x, y, yaw) joint origins and ``tip`` the (x, y) tip offset,
    exactly as written in the URDF; joint axes are +z.
    """
    t1 = homog(*base) @ homog(*j1) @ homog(0.0, 0.0, q[0])
    t2 = t1 @ homog(*j2) @ homog(0.0, 0.0, q[1])
    tip_h = t2 @ np.array([tip[0], tip[1], 1.0])
    return t1[:2, 2], t2[:2, 2], tip_h[:2]


def hand_fk_along_x(base, l1, l2, q) -> np.ndarray:
    """Textbook tip position of a 2R arm with links along x, mapped by the base pose."""
    x, y, th = base
    local = np.array(
        [l1 * math.cos(q[0]) + l2 * math.cos(q[0] + q[1]), l1 * math.sin(q[0]) + l2 * math.sin(q[0] + q[1])]
    )
    return np.array([x, y]) + rot2(th) @ local


def pin_joint_positions(finger: Finger, q) -> tuple[np.ndarray, np.ndarray]:
    """Joint 1 and joint 2 origins from the finger's Pinocchio model (not the closed form)."""
    data = finger.model.createData()
    pin.forwardKinematics(finger.model, data, np.asarray(q, dtype=float))
    return data.oMi[1].translation[:2].copy(), data.oMi[2].translation[:2].copy()


def wrapped_diff(a, b) -> np.ndarray:
    d = np.asarray(a, dtype=float) - np.asarray(b, dtype=float)
    return np.mod(d + math.pi, 2.0 * math.pi) - math.pi


# ---- a small URDF writer for the validation variants
def _fmt(v) -> str:
    return " ".join(repr(float(c)) for c in v)


def joint_xml(name, parent, child, *, jtype="revolute", xyz=(0, 0, 0), rpy=(0, 0, 0), axis=(0, 0, 1)) -> str:
    out = f'  <joint name="{name}" type="{jtype}">\n'
    out += f'    <parent link="{parent}"/>\n    <child link="{child}"/>\n'
    out += f'    <origin xyz="{_fmt(xyz)}" rpy="{_fmt(rpy)}"/>\n'
    if jtype != "fixed":
        out += f'    <axis xyz="{_fmt(axis)}"/>\n'
    if jtype in ("revolute", "prismatic"):
        out += '    <limit lower="-3.14159" upper="3.14159" effort="5" velocity="20"/>\n'
    return out + "  </joint>\n"


def link_xml(name: str, mass: float | None = 0.01) -> str:
    if mass is None:
        return f'  <link name="{name}"/>\n'
    return (
        f'  <link name="{name}"><inertial><origin xyz="0 0 0" rpy="0 0 0"/><mass value="{mass!r}"/>'
        '<inertia ixx="1e-6" ixy="0" ixz="0" iyy="1e-6" iyz="0" izz="1e-6"/></inertial></link>\n'
    )


def robot_xml(joints: list[str], links: list[str], name: str = "test_finger") -> str:
    return f'<?xml version="1.0"?>\n<robot name="{name}">\n' + "".join(links) + "".join(joints) + "</robot>\n"


def standard_chain(
    *,
    l1=0.1,
    l2=0.06,
    j1_kw=None,
    j2_kw=None,
    tip_parent="link2",
    tip_xyz=None,
    tip_name="tip",
    extra_joints=(),
    extra_links=(),
) -> str:
    """base -joint1-> link1 -joint2-> link2 -tip_joint(fixed)-> tip, with overridable pieces."""
    j1 = dict(xyz=(0, 0, 0))
    j1.update(j1_kw or {})
    j2 = dict(xyz=(l1, 0, 0))
    j2.update(j2_kw or {})
    tip_xyz = (l2, 0, 0) if tip_xyz is None else tip_xyz
    joints = [
        joint_xml("joint1", "base", "link1", **j1),
        joint_xml("joint2", "link1", "link2", **j2),
        joint_xml("tip_joint", tip_parent, tip_name, jtype="fixed", xyz=tip_xyz),
        *extra_joints,
    ]
    links = [link_xml("base", None), link_xml("link1"), link_xml("link2"), link_xml(tip_name, None), *extra_links]
    return robot_xml(joints, links)


# Non-trivial geometry: links not along x, a yawed joint-2 origin, an off-axis tip.
OFFSET_J2 = (0.08, 0.03, 0.4)  # x, y, yaw of joint 2's origin in link 1
OFFSET_TIP = (0.05, -0.01)


def offset_urdf(j1=(0.0, 0.0, 0.0)) -> str:
    return standard_chain(
        j1_kw=dict(xyz=(j1[0], j1[1], 0.0), rpy=(0.0, 0.0, j1[2])),
        j2_kw=dict(xyz=(OFFSET_J2[0], OFFSET_J2[1], 0.0), rpy=(0.0, 0.0, OFFSET_J2[2])),
        tip_xyz=(OFFSET_TIP[0], OFFSET_TIP[1], 0.0),
    )


OFFSET_J1_VARIANTS = [(0.0, 0.0, 0.0), (0.015, -0.02, -0.7)]


def write(tmp_path: Path, text: str, name: str = "finger.urdf") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


# --------------------------------------------------------------------------- 1. loading
@pytest.mark.parametrize("name", SHIPPED_NAMES)
def test_shipped_urdfs_load_with_lengths_from_the_joint_offsets(name):
    path = shipped_path(name)
    finger = Finger.from_urdf(path)
    # Independent read of the URDF: joint2 origin and tip_joint origin.
    root = ET.parse(path).getroot()
    offsets = {
        j.get("name"): np.array([float(v) for v in j.find("origin").get("xyz").split()])
        for j in root.findall("joint")
    }
    l1_xml = float(np.linalg.norm(offsets["joint2"]))
    l2_xml = float(np.linalg.norm(offsets["tip_joint"]))
    assert finger.link_lengths == pytest.approx((l1_xml, l2_xml), abs=1e-15)
    assert finger.link_lengths == pytest.approx(SHIPPED[name], abs=1e-15)
    l1, l2 = SHIPPED[name]
    assert finger.reach == pytest.approx((abs(l1 - l2), l1 + l2), abs=1e-15)
    assert finger.model.existFrame("tip")
    assert finger.model.frames[finger.tip_frame_id].name == "tip"
    assert finger.model.frames[finger.tip_frame_id].parentJoint == 2
    assert finger.name == path.stem
    assert finger.source == str(path)
    assert finger.theta2_offset == pytest.approx(0.0, abs=1e-15)
    assert finger.psi1_offset == pytest.approx(0.0, abs=1e-15)
    assert finger.model.nq == 2


@pytest.mark.parametrize("name", SHIPPED_NAMES)
def test_shipped_urdfs_have_one_cylinder_per_link(name):
    finger = Finger.from_urdf(shipped_path(name))
    shapes = finger.link_shapes()
    assert sorted(s.link for s in shapes) == [0, 1]
    for shape, length in zip(sorted(shapes, key=lambda s: s.link), SHIPPED[name]):
        assert type(shape.geometry).__name__ == "Cylinder"
        assert 2.0 * shape.geometry.halfLength == pytest.approx(length, abs=1e-15)
        assert shape.placement_in_joint.translation == pytest.approx([length / 2, 0.0, 0.0], abs=1e-15)


def test_repr_and_configuration_parse():
    finger = Finger.from_urdf(shipped_path(SHIPPED_NAMES[0]), configuration="RIGHT", name="f1")
    assert finger.configuration is Configuration.RIGHT
    assert "f1" in repr(finger) and "right" in repr(finger)
    assert Configuration.parse("left") is Configuration.LEFT
    assert Configuration.parse(Configuration.RIGHT) is Configuration.RIGHT
    assert Configuration.LEFT.sign == 1 and Configuration.RIGHT.sign == -1


# --------------------------------------------------------------------------- 2. FK
@pytest.mark.parametrize("name", SHIPPED_NAMES)
def test_forward_kinematics_matches_closed_form_and_hand_formula(name):
    rng = np.random.default_rng(11)
    l1, l2 = SHIPPED[name]
    unplaced = Finger.from_urdf(shipped_path(name))
    for _ in range(40):
        base = random_base(rng)
        finger = unplaced.with_placement(base_in_hand=base)
        for _ in range(5):
            q = random_q(rng)
            fk = finger.forward_kinematics(q)
            closed = finger.joint_positions_in_hand(q)
            expected = hand_fk_along_x(base, l1, l2, q)
            assert fk.shape == (2,)
            np.testing.assert_allclose(fk, expected, rtol=0, atol=1e-15)
            np.testing.assert_allclose(closed[2], expected, rtol=0, atol=1e-15)
            # joint 1 and the elbow agree with Pinocchio's joint placements and with the formula
            o1, elbow = pin_joint_positions(finger, q)
            np.testing.assert_allclose(closed[0], base[:2], rtol=0, atol=1e-15)
            np.testing.assert_allclose(closed[0], o1, rtol=0, atol=1e-15)
            np.testing.assert_allclose(closed[1], elbow, rtol=0, atol=1e-15)
            np.testing.assert_allclose(
                closed[1], base[:2] + rot2(base[2]) @ [l1 * math.cos(q[0]), l1 * math.sin(q[0])], rtol=0, atol=1e-15
            )
            np.testing.assert_allclose(finger.joint1_in_hand, base[:2], rtol=0, atol=0)


@pytest.mark.parametrize("j1", OFFSET_J1_VARIANTS)
def test_forward_kinematics_with_geometry_offsets(j1):
    rng = np.random.default_rng(12)
    unplaced = Finger.from_urdf_string(offset_urdf(j1))
    l1 = math.hypot(OFFSET_J2[0], OFFSET_J2[1])
    l2 = math.hypot(*OFFSET_TIP)
    assert unplaced.link_lengths == pytest.approx((l1, l2), abs=1e-16)
    for _ in range(30):
        base = random_base(rng)
        finger = unplaced.with_placement(base_in_hand=base)
        for _ in range(5):
            q = random_q(rng)
            e_o1, e_elbow, e_tip = planar_chain(base, j1, OFFSET_J2, OFFSET_TIP, q)
            np.testing.assert_allclose(finger.forward_kinematics(q), e_tip, rtol=0, atol=1e-15)
            closed = finger.joint_positions_in_hand(q)
            np.testing.assert_allclose(closed, np.stack([e_o1, e_elbow, e_tip]), rtol=0, atol=1e-15)
            # geometric theta2: angle from link-1 direction to link-2 direction
            d1, d2 = e_elbow - e_o1, e_tip - e_elbow
            theta2 = math.atan2(cross2(d1, d2), float(d1 @ d2))
            assert abs(wrapped_diff(finger.theta2(q), theta2)) < 1e-13


# --------------------------------------------------------------------------- 3. Jacobian
@pytest.mark.parametrize("name", SHIPPED_NAMES + ["offset"])
def test_tip_jacobian_matches_central_finite_differences(name):
    rng = np.random.default_rng(13)
    if name == "offset":
        unplaced = Finger.from_urdf_string(offset_urdf(OFFSET_J1_VARIANTS[1]))
    else:
        unplaced = Finger.from_urdf(shipped_path(name))
    l1, l2 = unplaced.link_lengths
    h = 1e-6
    for _ in range(25):
        base = random_base(rng)
        finger = unplaced.with_placement(base_in_hand=base)
        scale = l1 + l2 + float(np.linalg.norm(base[:2]))  # magnitude of the FK values
        tol = 10.0 * h**2 * (l1 + l2) + 1e-15 * scale / h
        for _ in range(4):
            q = random_q(rng)
            jac = finger.tip_jacobian(q)
            assert jac.shape == (2, 2)
            fd = np.empty((2, 2))
            for k in range(2):
                dq = np.zeros(2)
                dq[k] = h
                fd[:, k] = (finger.forward_kinematics(q + dq) - finger.forward_kinematics(q - dq)) / (2.0 * h)
            np.testing.assert_allclose(jac, fd, rtol=0, atol=tol)
            # and against the exact derivative of the planar chain: J[:, k] = perp(tip - joint_k)
            o1, elbow, tip = finger.joint_positions_in_hand(q)
            exact = np.column_stack([[-(tip - o1)[1], (tip - o1)[0]], [-(tip - elbow)[1], (tip - elbow)[0]]])
            np.testing.assert_allclose(jac, exact, rtol=0, atol=1e-15)


# --------------------------------------------------------------------------- 4. IK
@pytest.mark.parametrize("configuration", ["left", "right"])
@pytest.mark.parametrize("name", SHIPPED_NAMES)
def test_inverse_kinematics_round_trip_in_the_finger_configuration(name, configuration):
    rng = np.random.default_rng(14)
    unplaced = Finger.from_urdf(shipped_path(name), configuration=configuration)
    l1, l2 = unplaced.link_lengths
    tol = 1e-12 * (l1 + l2)
    n_same = 0
    for _ in range(30):
        finger = unplaced.with_placement(base_in_hand=random_base(rng))
        for _ in range(5):
            q = random_q(rng)
            if abs(math.sin(finger.theta2(q))) < 1e-3:
                continue
            target = finger.forward_kinematics(q)
            q_ik = finger.inverse_kinematics(target)
            assert q_ik.shape == (2,)
            assert np.all(np.abs(q_ik) <= math.pi)
            np.testing.assert_allclose(finger.forward_kinematics(q_ik), target, rtol=0, atol=tol)
            assert finger.configuration_of(q_ik) is finger.configuration
            if finger.configuration_of(q) is finger.configuration:
                n_same += 1
                assert np.max(np.abs(wrapped_diff(q_ik, q))) < 1e-9
    assert n_same > 30


@pytest.mark.parametrize("name", SHIPPED_NAMES)
def test_left_and_right_give_mirror_elbows(name):
    rng = np.random.default_rng(15)
    left0 = Finger.from_urdf(shipped_path(name), configuration="left")
    l1, l2 = left0.link_lengths
    for _ in range(60):
        base = random_base(rng)
        left = left0.with_placement(base_in_hand=base)
        right = left.with_placement(configuration="right")
        q = random_q(rng)
        if abs(math.sin(q[1])) < 1e-3:
            continue
        target = left.forward_kinematics(q)
        o1 = base[:2]
        ray = target - o1
        u = ray / np.linalg.norm(ray)
        elbows = {}
        for finger in (left, right):
            q_ik = finger.inverse_kinematics(target)
            _, elbow = pin_joint_positions(finger, q_ik)
            assert np.linalg.norm(elbow - o1) == pytest.approx(l1, abs=1e-14)
            assert np.linalg.norm(target - elbow) == pytest.approx(l2, abs=1e-13)
            elbows[finger.configuration] = elbow
        e_left, e_right = elbows[Configuration.LEFT], elbows[Configuration.RIGHT]
        # "left": the elbow is on the left of the ray joint 1 -> tip
        assert cross2(ray, e_left - o1) > 0
        assert cross2(ray, e_right - o1) < 0
        # mirror images across the line joint 1 -> tip
        v = e_left - o1
        mirrored = o1 + 2.0 * (v @ u) * u - v
        np.testing.assert_allclose(e_right, mirrored, rtol=0, atol=1e-13)


def _unreachable_cases(finger: Finger, rng: np.random.Generator):
    inner, outer = finger.reach
    for _ in range(10):
        phi = rng.uniform(-math.pi, math.pi)
        u = np.array([math.cos(phi), math.sin(phi)])
        yield finger.joint1_in_hand + outer * (1.0 + 1e-10) * u, outer * (1.0 + 1e-10)
        yield finger.joint1_in_hand + (outer + 1e-3) * u, outer + 1e-3
        yield finger.joint1_in_hand + (inner - 1e-10 * outer) * u, inner - 1e-10 * outer
        yield finger.joint1_in_hand + 0.5 * inner * u, 0.5 * inner
    yield finger.joint1_in_hand.copy(), 0.0


@pytest.mark.parametrize("name", SHIPPED_NAMES)
def test_targets_outside_the_annulus_raise_unreachable(name):
    rng = np.random.default_rng(16)
    finger = Finger.from_urdf(shipped_path(name), base_in_hand=(0.03, -0.05, 0.8), name="index")
    l1, l2 = finger.link_lengths
    assert l1 != l2
    for target, dist in _unreachable_cases(finger, rng):
        with pytest.raises(UnreachableError) as info:
            finger.inverse_kinematics(target)
        err = info.value
        assert isinstance(err, ValueError)
        assert err.finger == "index"
        assert err.distance == pytest.approx(dist, rel=1e-12, abs=1e-17)
        assert tuple(err.reach) == pytest.approx(finger.reach, abs=0)
        np.testing.assert_allclose(np.asarray(err.target, dtype=float), target, rtol=0, atol=0)
        assert "index" in str(err)


@pytest.mark.parametrize("configuration", ["left", "right"])
@pytest.mark.parametrize("name", SHIPPED_NAMES)
def test_targets_on_the_boundary_within_slack_succeed(name, configuration):
    rng = np.random.default_rng(17)
    finger = Finger.from_urdf(shipped_path(name), base_in_hand=(-0.04, 0.07, -2.1), configuration=configuration)
    inner, outer = finger.reach
    for _ in range(10):
        phi = rng.uniform(-math.pi, math.pi)
        u = np.array([math.cos(phi), math.sin(phi)])
        for dist in (
            outer,
            outer * (1.0 + 0.5e-12),
            outer * (1.0 - 0.5e-12),
            inner,
            inner - 0.5e-12 * outer,
            inner + 0.5e-12 * outer,
        ):
            target = finger.joint1_in_hand + dist * u
            q = finger.inverse_kinematics(target)
            assert np.all(np.isfinite(q))
            np.testing.assert_allclose(finger.forward_kinematics(q), target, rtol=0, atol=2e-12 * outer)


@pytest.mark.parametrize("j1", OFFSET_J1_VARIANTS)
@pytest.mark.parametrize("configuration", ["left", "right"])
def test_inverse_kinematics_with_geometry_offsets(j1, configuration):
    rng = np.random.default_rng(18)
    unplaced = Finger.from_urdf_string(offset_urdf(j1), configuration=configuration)
    l1, l2 = unplaced.link_lengths
    tol = 1e-12 * (l1 + l2)
    for _ in range(30):
        base = random_base(rng)
        finger = unplaced.with_placement(base_in_hand=base)
        for _ in range(5):
            q = random_q(rng)
            _, _, target = planar_chain(base, j1, OFFSET_J2, OFFSET_TIP, q)
            q_ik = finger.inverse_kinematics(target)
            o1, elbow, tip = planar_chain(base, j1, OFFSET_J2, OFFSET_TIP, q_ik)
            np.testing.assert_allclose(tip, target, rtol=0, atol=tol)
            np.testing.assert_allclose(finger.forward_kinematics(q_ik), target, rtol=0, atol=tol)
            # judged on the geometry: sign of cross(link 1 direction, link 2 direction)
            s = cross2(elbow - o1, tip - elbow)
            assert abs(s) > 0
            geometric = Configuration.LEFT if s < 0 else Configuration.RIGHT
            assert geometric is finger.configuration
            assert finger.configuration_of(q_ik) is finger.configuration
            assert (cross2(tip - o1, elbow - o1) > 0) == (finger.configuration is Configuration.LEFT)


def test_configuration_uses_geometric_theta2_not_raw_q2():
    finger = Finger.from_urdf_string(offset_urdf())
    expected_offset = OFFSET_J2[2] + math.atan2(OFFSET_TIP[1], OFFSET_TIP[0]) - math.atan2(OFFSET_J2[1], OFFSET_J2[0])
    assert finger.theta2_offset == pytest.approx(expected_offset, abs=1e-15)
    assert expected_offset < -0.1  # so q2 in (0, -offset) is geometrically LEFT
    for q2 in (0.02, 0.08, -expected_offset - 0.02):
        q = np.array([0.3, q2])
        o1, elbow, tip = planar_chain((0, 0, 0), (0, 0, 0), OFFSET_J2, OFFSET_TIP, q)
        assert cross2(elbow - o1, tip - elbow) < 0  # link 2 turns clockwise: theta2 < 0
        assert q2 > 0
        assert finger.configuration_of(q) is Configuration.LEFT
    q = np.array([0.3, -expected_offset + 0.05])
    assert finger.configuration_of(q) is Configuration.RIGHT
    # exactly stretched or folded (geometric theta2 = 0 or pi): neither configuration
    assert finger.configuration_of([0.3, -finger.theta2_offset]) is None
    assert finger.configuration_of([0.3, math.pi - finger.theta2_offset]) is None


# --------------------------------------------------------------------------- 5. validation
def expect_model_error(tmp_path: Path, text: str, joint: str | None, *words: str, **kw) -> FingerModelError:
    """Load ``text`` from a file; check the error type, the file and the joint in the message."""
    path = write(tmp_path, text)
    with pytest.raises(FingerModelError) as info:
        Finger.from_urdf(path, **kw)
    err = info.value
    msg = str(err)
    assert str(path) in msg
    assert err.source == str(path)
    if joint is not None:
        assert err.joint == joint
        assert f"'{joint}'" in msg
    for word in words:
        assert re.search(word, msg, re.IGNORECASE), (word, msg)
    # the same text from a string gives the same diagnosis
    with pytest.raises(FingerModelError) as info2:
        Finger.from_urdf_string(text, **kw)
    assert info2.value.joint == err.joint
    return err


def test_standard_chain_helper_builds_a_valid_finger():
    finger = Finger.from_urdf_string(standard_chain(l1=0.1, l2=0.06))
    assert finger.link_lengths == pytest.approx((0.1, 0.06), abs=1e-16)


def test_missing_file(tmp_path):
    path = tmp_path / "nope" / "missing_finger.urdf"
    with pytest.raises(FingerModelError) as info:
        Finger.from_urdf(path)
    assert str(path) in str(info.value)
    assert info.value.source == str(path)
    with pytest.raises(FingerModelError):
        Finger.from_urdf(tmp_path)  # a directory is not a file


def test_three_revolute_joints_names_the_third(tmp_path):
    text = standard_chain(
        tip_parent="link3",
        extra_joints=[joint_xml("joint3", "link2", "link3", xyz=(0.06, 0, 0))],
        extra_links=[link_xml("link3")],
    )
    expect_model_error(tmp_path, text, "joint3", "two")


def test_prismatic_joint(tmp_path):
    text = standard_chain(j2_kw=dict(jtype="prismatic", axis=(1, 0, 0)))
    expect_model_error(tmp_path, text, "joint2", "prismatic")


@pytest.mark.parametrize("axis", [(0, 0, 1), (1, 0, 0)])
def test_prismatic_first_joint(tmp_path, axis):
    text = standard_chain(j1_kw=dict(jtype="prismatic", axis=axis))
    expect_model_error(tmp_path, text, "joint1", "prismatic")


def test_continuous_joint(tmp_path):
    text = standard_chain(j2_kw=dict(jtype="continuous"))
    expect_model_error(tmp_path, text, "joint2", "continuous")


@pytest.mark.parametrize(
    ("axis", "word"),
    [((1, 0, 0), "about x"), ((0, 1, 0), "about y"), ((0, 0.6, 0.8), r"\+z"), ((0, 0, -1), r"\+z")],
)
@pytest.mark.parametrize("joint", ["joint1", "joint2"])
def test_revolute_joint_not_about_plus_z(tmp_path, axis, word, joint):
    kw = {("j1_kw" if joint == "joint1" else "j2_kw"): dict(axis=axis)}
    text = standard_chain(**kw)
    expect_model_error(tmp_path, text, joint, word)


def test_axis_minus_z_is_an_unaligned_revolute_in_pinocchio_and_is_rejected(tmp_path):
    """Pinocchio turns axis (0, 0, -1) into a JointModelRevoluteUnaligned (not an RZ with a sign).

    The library rejects it with a clear FingerModelError rather than silently mis-reading
    the direction of q (it does not handle it by flipping the sign).
    """
    text = standard_chain(j2_kw=dict(axis=(0, 0, -1)))
    model = pin.buildModelFromXML(text)
    assert model.joints[2].shortname() == "JointModelRevoluteUnaligned"
    np.testing.assert_allclose(model.joints[2].extract().axis, [0, 0, -1])
    err = expect_model_error(tmp_path, text, "joint2", "axis")
    assert "+z" in str(err)


@pytest.mark.parametrize(
    "origin",
    [
        dict(xyz=(0.1, 0, 0.01)),
        dict(xyz=(0.1, 0, 0), rpy=(0.2, 0, 0)),
        dict(xyz=(0.1, 0, 0), rpy=(0, 0.2, 0)),
        dict(xyz=(0.1, 0, 0), rpy=(math.pi, 0, 0)),
    ],
)
def test_joint2_origin_out_of_plane(tmp_path, origin):
    expect_model_error(tmp_path, standard_chain(j2_kw=origin), "joint2", "plane")


@pytest.mark.parametrize("origin", [dict(xyz=(0, 0, 0.02)), dict(rpy=(0.3, 0, 0))])
def test_joint1_origin_out_of_plane(tmp_path, origin):
    expect_model_error(tmp_path, standard_chain(j1_kw=origin), "joint1", "plane")


def test_tip_frame_out_of_plane(tmp_path):
    expect_model_error(tmp_path, standard_chain(tip_xyz=(0.06, 0, 0.01)), "tip", "plane")


def test_missing_tip_frame(tmp_path):
    text = standard_chain(tip_name="fingertip")
    expect_model_error(tmp_path, text, "tip", "no frame")
    # but asking for that name works
    finger = Finger.from_urdf_string(text, tip_frame="fingertip")
    assert finger.link_lengths == pytest.approx((0.1, 0.06))


def test_tip_frame_on_link1(tmp_path):
    text = standard_chain(tip_parent="link1", tip_xyz=(0.1, 0.0, 0.0))
    expect_model_error(tmp_path, text, "tip", "joint1")


def test_zero_length_links(tmp_path):
    expect_model_error(tmp_path, standard_chain(j2_kw=dict(xyz=(0, 0, 0))), "joint2", "zero length")
    expect_model_error(tmp_path, standard_chain(tip_xyz=(0, 0, 0)), "tip", "zero length")


@pytest.mark.parametrize("text", ["<robot name='x'><link name='base'>", "this is not xml", ""])
def test_malformed_xml(tmp_path, text):
    path = write(tmp_path, text, "broken.urdf")
    with pytest.raises(FingerModelError) as info:
        Finger.from_urdf(path)
    assert str(path) in str(info.value)
    with pytest.raises(FingerModelError) as info2:
        Finger.from_urdf_string(text)
    assert "<string>" in str(info2.value)


def test_branch_two_joints_from_the_base(tmp_path):
    # base -> joint1 -> link1 (elbow) and base -> joint2 -> link2 (with the tip)
    joints = [
        joint_xml("joint1", "base", "link1"),
        joint_xml("joint2", "base", "link2", xyz=(0.1, 0, 0)),
        joint_xml("tip_joint", "link2", "tip", jtype="fixed", xyz=(0.06, 0, 0)),
    ]
    links = [link_xml("base", None), link_xml("link1"), link_xml("link2"), link_xml("tip", None)]
    text = robot_xml(joints, links)
    assert list(pin.buildModelFromXML(text).parents) == [0, 0, 0]
    expect_model_error(tmp_path, text, "joint2", "serial")


def test_branch_extra_joint_from_the_base(tmp_path):
    # a valid 2R chain plus a third revolute joint hanging off the base
    text = standard_chain(
        extra_joints=[joint_xml("side_joint", "base", "side_link", xyz=(0, 0.05, 0))],
        extra_links=[link_xml("side_link")],
    )
    model = pin.buildModelFromXML(text)
    assert model.njoints == 4
    expect_model_error(tmp_path, text, model.names[3])


@pytest.mark.parametrize("n_revolute", [0, 1])
def test_too_few_joints(tmp_path, n_revolute):
    joints = [joint_xml("joint1", "base", "link1", jtype="revolute" if n_revolute else "fixed")]
    joints.append(joint_xml("tip_joint", "link1", "tip", jtype="fixed", xyz=(0.1, 0, 0)))
    text = robot_xml(joints, [link_xml("base", None), link_xml("link1"), link_xml("tip", None)])
    assert pin.buildModelFromXML(text).njoints == 1 + n_revolute
    expect_model_error(tmp_path, text, None, f"found {n_revolute}")


def test_direct_construction_from_a_model_without_geometry():
    model = pin.buildModelFromUrdf(str(shipped_path(SHIPPED_NAMES[0])))
    finger = Finger(model, base_in_hand=[0.01, 0.0, 0.0])
    assert finger.source == "<model>"
    assert finger.link_shapes() == ()
    assert finger.collision_model is None
    bad = pin.Model(model)
    bad.jointPlacements[2] = pin.SE3(np.eye(3), np.array([0.12, 0.0, 0.003]))
    with pytest.raises(FingerModelError) as info:
        Finger(bad, source="hand.urdf")
    assert info.value.joint == "joint2" and "hand.urdf" in str(info.value)


@pytest.mark.parametrize("j1", OFFSET_J1_VARIANTS)
def test_unreachable_with_geometry_offsets(j1):
    rng = np.random.default_rng(20)
    finger = Finger.from_urdf_string(offset_urdf(j1), base_in_hand=(0.02, 0.03, -0.4))
    o1, _, _ = planar_chain((0.02, 0.03, -0.4), j1, OFFSET_J2, OFFSET_TIP, (0.0, 0.0))
    np.testing.assert_allclose(finger.joint1_in_hand, o1, rtol=0, atol=1e-16)
    for target, dist in _unreachable_cases(finger, rng):
        with pytest.raises(UnreachableError) as info:
            finger.inverse_kinematics(target)
        assert info.value.distance == pytest.approx(dist, rel=1e-12, abs=1e-17)


def test_bad_configuration_string():
    path = shipped_path(SHIPPED_NAMES[0])
    for bad in ("up", "", "l", None, 3):
        with pytest.raises(InvalidParameterError):
            Finger.from_urdf(path, configuration=bad)
        with pytest.raises(InvalidParameterError):
            Configuration.parse(bad)
    finger = Finger.from_urdf(path)
    with pytest.raises(InvalidParameterError):
        finger.with_placement(configuration="down")


@pytest.mark.parametrize(
    "base", [(math.nan, 0, 0), (0, math.inf, 0), (0, 0, -math.inf), (0, 0), (0, 0, 0, 0), "abc", [[0, 0, 0]]]
)
def test_bad_base_pose(base):
    path = shipped_path(SHIPPED_NAMES[0])
    with pytest.raises(InvalidParameterError):
        Finger.from_urdf(path, base_in_hand=base)
    with pytest.raises(InvalidParameterError):
        Finger.from_urdf(path).with_placement(base_in_hand=base)


@pytest.mark.parametrize(
    "q", [[0.1], [0.1, 0.2, 0.3], [[0.1, 0.2]], 0.1, [0.1, math.nan], [math.inf, 0.0], np.zeros((2, 1)), "ab"]
)
def test_bad_q(q):
    finger = Finger.from_urdf(shipped_path(SHIPPED_NAMES[0]))
    for method in (
        finger.forward_kinematics,
        finger.tip_jacobian,
        finger.joint_positions_in_hand,
        finger.theta2,
        finger.configuration_of,
        finger.inverse_kinematics,
    ):
        with pytest.raises(InvalidParameterError):
            method(q)


# --------------------------------------------------------------------------- 6. no mutation
def test_callers_model_is_not_mutated():
    text = shipped_path(SHIPPED_NAMES[0]).read_text()
    model = pin.buildModelFromXML(text)
    geom = pin.buildGeomFromUrdfString(model, text, pin.GeometryType.COLLISION)
    placements = [pin.SE3(m).homogeneous.copy() for m in model.jointPlacements]
    frames = [f.placement.homogeneous.copy() for f in model.frames]
    gravity = pin.Motion(model.gravity).vector.copy()
    geom_placements = [o.placement.homogeneous.copy() for o in geom.geometryObjects]

    base = (0.05, -0.03, 1.1)
    finger = Finger(model, geom, base_in_hand=base)
    q = np.array([0.4, -0.9])
    finger.forward_kinematics(q)
    finger.tip_jacobian(q)
    finger.inverse_kinematics(finger.forward_kinematics(q))
    finger.with_placement(base_in_hand=(0.2, 0.2, 0.2))

    assert [m.homogeneous.tolist() for m in model.jointPlacements] == [p.tolist() for p in placements]
    assert [f.placement.homogeneous.tolist() for f in model.frames] == [p.tolist() for p in frames]
    assert model.gravity.vector.tolist() == gravity.tolist()
    assert [o.placement.homogeneous.tolist() for o in geom.geometryObjects] == [p.tolist() for p in geom_placements]
    assert finger.model is not model

    # and the finger does not alias the caller's model either
    tip_before = finger.forward_kinematics(q)
    model.jointPlacements[2] = pin.SE3(np.eye(3), np.array([0.5, 0.0, 0.0]))
    model.jointPlacements[1] = pin.SE3(np.eye(3), np.array([1.0, 1.0, 0.0]))
    np.testing.assert_array_equal(finger.forward_kinematics(q), tip_before)
    np.testing.assert_allclose(tip_before, hand_fk_along_x(base, 0.12, 0.045, q), rtol=0, atol=1e-15)


def _assert_equivalent(a: Finger, b: Finger, rng: np.random.Generator) -> None:
    assert a.name == b.name
    assert a.configuration is b.configuration
    assert a.link_lengths == b.link_lengths
    assert a.reach == b.reach
    np.testing.assert_array_equal(a.base_in_hand, b.base_in_hand)
    np.testing.assert_allclose(a.joint1_in_hand, b.joint1_in_hand, rtol=0, atol=1e-16)
    assert a.psi1_offset == pytest.approx(b.psi1_offset, abs=1e-15)
    assert a.theta2_offset == pytest.approx(b.theta2_offset, abs=1e-15)
    assert [s.name for s in a.link_shapes()] == [s.name for s in b.link_shapes()]
    for _ in range(20):
        q = random_q(rng)
        np.testing.assert_allclose(a.forward_kinematics(q), b.forward_kinematics(q), rtol=0, atol=1e-15)
        np.testing.assert_allclose(a.tip_jacobian(q), b.tip_jacobian(q), rtol=0, atol=1e-15)
        np.testing.assert_allclose(a.joint_positions_in_hand(q), b.joint_positions_in_hand(q), rtol=0, atol=1e-15)
        assert a.configuration_of(q) == b.configuration_of(q)
        target = a.forward_kinematics(q)
        np.testing.assert_allclose(a.inverse_kinematics(target), b.inverse_kinematics(target), rtol=0, atol=1e-12)


@pytest.mark.parametrize("name", SHIPPED_NAMES + ["offset"])
def test_with_placement_equals_construction_from_scratch(name):
    rng = np.random.default_rng(19)

    def build(**kw):
        if name == "offset":
            return Finger.from_urdf_string(offset_urdf(OFFSET_J1_VARIANTS[1]), name="offset", **kw)
        return Finger.from_urdf(shipped_path(name), **kw)

    first = build(base_in_hand=(0.02, 0.01, 0.5), configuration="left")
    snapshot = first.forward_kinematics([0.3, 0.4])
    for _ in range(5):
        base = random_base(rng)
        moved = first.with_placement(base_in_hand=base, configuration="right")
        _assert_equivalent(moved, build(base_in_hand=base, configuration="right"), rng)
        # chaining does not compose base poses
        again = moved.with_placement(base_in_hand=(0.02, 0.01, 0.5), configuration="left")
        _assert_equivalent(again, first, rng)
    _assert_equivalent(first.with_placement(), first, rng)
    renamed = first.with_placement(name="thumb")
    assert renamed.name == "thumb" and first.name != "thumb"
    # the original is untouched
    np.testing.assert_array_equal(first.forward_kinematics([0.3, 0.4]), snapshot)
    np.testing.assert_array_equal(first.base_in_hand, [0.02, 0.01, 0.5])


# --------------------------------------------------------------------------- 7. property
FINGERS = {
    "short_distal": Finger.from_urdf(shipped_path(SHIPPED_NAMES[0])),
    "long_distal": Finger.from_urdf(shipped_path(SHIPPED_NAMES[1])),
    "offset": Finger.from_urdf_string(offset_urdf(OFFSET_J1_VARIANTS[1])),
}

angle = st.floats(-math.pi, math.pi, allow_nan=False)
coord = st.floats(-0.3, 0.3, allow_nan=False)


@settings(derandomize=True, max_examples=300, deadline=None)
@given(
    key=st.sampled_from(sorted(FINGERS)),
    configuration=st.sampled_from(["left", "right"]),
    x=coord,
    y=coord,
    theta=angle,
    q1=angle,
    q2=angle,
)
def test_property_ik_inverts_fk(key, configuration, x, y, theta, q1, q2):
    finger = FINGERS[key].with_placement(base_in_hand=(x, y, theta), configuration=configuration)
    q = np.array([q1, q2])
    assume(abs(math.sin(finger.theta2(q))) > 1e-3)
    target = finger.forward_kinematics(q)
    q_ik = finger.inverse_kinematics(target)
    l1, l2 = finger.link_lengths
    assert np.linalg.norm(finger.forward_kinematics(q_ik) - target) <= 1e-12 * (l1 + l2)
    assert finger.configuration_of(q_ik) is finger.configuration
    if finger.configuration_of(q) is finger.configuration:
        assert np.max(np.abs(wrapped_diff(q_ik, q))) < 1e-9


def test_effort_limits_come_from_the_urdf_or_an_override():
    from regrasp.model.finger import as_effort_limit
    from regrasp.model.finger_urdf import planar_2r_urdf

    urdf = planar_2r_urdf(0.1, 0.05)
    assert Finger.from_urdf_string(urdf).effort_limit.tolist() == [5.0, 5.0]
    none = Finger.from_urdf_string(urdf.replace('effort="5.0"', 'effort="0"'))
    assert np.isinf(none.effort_limit).all()  # (a URDF effort of 0: no limit)
    limited = Finger.from_urdf_string(urdf, effort_limit=[0.3, 0.2])
    assert limited.effort_limit.tolist() == [0.3, 0.2]
    assert limited.with_placement(name="other").effort_limit.tolist() == [0.3, 0.2]
    assert limited.with_placement(effort_limit=0.1).effort_limit.tolist() == [0.1, 0.1]
    assert limited.model.effortLimit.tolist() == [0.3, 0.2]  # (the model carries them: Hand and kernels read it)
    for bad in (0.0, -1.0, float("nan"), [0.3], [0.1, 0.2, 0.3], "1", True, [[0.1, 0.2]], [0.1, -0.2]):
        with pytest.raises(InvalidParameterError):
            as_effort_limit("effort_limit", bad)

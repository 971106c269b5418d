"""The compiled kernels against their references: the finger terms against Pinocchio on general planar
fingers, the hand's check and fallback, the plant's compiled step against its reference path."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import regrasp.kernels.finger as kernel_finger
from regrasp import Hand, RunSpec, load_scenario
from regrasp.core.contact import ContactMode, Friction
from regrasp.core.exceptions import InvalidParameterError
from regrasp.core.polygon import ConvexPolygon
from regrasp.kernels import finger_parameters, finger_terms_at
from regrasp.kernels.finger import largest_disagreement, reference_terms
from regrasp.model.finger import Finger
from regrasp.model.hand import KERNEL_TOLERANCE, KernelMismatchWarning
from regrasp.plants.project.plant import Plant
from regrasp.plants.project.state import PlantContact

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "scenarios"


def general_urdf(rng: np.random.Generator) -> str:
    """A planar 2R finger with everything a URDF may vary: yawed joint origins, off-axis centres of mass,
    a full inertia tensor, a tip off the link's axis, fixed links merged into the bodies."""
    def inertial():
        m = float(rng.uniform(0.01, 0.2))
        a = rng.uniform(-1, 1, (3, 3)) * 1e-4
        tensor = (a @ a.T + np.eye(3) * 1e-5).tolist()
        x, y, z = rng.uniform(-0.05, 0.05, 3).tolist()
        return (f'<inertial><origin xyz="{x!r} {y!r} {z!r}" rpy="0 0 0"/><mass value="{m!r}"/>'
                f'<inertia ixx="{tensor[0][0]!r}" ixy="{tensor[0][1]!r}" ixz="{tensor[0][2]!r}" '
                f'iyy="{tensor[1][1]!r}" iyz="{tensor[1][2]!r}" izz="{tensor[2][2]!r}"/></inertial>')

    def joint(name, parent, child, kind="revolute"):
        x, y = rng.uniform(-0.1, 0.1, 2).tolist()
        yaw = float(rng.uniform(-math.pi, math.pi))
        extra = ('<axis xyz="0 0 1"/><limit lower="-3.14" upper="3.14" effort="5" velocity="20"/>'
                 f'<dynamics damping="{float(rng.uniform(0, 0.01))!r}"/>' if kind == "revolute" else "")
        return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
                f'<origin xyz="{x!r} {y!r} 0" rpy="0 0 {yaw!r}"/>{extra}</joint>')

    return ('<robot name="general">'
            '<link name="base"/>'
            f'<link name="link1">{inertial()}</link><link name="link2">{inertial()}</link>'
            f'<link name="pad">{inertial()}</link><link name="tip"/>'
            + joint("joint1", "base", "link1") + joint("joint2", "link1", "link2")
            + joint("pad_joint", "link2", "pad", "fixed") + joint("tip_joint", "link2", "tip", "fixed")
            + '</robot>')


@pytest.mark.parametrize("seed", range(8))
def test_finger_terms_equal_pinocchio_on_general_fingers(seed):
    rng = np.random.default_rng(seed)
    fingers = []
    for i in range(3):
        finger = Finger.from_urdf_string(general_urdf(rng), base_in_hand=tuple(rng.uniform(-0.1, 0.1, 3)),
                                         name=f"f{i}")
        fingers.append(finger)
    gravity = rng.uniform(-10, 10, 2)
    for damped in (True, False):
        hand = Hand(fingers, gravity_in_hand=gravity, damping=damped, link_mass_scale=rng.uniform(0.5, 2.0))
        assert hand.kernel_parameters is not None
        # an independent draw of states, and the armature Pinocchio adds to M's diagonal
        model = pin.Model(hand.pinocchio_model)
        model.armature = rng.uniform(0, 1e-4, model.nv)
        params = np.stack([finger_parameters(model, tip, 2 * i + 1) for i, tip in enumerate(hand.tip_frame_ids)])
        worst, where = largest_disagreement(model, hand.tip_frame_ids, params, gravity, damped, states=32,
                                            seed=seed + 100)
        assert worst <= KERNEL_TOLERANCE, where


def test_finger_terms_include_what_they_claim():
    """The terms are not trivially equal: each of gravity, damping and velocity changes N, and armature M."""
    sc = load_scenario(EXAMPLES / "paper_trajectory_2_three_fingers.toml")
    hand = Hand([c.finger for c in sc.contacts])
    params = hand.kernel_parameters
    q, v = np.linspace(-1, 1, 6), np.linspace(2, -2, 6)
    base = finger_terms_at(params, q, v, (0.0, -9.81), True)
    for other in (finger_terms_at(params, q, v, (0.0, 0.0), True), finger_terms_at(params, q, v, (0.0, -9.81), False),
                  finger_terms_at(params, q, 0 * v, (0.0, -9.81), True)):
        assert np.all(np.abs(other["n0"] - base["n0"]) > 1e-6)
    heavy = params.copy()
    heavy["armature1"] = 1e-3
    assert np.allclose(finger_terms_at(heavy, q, v, (0.0, -9.81), True)["m00"] - base["m00"], 1e-3, rtol=0, atol=1e-15)


def test_a_hand_whose_kernels_disagree_warns_and_keeps_pinocchio(monkeypatch):
    sc = load_scenario(EXAMPLES / "paper_trajectory_2_three_fingers.toml")
    real = kernel_finger.finger_parameters

    def off(model, tip, first_joint=1):
        out = real(model, tip, first_joint)
        out["m2"] *= 1.0 + 1e-9  # a kernel built from the wrong constants
        return out

    monkeypatch.setattr(kernel_finger, "finger_parameters", off)
    with pytest.warns(KernelMismatchWarning, match="keeps the Pinocchio path"):
        hand = Hand([c.finger for c in sc.contacts])
    assert hand.kernel_parameters is None
    assert hand.kernel_disagreement[0] > KERNEL_TOLERANCE
    contacts = [PlantContact(c.edge, "fixed", 0.0) for c in sc.contacts]
    assert Plant(hand, sc.polygon, contacts, collision_check=False).compiled is False
    with pytest.raises(InvalidParameterError, match="compiled"):
        Plant(hand, sc.polygon, contacts, collision_check=False, compiled=True)


def test_reference_terms_agree_with_the_hand():
    """The check's reference is the hand's own Pinocchio path."""
    sc = load_scenario(EXAMPLES / "paper_trajectory_2_three_fingers.toml")
    hand = Hand([c.finger for c in sc.contacts])
    q, v = np.linspace(-1, 1, 6), np.linspace(2, -2, 6)
    dyn = hand.dynamics(q, v)
    model = hand.pinocchio_model
    ref = reference_terms(model, model.createData(), hand.tip_frame_ids[1], 3, q, v, True)
    np.testing.assert_allclose(ref["M"], dyn.mass_matrix[2:4, 2:4], atol=1e-15)
    np.testing.assert_allclose(ref["N"], dyn.nonlinear[2:4], atol=1e-15)
    np.testing.assert_allclose(ref["Jdv"], dyn.jacobian_dot_v[2:4], atol=1e-15)


# ---------------------------------------------------------------------------------------- the plant
def _plants(friction, collision_check=False):
    sc = load_scenario(EXAMPLES / "paper_trajectory_2_three_fingers.toml")
    hand = Hand([c.finger for c in sc.contacts])
    contacts = [PlantContact(c.edge, "fixed", 0.0) for c in sc.contacts]
    return sc, [Plant(hand, sc.polygon, contacts, friction=friction, compiled=compiled, stop_on=(),
                      collision_check=collision_check) for compiled in (False, True)]


def _random_contacts(rng, polygon: ConvexPolygon, m: int) -> list[PlantContact]:
    out = []
    for _ in range(m):
        edge = int(rng.integers(len(polygon.edges)))
        lo, hi = polygon.edge(edge).xi_range
        mode = [ContactMode.FIXED, ContactMode.SLIDING, ContactMode.SEPARATED][int(rng.choice(3, p=[0.5, 0.35, 0.15]))]
        out.append(PlantContact(edge, mode, float(rng.uniform(lo, hi)), float(rng.choice([-1.0, 1.0]))))
    return out


def _assert_same_step(a, b):
    scale = lambda x: np.maximum(1.0, np.abs(x))  # noqa: E731
    for name in ("q", "v", "X", "V"):
        x, y = getattr(a.state, name), getattr(b.state, name)
        assert np.all(np.abs(x - y) <= 1e-12 * scale(x)), name
    for name in ("torque_work", "damping_work", "contact_work"):
        assert abs(getattr(a.state, name) - getattr(b.state, name)) <= 1e-12, name
    for name in ("forces_surface", "xi", "xi_dot"):
        x, y = getattr(a, name), getattr(b, name)
        assert np.all(np.abs(x - y) <= 1e-9 * scale(x)), name
    assert abs(a.constraint_error - b.constraint_error) <= 1e-12
    assert a.modes == b.modes
    assert [(e.kind, e.contact) for e in a.events] == [(e.kind, e.contact) for e in b.events]


@pytest.mark.parametrize("seed", range(12))
def test_compiled_plant_step_equals_the_reference(seed):
    """Random states (the constraints violated: Baumgarte at work), modes, edges and torques; several steps,
    the events' mode switches included."""
    rng = np.random.default_rng(seed)
    friction = [Friction(mu, mu * rng.uniform(0.5, 1.0)) for mu in rng.uniform(0.2, 1.2, 3)]
    sc, (ref, fast) = _plants(friction)
    contacts = _random_contacts(rng, sc.polygon, 3)
    q = np.array([0.3, 1.2, -0.3, -1.2, 0.5, 1.0]) + rng.uniform(-0.2, 0.2, 6)
    v, X, V = rng.uniform(-1, 1, 6), rng.uniform(-0.01, 0.01, 3), rng.uniform(-0.05, 0.05, 3)
    tau = rng.uniform(-0.05, 0.05, 6)
    for plant in (ref, fast):
        plant.reset(q, v, X + np.array([0.0, 0.12, 0.0]), V, contacts=contacts)
    kinds = set()
    for _ in range(20):
        a, b = ref.step(tau), fast.step(tau)
        _assert_same_step(a, b)
        kinds |= {e.kind for e in a.events}
        assert [c.mode for c in ref.contacts] == [c.mode for c in fast.contacts]
    np.testing.assert_allclose(fast.accelerations(fast.state, tau)[0], ref.accelerations(ref.state, tau)[0],
                               rtol=1e-9, atol=1e-9)


def test_compiled_plant_meets_every_event_kind_the_reference_does():
    """Over the seeds above the random steps fire separation, slip and left_edge on both paths."""
    seen = set()
    for seed in range(12):
        rng = np.random.default_rng(seed)
        friction = [Friction(mu, mu * rng.uniform(0.5, 1.0)) for mu in rng.uniform(0.2, 1.2, 3)]
        sc, (_, fast) = _plants(friction)
        contacts = _random_contacts(rng, sc.polygon, 3)
        q = np.array([0.3, 1.2, -0.3, -1.2, 0.5, 1.0]) + rng.uniform(-0.2, 0.2, 6)
        fast.reset(q, rng.uniform(-1, 1, 6), rng.uniform(-0.01, 0.01, 3) + np.array([0.0, 0.12, 0.0]),
                   rng.uniform(-0.05, 0.05, 3), contacts=contacts)
        for _ in range(20):
            seen |= {e.kind.value for e in fast.step(rng.uniform(-0.05, 0.05, 6)).events}
    assert {"separation", "slip"} <= seen, seen


@pytest.mark.slow
def test_a_scheduled_rollout_is_the_same_on_both_paths():
    """The three-finger scheduled rollout (collision checks, slides, sticks) for 1.5 s on each path (slips at 0.82 s,
    sticks at 1.37 s)."""
    from regrasp import build_rollout

    sc = load_scenario(EXAMPLES / "paper_trajectory_2_three_fingers.toml")
    runs = []
    for compiled in (False, True):
        rollout = build_rollout(sc, RunSpec(duration=1.5))
        rollout.plant.compiled = compiled
        result = rollout.run()
        runs.append((rollout.plant.state, [(e.kind, e.contact) for e in rollout.plant.events], result.success))
    (a, events_a, ok_a), (b, events_b, ok_b) = runs
    assert ok_a and ok_b
    assert events_a == events_b and any(kind.value == "stick" for kind, _ in events_a)
    for name in ("q", "v", "X", "V"):
        np.testing.assert_allclose(getattr(b, name), getattr(a, name), rtol=0, atol=1e-10)


# ---------------------------------------------------------------------------------------- the reduced model
def _models(modes, xi, singular_threshold=1e4):
    from regrasp import Grasp, ReducedModel

    sc = load_scenario(EXAMPLES / "paper_trajectory_2_three_fingers.toml")
    hand = Hand([c.finger for c in sc.contacts], singular_threshold=singular_threshold)
    grasp = Grasp(sc.polygon, [c.edge for c in sc.contacts], modes)
    return [ReducedModel(hand, grasp, xi, compiled=compiled) for compiled in (False, True)]


@pytest.mark.parametrize("modes", [("fixed", "fixed", "fixed"), ("sliding", "fixed", "fixed"),
                                   ("fixed", "sliding", "sliding")])
def test_compiled_reduced_terms_equal_the_reference(modes):
    rng = np.random.default_rng(len(modes[0]) + modes.count("sliding"))
    ref, fast = _models(modes, [-0.0125, 0.0125, 0.0])
    assert fast.compiled and not ref.compiled
    p = modes.count("sliding")
    for _ in range(25):
        S = np.concatenate([[0.0, 0.12, 0.0] + rng.uniform(-0.005, 0.005, 3), rng.uniform(-0.01, 0.01, p)])
        S_dot = rng.uniform(-0.05, 0.05, 3 + p)
        a, b = ref.terms(S.tolist(), S_dot.tolist()), fast.terms(S.tolist(), S_dot.tolist())
        for name in a._fields:
            x, y = np.asarray(getattr(a, name), dtype=float), np.asarray(getattr(b, name), dtype=float)
            assert x.shape == y.shape, name
            assert np.all(np.abs(x - y) <= 1e-12 * np.maximum(1.0, np.abs(x))), name
        st_a, st_b = ref.state(S, S_dot), fast.state(S, S_dot)
        np.testing.assert_allclose(fast.mass_matrix(st_b), ref.mass_matrix(st_a), rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(fast.bias(st_b), ref.bias(st_a), rtol=1e-12, atol=1e-15)


def test_compiled_reduced_terms_raise_what_the_reference_raises():
    from regrasp.core.exceptions import SingularFingerError, UnreachableError

    ref, fast = _models(("fixed", "fixed", "fixed"), [-0.0125, 0.0125, 0.0])
    far = [0.0, 0.5, 0.0]  # the object out of every finger's reach
    for model in (ref, fast):
        with pytest.raises(UnreachableError) as info:
            model.terms(far, [0.0] * 3)
        assert info.value.finger == "finger1"
    errors = []
    for model in (ref, fast):  # the object drawn down until a finger is out of reach
        for y in np.linspace(0.1, 0.3, 400):
            try:
                model.terms([0.0, float(y), 0.0], [0.0] * 3)
            except (SingularFingerError, UnreachableError) as exc:
                errors.append((type(exc).__name__, exc.finger, round(float(y), 6)))
                break
    assert len(errors) == 2 and errors[0] == errors[1]
    strict = _models(("fixed", "fixed", "fixed"), [-0.0125, 0.0125, 0.0], singular_threshold=1.5)
    found = []
    for model in strict:  # a threshold every finger exceeds
        with pytest.raises(SingularFingerError) as info:
            model.terms([0.0, 0.12, 0.0], [0.0] * 3)
        found.append((info.value.finger, info.value.condition))
    assert found[0][0] == found[1][0] and found[0][1] == pytest.approx(found[1][1], rel=1e-12)

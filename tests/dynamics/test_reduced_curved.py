"""The reduced model of paper §3 on curved objects: the contact frame turns with ξ (κ terms), checked by finite
differences (the grasp's Ġ and Ṙ_f, the model's H and Ḣ Ṡ) to 1e-7, with a check that the curvature term is what
makes them agree (the edge-only formula misses by far more)."""

from pathlib import Path

import numpy as np
import pytest

from regrasp import Finger, Grasp, Hand, ReducedModel
from regrasp.core.curves import Disc, Ellipse, RoundedPolygon, SupportCurve
from regrasp.core.exceptions import InvalidParameterError

ROOT = Path(__file__).resolve().parents[2]
URDF = ROOT / "urdf" / "planar_2r_finger.urdf"

#: Objects whose left, right and bottom points are those of the 0.10 x 0.04 rectangle of test_reduced.py (or near):
#: each symmetric, so they sit at ξ = 3P/4, P/4 and P/2.
OBJECTS = {
    "disc": Disc(0.05, mass=0.08),
    "ellipse": Ellipse(0.05, 0.02, mass=0.08),
    "rounded box": RoundedPolygon(0.5 * np.array([[0.10, 0.04], [-0.10, 0.04], [-0.10, -0.04], [0.10, -0.04]]), 0.01,
                                  mass=0.08),
    "support curve": SupportCurve([0.035, 0.0, 0.012, 0.0, -0.0012], [0.0, 0.0, 0.0, 0.0], mass=0.08),
}
CASES = [
    (2, ("sliding", "fixed")),
    (2, ("fixed", "sliding")),
    (3, ("fixed", "sliding", "fixed")),
    (3, ("sliding", "fixed", "sliding")),
    (3, ("fixed", "fixed", "fixed")),
]


def make_model(obj, m, modes, gravity=(0.0, -9.81)):
    fingers = [
        Finger.from_urdf(URDF, base_in_hand=(-0.05, 0.0, np.pi / 2), configuration="left", name="f1"),
        Finger.from_urdf(URDF, base_in_hand=(0.05, 0.0, np.pi / 2), configuration="right", name="f2"),
        Finger.from_urdf(URDF, base_in_hand=(0.0, 0.0, np.pi / 2), configuration="left", name="f3"),
    ][:m]
    hand = Hand(fingers, gravity_in_hand=gravity)
    return ReducedModel(hand, Grasp(obj, [0] * m, modes), xi=np.zeros(m))


def random_state(rng, model):
    P = model.grasp.polygon.perimeter
    m, p = model.grasp.m, model.grasp.p
    xi = np.array([0.75 * P, 0.25 * P, 0.5 * P][:m]) + rng.uniform(-0.012, 0.012, size=m)
    model.xi = xi
    y = 0.12 if isinstance(model.grasp.polygon, (Ellipse, RoundedPolygon)) else 0.13
    S = np.concatenate([[rng.uniform(-0.004, 0.004), y + rng.uniform(-0.003, 0.003), rng.uniform(-0.1, 0.1)],
                        xi[list(model.grasp.sliding)]])
    S_dot = np.concatenate([rng.normal(size=3) * [0.05, 0.05, 0.5],
                            rng.choice([-1, 1], size=p) * rng.uniform(0.05, 0.2, size=p)])
    return S, S_dot


def _param_ids():
    return [(name, m, modes) for name in OBJECTS for m, modes in CASES]


@pytest.mark.parametrize("name,m,modes", _param_ids())
@pytest.mark.parametrize("seed", range(3))
def test_H_and_H_dot_S_dot_match_finite_differences_on_curves(name, m, modes, seed):
    rng = np.random.default_rng(seed)
    model = make_model(OBJECTS[name], m, modes)
    assert not model.compiled
    S, S_dot = random_state(rng, model)
    st = model.state(S, S_dot)
    h = 1e-5

    def fd(f):  # 4th-order central difference along S(t) = S + t Ṡ
        return (-f(S + 2 * h * S_dot) + 8 * f(S + h * S_dot) - 8 * f(S - h * S_dot) + f(S - 2 * h * S_dot)) / (12 * h)

    np.testing.assert_allclose(st.H @ S_dot, fd(model.joint_positions), atol=1e-7)
    hsd = fd(lambda s: model.state(s, S_dot).H @ S_dot)
    scale = max(1.0, np.abs(hsd).max())
    assert np.abs(st.H_dot_S_dot - hsd).max() <= 1e-7 * scale
    # the curvature term is what agrees: without κ ξ̇² n (the edge's formula) Ḣ Ṡ misses by far more
    pose, xi, _, xi_dot = model.split(S, S_dot)
    kappa = model.grasp.curvatures(xi)
    normals = model.grasp.surface_frames(pose, xi)[:, :, 0]
    missing = np.concatenate([np.linalg.solve(st.hand.jacobian[2 * i:2 * i + 2, 2 * i:2 * i + 2],
                                              kappa[i] * xi_dot[i] ** 2 * normals[i]) for i in range(m)])
    if model.grasp.p and np.any(kappa[list(model.grasp.sliding)] > 0):
        assert np.abs(st.H_dot_S_dot - missing - hsd).max() > 1e3 * 1e-7 * scale


@pytest.mark.parametrize("name", list(OBJECTS))
@pytest.mark.parametrize("seed", range(4))
def test_grasp_matrix_and_frame_rates_match_finite_differences(name, seed):
    rng = np.random.default_rng(10 + seed)
    grasp = Grasp(OBJECTS[name], [0, 0, 0], ("sliding", "fixed", "sliding"))
    P = grasp.polygon.perimeter
    pose, xi = rng.normal(size=3) * [0.01, 0.01, 0.5], rng.uniform(0, P, size=3)
    pose_dot, xi_dot = rng.normal(size=3), rng.normal(size=3) * [0.1, 0.0, 0.1]
    h = 1e-5

    def fd(f):
        def at(k):
            return f(pose + k * h * pose_dot, xi + k * h * xi_dot)
        return (-at(2) + 8 * at(1) - 8 * at(-1) + at(-2)) / (12 * h)

    np.testing.assert_allclose(grasp.grasp_matrix_dot(pose, xi, pose_dot, xi_dot), fd(grasp.grasp_matrix), atol=1e-7)
    np.testing.assert_allclose(grasp.surface_rotation_dot(pose, pose_dot, xi, xi_dot), fd(grasp.surface_rotation),
                               atol=1e-7)
    # points move along the tangent: d/dξ c(ξ) = t, as the velocity relation q̇ = H Ṡ assumes
    np.testing.assert_allclose(fd(lambda p, x: grasp.points(p, x)),
                               pose_dot[:2] + pose_dot[2] * (grasp.lever_arms(pose, xi) @ [[0, 1], [-1, 0]])
                               + xi_dot[:, None] * grasp.surface_frames(pose, xi)[:, :, 1], atol=1e-9)


def test_curved_grasp_errors():
    grasp = Grasp(OBJECTS["disc"], [0, 0], ("sliding", "fixed"))
    with pytest.raises(InvalidParameterError, match="depends on ξ"):
        grasp.surface_frames(np.zeros(3))
    with pytest.raises(InvalidParameterError, match="κ ξ̇"):
        grasp.surface_rotation_dot(np.zeros(3), np.zeros(3), np.zeros(2))
    with pytest.raises(InvalidParameterError, match="curved object"):
        fingers = [Finger.from_urdf(URDF, base_in_hand=(x, 0.0, np.pi / 2), name=f"f{k}")
                   for k, x in enumerate((-0.05, 0.05))]
        ReducedModel(Hand(fingers), grasp, xi=np.zeros(2), compiled=True)

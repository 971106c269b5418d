"""Grasp matrices (paper §3.1, §3.4): G against explicit wrenches, exact derivatives against finite
differences, B_v/B_f/G_f/P against the object's equation solved directly, and Remark 3.2."""

import numpy as np
import pytest

from regrasp import ConvexPolygon, Friction, InvalidParameterError
from regrasp.core import SlidingContactCountError
from regrasp.dynamics.grasp import Grasp

H_STEP = 1e-6


def rectangle():
    return ConvexPolygon.rectangle(0.10, 0.04, mass=0.08)


def random_state(rng, grasp):
    pose = np.array([rng.uniform(-0.02, 0.02), rng.uniform(0.1, 0.14), rng.uniform(-0.5, 0.5)])
    xi = rng.uniform(-0.015, 0.015, size=grasp.m)
    twist = rng.normal(size=3) * np.array([0.05, 0.05, 1.0])
    xi_dot = np.where([m.value == "sliding" for m in grasp.modes], rng.normal(size=grasp.m) * 0.02, 0.0)
    return pose, xi, twist, xi_dot


@pytest.mark.parametrize("seed", range(10))
def test_grasp_matrix_is_the_sum_of_contact_wrenches(seed):
    rng = np.random.default_rng(seed)
    grasp = Grasp(rectangle(), [1, 3, 2], ["fixed", "sliding", "fixed"])
    pose, xi, _, _ = random_state(rng, grasp)
    f = rng.normal(size=(3, 2))
    pts = grasp.points(pose, xi)
    expected = np.zeros(3)
    for p, fi in zip(pts, f):
        r = p - pose[:2]
        expected += [fi[0], fi[1], r[0] * fi[1] - r[1] * fi[0]]
    G = grasp.grasp_matrix(pose, xi)
    assert G.shape == (3, 6)
    np.testing.assert_allclose(G @ f.reshape(-1), expected, atol=1e-15)
    # the contact points lie on their edges, in the hand frame
    for k, (edge, p) in enumerate(zip(grasp.edges, pts)):
        rot = np.array([[np.cos(pose[2]), -np.sin(pose[2])], [np.sin(pose[2]), np.cos(pose[2])]])
        local = rot.T @ (p - pose[:2])
        assert abs(edge.inward_normal @ (local - edge.start)) < 1e-15


@pytest.mark.parametrize("seed", range(10))
def test_exact_derivatives_match_finite_differences(seed):
    rng = np.random.default_rng(seed)
    grasp = Grasp(rectangle(), [1, 3, 0], ["sliding", "fixed", "sliding"])
    pose, xi, twist, xi_dot = random_state(rng, grasp)
    h = H_STEP
    dG = (grasp.grasp_matrix(pose + h * twist, xi + h * xi_dot)
          - grasp.grasp_matrix(pose - h * twist, xi - h * xi_dot)) / (2 * h)
    # central differences: error ~ h^2 * |third derivative| (<~ 1e-12 here) plus roundoff ~ eps * scale / h
    tol = 1e-12 + 1e-16 * 0.2 / h
    np.testing.assert_allclose(grasp.grasp_matrix_dot(pose, xi, twist, xi_dot), dG, atol=tol)
    dR = (grasp.surface_rotation(pose + h * twist) - grasp.surface_rotation(pose - h * twist)) / (2 * h)
    np.testing.assert_allclose(grasp.surface_rotation_dot(pose, twist), dR, atol=1e-9)


def test_omega_cross_sign():
    """Ṙ Rᵀ = ω [[0, -1], [1, 0]] (the paper prints the opposite sign)."""
    beta, omega, h = 0.7, 1.3, 1e-6
    R = lambda b: np.array([[np.cos(b), -np.sin(b)], [np.sin(b), np.cos(b)]])  # noqa: E731
    R_dot = (R(beta + h * omega) - R(beta - h * omega)) / (2 * h)
    np.testing.assert_allclose(R_dot @ R(beta).T, omega * np.array([[0, -1], [1, 0]]), atol=1e-9)


def test_bv_bf_shapes_and_values():
    grasp = Grasp(rectangle(), [1, 3, 2], ["fixed", "sliding", "fixed"])
    Bv = grasp.sliding_directions()
    assert Bv.shape == (6, 1) and Bv[3, 0] == 1.0 and Bv.sum() == 1.0
    Bf = grasp.force_basis([-1.0], 0.3)
    assert Bf.shape == (6, 5)
    np.testing.assert_allclose(Bf[2:4, 2], [1.0, -0.3])
    np.testing.assert_allclose(Bf[0:2, 0:2], np.eye(2))
    with pytest.raises(Exception, match=r"\+1 or -1"):
        grasp.force_basis([0.5], 0.3)


@pytest.mark.parametrize("seed", range(10))
def test_friction_map_P_matches_the_object_equation_solved_directly(seed):
    """m = 2, p = 1: f_ξ = P (M_o Ẍ - f_g) (eq. 3.4.9) equals the tangential force found by solving
    G f = w with the friction law μ s n·f_1 = t·f_1 written out by hand."""
    rng = np.random.default_rng(seed)
    grasp = Grasp(rectangle(), [1, 3], ["sliding", "fixed"])
    pose, xi, _, _ = random_state(rng, grasp)
    mu, s = 0.35, float(rng.choice([-1.0, 1.0]))
    wrench = rng.normal(size=3)  # M_o Ẍ - f_g
    # the sliding contact's kinetic coefficient (its μ_s and the fixed contact's friction play no part)
    P = grasp.friction_map(pose, xi, [s], [Friction(0.9, mu), Friction(0.2, 0.1)])
    np.testing.assert_array_equal(P, grasp.friction_map(pose, xi, [s], mu))
    frames = grasp.surface_frames(pose)
    n1, t1 = frames[0][:, 0], frames[0][:, 1]
    G = grasp.grasp_matrix(pose, xi)
    # unknown f = (f1, f2) in R^4: G f = wrench (3 rows), t1.f1 - mu s n1.f1 = 0 (1 row)
    A = np.vstack([G, np.concatenate([t1 - mu * s * n1, [0.0, 0.0]])])
    f = np.linalg.solve(A, np.concatenate([wrench, [0.0]]))
    np.testing.assert_allclose(P @ wrench, [t1 @ f[:2]], rtol=1e-10, atol=1e-14)
    Gf = grasp.sliding_grasp_matrix(pose, xi, [s], mu)
    assert Gf.shape == (3, 3)


def test_remark_3_2_limits_sliding_contacts():
    with pytest.raises(SlidingContactCountError) as err:
        Grasp(rectangle(), [1, 3], ["sliding", "sliding"])
    assert err.value.m == 2 and err.value.p == 2 and "2m >= 3 + p" in str(err.value)
    Grasp(rectangle(), [1, 3, 2], ["sliding", "sliding", "sliding"])  # 6 >= 6
    with pytest.raises(SlidingContactCountError):
        Grasp(rectangle(), [1], ["fixed"])  # one finger cannot hold a planar object
    with pytest.raises(Exception, match="m = 2 fingers with p = 1"):
        Grasp(rectangle(), [1, 3, 2], ["sliding", "fixed", "fixed"]).friction_map(np.zeros(3), np.zeros(3), [1.0], 0.3)


def test_force_basis_takes_each_sliding_contacts_kinetic_coefficient():
    """B_f's column of sliding contact i is (1, s_i μ_k,i) in its surface frame; fixed blocks are I_2."""
    grasp = Grasp(rectangle(), [1, 3, 2], ["sliding", "fixed", "sliding"])
    bf = grasp.force_basis([1.0, -1.0], [Friction(0.9, 0.4), Friction(0.8, 0.1), Friction(0.7, 0.25)])
    expected = np.zeros((6, 4))
    expected[0:2, 0] = (1.0, 0.4)
    expected[2:4, 1:3] = np.eye(2)
    expected[4:6, 3] = (1.0, -0.25)
    np.testing.assert_array_equal(bf, expected)
    np.testing.assert_array_equal(grasp.force_basis([1.0, -1.0], Friction(0.5)), grasp.force_basis([1.0, -1.0], 0.5))
    for bad in (-0.1, float("nan"), [0.5, 0.5], "0.5"):
        with pytest.raises(InvalidParameterError):
            grasp.force_basis([1.0, -1.0], bad)

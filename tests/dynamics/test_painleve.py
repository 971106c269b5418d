"""The sliders' normal response (regrasp.dynamics.painleve) against the project plant: its own Delassus system's Schur
complement, and the change of its normal forces under a change of the torques."""

from __future__ import annotations

import functools
import math
from pathlib import Path

import numpy as np
import pytest

from regrasp import Hand, Plant, PlantContact, load_scenario
from regrasp.core.exceptions import InvalidParameterError, UnreachableError
from regrasp.dynamics.painleve import composite_inverse_mass, is_p_matrix, sliding_response, tip_mobility

ROOT = Path(__file__).resolve().parents[2]


@functools.lru_cache(maxsize=1)
def _scenario():
    return load_scenario(ROOT / "examples" / "scenarios" / "paper_trajectory_2_three_fingers.toml")


def _state(seed: int, modes: tuple):
    """A plant at a consistent state (every tip on its contact point) with contacts in ``modes`` (None: fixed, ±1:
    sliding that way) and the terms sliding_response takes."""
    rng = np.random.default_rng(seed)
    sc = _scenario()
    hand = Hand([c.finger for c in sc.contacts])
    edges = [sc.polygon.edge(c.edge) for c in sc.contacts]
    for _ in range(1000):  # (a pose of the trajectory and positions near the middles that every finger reaches)
        X = sc.trajectory.pose(float(rng.uniform(sc.trajectory.t_start, sc.trajectory.t_end)))
        rot = np.array([[math.cos(X[2]), -math.sin(X[2])], [math.sin(X[2]), math.cos(X[2])]])
        xi = rng.uniform(-0.004, 0.004, size=len(edges))
        points = np.array([rot @ e.point(x) for e, x in zip(edges, xi)])
        try:
            q = hand.inverse_kinematics(X[:2] + points)
            break
        except UnreachableError:
            continue
    else:
        raise AssertionError("no reachable state drawn")
    v = rng.normal(0.0, 0.2, size=q.shape)
    contacts = [PlantContact(c.edge, "fixed" if d is None else "sliding", float(x), 1.0 if d is None else float(d))
                for c, x, d in zip(sc.contacts, xi, modes)]
    plant = Plant(hand, sc.polygon, contacts, friction=[c.friction for c in sc.contacts], collision_check=False)
    plant.reset(q, v, X, rng.normal(0.0, 0.1, size=3), contacts=contacts)
    dyn = hand.dynamics(q, v)
    m = len(edges)
    W = np.array([tip_mobility(dyn.jacobian[2 * i:2 * i + 2, 2 * i:2 * i + 2],
                               dyn.mass_matrix[2 * i:2 * i + 2, 2 * i:2 * i + 2]) for i in range(m)])
    normals = np.array([rot @ e.inward_normal for e in edges])
    tangents = np.array([rot @ e.xi_direction for e in edges])
    ratios = [None if d is None else d * c.friction.kinetic for c, d in zip(sc.contacts, modes)]
    return plant, dyn, (points, normals, tangents, W, ratios)


MODES = [(1, None, None), (-1, None, None), (None, 1, None), (None, None, -1), (1, -1, None), (-1, None, 1)]


@pytest.mark.parametrize("modes", MODES)
@pytest.mark.parametrize("seed", range(3))
def test_response_is_the_plants_schur_complement(modes, seed):
    """A equals the Schur complement of the held contacts' rows in the plant's Delassus matrix (built from the plant's
    constraint rows in joint and object coordinates: another derivation of the same physics)."""
    plant, _, (points, normals, tangents, W, ratios) = _state(100 + seed, modes)
    eq, st = plant.equations, plant.state
    fingers = eq.pin_pass(st.q, st.v)
    rows, _, cols = eq.rows(fingers, eq.specs(plant.contacts), st.X.tolist(), st.V.tolist())
    D = np.empty((len(rows), len(cols)))
    for a, (ri, dx, dy, c0, c1, c2) in enumerate(rows):
        l00, l01, l11 = fingers[ri][18:21]
        ux, uy = dx * l00 + dy * l01, dx * l01 + dy * l11
        for b, (ci, fx, fy, o0, o1, o2) in enumerate(cols):
            D[a, b] = c0 * o0 / eq.mass + c1 * o1 / eq.mass + c2 * o2 / eq.inertia - (ux * fx + uy * fy if ri == ci
                                                                                      else 0.0)
    slide = [a for a, r in enumerate(rows) if ratios[r[0]] is not None]
    held = [a for a in range(len(rows)) if a not in slide]
    schur = D[np.ix_(slide, slide)] - D[np.ix_(slide, held)] @ np.linalg.solve(D[np.ix_(held, held)],
                                                                               D[np.ix_(held, slide)])
    A = sliding_response(eq.mass, eq.inertia, points, normals, tangents, W, ratios)
    # (the plant's rows measure the gap the other way: its Delassus block is -A)
    np.testing.assert_allclose(-schur, A, rtol=1e-10, atol=1e-10 * np.abs(A).max())


@pytest.mark.parametrize("modes", MODES)
@pytest.mark.parametrize("seed", range(3))
def test_response_predicts_the_plants_normal_forces_under_a_torque_change(modes, seed):
    r"""The plant's forces are affine in the torques for fixed modes: a torque change δ on the sliders' fingers
    changes their normal forces by :math:`A^{-1} (n_a^T J_a M_a^{-1} \delta_a)_a`."""
    plant, dyn, (points, normals, tangents, W, ratios) = _state(200 + seed, modes)
    eq, st = plant.equations, plant.state
    A = sliding_response(eq.mass, eq.inertia, points, normals, tangents, W, ratios)
    sliders = [i for i, r in enumerate(ratios) if r is not None]
    rng = np.random.default_rng(300 + seed)
    tau = rng.normal(0.0, 0.01, size=plant.hand.nq)
    delta = np.zeros_like(tau)
    for i in sliders:
        delta[2 * i:2 * i + 2] = rng.normal(0.0, 1e-3, size=2)
    _, _, f0 = plant.accelerations(st, tau)
    _, _, f1 = plant.accelerations(st, tau + delta)
    measured = np.array([(f1[i] - f0[i]) @ normals[i] for i in sliders])
    drive = np.array([normals[i] @ dyn.jacobian[2 * i:2 * i + 2, 2 * i:2 * i + 2]
                      @ np.linalg.solve(dyn.mass_matrix[2 * i:2 * i + 2, 2 * i:2 * i + 2], delta[2 * i:2 * i + 2])
                      for i in sliders])
    np.testing.assert_allclose(measured, np.linalg.solve(A, drive), rtol=1e-7, atol=1e-12)


def test_frictionless_response_is_symmetric_positive_definite_and_friction_can_break_it():
    """Without friction A is symmetric positive definite; a ratio large enough against the finger's coupling of normal
    and tangential mobility makes a diagonal entry negative (Painlevé), and then A is not a P-matrix."""
    plant, _, (points, normals, tangents, W, _) = _state(7, (1, -1, None))
    eq = plant.equations
    A0 = sliding_response(eq.mass, eq.inertia, points, normals, tangents, W, [0.0, 0.0, None])
    np.testing.assert_allclose(A0, A0.T, rtol=1e-12, atol=1e-12 * np.abs(A0).max())
    assert np.linalg.eigvalsh(A0).min() > 0.0 and is_p_matrix(A0)
    coupling = sliding_response(eq.mass, eq.inertia, points, normals, tangents, W, [1.0, None, None])[0, 0] \
        - sliding_response(eq.mass, eq.inertia, points, normals, tangents, W, [0.0, None, None])[0, 0]
    ratio = -2.0 * sliding_response(eq.mass, eq.inertia, points, normals, tangents, W, [0.0, None, None])[0, 0] \
        / coupling  # A_00 is affine in the ratio: this one makes it -A_00(0)
    A = sliding_response(eq.mass, eq.inertia, points, normals, tangents, W, [ratio, None, None])
    assert A[0, 0] < 0.0 and not is_p_matrix(A)


def test_p_matrix_needs_every_principal_minor():
    assert is_p_matrix(np.array([[1.0, 3.0], [-1.0, 1.0]]))  # not symmetric, still a P-matrix
    assert not is_p_matrix(np.array([[1.0, 2.0], [2.0, 1.0]]))  # positive diagonal, negative determinant
    assert is_p_matrix(np.stack([np.eye(3), -np.eye(3)])).tolist() == [True, False]


def test_composite_inverse_mass_welds_fingers_and_takes_a_singular_mobility():
    """Welding a finger adds its tip inertia W^-1 at its point; a finger that cannot move a direction (W singular)
    makes the composite rigid that way, without an inverse of W."""
    rng = np.random.default_rng(5)
    mass, inertia = 0.1, 2e-4
    p = rng.normal(0.0, 0.03, size=(1, 2))
    Wj = np.array([[[3.0, 1.0], [1.0, 2.0]]])
    G = np.array([[1.0, 0.0], [0.0, 1.0], [-p[0, 1], p[0, 0]]])
    expected = np.linalg.inv(np.diag([mass, mass, inertia]) + G @ np.linalg.inv(Wj[0]) @ G.T)
    np.testing.assert_allclose(composite_inverse_mass(mass, inertia, p, Wj), expected, rtol=1e-12)
    singular = np.array([[[1.0, 0.0], [0.0, 0.0]]])  # moves along x only
    inv = composite_inverse_mass(mass, inertia, np.zeros((1, 2)), singular)
    assert np.isfinite(inv).all() and abs(inv[1, 1]) < 1e-12  # the weld holds the object in y
    np.testing.assert_allclose(composite_inverse_mass(mass, inertia, np.zeros((0, 2)), np.zeros((0, 2, 2))),
                               np.diag([1 / mass, 1 / mass, 1 / inertia]))


def test_bad_input_is_refused():
    points, frames, W = np.zeros((2, 2)), np.tile([1.0, 0.0], (2, 1)), np.tile(np.eye(2), (2, 1, 1))
    with pytest.raises(InvalidParameterError, match="positive mass"):
        sliding_response(0.0, 1e-4, points, frames, frames, W, [0.5, None])
    with pytest.raises(InvalidParameterError, match="one per contact"):
        sliding_response(0.1, 1e-4, points, frames, frames, W, [0.5])
    with pytest.raises(InvalidParameterError):
        sliding_response(0.1, 1e-4, np.full((2, 2), np.nan), frames, frames, W, [0.5, None])

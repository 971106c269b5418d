"""The internal-force QP's test cases (``dynamics/internal_force/test_solver.py``, ``test_margin.py`` and the
kernels' tests): the hand of ``paper_trajectory_2.toml`` with a third finger under the object, seeded random
states, and the QP's constraints written from its definition."""

from __future__ import annotations

import functools
import itertools
from pathlib import Path

import numpy as np

from regrasp import (
    Finger,
    Friction,
    Grasp,
    Hand,
    ReducedModel,
    load_scenario,
)
from regrasp.core.exceptions import (
    SingularFingerError,
    UnreachableError,
)
from regrasp.dynamics.control import Gains
from regrasp.dynamics.internal_force.settings import InternalForceSettings
from regrasp.dynamics.laws import FixedContactController, Proposition1Controller

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "examples" / "scenarios" / "paper_trajectory_2.toml"
URDF = ROOT / "urdf" / "planar_2r_finger.urdf"
EDGES = {2: (1, 3), 3: (1, 3, 2)}
Y0 = 0.12  # the object's centre height in the scenario


# ---------------------------------------------------------------------------- set-up
@functools.lru_cache(maxsize=None)
def scenario():
    return load_scenario(SCENARIO)


@functools.lru_cache(maxsize=None)
def fingers():
    f1, f2 = (c.finger for c in scenario().contacts)
    f3 = Finger.from_urdf(URDF, base_in_hand=(0.04, -0.02, np.pi / 2), configuration="left", name="finger3")
    return (f1, f2, f3)


def polygon():
    return scenario().polygon


def make_hand(m: int, gravity=(0.0, -9.81)) -> Hand:
    return Hand(list(fingers()[:m]), gravity_in_hand=gravity)


def qp_data(model: ReducedModel, S, S_dot):
    """(state, A, surface frames, fixed mask) at (S, Ṡ) (the mask for this file's own checks; the
    library takes the grasp's modes)."""
    st = model.state(S, S_dot)
    A = np.hstack([st.G.T, st.R_f @ st.B_v])
    frames = model.grasp.surface_frames(st.S[:3])
    fixed = np.array([mode.value == "fixed" for mode in model.grasp.modes])
    return st, A, frames, fixed


def to_surface(frames, forces) -> np.ndarray:
    """Hand-frame forces (m, 2) -> (normal, tangential) per contact."""
    forces = np.asarray(forces, float).reshape(len(frames), 2)
    return np.stack([frames[i].T @ forces[i] for i in range(len(frames))])


def from_surface(frames, surface) -> np.ndarray:
    """(normal, tangential) per contact -> hand-frame forces, flattened (2m,)."""
    return np.concatenate([frames[i] @ np.asarray(surface[i], float) for i in range(len(frames))])


def constraint_rows(frames, fixed, mu, settings: InternalForceSettings):
    """The QP's inequalities on the total force f = f_m + f_c as rows (a, lo): a . f >= lo.

    Written from the module docstring: n_i . f_i >= f_min for every contact, and
    (μ_i - margin) n_i . f_i ∓ t_i . f_i >= 0 for fixed contacts (μ_i: the static coefficients).
    """
    m = len(frames)
    rows = []
    for i in range(m):
        n, t = frames[i][:, 0], frames[i][:, 1]
        a = np.zeros(2 * m)
        a[2 * i:2 * i + 2] = n
        rows.append((a, settings.f_min))
        if fixed[i]:
            slope = mu[i] - settings.friction_margin
            for sgn in (1.0, -1.0):
                a = np.zeros(2 * m)
                a[2 * i:2 * i + 2] = slope * n - sgn * t
                rows.append((a, 0.0))
    return rows


def worst_violation(forces, frames, fixed, mu, settings) -> float:
    """Largest violation [N] of the QP's inequalities by the total forces (m, 2) (<= 0: all hold)."""
    surface = to_surface(frames, forces)
    worst = -np.inf
    for i, (fn, ft) in enumerate(surface):
        worst = max(worst, settings.f_min - fn)
        if fixed[i]:
            worst = max(worst, abs(ft) - (mu[i] - settings.friction_margin) * fn)
    return float(worst)


def brute_force_min_norm(A, f_m, frames, fixed, mu, settings):
    """Exact least-norm f_c with Aᵀ f_c = 0 and every constraint on f_m + f_c, by enumeration of
    active sets (see the module docstring); returns (f_c, number of feasible candidates)."""
    rows = constraint_rows(frames, fixed, mu, settings)
    k = A.shape[0] - np.linalg.matrix_rank(A)
    scale = max(1.0, np.abs(f_m).max())
    best, candidates = None, 0
    for r in range(k + 1):
        for subset in itertools.combinations(range(len(rows)), r):
            E = np.vstack([A.T] + [rows[j][0] for j in subset])
            rhs = np.concatenate([np.zeros(A.shape[1]), [rows[j][1] - rows[j][0] @ f_m for j in subset]])
            f_c = np.linalg.lstsq(E, rhs, rcond=None)[0]  # least-norm solution of the (consistent) system
            if np.linalg.norm(E @ f_c - rhs) > 1e-9 * scale:
                continue  # inconsistent active set
            f = f_m + f_c
            if all(a @ f >= lo - 1e-10 * scale for a, lo in rows):
                candidates += 1
                if best is None or np.linalg.norm(f_c) < np.linalg.norm(best):
                    best = f_c
    return best, candidates


# ---------------------------------------------------------------------------- random cases
KINDS = {
    "m2": (2, ("fixed", "fixed")),
    "m3p0": (3, ("fixed", "fixed", "fixed")),
    "m3p1-left": (3, ("sliding", "fixed", "fixed")),
    "m3p1-bottom": (3, ("fixed", "fixed", "sliding")),
}


def random_case(kind: str, seed: int):
    """A seeded random state, friction, margins and motion forces f_m for grasp ``kind``."""
    m, modes = KINDS[kind]
    rng = np.random.default_rng(seed)
    angle = rng.uniform(-0.4, 0.4)
    hand = make_hand(m, gravity=9.81 * np.array([np.sin(angle), -np.cos(angle)]))
    grasp = Grasp(polygon(), EDGES[m], modes)
    while True:
        xi = np.array([rng.uniform(-0.012, 0.012), rng.uniform(-0.012, 0.012), rng.uniform(-0.03, 0.03)][:m])
        model = ReducedModel(hand, grasp, xi)
        S = np.concatenate([[rng.uniform(-0.02, 0.02), Y0 + rng.uniform(-0.015, 0.015), rng.uniform(-0.15, 0.15)],
                            xi[list(grasp.sliding)]])
        S_dot = np.concatenate([rng.uniform(-0.05, 0.05, 2), [rng.uniform(-0.5, 0.5)],
                                rng.uniform(-0.02, 0.02, grasp.p)])
        try:
            st, A, frames, fixed = qp_data(model, S, S_dot)
        except (UnreachableError, SingularFingerError):
            continue
        break
    mu = rng.uniform(0.45, 1.0, m)
    settings = InternalForceSettings(f_min=rng.uniform(0.2, 1.0), friction_margin=rng.uniform(0.0, 0.1))
    if seed % 2 == 0:
        # the motion part of a controller (no internal force): f_m = J^-T (τ_m - M q̈ - N)
        gains = Gains.critically_damped(rng.uniform(5.0, 30.0), model.n)
        cls = FixedContactController if grasp.p == 0 else Proposition1Controller
        controller = cls(model, gains, mu, internal_force=None)
        S_d = S + np.concatenate([rng.uniform(-0.005, 0.005, 2), [rng.uniform(-0.05, 0.05)],
                                  rng.uniform(-0.003, 0.003, grasp.p)])
        out = controller(S, S_dot, S_d, rng.uniform(-0.05, 0.05, model.n), rng.uniform(-1.0, 1.0, model.n))
        assert out.internal is None
        f_m = out.contact_forces.reshape(-1)
        source = "controller"
    else:
        # random forces producing a random wrench: a particular solution of G f = M_o Ẍ - f_g plus
        # random forces in null(G) (any tangential force at a sliding contact included)
        wrench = model.M_o @ rng.uniform(-2.0, 2.0, 3) * np.array([1, 1, 10]) - model.f_g
        f_m = np.linalg.lstsq(st.G, wrench, rcond=None)[0]
        null_g = np.linalg.svd(st.G)[2][3:].T
        f_m = f_m + null_g @ rng.normal(0.0, 1.0, null_g.shape[1])
        assert np.allclose(st.G @ f_m, wrench, atol=1e-12)
        source = "random"
    # μ are the static coefficients; the kinetic ones are 20 to 90 % of them (the QP must not use them)
    friction = [Friction(s, s * k) for s, k in zip(mu, rng.uniform(0.2, 0.9, m))]
    return dict(kind=kind, m=m, model=model, st=st, A=A, frames=frames, fixed=fixed, mu=mu, settings=settings,
                f_m=f_m, source=source, seed=seed, modes=grasp.modes, friction=friction)


CASES = [(kind, seed) for kind in KINDS for seed in range(12)]


def cone_edge_case(seed: int):
    rng = np.random.default_rng(1000 + seed)
    model = ReducedModel(make_hand(3), Grasp(polygon(), EDGES[3], ["fixed"] * 3),
                         [rng.uniform(-0.01, 0.01), rng.uniform(-0.01, 0.01), rng.uniform(-0.02, 0.02)])
    S = [rng.uniform(-0.015, 0.015), Y0 + rng.uniform(-0.01, 0.01), rng.uniform(-0.1, 0.1)]
    st, A, frames, fixed = qp_data(model, S, [0.0, 0.0, 0.0])
    mu = rng.uniform(0.5, 1.0, 3)
    f_m = np.linalg.lstsq(st.G, model.M_o @ rng.uniform(-1, 1, 3) - model.f_g, rcond=None)[0]
    return A, f_m, frames, fixed, mu, model.grasp.modes



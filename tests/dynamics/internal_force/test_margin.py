"""The internal-force QP's target cone margin and several cone edges (``regrasp.dynamics.internal_force.problem``).

The random cases are those of ``tests/dynamics/internal_force/test_solver.py`` (seeded states of m = 2 and m = 3
grasps, motion forces from a controller or random). With a target cone margin the QP must give
every fixed contact at least min(target, best achievable) newtons inside its (μ_s - margin) cone.
The best achievable smallest margin is computed here independently, by an LP (HiGHS) over
(y, s) on the constraints written from the module docstring and scipy's own null-space basis.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import scipy.linalg
import scipy.optimize

from internal_force_cases import (
    CASES,
    cone_edge_case,
    constraint_rows,
    make_hand,
    polygon,
    qp_data,
    random_case,
    to_surface,
    worst_violation,
)
from regrasp import Grasp, ReducedModel
from regrasp.core.exceptions import InvalidParameterError
from regrasp.dynamics.internal_force.problem import (
    InternalForceInfeasibleError,
    build_internal_force_qp,
    solve_internal_force_qp,
)
from regrasp.dynamics.internal_force.settings import ConeEdge, InternalForceSettings
from regrasp.dynamics.internal_force.solver import InternalForceSolver

TARGETS = (0.3, 5.0)  # [N]: one usually reachable, one usually capped by f_max


def best_margin(case, settings) -> float | None:
    """max s over f = f_m + N y: every row of the QP holds and every fixed contact's
    (μ_s - margin) f_n - |f_t| >= s, 0 <= s <= target (LP); None when infeasible."""
    A, f_m, frames, fixed, mu = (case[k] for k in ("A", "f_m", "frames", "fixed", "mu"))
    N = scipy.linalg.null_space(A.T)
    k = N.shape[1]
    rows = [(a, lo, lo == 0.0) for a, lo in constraint_rows(frames, fixed, mu, settings)]  # cone rows: lo = 0
    for i in range(len(frames)):
        if np.isfinite(settings.f_max):
            a = np.zeros(2 * len(frames))
            a[2 * i:2 * i + 2] = -frames[i][:, 0]
            rows.append((a, -settings.f_max, False))
    # a (f_m + N y) - [cone] s >= lo  <=>  -(a N) y + [cone] s <= a f_m - lo
    A_ub = np.array([np.append(-(a @ N), 1.0 if cone else 0.0) for a, _, cone in rows])
    b_ub = np.array([a @ f_m - lo for a, lo, _ in rows])
    res = scipy.optimize.linprog(np.append(np.zeros(k), -1.0), A_ub=A_ub, b_ub=b_ub,
                                 bounds=[(None, None)] * k + [(0.0, settings.target_cone_margin)], method="highs")
    assert res.status in (0, 2), res.message
    return -res.fun if res.status == 0 else None


def margin_of(forces, frames, fixed, mu, margin) -> float:
    """The smallest (μ_s - margin) f_n - |f_t| of the fixed contacts, from the forces."""
    surface = to_surface(frames, forces)
    return min(((mu[i] - margin) * fn - abs(ft) for i, (fn, ft) in enumerate(surface) if fixed[i]), default=np.inf)


@pytest.mark.parametrize("kind,seed", CASES)
def test_target_margin_reaches_the_lp_optimum_and_both_paths_agree(kind, seed):
    case = random_case(kind, seed)
    A, f_m, frames, fixed, mu, modes, friction = (case[k] for k in ("A", "f_m", "frames", "fixed", "mu", "modes",
                                                                    "friction"))
    for target in TARGETS:
        settings = dataclasses.replace(case["settings"], target_cone_margin=target, f_max=3.0 if target > 1 else np.inf)
        least = dataclasses.replace(settings, target_cone_margin=0.0)
        qp = build_internal_force_qp(A, f_m, frames, modes, friction, settings)
        best = best_margin(case, settings)
        try:
            plain = solve_internal_force_qp(build_internal_force_qp(A, f_m, frames, modes, friction, least), frames,
                                            modes, friction)
        except InternalForceInfeasibleError:
            # infeasible exactly when the least-squeeze QP is
            assert best is None
            with pytest.raises(InternalForceInfeasibleError):
                solve_internal_force_qp(qp, frames, modes, friction)
            with pytest.raises(InternalForceInfeasibleError):
                InternalForceSolver(settings).solve(A, f_m, frames, modes, friction)
            continue
        assert best is not None
        one_shot = solve_internal_force_qp(qp, frames, modes, friction)
        persistent = InternalForceSolver(settings).solve(A, f_m, frames, modes, friction)
        scale = max(1.0, np.abs(f_m).max())
        for result in (one_shot, persistent):
            assert result.feasible
            assert worst_violation(result.forces, frames, fixed, mu, settings) <= 10 * settings.tolerance * scale
            assert to_surface(frames, result.forces)[:, 0].max() <= settings.f_max + 10 * settings.tolerance * scale
            assert np.linalg.norm(A.T @ result.f_c) <= 1e-9 * np.linalg.norm(A, 2) * max(np.linalg.norm(result.f_c), 1)
            # the reached margin, from the returned forces, is the LP's best (capped at the target)
            reached = margin_of(result.forces, frames, fixed, mu, settings.friction_margin)
            assert result.cone_margin == pytest.approx(reached, abs=1e-12 * scale)
            assert abs(min(reached, target) - best) <= 1e-4, (target, reached, best)
            # never less margin than the least squeeze gives
            assert reached >= min(plain.cone_margin, target) - 1e-6
        np.testing.assert_allclose(persistent.forces, one_shot.forces, rtol=0, atol=1e-6)


def test_target_margin_cases_cover_capped_and_reached_targets():
    """The checks above see both a reached target and a margin capped below it (by f_max), and the
    margin is larger than the least squeeze's in most cases."""
    capped = reached = raised = 0
    for kind, seed in CASES:
        case = random_case(kind, seed)
        for target in TARGETS:
            settings = dataclasses.replace(case["settings"], target_cone_margin=target,
                                           f_max=3.0 if target > 1 else np.inf)
            best = best_margin(case, settings)
            if best is None:
                continue
            if best < target - 1e-3:
                capped += 1
            else:
                reached += 1
            least = dataclasses.replace(settings, target_cone_margin=0.0)
            try:
                plain = InternalForceSolver(least).solve(case["A"], case["f_m"], case["frames"], case["modes"],
                                                         case["friction"])
            except InternalForceInfeasibleError:
                continue
            raised += plain.cone_margin < best - 1e-3
    assert capped >= 5 and reached >= 20 and raised >= 20, (capped, reached, raised)


def test_default_settings_report_the_least_squeeze_margin_and_target_zero_is_todays_qp():
    case = random_case("m3p0", 2)
    A, f_m, frames, fixed, mu, modes, friction = (case[k] for k in ("A", "f_m", "frames", "fixed", "mu", "modes",
                                                                    "friction"))
    settings = case["settings"]
    qp = build_internal_force_qp(A, f_m, frames, modes, friction, settings)
    assert qp.problem.P.shape == (3, 3)  # y only
    with_zero = build_internal_force_qp(A, f_m, frames, modes, friction,
                                        dataclasses.replace(settings, target_cone_margin=0.0))
    np.testing.assert_array_equal(with_zero.problem.G.toarray(), qp.problem.G.toarray())
    result = solve_internal_force_qp(qp, frames, modes, friction)
    assert result.cone_margin == pytest.approx(margin_of(result.forces, frames, fixed, mu, settings.friction_margin),
                                               abs=1e-12)
    target = build_internal_force_qp(A, f_m, frames, modes, friction,
                                     dataclasses.replace(settings, target_cone_margin=0.3))
    assert target.problem.P.shape == (4, 4)  # (y, s)


@pytest.mark.parametrize("field,value", [("f_min", -0.1), ("friction_margin", -0.01), ("tolerance", 0.0),
                                         ("f_max", 0.5), ("target_cone_margin", -1.0), ("target_cone_margin", np.inf),
                                         ("target_cone_margin", np.nan), ("f_min", "0.5")])
def test_settings_are_validated(field, value):
    with pytest.raises(InvalidParameterError) as info:
        InternalForceSettings(**{field: value})
    assert info.value.name == field


# ---------------------------------------------------------------------------- several cone edges
def test_two_cone_edges_put_both_contacts_on_their_edges():
    """m = 3, p = 0, two ConeEdges: each contact is on its edge, the third keeps its cone, the
    one-shot and persistent paths agree; a single ConeEdge and the tuple of it are the same QP."""
    solved = 0
    settings = InternalForceSettings(f_min=0.5, friction_margin=0.05)
    for seed in range(6):
        A, f_m, frames, _, mu, modes = cone_edge_case(seed)
        for signs in ((1.0, 1.0), (1.0, -1.0), (-1.0, 1.0)):
            edges = (ConeEdge(0, signs[0], mu[0]), ConeEdge(1, signs[1], mu[1]))
            qp = build_internal_force_qp(A, f_m, frames, modes, mu, settings, edges)
            assert qp.problem.A.shape[0] == 2
            try:
                one_shot = solve_internal_force_qp(qp, frames, modes, mu, edges)
            except InternalForceInfeasibleError:
                with pytest.raises(InternalForceInfeasibleError):
                    InternalForceSolver(settings).solve(A, f_m, frames, modes, mu, list(edges))
                continue
            persistent = InternalForceSolver(settings).solve(A, f_m, frames, modes, mu, list(edges))
            np.testing.assert_allclose(persistent.forces, one_shot.forces, rtol=0, atol=1e-6)
            surface = to_surface(frames, one_shot.forces)
            for j in (0, 1):
                assert abs(surface[j, 1] - signs[j] * mu[j] * surface[j, 0]) <= 1e-7 * max(1.0, np.abs(surface).max())
            others = np.array([False, False, True])
            assert worst_violation(one_shot.forces, frames, others, mu, settings) <= 1e-7
            assert one_shot.cone_margin == pytest.approx(margin_of(one_shot.forces, frames, others, mu, 0.05),
                                                         abs=1e-12)
            solved += 1
        single = ConeEdge(2, 1.0, mu[2])
        a = build_internal_force_qp(A, f_m, frames, modes, mu, settings, single).problem
        b = build_internal_force_qp(A, f_m, frames, modes, mu, settings, (single,)).problem
        np.testing.assert_array_equal(a.A.toarray(), b.A.toarray())
        np.testing.assert_array_equal(a.G.toarray(), b.G.toarray())
    assert solved >= 4


@pytest.mark.parametrize("edges", [(ConeEdge(0, 1.0, 0.5), ConeEdge(0, -1.0, 0.5)),
                                   (ConeEdge(0, 1.0, 0.5), ConeEdge(3, 1.0, 0.5)),
                                   (ConeEdge(0, 1.0, 0.5), "edge"), 0.5])
def test_cone_edges_are_validated(edges):
    model = ReducedModel(make_hand(3), Grasp(polygon(), (1, 3, 2), ["fixed"] * 3), [0.0, 0.0, 0.0])
    _, A, frames, _ = qp_data(model, [0.0, 0.12, 0.0], [0.0, 0.0, 0.0])
    with pytest.raises(InvalidParameterError, match="cone_edge"):
        build_internal_force_qp(A, np.zeros(6), frames, model.grasp.modes, 0.5, InternalForceSettings(), edges)
    with pytest.raises(InvalidParameterError, match="cone_edge"):
        InternalForceSolver().solve(A, np.zeros(6), frames, model.grasp.modes, 0.5, edges)


def _margin_cases():
    """Each random case with a fixed contact: (case, its settings with a 0.2 N target margin, a grid of friction
    margins from 0 to the fixed contacts' least μ, the grid's margins the LP finds feasible)."""
    for kind, seed in CASES:
        case = random_case(kind, seed)
        fixed, mu = case["fixed"], case["mu"]
        if not any(fixed):
            continue
        base = dataclasses.replace(case["settings"], target_cone_margin=0.2)
        grid = np.linspace(0.0, min(mu[i] for i in range(len(mu)) if fixed[i]), 21)
        feasible = [m for m in grid if best_margin(case, dataclasses.replace(base, friction_margin=m)) is not None]
        yield case, base, grid, feasible


def test_a_fallback_margin_answers_where_the_margin_cannot_be_kept_and_only_there():
    """For each random case, the largest friction margin the LP still finds feasible, m*: with margin above m*
    and a fallback below it the solver answers with forces inside the fallback's cones (and fails without the
    fallback); with a margin the forces allow, the fallback is not used and the answer is the plain one."""
    relaxed = kept = 0
    for case, base, grid, feasible in _margin_cases():
        A, f_m, frames, fixed, mu, modes, friction = (case[k] for k in ("A", "f_m", "frames", "fixed", "mu", "modes",
                                                                        "friction"))
        if len(feasible) < 2 or feasible[-1] == grid[-1]:
            continue
        # infeasible at high (the LP); low a grid step inside the feasible margins (at their very edge the
        # feasible set is a point, and OSQP's iterations run out)
        low, high = feasible[-2], grid[len(feasible)]
        strict = dataclasses.replace(base, friction_margin=high)
        with pytest.raises(InternalForceInfeasibleError):
            InternalForceSolver(strict).solve(A, f_m, frames, modes, friction)
        solver = InternalForceSolver(dataclasses.replace(strict, fallback_friction_margin=low))
        result = solver.solve(A, f_m, frames, modes, friction)
        scale = max(1.0, np.abs(f_m).max())
        assert solver.relaxations == 1 and result.feasible
        assert worst_violation(result.forces, frames, fixed, mu, dataclasses.replace(base, friction_margin=low)) \
            <= 10 * base.tolerance * scale
        assert np.linalg.norm(A.T @ result.f_c) <= 1e-9 * np.linalg.norm(A, 2) * max(np.linalg.norm(result.f_c), 1)
        relaxed += 1
        inside = feasible[-3] if len(feasible) > 2 else 0.0  # a margin inside the feasible ones
        easy = dataclasses.replace(base, friction_margin=inside)
        if inside > 0.0:
            with_fallback = InternalForceSolver(dataclasses.replace(easy, fallback_friction_margin=0.0))
            plain = InternalForceSolver(easy).solve(A, f_m, frames, modes, friction)
            np.testing.assert_allclose(with_fallback.solve(A, f_m, frames, modes, friction).forces, plain.forces,
                                       rtol=0, atol=1e-9 * scale)
            assert with_fallback.relaxations == 0
            kept += 1
    assert relaxed >= 10 and kept >= 5, (relaxed, kept)
    for bad in (0.05, 0.1, -0.01, np.nan):  # at least the margin, negative, not a number
        with pytest.raises(InvalidParameterError, match="fallback_friction_margin"):
            InternalForceSettings(friction_margin=0.05, fallback_friction_margin=bad)


def test_the_last_friction_margin_answers_where_the_fallback_cannot_be_kept():
    """A chain of two relaxations: with the margin and the fallback both above the largest feasible margin m* (the
    LP's), the solver answers with the last margin, below m*, inside its cones; without it, it fails."""
    chained = 0
    for case, base, grid, feasible in _margin_cases():
        A, f_m, frames, fixed, mu, modes, friction = (case[k] for k in ("A", "f_m", "frames", "fixed", "mu", "modes",
                                                                        "friction"))
        if len(feasible) < 2 or len(feasible) + 1 >= len(grid):
            continue
        low, high, higher = feasible[-2], grid[len(feasible)], grid[len(feasible) + 1]
        strict = dataclasses.replace(base, friction_margin=higher, fallback_friction_margin=high)
        with pytest.raises(InternalForceInfeasibleError):
            InternalForceSolver(strict).solve(A, f_m, frames, modes, friction)
        solver = InternalForceSolver(dataclasses.replace(strict, last_friction_margin=low))
        result = solver.solve(A, f_m, frames, modes, friction)
        scale = max(1.0, np.abs(f_m).max())
        assert solver.relaxations == 1 and result.feasible
        assert worst_violation(result.forces, frames, fixed, mu, dataclasses.replace(base, friction_margin=low)) \
            <= 10 * base.tolerance * scale
        chained += 1
    assert chained >= 10, chained

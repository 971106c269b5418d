"""The internal-force QP (``regrasp.dynamics.internal_force.problem``, paper §3.3 eq. 3.3.7) against its definition.

Set-up: the hand of ``examples/scenarios/paper_trajectory_2.toml`` holding its 0.10 x 0.04 m,
0.08 kg rectangle (finger 1 on edge 1 = left side, ξ up; finger 2 on edge 3 = right side, ξ
down), plus, for m = 3, a third finger of the same URDF under the object on edge 2 (the bottom,
ξ pointing -x). States come from ``ReducedModel.state``; the QP data are
:math:`A = [G^T \\mid R_f B_v]` and the surface frames of ``Grasp.surface_frames``.

What is checked, on seeded random states of m = 2 (both fixed, k = 1), m = 3 with p = 0
(k = 3) and p = 1 (k = 2), with motion forces f_m either from a controller's motion part or
drawn around a particular solution of :math:`G f = M_o\\ddot X - f_g`:

* :math:`A^T f_c = 0` (the object's wrench and the sliding contacts' tangential forces are
  unchanged) and :math:`f = f_m + f_c`;
* every constraint of the QP holds at f (normal ≥ f_min, |f_t| ≤ (μ_s - margin) f_n at fixed
  contacts: the static coefficient, random pairs μ_s > μ_k), to a tolerance tied to the OSQP
  tolerance;
* optimality: :math:`\\|f_c\\|` equals the minimum found by an *exact* brute force written here:
  the minimiser of a strictly convex QP is the least-norm point of the affine set of some
  subset of at most k active constraints (plus :math:`A^T f_c = 0`), so enumerating every
  subset, keeping the feasible least-norm points and taking the smallest gives the optimum
  without any solver or the library's null-space basis;
* the cone-edge option (at the coefficient the ConeEdge carries), infeasible problems (typed
  error carrying the problem and the status, the status confirmed by an LP), the empty null
  space of m = 2, p = 1, and a hold whose least squeeze is μ_s's, not μ_k's (closed form).
"""

from __future__ import annotations

import itertools
import math
import warnings

import numpy as np
import pytest
import qpsolvers
import scipy.linalg
import scipy.optimize

from internal_force_cases import (  # noqa: F401
    CASES,
    EDGES,
    KINDS,
    ROOT,
    SCENARIO,
    URDF,
    Y0,
    brute_force_min_norm,
    cone_edge_case,
    constraint_rows,
    fingers,
    from_surface,
    make_hand,
    polygon,
    qp_data,
    random_case,
    scenario,
    to_surface,
    worst_violation,
)
from regrasp import (
    ContactMode,
    Friction,
    Grasp,
    ReducedModel,
)
from regrasp.core.exceptions import (
    InvalidParameterError,
)
from regrasp.dynamics.internal_force.problem import (
    InternalForceInfeasibleError,
    InternalForceQP,
    build_internal_force_qp,
    solve_internal_force_qp,
)
from regrasp.dynamics.internal_force.settings import ConeEdge, InternalForceSettings


@pytest.mark.parametrize("kind,seed", CASES)
def test_qp_solution_is_internal_feasible_and_least_squeeze(kind, seed):
    case = random_case(kind, seed)
    A, f_m, frames, fixed, mu, settings = (case[k] for k in ("A", "f_m", "frames", "fixed", "mu", "settings"))
    modes, friction = case["modes"], case["friction"]
    m = case["m"]
    k = 2 * m - 3 - case["model"].grasp.p
    qp = build_internal_force_qp(A, f_m, frames, modes, friction, settings)
    assert isinstance(qp.problem, qpsolvers.Problem)
    assert qp.null_basis.shape == (2 * m, k)
    best, candidates = brute_force_min_norm(A, f_m, frames, fixed, mu, settings)
    if not lp_feasible(qp.problem):
        # no squeeze works (e.g. a large random tangential force at a sliding contact): the
        # enumeration agrees, and the library raises its typed error
        assert best is None
        with pytest.raises(InternalForceInfeasibleError):
            solve_internal_force_qp(qp, frames, modes, friction)
        return
    result = solve_internal_force_qp(qp, frames, modes, friction)
    scale = max(1.0, np.abs(f_m).max())

    assert result.null_space_dim == k
    assert result.feasible
    assert result.status == "solved"
    f_c = result.f_c
    np.testing.assert_allclose(result.forces.reshape(-1), f_m + f_c, rtol=0, atol=1e-12 * scale)

    # f_c changes neither the object's wrench nor the sliding contacts' tangential forces
    assert np.linalg.norm(A.T @ f_c) <= 1e-9 * np.linalg.norm(A, 2) * max(np.linalg.norm(f_c), 1e-12)
    assert np.allclose(case["st"].G @ result.forces.reshape(-1), case["st"].G @ f_m, rtol=0, atol=1e-9 * scale)

    # every constraint holds (OSQP tolerance 1e-9, polished)
    tol = 10 * settings.tolerance * scale
    assert worst_violation(result.forces, frames, fixed, mu, settings) <= tol

    # optimality against the exact enumeration
    assert best is not None and candidates >= 1
    gap = (np.linalg.norm(f_c) - np.linalg.norm(best)) / max(np.linalg.norm(best), 1e-9)
    assert abs(gap) <= 1e-5, (gap, np.linalg.norm(f_c), np.linalg.norm(best))
    # the minimiser of a strictly convex QP is unique: the vectors agree too
    np.testing.assert_allclose(f_c, best, rtol=0, atol=1e-6 * max(np.linalg.norm(best), 1e-3))


def test_qp_cases_cover_both_force_sources_and_active_squeezes():
    """The random cases above are not trivial: both sources of f_m appear, and most need a squeeze."""
    sources, squeezed, feasible = set(), 0, 0
    for kind, seed in CASES:
        case = random_case(kind, seed)
        sources.add(case["source"])
        violation = worst_violation(case["f_m"].reshape(case["m"], 2), case["frames"], case["fixed"], case["mu"],
                                    case["settings"])
        squeezed += violation > 0
        qp = build_internal_force_qp(case["A"], case["f_m"], case["frames"], case["modes"], case["friction"],
                                     case["settings"])
        feasible += lp_feasible(qp.problem)
    assert sources == {"controller", "random"}
    assert squeezed >= len(CASES) // 2
    assert feasible >= len(CASES) - 8  # the optimality checks run on most cases


def test_already_feasible_motion_forces_need_no_squeeze():
    """f_m that already satisfies every constraint: the least squeeze is zero."""
    model = ReducedModel(make_hand(3), Grasp(polygon(), EDGES[3], ["fixed"] * 3), [0.003, -0.004, 0.01])
    st, A, frames, fixed = qp_data(model, [0.005, Y0, 0.05], [0.0, 0.0, 0.0])
    mu = np.full(3, 0.8)
    # a gravity hold with a generous squeeze: pick surface forces, then fix the wrench with null(G)
    f = from_surface(frames, [[3.0, 0.1], [3.0, 0.1], [3.0, 0.1]])
    f = f + np.linalg.lstsq(st.G, -model.f_g - st.G @ f, rcond=None)[0]
    settings = InternalForceSettings()
    assert worst_violation(f.reshape(3, 2), frames, fixed, mu, settings) < -0.1
    modes = model.grasp.modes
    result = solve_internal_force_qp(build_internal_force_qp(A, f, frames, modes, mu, settings), frames, modes, mu)
    assert np.linalg.norm(result.f_c) <= 1e-7
    assert result.feasible


# ---------------------------------------------------------------------------- cone edge
def cone_edge_brute_force(A, f_m, frames, others, mu, settings, j, sign):
    """Least-norm f_c with Aᵀ f_c = 0, contact j on its cone edge and the other constraints (the
    edge row is always active in the enumeration); None when infeasible."""
    scale = max(1.0, np.abs(f_m).max())
    rows = constraint_rows(frames, others, mu, settings)
    e_row = np.zeros(A.shape[0])
    e_row[2 * j:2 * j + 2] = frames[j][:, 1] - sign * mu[j] * frames[j][:, 0]
    k = A.shape[0] - np.linalg.matrix_rank(A) - 1
    best = None
    for r in range(0, k + 1):
        for subset in itertools.combinations(range(len(rows)), r):
            E = np.vstack([A.T, e_row] + [rows[i][0] for i in subset])
            rhs = np.concatenate([np.zeros(A.shape[1]), [-e_row @ f_m],
                                  [rows[i][1] - rows[i][0] @ f_m for i in subset]])
            f_c = np.linalg.lstsq(E, rhs, rcond=None)[0]
            if np.linalg.norm(E @ f_c - rhs) > 1e-9 * scale:
                continue
            if all(a @ (f_m + f_c) >= lo - 1e-10 * scale for a, lo in rows):
                if best is None or np.linalg.norm(f_c) < np.linalg.norm(best):
                    best = f_c
    return best


CONE_EDGE_SEEDS = range(6)


@pytest.mark.parametrize("seed", CONE_EDGE_SEEDS)
def test_cone_edge_puts_the_contact_on_its_cone_edge(seed):
    """ConeEdge(j, s, μ_j) for every fixed contact j and both s, m = 3, p = 0: when the problem is
    feasible (independent LP), t_j . f_j = s μ_j n_j . f_j to tight tolerance, n_j . f_j >= f_min,
    the other contacts keep their constraints, Aᵀ f_c = 0, and ‖f_c‖ is the enumeration's minimum;
    otherwise the typed error."""
    A, f_m, frames, fixed, mu, modes = cone_edge_case(seed)
    settings = InternalForceSettings(f_min=0.5, friction_margin=0.05)
    scale = max(1.0, np.abs(f_m).max())
    for j in range(3):
        for sign in (1.0, -1.0):
            edge = ConeEdge(j, sign, mu[j])
            qp = build_internal_force_qp(A, f_m, frames, modes, mu, settings, edge)
            assert qp.problem.A is not None and qp.problem.A.shape[0] == 1  # one equality row
            others = fixed.copy()
            others[j] = False  # contact j: only its normal bound besides the equality
            best = cone_edge_brute_force(A, f_m, frames, others, mu, settings, j, sign)
            if not lp_feasible(qp.problem):
                assert best is None
                with pytest.raises(InternalForceInfeasibleError):
                    solve_internal_force_qp(qp, frames, modes, mu, edge)
                continue
            result = solve_internal_force_qp(qp, frames, modes, mu, edge)
            fn, ft = to_surface(frames, result.forces)[j]
            # OSQP's primal residual bound: eps_abs + eps_rel * |row| (tolerance 1e-9)
            tight = 10 * settings.tolerance * max(scale, np.abs(result.forces).max())
            assert abs(ft - sign * mu[j] * fn) <= tight, (j, sign, ft, sign * mu[j] * fn)
            assert fn >= settings.f_min - 10 * settings.tolerance * scale
            assert worst_violation(result.forces, frames, others, mu, settings) <= 10 * settings.tolerance * scale
            assert np.linalg.norm(A.T @ result.f_c) <= 1e-9 * np.linalg.norm(A, 2) * max(np.linalg.norm(result.f_c),
                                                                                         1e-12)
            assert best is not None
            gap = abs(np.linalg.norm(result.f_c) - np.linalg.norm(best)) / max(np.linalg.norm(best), 1e-9)
            assert gap <= 1e-5, (j, sign, gap)


def test_cone_edge_cases_are_mostly_feasible():
    """The cone-edge checks above do exercise solutions (not only the error)."""
    settings = InternalForceSettings(f_min=0.5, friction_margin=0.05)
    feasible = total = 0
    for seed in CONE_EDGE_SEEDS:
        A, f_m, frames, fixed, mu, modes = cone_edge_case(seed)
        for j in range(3):
            for sign in (1.0, -1.0):
                total += 1
                feasible += lp_feasible(build_internal_force_qp(A, f_m, frames, modes, mu, settings,
                                                                ConeEdge(j, sign, mu[j])).problem)
    assert feasible >= total // 2, (feasible, total)


def test_cone_edge_two_finger_hold_one_direction_only():
    """Two fixed side fingers holding the object against gravity: finger 1 (left, ξ up) can be put
    on its upward cone edge (friction carries its share of the weight), not on the downward one
    (that needs a pull)."""
    model = ReducedModel(make_hand(2), Grasp(polygon(), EDGES[2], ["fixed", "fixed"]), [0.0, 0.0])
    st, A, frames, fixed = qp_data(model, [0.0, Y0, 0.0], [0.0, 0.0, 0.0])
    mu = np.array([0.5, 0.6])  # finger 2 keeps |f_t| <= 0.55 f_n: room for the same f_t / f_n = 0.5
    modes = model.grasp.modes
    settings = InternalForceSettings()
    f_m = np.linalg.lstsq(st.G, -model.f_g, rcond=None)[0]
    up = ConeEdge(0, 1.0, 0.5)
    result = solve_internal_force_qp(build_internal_force_qp(A, f_m, frames, modes, mu, settings, up),
                                     frames, modes, mu, up)
    surface = to_surface(frames, result.forces)
    weight = model.object_mass * 9.81
    # symmetric hold: each finger carries half the weight, finger 1 exactly on its cone edge
    np.testing.assert_allclose(surface[0], [weight / 2 / 0.5, weight / 2], rtol=1e-8)
    assert surface[0, 1] == pytest.approx(0.5 * surface[0, 0], rel=1e-10)
    down = ConeEdge(0, -1.0, 0.5)
    with pytest.raises(InternalForceInfeasibleError):
        solve_internal_force_qp(build_internal_force_qp(A, f_m, frames, modes, mu, settings, down),
                                frames, modes, mu, down)


def test_fixed_cones_use_the_static_coefficient_and_a_cone_edge_its_own():
    """Two fixed side fingers hold the object against gravity (symmetric, f_min small): the least
    squeeze puts each on its cone with the margin, |f_t| = (μ_s - margin) f_n, so that each finger
    carries half the weight W with f_n = W / 2 / (μ_s - margin) (closed form). With μ_s = 0.6,
    μ_k = 0.2 that is W / 1.1, not W / 0.3 (μ_k's). A ConeEdge puts finger 1 at the coefficient it
    carries, whatever the contact's friction. The persistent solver's row cache tells frictions and
    modes apart (the same solver, the same geometry, other answers)."""
    from regrasp.dynamics.internal_force.solver import InternalForceSolver

    model = ReducedModel(make_hand(2), Grasp(polygon(), EDGES[2], ["fixed", "fixed"]), [0.0, 0.0])
    st, A, frames, _ = qp_data(model, [0.0, Y0, 0.0], [0.0, 0.0, 0.0])
    weight = model.object_mass * 9.81
    settings = InternalForceSettings(f_min=0.01, friction_margin=0.05)
    f_m = np.linalg.lstsq(st.G, -model.f_g, rcond=None)[0]  # (W/2 up each, no squeeze)
    modes = model.grasp.modes
    solver = InternalForceSolver(settings)
    for friction, mu_s in ((Friction(0.6, 0.2), 0.6), (Friction(0.3, 0.2), 0.3), ([Friction(0.6, 0.2), 0.3], None)):
        one_shot = solve_internal_force_qp(build_internal_force_qp(A, f_m, frames, modes, friction, settings), frames,
                                           modes, friction)
        persistent = solver.solve(A, f_m, frames, modes, friction)
        for result in (one_shot, persistent):
            surface = to_surface(frames, result.forces)
            np.testing.assert_allclose(np.abs(surface[:, 1]), [weight / 2, weight / 2], rtol=1e-7)  # (ξ up, ξ down)
            if mu_s is not None:
                np.testing.assert_allclose(surface[:, 0], weight / 2 / (mu_s - settings.friction_margin), rtol=1e-6)
            else:  # finger 2 (μ_s = 0.3) needs the larger squeeze; finger 1 then sits inside its cone
                assert surface[1, 0] == pytest.approx(weight / 2 / (0.3 - settings.friction_margin), rel=1e-6)
                assert abs(surface[0, 1]) < (0.6 - settings.friction_margin) * surface[0, 0]
    # a cone edge at μ_k puts finger 1 at t·f = μ_k n·f: f_n = W / 2 / 0.2 (finger 2 then well inside)
    edge = ConeEdge(0, 1.0, 0.2)
    for result in (solve_internal_force_qp(build_internal_force_qp(A, f_m, frames, modes, Friction(0.6, 0.2),
                                                                   settings, edge), frames, modes, Friction(0.6, 0.2),
                                           edge),
                   solver.solve(A, f_m, frames, modes, Friction(0.6, 0.2), edge)):
        surface = to_surface(frames, result.forces)
        np.testing.assert_allclose(surface[0], [weight / 2 / 0.2, weight / 2], rtol=1e-7)
    # a sliding finger gets no cone row: m = 3, the left finger sliding with |f_t| = 0.3 f_n, which no
    # squeeze changes (A's sliding column): feasible as it is, infeasible if the modes call it fixed
    # (its static cone, μ_s = 0.06, could hold that force only with f_n >= 30 N > f_max)
    three = ReducedModel(make_hand(3), Grasp(polygon(), EDGES[3], ["sliding", "fixed", "fixed"]), [0.0, 0.0, 0.01])
    st3, A3, frames3, _ = qp_data(three, [0.0, Y0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0])
    f3 = from_surface(frames3, [[1.0, 0.3], [1.0, 0.0], [1.0, 0.0]])
    f3[2:] += np.linalg.lstsq(st3.G[:, 2:], -three.f_g - st3.G @ f3, rcond=None)[0]  # (the others balance)
    tiny = [Friction(0.06, 0.0), Friction(0.8, 0.5), Friction(0.8, 0.5)]
    bounded = InternalForceSolver(InternalForceSettings(f_min=0.01, friction_margin=0.05, f_max=5.0))
    sliding = bounded.solve(A3, f3, frames3, three.grasp.modes, tiny)
    assert sliding.feasible
    assert to_surface(frames3, sliding.forces)[0, 1] == pytest.approx(to_surface(frames3, f3)[0, 1], rel=1e-9)
    with pytest.raises(InternalForceInfeasibleError):
        bounded.solve(A3, f3, frames3, [ContactMode.FIXED] * 3, tiny)


def test_cone_edge_contact_index_is_validated():
    model = ReducedModel(make_hand(2), Grasp(polygon(), EDGES[2], ["fixed", "fixed"]), [0.0, 0.0])
    st, A, frames, fixed = qp_data(model, [0.0, Y0, 0.0], [0.0, 0.0, 0.0])
    with pytest.raises(InvalidParameterError):
        build_internal_force_qp(A, np.zeros(4), frames, model.grasp.modes, np.full(2, 0.5), InternalForceSettings(),
                                ConeEdge(2, 1.0, 0.5))
    for sign, mu in ((0.0, 0.5), (2.0, 0.5), (1.0, -0.1), (1.0, float("nan")), (1.0, float("inf")), (1.0, "0.5")):
        with pytest.raises(InvalidParameterError):
            ConeEdge(0, sign, mu)
    # the contacts' modes: ContactMode members or their strings, one per contact (not a boolean mask)
    for modes in (np.array([True, True]), ["fixed"], ["fixed", "rolling"], "fixed"):
        with pytest.raises(InvalidParameterError):
            build_internal_force_qp(A, np.zeros(4), frames, modes, 0.5)


# ---------------------------------------------------------------------------- infeasible
def lp_feasible(problem: qpsolvers.Problem) -> bool:
    """Whether G y <= h (and A y = b) has a solution, by an LP (HiGHS)."""
    G = problem.G.toarray() if hasattr(problem.G, "toarray") else problem.G
    kwargs = {}
    if problem.A is not None:
        kwargs = dict(A_eq=problem.A.toarray() if hasattr(problem.A, "toarray") else problem.A, b_eq=problem.b)
    res = scipy.optimize.linprog(np.zeros(G.shape[1]), A_ub=G, b_ub=problem.h, bounds=(None, None),
                                 method="highs", **kwargs)
    assert res.status in (0, 2), res.message
    return res.status == 0


def osqp_status(problem: qpsolvers.Problem) -> str:
    """The status OSQP itself reports on ``problem``."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # OSQP/qpsolvers warn on infeasibility
        solution = qpsolvers.solve_problem(problem, solver="osqp", eps_abs=1e-9, eps_rel=1e-9, polishing=True,
                                           verbose=False, max_iter=20000)
    return solution.extras["info"].status


def infeasible_cases():
    hand = make_hand(2)
    cases = []
    # (a) μ = margin: no tangential force allowed at a fixed contact, yet the weight must be carried
    model = ReducedModel(hand, Grasp(polygon(), EDGES[2], ["fixed", "fixed"]), [0.0, 0.0])
    st, A, frames, fixed = qp_data(model, [0.0, Y0, 0.0], [0.0, 0.0, 0.0])
    f_m = np.linalg.lstsq(st.G, -model.f_g, rcond=None)[0]
    cases.append(("mu=0.05", A, f_m, frames, model.grasp.modes, np.full(2, 0.05),
                  InternalForceSettings(f_min=0.5, friction_margin=0.05)))
    # (b) f_min huge for the geometry: contacts 30 mm apart vertically over 100 mm, so the squeeze
    # direction is 16.7° off the normals, outside cones of slope 0.25; a big squeeze leaves the cones
    model = ReducedModel(hand, Grasp(polygon(), EDGES[2], ["fixed", "fixed"]), [-0.015, -0.015])
    st, A, frames, fixed = qp_data(model, [0.0, Y0, 0.0], [0.0, 0.0, 0.0])
    f_m = np.linalg.lstsq(st.G, -model.f_g, rcond=None)[0]
    cases.append(("f_min=50", A, f_m, frames, model.grasp.modes, np.full(2, 0.3),
                  InternalForceSettings(f_min=50.0, friction_margin=0.05)))
    # (c) m = 3, sliding left finger, low friction, and a large upward tangential motion force at
    # the sliding contact (which no squeeze may change): the moments cannot be balanced by pushes
    model = ReducedModel(make_hand(3), Grasp(polygon(), EDGES[3], ["sliding", "fixed", "fixed"]),
                         [0.0, 0.0, 0.01])
    st, A, frames, fixed = qp_data(model, [0.0, Y0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0])
    f_m = from_surface(frames, [[0.0, 20.0], [0.0, 0.0], [0.0, 0.0]])
    f_m = f_m + np.linalg.lstsq(st.G, -model.f_g - st.G @ f_m, rcond=None)[0]
    cases.append(("m3 large tangential", A, f_m, frames, model.grasp.modes, np.full(3, 0.1),
                  InternalForceSettings(f_min=0.5, friction_margin=0.05)))
    return cases


@pytest.mark.parametrize("index", range(3))
def test_infeasible_problem_raises_typed_error(index):
    name, A, f_m, frames, modes, mu, settings = infeasible_cases()[index]
    qp = build_internal_force_qp(A, f_m, frames, modes, mu, settings)
    assert not lp_feasible(qp.problem), name  # the problem really has no solution
    with pytest.raises(InternalForceInfeasibleError) as info:
        solve_internal_force_qp(qp, frames, modes, mu)
    exc = info.value
    assert isinstance(exc.qp, InternalForceQP)
    assert isinstance(exc.qp.problem, qpsolvers.Problem)
    np.testing.assert_array_equal(exc.qp.motion_forces, f_m)
    direct = osqp_status(exc.qp.problem)
    assert "infeasible" in direct
    assert direct in exc.status
    message = str(exc)
    # the message states the minimum normal force and the friction margin that were asked for
    assert f">= {settings.f_min} N" in message
    assert f"margin {settings.friction_margin}" in message


# ---------------------------------------------------------------------------- empty null space
def test_empty_null_space_only_checks_the_given_forces():
    """m = 2, p = 1: A is square and invertible, nothing to choose; the result reports whether the
    motion forces satisfy the constraints (sliding contact: normal only; fixed: normal and cone)."""
    model = ReducedModel(make_hand(2), Grasp(polygon(), EDGES[2], ["sliding", "fixed"]), [-0.005, 0.003])
    st, A, frames, fixed = qp_data(model, [0.004, Y0 + 0.005, 0.08, -0.005], [0.01, 0.0, 0.1, 0.002])
    assert A.shape == (4, 4) and np.linalg.matrix_rank(A) == 4
    mu = np.array([0.5, 0.5])
    settings = InternalForceSettings(f_min=0.5, friction_margin=0.05)  # fixed contact: |f_t| <= 0.45 f_n
    cases = {
        # (normal, tangential) per contact -> expected feasibility
        "inside": ([[1.0, 0.7], [1.0, 0.4]], True),  # sliding contact's tangential force is free
        "fixed outside its cone": ([[1.0, 0.2], [1.0, 0.47]], False),
        "sliding contact too light": ([[0.4, 0.0], [1.0, 0.0]], False),
    }
    for name, (surface, expected) in cases.items():
        f_m = from_surface(frames, surface)
        qp = build_internal_force_qp(A, f_m, frames, model.grasp.modes, mu, settings)
        assert qp.problem is None, name
        assert qp.null_basis.shape == (4, 0), name
        result = solve_internal_force_qp(qp, frames, model.grasp.modes, mu)
        assert result.null_space_dim == 0, name
        assert result.status == "empty null space", name
        np.testing.assert_array_equal(result.f_c, np.zeros(4))
        np.testing.assert_allclose(result.forces, f_m.reshape(2, 2), rtol=0, atol=0)
        assert result.feasible is expected, name


def test_persistent_solver_matches_the_one_shot_qp():
    """InternalForceSolver (one persistent OSQP per problem shape, warm-started) gives the same f_c
    as build_internal_force_qp + solve_internal_force_qp, and raises the same typed error, across a
    sequence of problems reusing the same solver object."""
    from regrasp.dynamics.internal_force.solver import InternalForceSolver

    solvers = {}
    compared = raised = 0
    for kind, seed in CASES:
        case = random_case(kind, seed)
        A, f_m, frames, settings = (case[k] for k in ("A", "f_m", "frames", "settings"))
        modes, friction = case["modes"], case["friction"]
        solver = solvers.setdefault((kind, settings), InternalForceSolver(settings))
        try:
            expected = solve_internal_force_qp(build_internal_force_qp(A, f_m, frames, modes, friction, settings),
                                               frames, modes, friction)
        except InternalForceInfeasibleError:
            with pytest.raises(InternalForceInfeasibleError) as err:
                solver.solve(A, f_m, frames, modes, friction)
            assert isinstance(err.value.qp.problem, qpsolvers.Problem)
            raised += 1
            continue
        got = solver.solve(A, f_m, frames, modes, friction)
        scale = max(1.0, np.abs(expected.f_c).max())
        np.testing.assert_allclose(got.f_c, expected.f_c, atol=1e-6 * scale)
        assert got.null_space_dim == expected.null_space_dim and got.feasible
        compared += 1
    # the same solver object reused across states of one kind (warm start, value updates only)
    shared = InternalForceSolver(InternalForceSettings())
    for seed in range(6):
        case = random_case("m3p0", seed)
        A, f_m, frames, modes, friction = (case[k] for k in ("A", "f_m", "frames", "modes", "friction"))
        try:
            expected = solve_internal_force_qp(build_internal_force_qp(A, f_m, frames, modes, friction), frames,
                                               modes, friction)
        except InternalForceInfeasibleError:
            continue
        np.testing.assert_allclose(shared.solve(A, f_m, frames, modes, friction).f_c, expected.f_c,
                                   atol=1e-6 * max(1.0, np.abs(expected.f_c).max()))
    assert compared >= 30 and raised >= 1


def test_null_basis_is_orthonormal_and_falls_back_on_rank_deficient_matrices():
    """The persistent solver's null basis (Householder QR) spans null(Aᵀ) with orthonormal columns;
    a rank-deficient A takes scipy's SVD (numerical rank), a square full-rank one has none."""
    import scipy.linalg

    from regrasp.dynamics.internal_force.rows import null_basis

    rng = np.random.default_rng(3)
    for rows, cols in ((4, 3), (6, 4), (6, 3), (4, 4)):
        A = rng.normal(size=(rows, cols))
        N = null_basis(A)
        assert N.shape == (rows, rows - cols)
        np.testing.assert_allclose(N.T @ N, np.eye(rows - cols), atol=1e-14)
        np.testing.assert_allclose(A.T @ N, 0.0, atol=1e-14)
    A = rng.normal(size=(6, 4))
    A[:, 3] = A[:, 0] - 2.0 * A[:, 1]  # rank 3
    N = null_basis(A)
    assert N.shape == scipy.linalg.null_space(A.T).shape == (6, 3)
    np.testing.assert_allclose(A.T @ N, 0.0, atol=1e-13)


@pytest.mark.parametrize("path", ["persistent", "one-shot"])
def test_ctrl_c_during_an_osqp_solve_reaches_python(path):
    """OSQP's C library takes a SIGINT that arrives during its solve (status ``interrupted``; Python never sees
    it): the solver hands it on. Each trial sends one SIGINT from another thread while solves run back to back
    (most of the loop's time is inside OSQP); the KeyboardInterrupt must come, every time."""
    import os
    import signal
    import threading
    import time

    from regrasp.dynamics.internal_force.solver import InternalForceSolver

    case = random_case("three_sliding" if "three_sliding" in KINDS else next(iter(KINDS)), 1)
    args = (case["A"], case["f_m"], case["frames"], case["modes"], case["friction"])
    solver = InternalForceSolver(case["settings"])

    def solve():
        if path == "persistent":
            solver.solve(*args)
        else:
            qp = build_internal_force_qp(case["A"], case["f_m"], case["frames"], case["modes"], case["friction"],
                                         case["settings"])
            solve_internal_force_qp(qp, case["frames"], case["modes"], case["friction"])

    solve()
    caught = 0
    for trial in range(20):
        timer = threading.Timer(0.002 + 0.0007 * trial, os.kill, (os.getpid(), signal.SIGINT))
        deadline = time.monotonic() + 1.0
        try:
            timer.start()
            while time.monotonic() < deadline:
                solve()
        except KeyboardInterrupt:
            caught += 1
        timer.join()
    assert caught == 20


@pytest.mark.parametrize("seed", range(6))
def test_per_contact_floors_are_met_with_the_least_squeeze(seed):
    """``InternalForceSettings.floors``: contact i pushes with at least max(f_min, floors[i]); the least squeeze that
    does so, checked against an independent solve (SciPy's SLSQP on scipy's own null space of Aᵀ)."""
    case = random_case("m3p0", seed)
    A, f_m, frames, mu = case["A"], case["f_m"], case["frames"], case["mu"]
    floors = (0.9, 0.2, 1.4)
    settings = InternalForceSettings(f_min=0.3, friction_margin=0.05, floors=floors)
    assert [settings.floor(i) for i in range(3)] == [0.9, 0.3, 1.4]
    qp = build_internal_force_qp(A, f_m, frames, case["modes"], case["friction"], settings)
    N = scipy.linalg.null_space(A.T)

    def normal_tangent(y):
        f = (f_m + N @ y).reshape(3, 2)
        return np.array([fr[:, 0] @ fi for fr, fi in zip(frames, f)]), np.array([fr[:, 1] @ fi for fr, fi in
                                                                                   zip(frames, f)])

    def constraints(y):
        n, t = normal_tangent(y)
        return np.concatenate([n - np.array([settings.floor(i) for i in range(3)]),
                               (mu - 0.05) * n - t, (mu - 0.05) * n + t])

    best = scipy.optimize.minimize(lambda y: 0.5 * y @ y, np.zeros(N.shape[1]), jac=lambda y: y,
                                   constraints=[{"type": "ineq", "fun": constraints}], method="SLSQP",
                                   options={"ftol": 1e-14, "maxiter": 500})
    if not (best.success and constraints(best.x).min() > -1e-7):
        with pytest.raises(InternalForceInfeasibleError):
            solve_internal_force_qp(qp, frames, case["modes"], case["friction"])
        return
    result = solve_internal_force_qp(qp, frames, case["modes"], case["friction"])
    normal = to_surface(frames, result.forces)[:, 0]
    assert (normal >= np.array([0.9, 0.3, 1.4]) - 1e-7).all()
    assert np.linalg.norm(result.f_c) == pytest.approx(np.linalg.norm(N @ best.x), rel=1e-4, abs=1e-7)


@pytest.mark.parametrize("floors", [(-0.1,), (math.nan,), ("0.5",), 0.5, (25.0,)])
def test_floors_refuse_bad_values(floors):
    with pytest.raises(InvalidParameterError):
        InternalForceSettings(f_min=0.2, f_max=20.0, floors=floors)

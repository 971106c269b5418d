"""Joint torque limits in the internal-force QP (``regrasp.dynamics.internal_force.torque``): rows
:math:`|w_j + J_j^T f_i| \\le e_j` on the predicted forces.

On the seeded random states of ``internal_force_cases`` (m = 3, p = 0 and p = 1; the hand's own J and
w = N(q, q̇)), with limits between the least possible largest torque e* (an LP written here) and the largest
torque of the answer without limits, so that they bind and a force within them exists:

* both paths (the compiled dense solver and OSQP) keep every |τ_j| <= e_j + 1e-9 N m and every other row;
* they agree, and their f_c is the least-norm one of an exact brute force written here (every subset of active
  rows, the torque rows included);
* below e* the typed error names the torque limit: the joint, and a shortfall of e* - e;
* limits far above what the state needs change nothing, bit for bit.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import scipy.optimize

from internal_force_cases import constraint_rows, random_case
from regrasp.dynamics.internal_force.problem import InternalForceInfeasibleError, build_internal_force_qp
from regrasp.dynamics.internal_force.solver import InternalForceSolver
from regrasp.dynamics.internal_force.torque import JointTorques, joint_torques, torque_rows

CASES = [(kind, seed) for kind in ("m3p0", "m3p1-left", "m3p1-bottom") for seed in range(8)]


def _torques(case, effort) -> JointTorques:
    st, m = case["st"], case["m"]
    jac = [tuple(st.hand.jacobian[2 * i:2 * i + 2, 2 * i:2 * i + 2].reshape(-1)) for i in range(m)]
    return JointTorques(jac, st.hand.nonlinear.tolist(), [effort] * (2 * m), ("f1", "f2", "f3"))


def _rows(case, torques):
    """Every row a . f >= lo, written from the definitions: the QP's own (``constraint_rows``) and two per joint,
    ±(w_j + J_jᵀ f_i) <= e_j."""
    m = case["m"]
    rows = constraint_rows(case["frames"], case["fixed"], case["mu"], case["settings"])
    for i, (a, b, c, d) in enumerate(torques.jacobians):
        for j, column in enumerate(((a, c), (b, d))):
            row = np.zeros(2 * m)
            row[2 * i:2 * i + 2] = column
            w, e = torques.wrench[2 * i + j], torques.effort[2 * i + j]
            rows += [(row, -e - w), (-row, w - e)]
    return rows


def _least_largest_torque(case, torques) -> float | None:
    """e*: the least max_j |τ_j| over forces f = f_m + f_c (Aᵀ f_c = 0) that keep the QP's rows (an LP in (f_c, t)),
    or None where none keeps them."""
    A, f_m, m = case["A"], case["f_m"], case["m"]
    rows = constraint_rows(case["frames"], case["fixed"], case["mu"], case["settings"])
    n = 2 * m
    A_ub, b_ub = [], []
    for a, lo in rows:  # a . (f_m + f_c) >= lo
        A_ub.append(np.append(-a, 0.0))
        b_ub.append(a @ f_m - lo)
    jt = np.zeros((n, n))
    for i, (a, b, c, d) in enumerate(torques.jacobians):
        jt[2 * i:2 * i + 2, 2 * i:2 * i + 2] = ((a, c), (b, d))
    base = np.array(torques.wrench) + jt @ f_m
    for j in range(n):
        for sign in (1.0, -1.0):  # sign (base + Jᵀ f_c) <= t
            A_ub.append(np.append(sign * jt[j], -1.0))
            b_ub.append(-sign * base[j])
    result = scipy.optimize.linprog(np.append(np.zeros(n), 1.0), A_ub=np.array(A_ub), b_ub=np.array(b_ub),
                                    A_eq=np.hstack([A.T, np.zeros((A.shape[1], 1))]), b_eq=np.zeros(A.shape[1]),
                                    bounds=[(None, None)] * (n + 1), method="highs")
    return float(result.x[-1]) if result.status == 0 else None


def _brute_force(case, rows):
    """The least-norm f_c with Aᵀ f_c = 0 and every row at f_m + f_c: the best feasible least-norm point of the
    affine sets of at most k active rows (the minimiser of a strictly convex QP is one of them)."""
    A, f_m = case["A"], case["f_m"]
    k = A.shape[0] - np.linalg.matrix_rank(A)
    scale = max(1.0, np.abs(f_m).max())
    best = None
    for r in range(k + 1):
        for subset in itertools.combinations(range(len(rows)), r):
            E = np.vstack([A.T] + [rows[j][0] for j in subset])
            rhs = np.concatenate([np.zeros(A.shape[1]), [rows[j][1] - rows[j][0] @ f_m for j in subset]])
            f_c = np.linalg.lstsq(E, rhs, rcond=None)[0]
            if np.linalg.norm(E @ f_c - rhs) > 1e-9 * scale:
                continue
            if all(a @ (f_m + f_c) >= lo - 1e-10 * scale for a, lo in rows):
                if best is None or np.linalg.norm(f_c) < np.linalg.norm(best):
                    best = f_c
    return best


def _binding_effort(case) -> float | None:
    """A limit for every joint between e* and the largest torque of the answer without limits (binding, with room
    for forces within it), or None where the state has none (no squeeze, or no force needs much less)."""
    try:
        free = _solve(case, None, True)
    except InternalForceInfeasibleError:
        return None
    largest = max(map(abs, joint_torques(_torques(case, np.inf), free.forces.reshape(-1))))
    least = _least_largest_torque(case, _torques(case, np.inf))
    # (a limit within 5 % of e* leaves a sliver of forces, which OSQP may call infeasible at its tolerance)
    return 0.5 * (least + largest) if least is not None and least < 0.95 * largest else None


def _solve(case, torques, compiled: bool):
    return InternalForceSolver(case["settings"], compiled=compiled).solve(
        case["A"], case["f_m"], case["frames"], case["modes"], case["friction"], torques=torques)


@pytest.mark.parametrize("kind,seed", CASES)
def test_torque_rows_bind_and_both_paths_give_the_least_squeeze_within_them(kind, seed):
    case = random_case(kind, seed)
    effort = _binding_effort(case)
    if effort is None:
        pytest.skip("no limit binds and leaves room here (test_enough_cases_bind counts them)")
    free = _solve(case, None, True)
    torques = _torques(case, effort)
    assert len(torque_rows(torques)) == 4 * case["m"]
    results = [_solve(case, torques, compiled) for compiled in (True, False)]
    best = _brute_force(case, _rows(case, torques))
    assert best is not None
    scale = max(1.0, np.abs(case["f_m"]).max())
    for result in results:
        forces = result.forces.reshape(-1)
        assert max(map(abs, joint_torques(torques, forces))) <= effort + 1e-9
        assert all(a @ forces >= lo - 10 * case["settings"].tolerance * scale for a, lo in _rows(case, torques))
        np.testing.assert_allclose(result.f_c, best, rtol=0, atol=1e-6 * max(np.linalg.norm(best), 1e-3))
    # the limits bind: the answer moved away from the one without them
    assert np.linalg.norm(results[0].f_c - free.f_c) > 1e-6
    np.testing.assert_allclose(results[0].forces, results[1].forces, rtol=0, atol=1e-7 * scale)


def test_enough_cases_bind():
    assert sum(_binding_effort(random_case(kind, seed)) is not None for kind, seed in CASES) >= 6


@pytest.mark.parametrize("kind,seed", CASES[::3])
def test_limits_below_the_least_largest_torque_raise_naming_the_joint_and_the_shortfall(kind, seed):
    case = random_case(kind, seed)
    least = _least_largest_torque(case, _torques(case, np.inf))
    if least is None:
        pytest.skip("no squeeze keeps this random state's cones")
    effort = 0.8 * least
    for compiled in (True, False):
        with pytest.raises(InternalForceInfeasibleError) as info:
            _solve(case, _torques(case, effort), compiled)
        shortfall = info.value.torque
        assert shortfall is not None and "joint torque limit" in str(info.value)
        assert shortfall.finger in ("f1", "f2", "f3") and shortfall.joint in (1, 2)
        assert shortfall.effort == effort
        assert shortfall.excess == pytest.approx(least - effort, rel=1e-6, abs=1e-9)
        assert f"{shortfall.finger} joint {shortfall.joint}" in str(info.value)
        # the error's problem carries the torque rows: it is infeasible as a whole
        assert info.value.qp.torques is not None and len(info.value.qp.problem.h) > len(info.value.qp.rows[1])


def test_limits_that_do_not_bind_change_nothing_bit_for_bit():
    for kind, seed in CASES:
        case = random_case(kind, seed)
        for compiled in (True, False):
            try:
                plain = _solve(case, None, compiled)
            except InternalForceInfeasibleError:
                continue
            limited = _solve(case, _torques(case, 5.0), compiled)
            assert np.array_equal(plain.f_c, limited.f_c) and np.array_equal(plain.forces, limited.forces)


def test_the_one_shot_problem_has_the_torque_rows():
    case = random_case("m3p0", 1)
    torques = _torques(case, 1.0)
    plain = build_internal_force_qp(case["A"], case["f_m"], case["frames"], case["modes"], case["friction"],
                                    case["settings"])
    limited = build_internal_force_qp(case["A"], case["f_m"], case["frames"], case["modes"], case["friction"],
                                      case["settings"], torques=torques)
    assert limited.problem.G.shape[0] == plain.problem.G.shape[0] + 4 * case["m"]

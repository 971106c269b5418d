"""The compiled dense QP (regrasp.kernels.qp) and internal-force step (regrasp.kernels.force), against OSQP,
scipy and the reference path."""

from dataclasses import replace

import numpy as np
import osqp
import pytest
import scipy.linalg
import scipy.optimize
import scipy.sparse as sp

from internal_force_cases import KINDS, random_case, worst_violation
from regrasp.dynamics.internal_force.problem import InternalForceInfeasibleError
from regrasp.dynamics.internal_force.solver import InternalForceSolver
from regrasp.kernels.force import null_basis
from regrasp.kernels.qp import INFEASIBLE, SOLVED, diagonal_qp


def random_qp(rng, n, n_ineq, n_eq, feasible=True):
    """A random QP with a diagonal Hessian, made feasible by construction (rows active or slack at a random
    point) unless ``feasible`` is False."""
    d = rng.uniform(0.5, 100.0, n)
    q = rng.normal(0.0, 10.0, n)
    a = rng.normal(0.0, 1.0, (n_ineq + n_eq, n))
    x0 = rng.normal(0.0, 3.0, n)
    b = a @ x0 - np.concatenate([rng.uniform(0.0, 2.0, n_ineq) * (rng.random(n_ineq) < 0.6), np.zeros(n_eq)])
    if not feasible:  # two opposite rows that cannot both hold: a0 x >= 1 and -a0 x >= 0
        a = np.vstack([a[:1], -a[:1], a[1:]])
        b = np.concatenate([[1.0, 0.0], b[1:]])
        n_ineq += 1
    return d, q, a, b, n_ineq


@pytest.fixture(autouse=True)
def _quiet_osqp_warnings():
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PendingDeprecationWarning)  # (osqp's raise_error default)
        yield


def osqp_solve(d, q, a, b, n_ineq):
    upper = np.concatenate([np.full(n_ineq, np.inf), b[n_ineq:]])
    solver = osqp.OSQP()
    solver.setup(P=sp.csc_matrix(np.diag(d)), q=q, A=sp.csc_matrix(a), l=b, u=upper, eps_abs=1e-12, eps_rel=1e-12,
                 polishing=True, verbose=False, max_iter=200000)
    result = solver.solve()
    return result.info.status, result.x


@pytest.mark.parametrize("seed", range(40))
def test_dense_qp_meets_kkt_and_matches_osqp(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 6))
    n_ineq, n_eq = int(rng.integers(1, 16)), int(rng.integers(0, min(n, 3)))
    d, q, a, b, n_ineq = random_qp(rng, n, n_ineq, n_eq)
    v = np.empty(n)
    assert diagonal_qp(d, q, a, b, n_ineq, v) == SOLVED
    residual = a @ v - b
    assert residual[:n_ineq].min() >= -1e-9 and np.abs(residual[n_ineq:]).max(initial=0.0) <= 1e-9
    # KKT: D v + q = a^T λ for some λ >= 0 on the active inequalities (any sign on the equalities: λ+ - λ-),
    # found by scipy's NNLS (the rows are often degenerate: more active rows than variables)
    active = np.abs(residual[:n_ineq]) <= 1e-8
    columns = np.vstack([a[:n_ineq][active], a[n_ineq:], -a[n_ineq:]]).T
    gradient = d * v + q
    multipliers, misfit = scipy.optimize.nnls(columns, gradient) if columns.size else (None, np.linalg.norm(gradient))
    assert misfit <= 1e-7 * max(1.0, np.abs(gradient).max(), np.abs(q).max())
    status, x = osqp_solve(d, q, a, b, n_ineq)
    assert status == "solved"
    objective = lambda z: 0.5 * z @ (d * z) + q @ z  # noqa: E731
    assert objective(v) <= objective(x) + 1e-7 * max(1.0, abs(objective(x)))
    np.testing.assert_allclose(v, x, atol=1e-5 * max(1.0, np.abs(x).max()))


@pytest.mark.parametrize("seed", range(10))
def test_dense_qp_reports_inconsistent_rows_as_infeasible(seed):
    rng = np.random.default_rng(100 + seed)
    n = int(rng.integers(1, 5))
    d, q, a, b, n_ineq = random_qp(rng, n, int(rng.integers(1, 10)), 0, feasible=False)
    assert diagonal_qp(d, q, a, b, n_ineq, np.empty(n)) == INFEASIBLE
    assert osqp_solve(d, q, a, b, n_ineq)[0].startswith("primal infeasible")


@pytest.mark.parametrize("seed", range(20))
def test_null_basis_is_orthonormal_and_spans_the_null_space(seed):
    rng = np.random.default_rng(seed)
    rows = int(rng.integers(2, 9))
    cols = int(rng.integers(1, rows + 1))
    A = rng.normal(size=(rows, cols))
    out = np.empty((rows, rows - cols))
    assert null_basis(A, out) == rows - cols
    np.testing.assert_allclose(out.T @ out, np.eye(rows - cols), atol=1e-13)
    assert np.abs(A.T @ out).max(initial=0.0) <= 1e-13 * max(1.0, np.abs(A).max())
    reference = scipy.linalg.null_space(A.T)  # the same space: the projectors agree
    np.testing.assert_allclose(out @ out.T, reference @ reference.T, atol=1e-12)
    deficient = np.hstack([A, A[:, :1]]) if cols < rows else None
    if deficient is not None:
        assert null_basis(deficient, np.empty((rows, rows - cols - 1))) == -1


@pytest.mark.parametrize("kind", list(KINDS))
def test_compiled_internal_force_equals_the_osqp_path(kind):
    """The solver's compiled default against its OSQP path (``compiled=False``), with and without a target cone
    margin, on the random grasps of test_internal_force: the same forces to 1e-8 N (OSQP's tolerance is 1e-9),
    the same cone margins; where OSQP fails, the compiled answer must still pass an independent check."""
    agreed = 0
    for seed in range(40):
        case = random_case(kind, seed)
        for target in (0.0, 0.3):
            settings = replace(case["settings"], target_cone_margin=target)
            args = (case["A"], case["f_m"], case["frames"], case["modes"], case["friction"])
            try:
                reference = InternalForceSolver(settings, compiled=False).solve(*args)
            except InternalForceInfeasibleError:
                reference = None
            try:
                compiled = InternalForceSolver(settings).solve(*args)
            except InternalForceInfeasibleError:
                assert reference is None  # never a failure where OSQP succeeds
                continue
            if reference is None:  # OSQP gave up ("inaccurate"): the compiled forces must be feasible
                assert worst_violation(compiled.forces.reshape(-1), case["frames"], case["fixed"], case["mu"],
                                       settings) <= 1e-9
                continue
            scale = max(1.0, np.abs(reference.forces).max())
            np.testing.assert_allclose(compiled.forces, reference.forces, rtol=0, atol=1e-8 * scale)
            assert compiled.cone_margin == pytest.approx(reference.cone_margin, abs=1e-8 * scale)
            assert compiled.null_space_dim == reference.null_space_dim and compiled.feasible
            agreed += 1
    assert agreed >= 60

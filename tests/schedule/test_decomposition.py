"""The decomposition planner (regrasp.schedule.decomposition): its compiled pair program against the plain-Python one,
the descent's monotone objective, its schedules against the exact planner's, the linear program that proves no force
system exists against a sampler, and its settings."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest

from regrasp import load_scenario
from regrasp.core.exceptions import InvalidParameterError
from regrasp.schedule.block_dp import PAIR_MOVES, block_dp, block_dp_reference
from regrasp.schedule.block_tables import ModeVertices
from regrasp.schedule.decomposition import block_solve, initial_path, path_failures, path_value
from regrasp.schedule.force_polytope import ForceLimits, force_vertices
from regrasp.schedule.force_proof import positions_admit_forces
from regrasp.schedule.planner import RegraspSettings, plan_regrasps, verify
from regrasp.schedule.problem import build_problem, slide_ratios
from regrasp.schedule.schedule import NoScheduleError, ScheduleLimit

SCENARIOS = Path(__file__).resolve().parents[2] / "examples" / "scenarios"
THREE = SCENARIOS / "paper_trajectory_2_three_fingers.toml"
FOUR = SCENARIOS / "four_fingers.toml"
#: A coarse lattice: 2 mm cells, 40 ms steps
COARSE = RegraspSettings(xi_resolution=2e-3, envelope_margin=1e-3, periodic=False)


def _random_tables(rng: np.random.Generator, L: int, ni: int, nj: int) -> tuple:
    nb = len(PAIR_MOVES)
    env = rng.random((L, 2, max(ni, nj))) < 0.9
    prox = rng.random((L, 2, max(ni, nj)))
    adm = rng.random((L, nb)) < 0.85
    adm[:, 0] = True
    new_ok = rng.random((L, nb, ni, nj)) < 0.9
    old_ok = rng.random((L, nb, ni, nj)) < 0.9
    trans_idx = rng.integers(-2, 3, size=(L, nb, nb))
    trans_tab = rng.random((3, ni, nj)) < 0.8
    init_ok = rng.random((ni, nj)) < 0.8
    return env, prox, PAIR_MOVES, adm, new_ok, old_ok, trans_idx, trans_tab, init_ok


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("ends", ["free", "fixed"])
def test_compiled_pair_program_equals_its_reference(seed, ends):
    rng = np.random.default_rng(seed)
    L, ni, nj = 7, 5, 4
    tables = _random_tables(rng, L, ni, nj)
    start = np.array([-1, -1]) if ends == "free" else np.array([2, 1])
    end = np.array([-1, -1]) if ends == "free" else np.array([2, 2])
    args = (*tables, start, end, 100.0, 0.05, 1e4)
    V, _, last = block_dp(*args)
    V_ref, last_ref = block_dp_reference(*args)
    assert last == last_ref
    if last == L - 1:
        np.testing.assert_array_equal(np.isfinite(V), np.isfinite(V_ref))
        np.testing.assert_allclose(V[np.isfinite(V)], V_ref[np.isfinite(V_ref)], rtol=0, atol=1e-9)


@pytest.fixture(scope="module")
def small_problem():
    """The three-finger scenario on a coarse lattice over 1.2 s (31 layers), not periodic."""
    return build_problem(load_scenario(THREE), COARSE, t_end=1.2, force_tables=False)


def test_each_pair_program_never_increases_the_objective(small_problem):
    problem = small_problem
    verts = ModeVertices(problem)
    paths = [initial_path(problem, i) for i in range(3)]
    cells = np.stack([p[0] for p in paths], axis=1)
    moves = np.stack([p[1] for p in paths], axis=1)
    value = path_value(problem, cells, moves, path_failures(problem, verts, cells, moves, {}))
    for block in list(itertools.combinations(range(3), 2)) * 2:
        found, cells, moves = block_solve(problem, verts, cells, moves, block, {})
        again = path_value(problem, cells, moves, path_failures(problem, verts, cells, moves, {}))
        assert found <= value + 1e-6
        assert again == pytest.approx(found, rel=1e-12, abs=1e-6)  # the program's value is the path's objective
        value = again
    assert not path_failures(problem, verts, cells, moves, {})


def test_decomposition_plans_what_verify_accepts_on_a_small_problem(small_problem):
    problem = small_problem
    schedule = plan_regrasps(problem.scenario, RegraspSettings(xi_resolution=2e-3, envelope_margin=1e-3,
                                                               periodic=False, method="decomposition"), t_end=1.2)
    violations, _ = verify(problem, schedule, 8)
    assert violations == []


@pytest.mark.slow
def test_decomposition_matches_the_exact_planner_on_three_fingers():
    scenario = load_scenario(THREE)
    exact = plan_regrasps(scenario, RegraspSettings(method="exact"))
    found = plan_regrasps(scenario, RegraspSettings(method="decomposition"))
    problem = build_problem(scenario, RegraspSettings(method="decomposition"), force_tables=False)
    assert verify(problem, found, 8)[0] == []
    assert found.periodic
    assert len(found.slides) >= len(exact.slides)


@pytest.mark.slow
def test_four_fingers_get_a_verified_periodic_schedule():
    scenario = load_scenario(FOUR)
    settings = RegraspSettings()
    schedule = plan_regrasps(scenario, settings)  # (the exact lattice's tables would not fit: dispatched)
    problem = build_problem(scenario, settings, force_tables=False)
    assert not problem.exact
    assert verify(problem, schedule, 16)[0] == []
    assert schedule.periodic and len(schedule.names) == 4
    assert schedule.min_envelope_margin >= settings.envelope_margin


def test_four_fingers_whose_forces_couple_them_get_a_verified_schedule():
    """With f_max = 3 N and a 1 N cone margin each finger's best path alone fails the forces (the descent's start
    fails at dozens of layers): the pair programs coordinate the fingers, and the schedule verifies."""
    scenario = load_scenario(FOUR)
    settings = RegraspSettings(cone_margin=1.0, f_max=3.0, xi_resolution=2e-3)
    problem = build_problem(scenario, settings, force_tables=False)
    verts = ModeVertices(problem)
    paths = [initial_path(problem, i) for i in range(4)]
    cells, moves = np.stack([p[0] for p in paths], axis=1), np.stack([p[1] for p in paths], axis=1)
    assert len(path_failures(problem, verts, cells, moves, {})) > 10
    schedule = plan_regrasps(scenario, settings)
    assert verify(problem, schedule, 8)[0] == []
    assert schedule.min_cone_margin >= settings.cone_margin


@pytest.mark.slow
def test_decomposition_finds_as_few_slides_as_the_exact_planner_on_a_coarse_four_finger_lattice():
    """3 mm cells and two sliders at most: the exact lattice holds four fingers; with forces that couple them (f_max
    3 N, cone margin 1 N) the exact optimum needs the three-contact coordination the best-improvement descent finds.
    (The problem as it was built, without a position margin: on 3 mm cells the lattice's margin is a whole cell.)"""
    scenario = load_scenario(FOUR)
    coarse = dict(xi_resolution=3e-3, envelope_margin=1.5e-3, max_sliders=2, f_max=3.0, cone_margin=1.0,
                  position_margin=0.0)
    exact = plan_regrasps(scenario, RegraspSettings(method="exact", **coarse))
    found = plan_regrasps(scenario, RegraspSettings(method="decomposition", **coarse))
    assert len(found.slides) == len(exact.slides) >= exact.slides_lower_bound


def test_the_exact_planner_refuses_four_fingers_and_the_default_dispatches():
    scenario = load_scenario(FOUR)
    with pytest.raises(InvalidParameterError, match="force tables"):
        build_problem(scenario, RegraspSettings(method="exact"), force_tables=True)
    assert not build_problem(scenario, RegraspSettings(), force_tables=None).exact
    assert build_problem(load_scenario(THREE), RegraspSettings(), force_tables=None).exact


def test_bad_method_is_refused():
    with pytest.raises(InvalidParameterError, match="method"):
        RegraspSettings(method="greedy")


def test_an_emptying_envelope_is_named():
    scenario = load_scenario(SCENARIOS / "paper_trajectory_1.toml")
    with pytest.raises(NoScheduleError) as info:
        plan_regrasps(scenario, RegraspSettings(method="decomposition"))
    assert info.value.limit in (ScheduleLimit.ENVELOPE, ScheduleLimit.SPEED)
    assert info.value.latest_time < 0.2


def test_no_force_system_at_all_is_proven():
    """f_max 0.25 N cannot carry the object's weight: the linear programs prove it at the start."""
    settings = RegraspSettings(f_max=0.25, slider_floor=0.1, holder_preload=0.1, xi_resolution=2e-3, periodic=False,
                               method="decomposition")
    with pytest.raises(NoScheduleError) as info:
        plan_regrasps(load_scenario(THREE), settings, t_end=1.2)
    assert info.value.limit is ScheduleLimit.FORCES and info.value.latest_time == 0.0
    assert "linear program" in str(info.value)


def test_two_fingers_fail_the_forces_as_the_exact_planner_says():
    """Two fingers on trajectory 2: the one pair's program is exact, so its failure is a proof (FORCES), never
    SEARCH."""
    with pytest.raises(NoScheduleError) as info:
        plan_regrasps(load_scenario(SCENARIOS / "paper_trajectory_2.toml"), RegraspSettings(method="decomposition"))
    assert info.value.limit is ScheduleLimit.FORCES


def test_a_failed_search_says_it_is_no_proof():
    """One slider at a time on three fingers: the exact planner proves no schedule exists (its forces diagnosis);
    the decomposition finds none either but proves nothing, and says so (SEARCH), not a made-up physical reason."""
    scenario = load_scenario(THREE)
    settings = dict(max_sliders=1, xi_resolution=2e-3)
    with pytest.raises(NoScheduleError) as exact:
        plan_regrasps(scenario, RegraspSettings(method="exact", **settings))
    with pytest.raises(NoScheduleError) as found:
        plan_regrasps(scenario, RegraspSettings(method="decomposition", **settings))
    assert exact.value.limit is ScheduleLimit.FORCES
    assert found.value.limit is ScheduleLimit.SEARCH and "not a proof" in str(found.value)


@pytest.mark.parametrize("seed", range(12))
def test_the_linear_program_agrees_with_a_sampler(small_problem, seed):
    """Infeasible ⇒ no sampled positions admit forces; feasible ⇒ its positions admit forces by the vertex test."""
    problem = small_problem
    rng = np.random.default_rng(seed)
    traj = problem.scenario.trajectory
    t = rng.uniform(traj.t_start, 1.2)
    smp = traj.sample(np.array([t]))
    limits = ForceLimits(0.2, rng.uniform(1.0, 20.0), rng.uniform(0.0, 0.5))
    mu_s = [f.static for f in problem.friction]
    d = [0, 0, 0] if seed % 2 == 0 else [int(rng.integers(-1, 2)), 0, 0]
    ratios = slide_ratios(d, problem.friction)
    width = rng.uniform(0.001, 0.03, size=3)
    centre = rng.uniform(-0.015, 0.015, size=3)
    box = np.stack([centre - width / 2, centre + width / 2], axis=1)
    found = positions_admit_forces(problem.geometry, float(smp.pose[0, 2]), smp.acceleration[0], box, ratios, mu_s,
                                   limits)
    fv = force_vertices(problem.geometry, smp.pose[:, 2], smp.acceleration, ratios, mu_s, limits)
    lam, q = fv.at(0)

    def holds(xi: np.ndarray) -> np.ndarray:
        if len(lam) == 0:
            return np.zeros(len(xi), dtype=bool)
        phi = xi @ lam.T - q
        return (phi.min(axis=1) <= 1e-9) & (phi.max(axis=1) >= -1e-9)

    if found is None:
        samples = box[:, 0] + rng.random((4000, 3)) * (box[:, 1] - box[:, 0])
        grid = np.stack(np.meshgrid(*[np.linspace(*b, 9) for b in box], indexing="ij"), -1).reshape(-1, 3)
        assert not holds(np.vstack([samples, grid])).any()
    else:
        assert np.all(found >= box[:, 0] - 1e-12) and np.all(found <= box[:, 1] + 1e-12)
        assert holds(found[None])[0]

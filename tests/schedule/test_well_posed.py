"""The slides' well-posedness in the planner (regrasp.schedule.well_posed): the lattice's condition against a brute
force over every position of the held contacts with the general response (regrasp.dynamics.painleve, itself checked
against the plant), the verification, the diagnosis, and issue 27's variant that lifted a finger off."""

from __future__ import annotations

import dataclasses
import functools
import itertools
from pathlib import Path

import numpy as np
import pytest

from regrasp import RunSpec, load_scenario
from regrasp.dynamics.painleve import is_p_matrix, sliding_response
from regrasp.rollout.build import build_rollout
from regrasp.schedule import RegraspSettings, ScheduleLimit, plan_regrasps
from regrasp.schedule.diagnosis import diagnose
from regrasp.schedule.lattice import run
from regrasp.schedule.problem import build_problem
from regrasp.schedule.tables import cut_tables
from regrasp.schedule.well_posed import lattice_geometry, slide_mask, violations

FIXTURE = Path(__file__).resolve().parents[1] / "fixtures" / "issue27_variant_e.toml"
FACTOR = RegraspSettings().sliding_friction_factor


@functools.lru_cache(maxsize=1)
def _problem():
    sc = load_scenario(FIXTURE)
    return sc, build_problem(sc, RegraspSettings())


def _brute(sc, geo, k: int, modes, cells, env_ok) -> tuple[bool, bool]:
    """(some, every): whether the sliders in ``modes`` at ``cells`` are well-posed at FACTOR x mu_k for some, and for
    every, admissible position of the held contacts at layer k (each contact's response: the general function)."""
    m = len(modes)
    held = [j for j in range(m) if modes[j] == 0]
    sliders = [j for j in range(m) if modes[j] != 0]
    options = [np.flatnonzero(env_ok[k, j, :geo[j].points.shape[1]] & geo[j].reachable[k]) for j in held]
    states = np.array(list(itertools.product(*options)), dtype=int).reshape(-1, len(held))
    C = len(states)
    points, mobility = np.empty((C, m, 2)), np.empty((C, m, 2, 2))
    for j in range(m):
        c = states[:, held.index(j)] if j in held else np.full(C, cells[sliders.index(j)])
        points[:, j], mobility[:, j] = geo[j].points[k, c], geo[j].mobility[k, c]
    normals = np.broadcast_to(np.stack([g.normal[k] for g in geo]), (C, m, 2))
    tangents = np.broadcast_to(np.stack([g.tangent[k] for g in geo]), (C, m, 2))
    ratios = [None if d == 0 else d * FACTOR * f.kinetic for d, f in zip(modes, (c.friction for c in sc.contacts))]
    ok = is_p_matrix(sliding_response(sc.polygon.mass, sc.polygon.inertia, points, normals, tangents, mobility, ratios))
    return bool(ok.any()), bool(ok.all())


def test_the_lattice_condition_against_every_position_of_the_held_contacts():
    """Where the lattice allows a slide some position of the held contacts makes it well-posed at both ends of its
    interval, and where every position does the lattice allows it (its held contacts are sampled): on layers of the
    variant where it excludes slides."""
    sc, problem = _problem()
    lat = problem.lattice
    sample = sc.trajectory.sample(problem.times)
    geo = lattice_geometry(problem.torque, sc, problem.grids, sample)
    mask, pairs = slide_mask(geo, lat.combos, problem.friction, FACTOR, lat.env_ok, sc.polygon.mass,
                             sc.polygon.inertia)
    excluded = [k for k in range(lat.layers) if not mask[k].all() or any(not ok[k].all() for _, _, ok in
                                                                         pairs.values())]
    assert excluded, "the variant has slides the condition excludes"
    rng = np.random.default_rng(27)
    checked = 0
    for k in rng.choice(excluded, size=min(4, len(excluded)), replace=False):
        for mu, modes in enumerate(lat.combos.tolist()):
            sliders = [j for j in range(len(modes)) if modes[j] != 0]
            if len(sliders) not in (1, 2):
                continue
            options = [np.flatnonzero(lat.env_ok[k, j, :geo[j].points.shape[1]] & geo[j].reachable[k])
                       for j in sliders]
            for cells in itertools.islice(itertools.product(*[rng.permutation(o) for o in options]), 6):
                allowed = mask[k, mu, sliders[0], cells[0]] if len(sliders) == 1 else pairs[mu][2][k, cells[0],
                                                                                                    cells[1]]
                some, every = _brute(sc, geo, k, modes, cells, lat.env_ok)
                start = [c - modes[j] for c, j in zip(cells, sliders)]  # (the slide's start: a layer and a cell back)
                if k > 0 and all(0 <= c < geo[j].points.shape[1] and lat.env_ok[k - 1, j, c] and geo[j].reachable[
                        k - 1, c] for c, j in zip(start, sliders)):
                    some_before, every_before = _brute(sc, geo, k - 1, modes, start, lat.env_ok)
                    some, every = some and some_before, every and every_before
                assert not allowed or some, (k, modes, cells)
                assert allowed or not every, (k, modes, cells)
                checked += 1
    assert checked >= 50


def test_the_planned_schedule_is_well_posed_and_without_the_check_it_is_not():
    """Planned with the check, the variant's schedule passes the exact check at FACTOR on a fine grid; planned without
    it, its finger 1 slides where the contact problem is ill-posed even at the model's own friction (factor 1)."""
    sc, _ = _problem()
    fine = np.linspace(0.0, sc.trajectory.period, 4001)
    pose = sc.trajectory.pose(fine)
    friction = tuple(c.friction for c in sc.contacts)
    torque = _problem()[1].torque
    checked = plan_regrasps(sc)
    at = checked.at(fine)
    assert violations(torque, sc, fine, pose, at.xi, at.direction, friction, FACTOR) == []
    blind = plan_regrasps(sc, RegraspSettings(sliding_friction_factor=None))
    at = blind.at(fine)
    found = violations(torque, sc, fine, pose, at.xi, at.direction, friction, 1.0)
    assert found and {i for _, _, i in found} == {0}, found[:3]


def test_a_condition_that_excludes_every_slide_is_named_as_the_limit():
    """With the tables cut by a condition that excludes every slide of finger 1 (the variant must slide it), the
    program dies and the diagnosis says PAINLEVE, naming finger 1 and its slide; the tables before the cut survive."""
    sc, problem = _problem()
    lat = problem.lattice
    mask = np.ones((lat.layers, len(lat.combos), len(problem.grids), lat.env_ok.shape[2]), dtype=bool)
    mask[:, lat.combos[:, 0] != 0, 0, :] = False
    lo, hi = lat.lo.copy(), lat.hi.copy()
    before = cut_tables(mask, problem.grids, lat.axis, lo, hi)
    assert before is not None
    cut = dataclasses.replace(problem, lattice=dataclasses.replace(lat, lo=lo, hi=hi), posed_tables=before,
                              posed_mask=(mask, {}))
    free = run(cut.lattice, start=cut.start_cells)
    assert free.last_layer < lat.layers - 1
    error = diagnose(cut, free)
    assert error.limit is ScheduleLimit.PAINLEVE and error.contacts == ("finger1",)
    assert "finger1 to slide" in str(error) and "Painleve" in str(error)


def test_settings_refuse_a_factor_below_one():
    from regrasp.core.exceptions import InvalidParameterError

    with pytest.raises(InvalidParameterError, match="sliding_friction_factor"):
        RegraspSettings(sliding_friction_factor=0.9)
    assert RegraspSettings(sliding_friction_factor=None).sliding_friction_factor is None


@pytest.mark.slow
def test_the_variant_that_lifted_a_finger_off_runs_two_periods():
    """Issue 27's default suite, variant 6: planned without the check its finger 1 lifts off in its second slide; with
    it, the schedule runs both periods on the project plant."""
    sc, _ = _problem()
    run_spec = RunSpec(duration=2 * sc.trajectory.period)
    result = build_rollout(sc, run_spec, policy="scheduled").run()
    assert result.success, result.failure
    blind = build_rollout(sc, run_spec, policy="scheduled",
                          regrasp_settings=RegraspSettings(sliding_friction_factor=None)).run()
    assert not blind.success and blind.failure.kind.value == "separation" and blind.failure.contact == "finger1"

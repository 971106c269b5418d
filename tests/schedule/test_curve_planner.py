"""The regrasp planner on a curved object (the disc of examples/scenarios/disc.toml), its schedule re-checked by
``tests/schedule_checks.check_schedule``: the envelopes by ``FingerEnvelope.at`` between the planner's samples, the
forces by a hand-frame linear program with the contact points and normals taken from the curve at each ξ
(``tests/factories.force_lp``), the break-aways and the slide profiles; and its tables against that LP."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from factories import force_lp
from regrasp import load_scenario
from regrasp.schedule.force_polytope import ForceLimits
from regrasp.schedule.planner import RegraspSettings, plan_regrasps
from regrasp.schedule.problem import build_problem
from regrasp.schedule.schedule import NoScheduleError, ScheduleLimit
from schedule_checks import check_schedule

SCENARIOS = Path(__file__).resolve().parents[2] / "examples" / "scenarios"
#: A coarse lattice over half a period: the disc's slides in a few seconds of planning.
SETTINGS = RegraspSettings(xi_resolution=0.004, envelope_margin=0.002, periodic=False)


@pytest.fixture(scope="module")
def disc():
    return load_scenario(SCENARIOS / "disc.toml")


def test_a_disc_turned_past_any_fixed_grasp_gets_a_schedule_that_passes_the_independent_checks(disc):
    schedule = plan_regrasps(disc, SETTINGS, start_time=0.7, t_end=2.45)  # (from the swing's one end to the other)
    assert any(s.name != "palm" for s in schedule.slides)  # (the side fingers must slide round the disc)
    margins = check_schedule(disc, schedule, SETTINGS)
    assert margins["envelope"] >= SETTINGS.envelope_margin - 1e-9


def test_a_disc_turned_too_far_gets_the_reason_not_a_traceback(tmp_path):
    """Turned 1.2 rad either way, finger1 must slide -xi round the disc where no force system allows it: the
    diagnosis names the slide and the contacts pushing along gravity, read from the curve at the relaxed path's
    positions (a curve has no fixed edges to read them from)."""
    text = (SCENARIOS / "disc.toml").read_text().replace("beta_a = 0.8", "beta_a = 1.2")
    path = tmp_path / "disc.toml"
    path.write_text(text.replace('"../../urdf/', f'"{SCENARIOS.parents[1] / "urdf"}/'))
    with pytest.raises(NoScheduleError) as failure:
        plan_regrasps(load_scenario(path), SETTINGS, start_time=0.7, t_end=2.45)
    error = failure.value
    assert error.limit is ScheduleLimit.FORCES and error.contacts == ("finger1",)
    assert "slide -xi" in str(error) and "along gravity" in str(error)


@pytest.fixture(scope="module")
def disc_problem(disc):
    return build_problem(disc, SETTINGS, t_end=0.6)


@pytest.mark.parametrize("which", ["layer", "middle"])
def test_the_curve_force_tables_agree_with_the_lp_on_sampled_states(disc, disc_problem, which):
    """Every cell the layer tables admit has forces by the LP: the tables never admit an infeasible state (they may
    refuse more: the envelopes, the joint torque limits, the position margin and Painlevé's condition cut them).
    The middle tables likewise at the middle of each move, the sliders half a cell back, one slider's moves too (on
    an arc the normal turns between the cells)."""
    problem = disc_problem
    lat, rng = problem.lattice, np.random.default_rng(3)
    friction = problem.friction
    limits = dataclasses.replace(problem.limits)
    mu_s = [f.static for f in friction]
    times = problem.times if which == "layer" else np.append(problem.times[0],
                                                             0.5 * (problem.times[1:] + problem.times[:-1]))
    sample = disc.trajectory.sample(times)
    lo_table, hi_table = (lat.lo, lat.hi) if which == "layer" else (lat.mid_lo, lat.mid_hi)
    h = problem.settings.xi_resolution
    axis, m = lat.axis, len(problem.grids)
    others = [i for i in range(m) if i != axis]
    sizes = [len(problem.grids[i]) for i in others]
    movers = [mu for mu, d in enumerate(lat.combos) if which == "layer" or np.count_nonzero(d) == 1]
    checked = 0
    for _ in range(60):
        k, mu = int(rng.integers(1, len(problem.times))), int(rng.choice(movers))
        row = int(rng.integers(int(np.prod(sizes))))
        lo, hi = float(lo_table[k, row, mu]), float(hi_table[k, row, mu])
        if not lo <= hi:
            continue
        cells = np.unravel_index(row, sizes)
        xi = np.zeros(m)
        for i, c in zip(others, cells):
            xi[i] = problem.grids[i][c]
        d = lat.combos[mu]
        back = 0.0 if which == "layer" else 0.5 * h * d
        ratios = [None if d[i] == 0 else d[i] * friction[i].kinetic for i in range(m)]
        grid = problem.grids[axis]
        inside = np.flatnonzero((grid >= lo) & (grid <= hi))
        for c in inside:
            xi[axis] = grid[c]
            assert force_lp(disc.polygon, [0] * m, sample.pose[k], sample.acceleration[k], xi - back, ratios, mu_s,
                            ForceLimits(limits.f_min, limits.f_max, limits.cone_margin,
                                        friction_margin=limits.friction_margin,
                                        slider_floor=limits.slider_floor, holder_preload=limits.holder_preload),
                            disc.gravity_in_hand), (k, row, mu, c)
            checked += 1
    assert checked > 50

"""The regrasp planner's tables (regrasp.schedule.problem) against independent checks.

Each table entry the lattice program reads (a layer, a move vector, the other contacts' cells,
the axis contact's cell) is compared with what it claims about real positions and times: the
force tables with an independent LP (tests/factories.force_lp) at the layer's time, the middle's
tables half a step earlier with the sliders half a cell back, the break-away tables at the layer
and half a ramp earlier with the other sliders that far back; the envelope tables with
``FingerEnvelope.at`` over the layer's window.
"""

from __future__ import annotations

import dataclasses
import itertools
from pathlib import Path

import numpy as np
import pytest

from factories import force_lp
from field_checks import field_tests, fields_of
from regrasp import Friction, load_scenario
from regrasp.core.exceptions import InvalidParameterError
from regrasp.schedule.problem import RegraspSettings, build_problem, trajectory_period, window_margin

SCENARIO = Path(__file__).resolve().parents[2] / "examples" / "scenarios" / "paper_trajectory_2_three_fingers.toml"


RAW = dict(position_margin=0.0, sliding_friction_factor=None)  # (the force tables as the LP gives them: no cuts)


def _scenario():
    sc = load_scenario(SCENARIO)
    return dataclasses.replace(sc, contacts=tuple(dataclasses.replace(c, friction=Friction(0.6, 0.45))
                                                  for c in sc.contacts))


@pytest.fixture(scope="module")
def problem():
    return build_problem(_scenario(), RegraspSettings(**RAW))


def test_the_position_margin_erodes_the_tables_to_the_lp_on_every_neighbour(problem):
    """With a one-cell position margin a table entry holds a position exactly where the LP finds a force system at
    every position of the box behind it: each contact that slides in the move vector at its cell or the one behind
    (against its move: a slide that lags; off the grid: none), the held ones at their cells."""
    eroded = build_problem(_scenario(), RegraspSettings(position_margin=problem.settings.xi_resolution,
                                                        sliding_friction_factor=None))
    sc, lat = problem.scenario, problem.lattice
    traj = sc.trajectory
    edges = [c.edge for c in sc.contacts]
    mu_s = [f.static for f in problem.friction]
    rng = np.random.default_rng(3)
    seen = []
    while len(seen) < 30:
        k, mu = int(rng.integers(0, lat.layers)), int(rng.integers(1, len(lat.combos)))  # (a move: 0 is at rest)
        other = int(rng.integers(0, lat.lo.shape[1]))
        cells = _cells(problem, other)
        grid = problem.grids[lat.axis]
        inside = np.flatnonzero((grid >= lat.lo[k, other, mu]) & (grid <= lat.hi[k, other, mu]))
        if inside.size == 0:
            continue
        # (half the samples at the uneroded interval's ends, where the erosion decides)
        axis_cell = int(rng.choice(inside[[0, -1]] if rng.random() < 0.5 else inside))
        full = cells[:lat.axis] + [axis_cell] + cells[lat.axis:]
        x_axis = grid[axis_cell]
        lo, hi = float(eroded.lattice.lo[k, other, mu]), float(eroded.lattice.hi[k, other, mu])
        if min(abs(x_axis - lo), abs(x_axis - hi)) < 1e-6 or not lat.lo[k, other, mu] <= x_axis <= lat.hi[k, other,
                                                                                                          mu]:
            continue  # (on a bound; or outside before the erosion: nothing to erode)
        smp = traj.sample(float(problem.times[k]))
        ratios = [None if d == 0 else d * f.kinetic for d, f in zip(lat.combos[mu], problem.friction)]
        every = True
        h = problem.settings.xi_resolution
        for shift in itertools.product(*[(0, -int(d)) if d != 0 else (0,) for d in lat.combos[mu]]):
            near = [c + s for c, s in zip(full, shift)]
            if not all(0 <= c < len(g) for j, (c, g) in enumerate(zip(near, problem.grids)) if j != lat.axis):
                every = False  # (another contact off its grid: no state; the axis's interval goes on past its grid)
                break
            xi = np.array([x_axis + h * shift[j] if j == lat.axis else g[c]
                           for j, (g, c) in enumerate(zip(problem.grids, near))])
            if not force_lp(sc.polygon, edges, smp.pose, smp.acceleration, xi, ratios, mu_s, problem.limits,
                            sc.gravity_in_hand):
                every = False
                break
        assert (lo <= x_axis <= hi) == every, (k, mu, full)
        seen.append(every)
    assert 0 < np.mean(seen) < 1


def _cells(problem, other: int) -> list[int]:
    """The other contacts' cells of a flat 'others' index (C order, the axis left out)."""
    lat = problem.lattice
    sizes = [len(problem.grids[i]) for i in range(len(problem.grids)) if i != lat.axis]
    return list(np.unravel_index(other, sizes))


def _check(problem, rng, table_lo, table_hi, when, positions, ratios, samples=150):
    """Compare random entries of one kind of table with the LP; returns the verdicts seen."""
    sc = problem.scenario
    lat = problem.lattice
    traj = sc.trajectory
    edges = [c.edge for c in sc.contacts]
    mu_s = [f.static for f in problem.friction]
    seen = []
    for _ in range(samples):
        k, column = when(rng)
        other = int(rng.integers(0, table_lo.shape[1]))
        cells = _cells(problem, other)
        axis_cell = int(rng.integers(0, len(problem.grids[lat.axis])))
        full = cells[:lat.axis] + [axis_cell] + cells[lat.axis:]
        t, xi = positions(k, column, np.array([g[c] for g, c in zip(problem.grids, full)]))
        x_axis = problem.grids[lat.axis][axis_cell]
        lo, hi = float(table_lo[k, other, column]), float(table_hi[k, other, column])
        if min(abs(x_axis - lo), abs(x_axis - hi)) < 1e-6:
            continue  # on a bound
        smp = traj.sample(float(np.clip(t, traj.t_start, traj.t_end)))
        expected = force_lp(sc.polygon, edges, smp.pose, smp.acceleration, xi, ratios(k, column), mu_s,
                            problem.limits, sc.gravity_in_hand)
        assert (lo <= x_axis <= hi) == expected, (k, column, full, lo, hi)
        seen.append(expected)
    return seen


def test_force_tables_say_what_the_lp_says(problem):
    rng = np.random.default_rng(0)
    lat = problem.lattice
    combos = lat.combos

    def ratios(k, mu):
        return [None if d == 0 else d * f.kinetic for d, f in zip(combos[mu], problem.friction)]

    seen = _check(problem, rng, lat.lo, lat.hi,
                  lambda r: (int(r.integers(0, lat.layers)), int(r.integers(0, len(combos)))),
                  lambda k, mu, xi: (problem.times[k], xi), ratios)
    assert 0.1 < np.mean(seen) < 0.95


def test_middle_tables_hold_the_middle_of_two_slider_moves(problem):
    rng = np.random.default_rng(1)
    lat = problem.lattice
    combos = lat.combos
    two = [mu for mu, d in enumerate(combos) if np.count_nonzero(d) >= 2]
    h = problem.settings.xi_resolution

    def ratios(k, mu):
        return [None if d == 0 else d * f.kinetic for d, f in zip(combos[mu], problem.friction)]

    def positions(k, mu, xi):  # half a step before layer k, the sliders half a cell back
        return 0.5 * (problem.times[k - 1] + problem.times[k]), xi - 0.5 * h * combos[mu]

    seen = _check(problem, rng, lat.mid_lo, lat.mid_hi,
                  lambda r: (int(r.integers(1, lat.layers)), int(r.choice(two))), positions, ratios)
    assert 0.05 < np.mean(seen) < 0.95


def test_breakaway_tables_hold_at_the_layer_and_where_it_starts(problem):
    _check_breakaway(problem)


def test_a_planned_priming_overshoot_gets_breakaway_tables_where_mu_s_is_mu_k():
    """``RegraspSettings.prime_overshoot``: with μ_s = μ_k a break-away needs no table of its own, unless the
    executor's priming overshoot is planned; then each starting slider's ratio is μ_s + the overshoot, and the
    tables say what the LP says there."""
    sc = load_scenario(SCENARIO)
    sc = dataclasses.replace(sc, contacts=tuple(dataclasses.replace(c, friction=Friction(0.5, 0.5))
                                                for c in sc.contacts))
    plain = build_problem(sc, RegraspSettings(periodic=False, prime_overshoot=0.0, **RAW), t_end=0.6)
    assert (plain.lattice.breakaway_slot < 0).all()
    _check_breakaway(build_problem(sc, RegraspSettings(periodic=False, prime_overshoot=0.05, **RAW), t_end=0.6))


def _check_breakaway(problem):
    rng = np.random.default_rng(2)
    lat = problem.lattice
    combos = lat.combos
    m = combos.shape[1]
    slots = {}  # slot: (move vector, the contacts primed together)
    for (mu, bits), s in np.ndenumerate(lat.breakaway_slot):
        if s >= 0:
            slots.setdefault(int(s), (mu, frozenset(i for i in range(m) if (bits >> i) & 1)))
    # every non-empty set of a move vector's sliders may start together (mu_s > mu_k), each mask its own check
    assert len(slots) == sum(2 ** np.count_nonzero(d) - 1 for d in combos)
    assert all(lat.breakaway_slot[mu, sum(1 << i for i in primed)] == s for s, (mu, primed) in slots.items())
    h, ramp, dt = problem.settings.xi_resolution, problem.settings.ramp, problem.dt
    mu_s = [f.static for f in problem.friction]
    edges = [c.edge for c in problem.scenario.contacts]
    traj = problem.scenario.trajectory
    seen = []
    for _ in range(120):
        k, slot = int(rng.integers(0, lat.layers)), int(rng.choice(list(slots)))
        mu, primed = slots[slot]
        other = int(rng.integers(0, lat.break_lo.shape[1]))
        cells = _cells(problem, other)
        axis_cell = int(rng.integers(0, len(problem.grids[lat.axis])))
        full = cells[:lat.axis] + [axis_cell] + cells[lat.axis:]
        xi = np.array([g[c] for g, c in zip(problem.grids, full)])
        lo, hi = float(lat.break_lo[k, other, slot]), float(lat.break_hi[k, other, slot])
        x_axis = xi[lat.axis]
        if min(abs(x_axis - lo), abs(x_axis - hi)) < 1e-6:
            continue
        overshoot = problem.settings.prime_overshoot  # (the executor's priming, planned)
        ratios = [None if d == 0 else d * (f.static + overshoot if j in primed else f.kinetic)
                  for j, (d, f) in enumerate(zip(combos[mu], problem.friction))]
        back = 0.5 * ramp / dt * h * np.array([0 if j in primed else d for j, d in enumerate(combos[mu])])
        both = True
        # (at a break-away the executor's last fallback keeps f_min alone and no cone margin in newtons)
        limits = dataclasses.replace(problem.limits, slider_floor=0.0, holder_preload=0.0, cone_margin=0.0)
        for t, pos in ((problem.times[k], xi), (problem.times[k] - 0.5 * ramp, xi - back)):
            smp = traj.sample(float(np.clip(t, traj.t_start, traj.t_end)))
            both &= force_lp(problem.scenario.polygon, edges, smp.pose, smp.acceleration, pos, ratios, mu_s,
                             limits, problem.scenario.gravity_in_hand)
        assert (lo <= x_axis <= hi) == both
        seen.append(both)
    assert 0.05 < np.mean(seen) < 0.95


def test_envelope_tables_keep_the_margin_over_each_window(problem):
    from regrasp.envelope.finger_envelope import FingerEnvelope

    rng = np.random.default_rng(3)
    sc = problem.scenario
    lat = problem.lattice
    em = problem.settings.envelope_margin
    envs = [FingerEnvelope(c.finger, sc.polygon, c.edge, geometry=sc.geometry, tip_clearance=c.tip_clearance)
            for c in sc.contacts]
    for _ in range(40):
        k = int(rng.integers(1, lat.layers - 1))
        i = int(rng.integers(0, len(envs)))
        c = int(rng.integers(0, len(problem.grids[i])))
        x = problem.grids[i][c]
        window = np.linspace(problem.times[k - 1], problem.times[k + 1], 33)
        margins = [envs[i].at(sc.trajectory.pose(t), float(t)).margin(x) for t in window]
        if lat.env_ok[k, i, c]:
            assert min(margins) >= em - 1e-9  # admissible: the margin holds over the whole window
        elif min(margins) > em + problem.envelope_buffer + 1e-4:
            pytest.fail(f"cell {x} of contact {i} refused at layer {k} with margins >= {min(margins)}")


def test_the_period_of_the_paper_trajectories():
    sc = load_scenario(SCENARIO)
    assert trajectory_period(sc.trajectory) == pytest.approx(np.pi)
    problem = build_problem(sc, RegraspSettings(periodic=False), t_end=1.0)
    assert not problem.periodic and problem.times[-1] == pytest.approx(1.0)
    assert problem.dt >= RegraspSettings().time_step - 1e-12  # never faster than the speed limit


def test_a_lattice_too_large_for_memory_is_refused_up_front():
    from regrasp.core.exceptions import InvalidParameterError

    sc = load_scenario(SCENARIO)
    four = dataclasses.replace(sc, contacts=sc.contacts + (dataclasses.replace(sc.contacts[2], edge=0),))
    with pytest.raises(InvalidParameterError) as info:
        build_problem(four, RegraspSettings())
    assert "GiB" in str(info.value) and "xi_resolution" in str(info.value)


SETTINGS_TABLE = fields_of(RegraspSettings(), {
    "nonneg": ("envelope_margin", "cone_margin", "friction_margin", "prime_overshoot", "slider_floor",
               "holder_preload", "position_margin"),
    "pos": ("f_min", "f_max", "max_slide_speed", "max_slide_acceleration", "xi_resolution", "comfort_margin",
            "sliding_friction_factor"),
    "count1": ("max_sliders", "envelope_substeps", "verify_substeps", "period_candidates"), "count0": ("max_repairs",),
    "flag": ("periodic",), "geometry": ("geometry",), "choice": ("method",)},
    optional=("max_sliders", "comfort_margin", "periodic", "geometry", "method", "sliding_friction_factor"),
    good={"max_sliders": 2, "periodic": True, "geometry": "urdf", "method": "decomposition"},
    choices={"method": ("exact", "decomposition")})

test_each_setting_refuses_bad_values, test_each_setting_refuses_generated_bad_values = field_tests(SETTINGS_TABLE)


@pytest.mark.parametrize("name", ["envelope_substeps", "verify_substeps", "max_repairs", "period_candidates",
                                  "max_sliders"])
def test_counts_are_bounded_and_numpy_integers_are_counts(name):
    """Issue 25: ``envelope_substeps=10**400`` was an OverflowError, ``np.int64(2)`` refused."""
    with pytest.raises(InvalidParameterError, match=name):
        RegraspSettings(**{name: 10**400})
    value = getattr(RegraspSettings(**{name: np.int64(2)}), name)
    assert value == 2 and type(value) is int


def test_window_margin_is_what_the_envelope_tables_admit():
    """The margin a refusal reports (window_margin) decides each cell exactly as the lattice's envelope tables do."""
    scenario = load_scenario("examples/scenarios/paper_trajectory_2_three_fingers.toml")
    problem = build_problem(scenario, RegraspSettings(xi_resolution=2e-3))
    need = problem.settings.envelope_margin + problem.envelope_buffer
    n = len(problem.times) - 1
    for k in (0, 1, n // 2, n):
        for i, grid in enumerate(problem.grids):
            found = [window_margin(problem, k, i, float(x)) for x in grid]
            assert all(problem.sub_times[0] - 1e-12 <= t <= problem.sub_times[-1] + 1e-12 for _, t in found)
            np.testing.assert_array_equal(problem.lattice.env_ok[k, i, :len(grid)],
                                          [m >= need for m, _ in found])

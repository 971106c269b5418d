"""The force tables on curves (regrasp.schedule.curve_forces) against an independent linear program: every cell the
compiled test calls feasible has a force system (HiGHS, on the tangent lines at the exact positions), and its run is
the longest run of cells the LP finds feasible."""

import itertools

import numpy as np
import pytest

from regrasp.core.curves import Disc, Ellipse, RoundedPolygon
from regrasp.schedule.curve_forces import feasible_runs, mode_polygon, tangent_geometry, wrench_maps
from regrasp.schedule.force_polytope import ForceLimits, force_system

LIMITS = ForceLimits(0.5, 20.0, 0.2, friction_margin=0.02)
CURVES = {
    "disc": Disc(0.04, mass=0.1),
    "ellipse": Ellipse(0.05, 0.03, mass=0.1),
    "rounded box": RoundedPolygon(0.5 * np.array([[0.1, 0.06], [-0.1, 0.06], [-0.1, -0.06], [0.1, -0.06]]), 0.01,
                                  mass=0.1),
}
MODES = [(None, None, None), (0.4, None, None), (None, -0.4, None), (0.45, None, -0.4)]


def _runs_of(flags):
    runs, current = [], None
    for c, ok in enumerate(flags):
        if ok:
            current = [c, c] if current is None else [current[0], c]
        elif current is not None:
            runs.append(current)
            current = None
    if current is not None:
        runs.append(current)
    return runs


def _check_against_lp(curve, grids, ratios, mu_s, axis, rng, scale=1.0):
    """Compares feasible_runs's runs with the LP's on sampled rows of two layers (a random required wrench, its
    accelerations times ``scale``); returns the number of feasible cells seen."""
    m, n = len(grids), len(grids[0])
    maps = [wrench_maps(curve, g) for g in grids]
    floors = LIMITS.floors(ratios)
    T = 2
    polygons, counts = np.zeros((T, m, n, 12, 2)), np.zeros((T, m, n), dtype=int)
    for i in range(m):
        q = mode_polygon(ratios[i], mu_s[i], floors[i], LIMITS)
        polygons[:, i, :, :len(q)], counts[:, i] = q, len(q)
    beta = rng.uniform(-0.5, 0.5, T)
    acc = np.column_stack([rng.normal(size=(T, 2)) * 3, rng.normal(size=T) * 30]) * scale
    gravity = np.array([0.0, -9.81]) * scale
    F = curve.mass * (acc[:, :2] - gravity)
    c, s = np.cos(beta), np.sin(beta)
    wrench = np.column_stack([c * F[:, 0] + s * F[:, 1], -s * F[:, 0] + c * F[:, 1], curve.inertia * acc[:, 2]])
    runs = feasible_runs(maps, polygons, counts, wrench, np.ones((T, m, n), dtype=bool), axis, 1e-9)
    others = list(itertools.product(*[range(n) for j in range(m) if j != axis]))
    checked = 0
    for k in range(T):
        for row in rng.choice(len(others), min(6, len(others)), replace=False):
            flags = []
            for cell in range(n):
                cells = list(others[row])
                cells.insert(axis, cell)
                xi = np.array([grids[i][cells[i]] for i in range(m)])
                geo = tangent_geometry(curve, xi, mass=curve.mass, inertia=curve.inertia, gravity=gravity)
                flags.append(force_system(geo, beta[k], acc[k], xi, ratios, mu_s, LIMITS).feasible)
            lp = _runs_of(flags)
            longest = max(lp, key=lambda r: r[1] - r[0]) if lp else [-1, -2]
            assert list(runs[k, row]) == longest, (k, row, flags)
            checked += sum(flags)
    return checked


@pytest.mark.parametrize("name", list(CURVES))
@pytest.mark.parametrize("mode", range(len(MODES)))
def test_feasible_runs_match_a_linear_program(name, mode):
    curve = CURVES[name]
    P = curve.perimeter
    grids = [c + 0.002 * np.arange(-5, 6) for c in (0.75 * P, 0.25 * P, 0.5 * P)]
    checked = _check_against_lp(curve, grids, MODES[mode], (0.6, 0.7, 0.6), mode % 3, np.random.default_rng(7 + mode))
    assert checked > 0  # (some cells are feasible: the test sees both verdicts)


@pytest.mark.parametrize("name", ["disc", "rounded box"])
def test_two_contacts_one_sliding_match_a_linear_program(name):
    """Two contacts, the other one sliding: its summand is a segment and so is W, whose ends (the slider's force
    bounds) take half-planes along it (a segment's own direction among the candidates)."""
    curve = CURVES[name]
    P = curve.perimeter
    grids = [c + 0.004 * np.arange(-10, 11) for c in (0.25 * P, 0.75 * P)]
    checked = _check_against_lp(curve, grids, (None, 0.4), (0.8, 0.8), 0, np.random.default_rng(11), scale=0.3)
    assert checked > 0


def test_tangent_geometry_reproduces_the_wrench_of_a_force_at_the_point():
    curve = CURVES["ellipse"]
    xi = np.array([0.01, 0.07, 0.13])
    geo = tangent_geometry(curve, xi, mass=1.0, inertia=1.0, gravity=np.zeros(2))
    maps = wrench_maps(curve, xi)
    lam, tau = np.array([1.0, 2.0, 0.5]), np.array([0.3, -0.2, 0.1])
    for i in range(3):
        moment = lam[i] * (geo.moment_normal[i] - xi[i]) + tau[i] * geo.moment_tangent[i]
        assert moment == pytest.approx(maps[i, 2] @ [lam[i], tau[i]], abs=1e-15)
        np.testing.assert_allclose(geo.normals[i] * lam[i] + geo.tangents[i] * tau[i], maps[i, :2] @ [lam[i], tau[i]],
                                   atol=1e-15)


def test_mode_polygon_is_the_cone_and_the_bounds():
    q = mode_polygon(None, 0.5, 1.0, LIMITS)
    slope = 0.5 - LIMITS.friction_margin
    np.testing.assert_allclose(q, [[1.0, -(slope - 0.2)], [20.0, -(20 * slope - 0.2)], [20.0, 20 * slope - 0.2],
                                   [1.0, slope - 0.2]])
    np.testing.assert_allclose(mode_polygon(0.3, 0.5, 1.0, LIMITS), [[1.0, 0.3], [20.0, 6.0]])
    assert len(mode_polygon(None, 0.01, 1.0, LIMITS)) == 0  # μ_s below the friction margin: no cone

"""The force polytope (regrasp.schedule.force_polytope) against an independent linear program.

The oracle (tests/factories.py, ``force_lp``) is written from scratch: the contact forces f_i in
the hand frame (2m unknowns), the object's Newton-Euler equations with the contact points and the
lever arms computed from the polygon's edges, each contact's normal and tangential components from
its rotated edge frame, and scipy's HiGHS for feasibility. It shares no code with the module under
test.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import replace

import numpy as np
import pytest

from factories import force_lp, random_polygon, rot
from field_checks import field_tests, fields_of
from regrasp.core.contact import Friction
from regrasp.core.exceptions import InvalidParameterError
from regrasp.schedule.force_polytope import ForceGeometry, ForceLimits, force_system, force_vertices, xi_intervals


def _case(rng):
    polygon = random_polygon(rng, rng.uniform(0.05, 0.15))
    polygon = type(polygon).from_vertices(polygon.vertices, mass=rng.uniform(0.05, 0.3),
                                          inertia=rng.uniform(1e-5, 1e-3))
    m = int(rng.integers(2, 4))
    edges = [int(e) for e in rng.choice(polygon.n_vertices, size=m, replace=polygon.n_vertices < m)]
    pose = np.array([rng.uniform(-0.05, 0.05), rng.uniform(-0.05, 0.05), rng.uniform(-np.pi, np.pi)])
    acc = rng.uniform(-2.0, 2.0, size=3) * np.array([1.0, 1.0, 20.0])
    gravity = rng.normal(size=2) * 9.81 / math.sqrt(2)
    frictions = [Friction(ms, ms * rng.uniform(0.3, 1.0)) for ms in rng.uniform(0.2, 1.2, size=m)]
    ratios = []
    for f in frictions:
        choice = rng.integers(0, 3)
        ratios.append(None if choice == 0 else float(rng.choice([-1, 1])) * (f.kinetic if choice == 1 else f.static))
    if sum(r is not None for r in ratios) >= m:
        ratios[0] = None
    limits = ForceLimits(rng.uniform(0.05, 0.3), rng.uniform(3.0, 20.0), rng.uniform(0.0, 0.2),
                         *rng.uniform(0.0, 0.6, 2))  # (the floors of sliders and of the holders while they slide)
    if rng.random() < 0.5:  # the executor's friction margin, a coefficient off μ_s
        limits = replace(limits, friction_margin=float(rng.uniform(0.0, 0.1)))
    return polygon, edges, pose, acc, gravity, frictions, ratios, limits


def _compare(seed: int, samples: int = 60) -> list[bool]:
    """The LP's verdicts at random positions, asserting the vertex test agrees with each."""
    rng = np.random.default_rng(seed)
    polygon, edges, pose, acc, gravity, frictions, ratios, limits = _case(rng)
    mu_s = [f.static for f in frictions]
    geo = ForceGeometry.of(polygon, edges, mass=polygon.mass, inertia=polygon.inertia, gravity=gravity)
    lam, q = force_vertices(geo, [pose[2]], [acc], ratios, mu_s, limits).at(0)
    verdicts = []
    for _ in range(samples):
        xi = np.array([rng.uniform(*polygon.edge(k).xi_range) for k in edges])
        expected = force_lp(polygon, edges, pose, acc, xi, ratios, mu_s, limits, gravity)
        phi = lam @ xi - q if len(lam) else np.array([np.inf])
        got = bool(len(lam) > 0 and phi.min() <= 1e-10 and phi.max() >= -1e-10)
        assert got == expected, (xi, got, expected)
        verdicts.append(expected)
    return verdicts


@pytest.mark.slow
def test_vertex_feasibility_equals_the_linear_program():
    verdicts = [v for seed in range(40) for v in _compare(seed)]
    # both answers occur often: the comparison is not vacuous
    assert 0.1 < np.mean(verdicts) < 0.9, np.mean(verdicts)


@pytest.mark.parametrize("seed", range(12))
def test_intervals_hold_exactly_the_feasible_positions(seed):
    rng = np.random.default_rng(100 + seed)
    for _ in range(20):  # find a case with a non-empty polytope
        polygon, edges, pose, acc, gravity, frictions, ratios, limits = _case(rng)
        mu_s = [f.static for f in frictions]
        geo = ForceGeometry.of(polygon, edges, mass=polygon.mass, inertia=polygon.inertia, gravity=gravity)
        lam, q = force_vertices(geo, [pose[2]], [acc], ratios, mu_s, limits).at(0)
        if len(lam):
            break
    else:
        pytest.skip("no feasible case found")
    m = len(edges)
    axis = int(rng.integers(0, m))
    others = np.array([[rng.uniform(*polygon.edge(edges[i]).xi_range) for i in range(m) if i != axis]
                       for _ in range(6)])
    lo, hi = xi_intervals(lam, q, axis, others)
    for row, a, b in zip(others, lo, hi):
        span = polygon.edge(edges[axis]).xi_range
        for x in np.linspace(span[0] - 0.05, span[1] + 0.05, 41):
            xi = np.insert(row, axis, x)
            inside = a - 1e-9 <= x <= b + 1e-9
            if min(abs(x - a), abs(x - b)) < 1e-7:
                continue  # on a bound: either answer within the LP's tolerance
            assert inside == force_lp(polygon, edges, pose, acc, xi, ratios, mu_s, limits, gravity)


@pytest.mark.parametrize("seed", range(15))
def test_force_system_has_the_largest_smallest_margin(seed):
    rng = np.random.default_rng(200 + seed)
    for _ in range(50):
        polygon, edges, pose, acc, gravity, frictions, ratios, limits = _case(rng)
        mu_s = [f.static for f in frictions]
        xi = np.array([rng.uniform(*polygon.edge(k).xi_range) for k in edges])
        best = force_lp(polygon, edges, pose, acc, xi, ratios, mu_s, replace(limits, cone_margin=0.0), gravity,
                        maximise_margin=True)
        if best is not None and best > limits.cone_margin + 1e-6:
            break
    else:
        pytest.skip("no feasible case found")
    geo = ForceGeometry.of(polygon, edges, mass=polygon.mass, inertia=polygon.inertia, gravity=gravity)
    system = force_system(geo, pose[2], acc, xi, ratios, mu_s, limits)
    assert system.feasible
    fixed = [i for i, r in enumerate(ratios) if r is None]
    # (the reported margins are the cone's own, μ_s f_n - |f_t|; the maximised one is off μ_s - friction_margin)
    assert min(system.cone_margins[fixed] - limits.friction_margin * system.normal[fixed]) == pytest.approx(best,
                                                                                                           abs=1e-7)
    # the system balances the object (hand-frame Newton-Euler, written here)
    R = rot(pose[2])
    total, moment = np.zeros(2), 0.0
    for k, x, lam, tau in zip(edges, xi, system.normal, system.tangential):
        e = polygon.edge(k)
        n = R @ e.inward_normal
        f = lam * n + tau * np.array([-n[1], n[0]])
        r = R @ e.point(x)
        total += f
        moment += r[0] * f[1] - r[1] * f[0]
    np.testing.assert_allclose(total, polygon.mass * (acc[:2] - gravity), atol=1e-7)
    assert moment == pytest.approx(polygon.inertia * acc[2], abs=1e-8)
    for i, r in enumerate(ratios):
        if r is not None:
            assert system.tangential[i] == pytest.approx(r * system.normal[i], abs=1e-8)
    assert np.all(system.normal >= np.array(limits.floors(ratios)) - 1e-8)
    assert np.all(system.normal <= limits.f_max + 1e-8)


def test_many_times_at_once_equal_one_at_a_time():
    rng = np.random.default_rng(7)
    polygon, edges, pose, acc, gravity, frictions, ratios, limits = _case(rng)
    mu_s = [f.static for f in frictions]
    geo = ForceGeometry.of(polygon, edges, mass=polygon.mass, inertia=polygon.inertia, gravity=gravity)
    betas = rng.uniform(-3, 3, size=5)
    accs = rng.uniform(-2, 2, size=(5, 3))
    batch = force_vertices(geo, betas, accs, ratios, mu_s, limits)
    for k in range(5):
        one = force_vertices(geo, [betas[k]], [accs[k]], ratios, mu_s, limits)
        np.testing.assert_allclose(np.sort(batch.at(k)[1]), np.sort(one.at(0)[1]), atol=1e-12)


def test_limits_are_validated():
    for args in [(0.0, 1.0, 0.1), (0.2, 0.1, 0.1), (0.2, math.inf, 0.1), (0.2, 5.0, -0.1), (math.nan, 5.0, 0.1)]:
        with pytest.raises(InvalidParameterError):
            ForceLimits(*args)
    polygon = random_polygon(np.random.default_rng(0), 0.1)
    geo = ForceGeometry.of(polygon, [0, 1], mass=1.0, inertia=1.0, gravity=(0, -9.81))
    with pytest.raises(InvalidParameterError):
        force_vertices(geo, [0.0], [[0, 0, 0]], [None], [0.5, 0.5], ForceLimits(0.1, 5, 0))


def test_vertices_are_on_their_active_constraints():
    """Every returned vertex satisfies the balance and has d - 2 active inequalities (a vertex)."""
    rng = np.random.default_rng(11)
    polygon, edges, pose, acc, gravity, frictions, ratios, limits = _case(rng)
    mu_s = [f.static for f in frictions]
    geo = ForceGeometry.of(polygon, edges, mass=polygon.mass, inertia=polygon.inertia, gravity=gravity)
    fv = force_vertices(geo, [pose[2]], [acc], ratios, mu_s, limits)
    keep = fv.valid[0]
    R = rot(pose[2])
    for lam, tau in zip(fv.normal[0, keep], fv.tangential[0, keep]):
        total = np.zeros(2)
        for k, a, b in zip(edges, lam, tau):
            n = R @ polygon.edge(k).inward_normal
            total += a * n + b * np.array([-n[1], n[0]])
        np.testing.assert_allclose(total, polygon.mass * (acc[:2] - gravity), atol=1e-8)
        active = sum(abs(a - floor) < 1e-8 or abs(a - limits.f_max) < 1e-8 for a, floor in zip(lam,
                                                                                              limits.floors(ratios)))
        active += sum(abs((mu_s[i] - limits.friction_margin) * a - abs(b) - limits.cone_margin) < 1e-8
                      for i, (a, b) in enumerate(zip(lam, tau)) if ratios[i] is None)
        d = len(edges) + sum(r is None for r in ratios)
        assert active >= d - 2
    assert list(itertools.islice(iter(keep), 1))  # (a valid polytope has vertices)


def test_floors_load_the_sliders_and_the_holders_while_one_slides():
    """``ForceLimits.slider_floor`` and ``holder_preload``: a contact on a cone edge pushes with at least the first,
    the fixed ones with at least the second while any contact is on an edge; at rest only f_min."""
    limits = ForceLimits(0.2, 20.0, 0.2, slider_floor=0.35, holder_preload=0.3)
    assert limits.floors([None, None, None]) == [0.2, 0.2, 0.2]
    assert limits.floors([0.5, None, None]) == [0.35, 0.3, 0.3]
    assert ForceLimits(0.4, 20.0, 0.2, slider_floor=0.35, holder_preload=0.3).floors([None, -0.5, None]) == [0.4] * 3
    for bad in (dict(slider_floor=-1.0), dict(holder_preload=math.inf), dict(slider_floor=20.0)):
        with pytest.raises(InvalidParameterError):
            ForceLimits(0.2, 20.0, 0.2, **bad)


LIMITS_TABLE = fields_of(ForceLimits(0.2, 20.0, 0.2, 0.3, 0.3), {
    "pos": ("f_min", "f_max"), "nonneg": ("cone_margin", "slider_floor", "holder_preload", "friction_margin")})

test_each_limit_refuses_bad_values, test_each_limit_refuses_generated_bad_values = field_tests(LIMITS_TABLE)

"""The lattice dynamic program (regrasp.schedule.lattice) against brute force on small lattices.

The brute force enumerates every start state and every sequence of move vectors, applies the
module docstring's admissibility rules written out here in plain Python, and keeps the cheapest
path. The program must find a path of exactly that cost, and its path must be admissible.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from regrasp.schedule.lattice import Lattice, motion_combos, path, run


def _random_lattice(rng, m, cells, layers, p_max, breakaway):
    grids = [0.001 * np.arange(cells) for _ in range(m)]
    combos = motion_combos(m, p_max)
    M = len(combos)
    env_ok = rng.random((layers, m, cells)) < 0.9
    env_ok[:2, 0, cells // 2:] = False  # contact 0 starts low and ends high: it must slide
    env_ok[-2:, 0, :cells // 2] = False
    proximity = rng.random((layers, m, cells)).round(2)
    axis = m - 1
    n_o = cells ** (m - 1)

    def table(shape=(layers, n_o, M)):
        lo = rng.uniform(-0.002, 0.0015, size=shape).astype(np.float32)
        return lo, (lo + rng.uniform(0.001, 0.005, size=shape)).astype(np.float32)

    lo, hi = table()
    mid_lo, mid_hi = table()
    single = np.count_nonzero(combos, axis=1) < 2  # (as on edges: no middle table for fewer than two sliders)
    mid_lo[:, :, single], mid_hi[:, :, single] = -np.inf, np.inf
    break_lo = break_hi = None
    slots = np.full((M, 2 ** m), -1, dtype=np.int64)
    if breakaway:  # a random check (or none) per move vector and starter mask
        masks = np.array([[all(d[i] != 0 for i in range(m) if (bits >> i) & 1) for bits in range(2 ** m)]
                          for d in combos])
        masks[:, 0] = False
        needs = masks & (rng.random((M, 2 ** m)) < 0.6)
        slots[needs] = rng.integers(0, max(int(needs.sum()), 1), size=int(needs.sum()))
        break_lo, break_hi = table((layers, n_o, max(int(needs.sum()), 1)))
    rest_only = np.zeros(layers, dtype=bool)
    rest_only[[0, 1, layers - 1]] = True
    return Lattice(np.arange(layers) * 0.02, grids, combos, env_ok, proximity, axis, lo, hi, mid_lo, mid_hi,
                   break_lo, break_hi, slots, rest_only, slide_cost=1.0 + layers * m * 1.05, move_cost=0.05)


def _other(lat, cells):
    return sum(int(c) * int(s) for c, s in zip(cells, lat.other_strides))


def _inside(lo, hi, k, other, column, x):
    return lo[k, other, column] - 1e-8 <= x <= hi[k, other, column] + 1e-8


def _state_cost(lat, k, cells, mu):
    """Secondary cost of entering state (cells, mu) at layer k, or None when not admissible there."""
    if not all(lat.env_ok[k, i, c] for i, c in enumerate(cells)):
        return None
    if not _inside(lat.lo, lat.hi, k, _other(lat, cells), mu, lat.axis_grid[cells[lat.axis]]):
        return None
    return sum(lat.proximity[k, i, c] for i, c in enumerate(cells)) + lat.move_cost * np.count_nonzero(lat.combos[mu])


def _transition_ok(lat, k, prev_cells, prev_mu, cells, mu):
    """Whether the move from (prev_cells, prev_mu) at layer k - 1 to (cells, mu) at layer k obeys the rules."""
    d, e = lat.combos[mu], lat.combos[prev_mu]
    if lat.rest_only[k] and mu != 0:
        return False
    for di, ei in zip(d, e):
        if di != 0 and ei not in (0, di):  # no reversal without a rest
            return False
    union = tuple(di if di else ei for di, ei in zip(d, e))
    index = {tuple(r): j for j, r in enumerate(lat.combos.tolist())}
    if union not in index:
        return False
    x_old = lat.axis_grid[prev_cells[lat.axis]]
    x_new = lat.axis_grid[cells[lat.axis]]
    if not _inside(lat.lo, lat.hi, k - 1, _other(lat, prev_cells), mu, x_old):
        return False
    u = index[union]
    if u not in (mu, prev_mu) and not _inside(lat.lo, lat.hi, k - 1, _other(lat, prev_cells), u, x_old):
        return False
    if not _inside(lat.mid_lo, lat.mid_hi, k, _other(lat, cells), mu, x_new):
        return False  # (the middle's table is indexed by the new cells; +-inf where no middle is checked)
    if lat.break_lo is not None:  # the starting contacts break away together, the others in the union move
        bits = sum(1 << i for i, (di, ei) in enumerate(zip(d, e)) if di != 0 and ei == 0)
        slot = lat.breakaway_slot[u, bits]
        if bits and slot >= 0 and not _inside(lat.break_lo, lat.break_hi, k - 1, _other(lat, prev_cells), slot,
                                              x_old):
            return False
    return True


def _brute_force(lat):
    """The cheapest admissible path, by depth-first enumeration of every admissible path."""
    m = len(lat.grids)
    cells_n = len(lat.grids[0])
    best = [np.inf]

    def extend(k, cells, mu, cost):
        if k == lat.layers:
            best[0] = min(best[0], cost)
            return
        for new_mu, d in enumerate(lat.combos):
            new_cells = cells + d
            if np.any(new_cells < 0) or np.any(new_cells >= cells_n):
                continue
            c = _state_cost(lat, k, new_cells, new_mu)
            if c is None or not _transition_ok(lat, k, cells, mu, new_cells, new_mu):
                continue
            starts = sum(1 for di, ei in zip(d, lat.combos[mu]) if di != 0 and ei == 0)
            extend(k + 1, new_cells, new_mu, cost + c + lat.slide_cost * starts)

    for start in itertools.product(range(cells_n), repeat=m):
        cost0 = _state_cost(lat, 0, start, 0)
        if cost0 is not None:
            extend(1, np.array(start), 0, cost0)
    return best[0]


@pytest.mark.parametrize("seed, m, cells, layers, p_max, breakaway", [
    (0, 2, 4, 7, 1, False), (1, 2, 4, 7, 1, True), (2, 2, 3, 8, 1, False),
    (3, 3, 3, 5, 2, False), (4, 3, 3, 5, 2, True), (5, 3, 3, 5, 1, True), (6, 3, 3, 6, 2, True),
])
def test_program_finds_the_brute_force_optimum(seed, m, cells, layers, p_max, breakaway):
    rng = np.random.default_rng(seed)
    for _ in range(30):  # a lattice with a path through it
        lat = _random_lattice(rng, m, cells, layers, p_max, breakaway)
        expected = _brute_force(lat)
        if np.isfinite(expected):
            break
    else:
        pytest.skip("no random lattice with a path")
    result = run(lat)
    assert result.last_layer == layers - 1
    value, mu, p = result.best()
    assert value == pytest.approx(expected, rel=1e-6)  # (float32 values)
    # the back-tracked path is admissible and costs what the program says
    cells_path, moves = path(lat, result, layers - 1, mu, p)
    cost = _state_cost(lat, 0, cells_path[0], 0)
    index = {tuple(r): j for j, r in enumerate(lat.combos.tolist())}
    for k in range(1, layers):
        mu_k, mu_prev = index[tuple(moves[k])], index[tuple(moves[k - 1])]
        np.testing.assert_array_equal(cells_path[k], cells_path[k - 1] + moves[k])
        assert _transition_ok(lat, k, cells_path[k - 1], mu_prev, cells_path[k], mu_k)
        starts = sum(1 for di, ei in zip(moves[k], moves[k - 1]) if di != 0 and ei == 0)
        cost += _state_cost(lat, k, cells_path[k], mu_k) + lat.slide_cost * starts
    assert cost == pytest.approx(value, rel=1e-6)


def _open_lattice(seed: int, layers: int):
    """A two-contact lattice where every cell is admissible and every force system exists."""
    lat = _random_lattice(np.random.default_rng(seed), 2, 4, layers, 1, False)
    lat.env_ok[:] = True
    lat.lo[:] = -1.0
    lat.hi[:] = 1.0
    return lat


def test_a_fixed_start_and_end_are_kept():
    lat = _open_lattice(9, 8)
    start = np.array([1, 2])
    result = run(lat, start=start, end=start)
    # the end constraint pruned every state that could not return to the start
    lo, n = result.boxes[-1]
    np.testing.assert_array_equal(lo, start)
    np.testing.assert_array_equal(n, [1, 1])
    assert np.isfinite(result.value(start))
    cells, _ = path(lat, result, lat.layers - 1, 0, 0)
    np.testing.assert_array_equal(cells[0], start)
    np.testing.assert_array_equal(cells[-1], start)


def test_bans_exclude_states():
    lat = _open_lattice(10, 6)
    free = run(lat)
    value, mu, p = free.best()
    cells, moves = path(lat, free, lat.layers - 1, mu, p)
    index = {tuple(r): j for j, r in enumerate(lat.combos.tolist())}
    bans = {k: [(index[tuple(moves[k])], cells[k])] for k in range(lat.layers)}
    other = run(lat, bans=bans)
    v2, mu2, p2 = other.best()
    cells2, _ = path(lat, other, lat.layers - 1, mu2, p2)
    assert v2 >= value and not np.array_equal(cells2, cells)

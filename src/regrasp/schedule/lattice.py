r"""The regrasp planner's lattice and its dynamic program (compiled with numba).

**Lattice.** Time layers :math:`t_k = t_0 + k\,\Delta t`, k = 0..N, and per contact a grid of
positions :math:`\xi = c\,h` on its edge. A state at layer k is every contact's cell and the move
each made over the interval :math:`[t_{k-1}, t_k]` (:math:`d_i \in \{-1, 0, +1\}` cells, at most
``p_max`` nonzero: those contacts slide). A contact moves one cell per interval, so the lattice
speed is :math:`h/\Delta t`. A state is admissible when

* every contact's cell keeps the envelope margin over the window :math:`[t_{k-1}, t_{k+1}]`
  (its own and the neighbouring intervals, on a finer grid of sub-samples), and
* a force system exists (:mod:`regrasp.schedule.force_polytope`) in the interval's mode (the moving contacts
  on their kinetic cone edges in their directions, the others fixed with the cone margin) both at
  :math:`t_k` with these positions and at :math:`t_{k-1}` with the previous ones.

Where one contact stops and another starts at the same layer, their slides' ramps overlap there,
so the force system must also exist at :math:`t_{k-1}` with both sliding (the *union* move). A
contact that starts a slide must also break away: a force system with it on its static cone edge
at :math:`t_{k-1}`, the others in the union move (checked when μ_s + the priming overshoot > μ_k); contacts that
start together break away together (the executor primes them at once). With two or more sliders the
feasible positions need not be convex (the plane less two convex sets), so the middle of their
move is checked too; on a curve the middle of every move (one slider's feasible positions on an arc
need not be an interval: its normal turns between the cells).

**Cost.** A transition costs ``K`` per slide it starts (a contact moving after resting), plus the
new state's secondary cost: per contact its envelope proximity (0 with at least the comfortable
margin, 1 at the required one) and ``move_cost`` per moving contact. ``K`` exceeds any sum of
secondary costs, so the program minimises the number of slides first. Slides cannot reverse
without a rest: a move of +1 follows a move of +1 or 0.

:func:`run` sweeps the layers forward with :func:`_layer` (compiled; one pass over the new layer's
states and their compatible predecessors) and keeps one back pointer per state.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numba
import numpy as np

__all__ = ["Lattice", "LatticeRun", "cells_of", "flat_index", "motion_combos", "move_runs", "path", "run"]

#: Slack [m] of the interval tests: the tables are float32 (ξ to ~1e-9 m)
_TOL = 1e-8


def motion_combos(m: int, p_max: int) -> np.ndarray:
    """Every move vector d in {-1, 0, 1}^m with at most ``p_max`` nonzero entries, (M, m) int64; row 0
    is all zero."""
    rows = [d for d in itertools.product((0, 1, -1), repeat=m) if sum(1 for x in d if x) <= p_max]
    return np.array(rows, dtype=np.int64).reshape(-1, m)


def _pairs(combos: np.ndarray):
    """For each new move μ its compatible previous moves μ' (CSR), the slides started, which contacts
    start (bit mask) and the union move (the contacts sliding at the layer between the two intervals,
    as the slides' ramps overlap there): contact i may keep its move d_i, start it from rest, or stop
    (d_i = 0 after anything); a move never follows the opposite one, and the union has at most as
    many sliders as a move vector may."""
    index = {tuple(d): j for j, d in enumerate(combos.tolist())}
    ptr, old, starts, bits, union = [0], [], [], [], []
    for d in combos.tolist():
        for j, e in enumerate(combos.tolist()):
            if not all(di == 0 or ei in (0, di) for di, ei in zip(d, e)):
                continue
            both = tuple(di if di else ei for di, ei in zip(d, e))
            if both not in index:
                continue
            started = [i for i, (di, ei) in enumerate(zip(d, e)) if di != 0 and ei == 0]
            old.append(j)
            starts.append(len(started))
            bits.append(sum(1 << i for i in started))
            union.append(index[both])
        ptr.append(len(old))
    return tuple(np.array(a, dtype=np.int64) for a in (ptr, old, starts, bits, union))


@dataclass(eq=False)
class Lattice:
    """Everything the dynamic program reads (see the module docstring).

    Attributes:
        times: Layer times t_k [s], (N + 1,).
        grids: Per contact its cells' ξ [m] (full edge), each (n_i,).
        combos: Move vectors, (M, m).
        env_ok: Envelope admissibility per layer, contact and cell, (N + 1, m, n_max) bool.
        proximity: Envelope proximity cost per layer, contact and cell, (N + 1, m, n_max).
        axis: The contact whose feasible positions the force tables give as intervals.
        lo, hi: Feasible ξ_axis interval per layer, cell of the other contacts and move vector,
            (N + 1, n_others, M) [m] (the moving contacts on their kinetic edges).
        mid_lo, mid_hi: The same at the middle of the interval ending at each layer, with the
            sliders half a cell back, for move vectors of two or more sliders (±inf for the others):
            indexed by the layer's own cells (others and axis), the bounds shifted accordingly.
        break_lo, break_hi: The same with the starting contacts on their static edges (primed), (N + 1, n_others,
            slots), or None when no contact's μ_s (+ the priming overshoot) exceeds its μ_k: the intersection of the
            intervals at the layer and at the real start, half a ramp earlier, with the other sliders that far back.
        breakaway_slot: Per move vector (the union move) and starter mask (bit i: contact i starts), the slot of
            that check, or -1 (none needed), (M, 2^m).
        rest_only: Layers whose states must not move (the first and last intervals), (N + 1,) bool.
        slide_cost: K, the cost of one slide.
        move_cost: Secondary cost per moving contact and interval.
    """

    times: np.ndarray
    grids: list
    combos: np.ndarray
    env_ok: np.ndarray
    proximity: np.ndarray
    axis: int
    lo: np.ndarray
    hi: np.ndarray
    mid_lo: np.ndarray
    mid_hi: np.ndarray
    break_lo: np.ndarray | None
    break_hi: np.ndarray | None
    breakaway_slot: np.ndarray
    rest_only: np.ndarray
    slide_cost: float
    move_cost: float

    def __post_init__(self):
        self.pair_ptr, self.pair_old, self.pair_starts, self.pair_bits, self.pair_union = _pairs(self.combos)
        self.sizes = np.array([len(g) for g in self.grids], dtype=np.int64)
        m = len(self.grids)
        # strides of the other contacts in the force tables' flat index (C order, the axis left out)
        strides, acc = np.zeros(m, dtype=np.int64), 1
        for i in reversed(range(m)):
            if i != self.axis:
                strides[i], acc = acc, acc * self.sizes[i]
        self.other_strides = strides
        self.axis_grid = np.asarray(self.grids[self.axis], dtype=float)
        self.moving = np.count_nonzero(self.combos, axis=1).astype(float)

    @property
    def layers(self) -> int:
        return len(self.times)

    def box(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """(first cell, count) per contact of the cells admissible at layer k (count 0: none)."""
        lo, n = np.zeros(len(self.grids), dtype=np.int64), np.zeros(len(self.grids), dtype=np.int64)
        for i, size in enumerate(self.sizes):
            ok = np.flatnonzero(self.env_ok[k, i, :size])
            if ok.size:
                lo[i], n[i] = ok[0], ok[-1] - ok[0] + 1
        return lo, n


@numba.njit(cache=True, parallel=True)
def _layer(V_old, alive_old, lo_old, n_old, lo_new, n_new, env_new, prox_new, tlo_new, thi_new, tlo_old, thi_old,
           mlo_new, mhi_new, blo_old, bhi_old, use_break, break_slot, combos, pair_ptr, pair_old, pair_starts,
           pair_bits, pair_union, K, move_cost, moving, axis, axis_grid, other_strides, rest_only):
    """One layer of the dynamic program: the new layer's values and back pointers (module docstring).
    Arrays are position-major: values (P, M), force tables (n_others, M), break-away (n_others, slots); ``alive_old``
    (P_old,): whether an old position has a finite value in some move vector (the others are passed over)."""
    M, m = combos.shape
    P = 1
    for i in range(m):
        P *= n_new[i]
    V = np.full((P, M), np.inf, dtype=np.float32)
    back = np.full((P, M), -1, dtype=np.int8)
    M_used = 1 if rest_only else M
    cells = np.empty((P, m), dtype=np.int64)
    for p in range(P):
        rem = p
        for i in range(m - 1, -1, -1):
            cells[p, i] = lo_new[i] + rem % n_new[i]
            rem //= n_new[i]
    for p in numba.prange(P):
        base = 0.0
        ok = True
        for i in range(m):
            if not env_new[i, cells[p, i]]:
                ok = False
                break
            base += prox_new[i, cells[p, i]]
        if not ok:
            continue
        other = 0
        for i in range(m):
            other += cells[p, i] * other_strides[i]
        x_new = axis_grid[cells[p, axis]]
        for mu in range(M_used):
            if not (tlo_new[other, mu] - _TOL <= x_new <= thi_new[other, mu] + _TOL):
                continue
            q_old, stride, inside, other_old = 0, 1, True, 0
            for i in range(m - 1, -1, -1):
                c = cells[p, i] - combos[mu, i]
                idx = c - lo_old[i]
                if idx < 0 or idx >= n_old[i]:
                    inside = False
                    break
                q_old += idx * stride
                stride *= n_old[i]
                other_old += c * other_strides[i]
            if not inside or not alive_old[q_old]:
                continue
            x_old = axis_grid[cells[p, axis] - combos[mu, axis]]
            if not (tlo_old[other_old, mu] - _TOL <= x_old <= thi_old[other_old, mu] + _TOL):
                continue
            # the middle of the move (the tables: the middle's positions under the new layer's cells; +-inf where
            # the ends suffice: on edges with fewer than two sliders)
            if not (mlo_new[other, mu] - _TOL <= x_new <= mhi_new[other, mu] + _TOL):
                continue
            best, arg = np.inf, -1
            for r in range(pair_ptr[mu], pair_ptr[mu + 1]):
                value = V_old[q_old, pair_old[r]] + K * pair_starts[r]
                if value >= best:
                    continue
                u = pair_union[r]
                if u != mu and u != pair_old[r] and not (
                        tlo_old[other_old, u] - _TOL <= x_old <= thi_old[other_old, u] + _TOL):
                    continue
                if use_break and pair_bits[r]:
                    slot = break_slot[u, pair_bits[r]]  # (the starters primed together)
                    if slot >= 0 and not (blo_old[other_old, slot] - _TOL <= x_old <= bhi_old[other_old, slot] + _TOL):
                        continue
                best, arg = value, pair_old[r]
            if arg >= 0:
                V[p, mu] = best + base + move_cost * moving[mu]
                back[p, mu] = arg
    return V, back


@dataclass(eq=False)
class LatticeRun:
    """The dynamic program's result.

    Attributes:
        values: The values (P, M) of the states of layer ``last_layer`` (position-major, float32).
        backs: Per layer the back pointers (P_k, M) int8 (the previous move vector).
        boxes: Per layer (first cell, count) per contact.
        last_layer: The last layer with a finite value (N when the program reached the end; -1: none).
    """

    values: np.ndarray | None
    backs: list
    boxes: list
    last_layer: int

    def best(self) -> tuple[float, int, int]:
        """(value, move vector, flat index) of the best state of the last layer."""
        V = self.values
        p, mu = divmod(int(np.argmin(V)), V.shape[1])
        return float(V[p, mu]), mu, p

    def value(self, cells: Iterable[int], mu: int = 0) -> float:
        """The value of the state (``cells``, move vector ``mu``) of the last layer (inf if none)."""
        p = flat_index(cells, self.boxes[self.last_layer])
        return math.inf if p < 0 else float(self.values[p, mu])


def flat_index(cells: Iterable[int], box: tuple[np.ndarray, np.ndarray]) -> int:
    """The flat index of global ``cells`` in a layer's ``box`` (-1 outside)."""
    lo, n = box
    p = 0
    for c, l0, size in zip(cells, lo, n):
        idx = int(c) - int(l0)
        if idx < 0 or idx >= size:
            return -1
        p = p * int(size) + idx
    return p


def cells_of(p: int, box: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """Global cells of flat index ``p`` in ``box``."""
    lo, n = box
    out = np.zeros(len(n), dtype=np.int64)
    for i in range(len(n) - 1, -1, -1):
        out[i] = lo[i] + p % n[i]
        p //= n[i]
    return out


@numba.njit(cache=True)
def _finite_range(V, lo, n):
    """Per contact the first and last cell of ``box`` (lo, n) holding a finite value of V (P, M)."""
    m = len(n)
    first = np.full(m, np.iinfo(np.int64).max)
    last = np.full(m, np.iinfo(np.int64).min)
    P, M = V.shape
    for p in range(P):
        finite = False
        for mu in range(M):
            if V[p, mu] < np.inf:
                finite = True
                break
        if finite:
            rem = p
            for i in range(m - 1, -1, -1):
                c = lo[i] + rem % n[i]
                rem //= n[i]
                first[i] = min(first[i], c)
                last[i] = max(last[i], c)
    return first, last


def _finite_box(V: np.ndarray, box) -> tuple[np.ndarray, np.ndarray]:
    """The per-contact range of cells of ``box`` holding a finite value."""
    first, last = _finite_range(V, box[0], box[1])
    if first[0] > last[0]:
        return box[0], np.zeros_like(box[1])
    return first, last - first + 1


def _intersect(a, b) -> tuple[np.ndarray, np.ndarray]:
    lo = np.maximum(a[0], b[0])
    hi = np.minimum(a[0] + a[1], b[0] + b[1])
    return lo, np.maximum(hi - lo, 0)


def run(lat: Lattice, start: Sequence[int] | np.ndarray | None = None,
        bans: Mapping[int, Iterable[tuple[int, Iterable[int] | None]]] | None = None,
        end: Sequence[int] | np.ndarray | None = None, init: LatticeRun | None = None, *,
        keep_backs: bool = True) -> LatticeRun:
    """Sweep the layers. ``start``: global cells of the contacts at layer 0 (at rest), or None for
    every admissible rest state; ``bans``: {layer: [(move vector, global cells or None: every position), ...]}
    states to exclude; ``end``: global cells the path must reach at the last layer (states that cannot are
    pruned), or None; ``init``: a finished run of a periodic lattice whose final values (at rest)
    start this one (a second period), or None; ``keep_backs``: False when no path will be traced
    back (a run's back pointers take about 100 MB for three fingers)."""
    N = lat.layers - 1
    M = len(lat.combos)
    use_break = lat.break_lo is not None
    dummy = np.zeros((1, 1), dtype=np.float32)
    box = lat.box(0)
    if start is not None:
        box = _intersect(box, (np.asarray(start, dtype=np.int64), np.ones(len(start), dtype=np.int64)))
    P = int(np.prod(box[1]))
    V = np.full((max(P, 1), M), np.inf, dtype=np.float32)
    if P:
        cells = (np.indices(tuple(box[1])).reshape(len(box[1]), -1).T + box[0])  # (P, m), C order
        m = cells.shape[1]
        ok = np.all([lat.env_ok[0, i, cells[:, i]] for i in range(m)], axis=0)
        other = cells @ lat.other_strides
        x = lat.axis_grid[cells[:, lat.axis]]
        ok &= (lat.lo[0, other, 0] - _TOL <= x) & (x <= lat.hi[0, other, 0] + _TOL)
        if init is None:
            cost = np.sum([lat.proximity[0, i, cells[:, i]] for i in range(m)], axis=0)
        else:
            cost = np.array([init.value(c) for c in cells], dtype=np.float32)
        V[ok, 0] = cost[ok]
    _apply_bans(V, box, (bans or {}).get(0, ()))
    backs, boxes = [np.full(V.shape, -1, dtype=np.int8)], [box]
    last, final = (0, V) if np.isfinite(V).any() else (-1, None)
    for k in range(1, N + 1):
        if last < k - 1:
            break
        reach = _finite_box(V, boxes[-1])
        new_box = _intersect(lat.box(k), (reach[0] - 1, reach[1] + 2))
        if end is not None:
            slack = N - k
            new_box = _intersect(new_box, (np.asarray(end) - slack, np.full(len(end), 2 * slack + 1)))
        if not new_box[1].all():
            break
        args = (lat.break_lo[k - 1], lat.break_hi[k - 1]) if use_break else (dummy, dummy)
        alive = np.isfinite(V).any(axis=1)
        V, back = _layer(V, alive, boxes[-1][0], boxes[-1][1], new_box[0], new_box[1], lat.env_ok[k],
                         lat.proximity[k], lat.lo[k], lat.hi[k], lat.lo[k - 1], lat.hi[k - 1], lat.mid_lo[k],
                         lat.mid_hi[k], args[0], args[1],
                         use_break, lat.breakaway_slot, lat.combos, lat.pair_ptr, lat.pair_old, lat.pair_starts,
                         lat.pair_bits, lat.pair_union, np.float32(lat.slide_cost), np.float32(lat.move_cost),
                         lat.moving, lat.axis, lat.axis_grid, lat.other_strides, bool(lat.rest_only[k]))
        _apply_bans(V, new_box, (bans or {}).get(k, ()))
        backs.append(back if keep_backs else None)
        boxes.append(new_box)
        if np.isfinite(V).any():
            last, final = k, V
    return LatticeRun(final, backs, boxes, last)


def _apply_bans(V, box, banned) -> None:
    for mu, cells in banned:
        if cells is None:  # the move vector at every position
            V[:, mu] = np.inf
            continue
        p = flat_index(cells, box)
        if p >= 0:
            V[p, mu] = np.inf


def move_runs(moves: np.ndarray, first: int = 1) -> list[tuple[int, int, int, int]]:
    """The runs of equal nonzero moves of each contact in a path's moves (k, m), from layer ``first``:
    (first layer, contact, move, last layer) each, in contact then time order. A run is one slide:
    the contact moves over the intervals ending at those layers."""
    out = []
    for i in range(moves.shape[1]):
        k = first
        while k < len(moves):
            d = int(moves[k, i])
            if d == 0:
                k += 1
                continue
            start = k
            while k + 1 < len(moves) and moves[k + 1, i] == d:
                k += 1
            out.append((start, i, d, k))
            k += 1
    return out


def path(lat: Lattice, result: LatticeRun, k: int, mu: int, p: int) -> tuple[np.ndarray, np.ndarray]:
    """Back-track from state (μ, p) of layer k: (cells (k + 1, m), moves (k + 1, m)) from layer 0."""
    m = len(lat.grids)
    cells = np.zeros((k + 1, m), dtype=np.int64)
    moves = np.zeros((k + 1, m), dtype=np.int64)
    for j in range(k, -1, -1):
        c = cells_of(p, result.boxes[j])
        cells[j], moves[j] = c, lat.combos[mu]
        if j == 0:
            break
        prev_mu = int(result.backs[j][p, mu])
        p = flat_index(c - lat.combos[mu], result.boxes[j - 1])
        mu = prev_mu
    return cells, moves

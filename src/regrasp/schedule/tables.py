"""Operations on the lattice's interval tables (:class:`~regrasp.schedule.lattice.Lattice`: per layer, state of the
contacts other than the axis one and move vector, the axis contact's positions [lo, hi] with a force system): cutting
them to per-cell conditions (the joint torque limits, the slides' well-posedness) and eroding them by a position
margin."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.ndimage import maximum_filter, minimum_filter

__all__ = ["cut_tables", "erode_tables"]


def cut_tables(allowed: np.ndarray, grids: Sequence[np.ndarray], axis: int, lo: np.ndarray, hi: np.ndarray,
               pairs: dict | None = None) -> tuple | None:
    """Cut the force tables ``lo``, ``hi`` in place to a per-cell condition ``allowed`` (N + 1, M, m, n_max): per
    layer and move vector, a state whose other contacts sit on a cell it excludes is dropped (its interval emptied),
    and the axis's interval is cut to the span of its allowed cells (a superset: the verification checks exactly);
    and to per-pair conditions ``pairs``, ``{mu: (a, b, (N + 1, n_a, n_b) bool)}`` (a < b: the cells of contacts a
    and b allowed together in move vector mu), the same way. Returns the tables as they were (None: the conditions
    excluded no cell)."""
    pairs = {mu: p for mu, p in (pairs or {}).items() if not p[2].all()}
    if allowed.all() and not pairs:
        return None
    free = (lo.copy(), hi.copy())
    m = len(grids)
    columns = [i for i in range(m) if i != axis]
    axis_grid = np.asarray(grids[axis])
    for k, mu in zip(*np.nonzero(~allowed.all(axis=(2, 3)))):
        ok_others = np.ones(1, dtype=bool)
        for i in columns:
            ok_others = np.outer(ok_others, allowed[k, mu, i, :len(grids[i])]).reshape(-1)
        cells = np.flatnonzero(allowed[k, mu, axis, :len(axis_grid)])
        lo[k, ~ok_others, mu], hi[k, ~ok_others, mu] = np.inf, -np.inf
        _cut_axis(lo, hi, k, mu, axis_grid, cells[0] if cells.size else None, cells[-1] if cells.size else None)
    sizes = [len(grids[i]) for i in columns]
    index = np.indices(sizes).reshape(len(columns), -1) if columns else np.zeros((0, 1), dtype=int)
    for mu, (a, b, ok) in pairs.items():
        for k in np.flatnonzero(~ok.all(axis=(1, 2))):
            if axis not in (a, b):  # both among the others: drop their states the pair's condition excludes
                lo[k, ~ok[k][index[columns.index(a)], index[columns.index(b)]], mu] = np.inf
                hi[k, ~ok[k][index[columns.index(a)], index[columns.index(b)]], mu] = -np.inf
                continue
            other, along = (a, ok[k]) if b == axis else (b, ok[k].T)  # along: (other's cell, axis cell)
            any_ok = along.any(axis=1)
            first = np.where(any_ok, along.argmax(axis=1), 0)
            last = np.where(any_ok, along.shape[1] - 1 - along[:, ::-1].argmax(axis=1), -1)
            c = index[columns.index(other)]  # per state, the other slider's cell
            lo[k, :, mu] = np.where(any_ok[c], np.maximum(lo[k, :, mu], axis_grid[first[c]] - 1e-6), np.inf)
            hi[k, :, mu] = np.where(any_ok[c], np.minimum(hi[k, :, mu], axis_grid[last[c]] + 1e-6), -np.inf)
    return free


def _cut_axis(lo, hi, k: int, mu: int, axis_grid: np.ndarray, first: int | None, last: int | None) -> None:
    """Cut layer k's intervals of move vector mu to the axis cells [first, last] (None: empty them)."""
    if first is None:
        lo[k, :, mu], hi[k, :, mu] = np.inf, -np.inf
    else:
        lo[k, :, mu] = np.maximum(lo[k, :, mu], axis_grid[first] - 1e-6)
        hi[k, :, mu] = np.minimum(hi[k, :, mu], axis_grid[last] + 1e-6)


def erode_tables(lo: np.ndarray, hi: np.ndarray, sizes: Sequence[int], h: float, moves: np.ndarray,
                 cells: int = 1) -> None:
    """Erode interval tables (N + 1, S, K) in place by ``cells`` cells of ``h`` [m] behind the contacts that move in
    each column: ``moves`` (K, m) in {-1, 0, 1}, the axis contact last (S: the flat product of the other contacts'
    ``sizes``, in their order). A state keeps the axis positions x with the segment from x - d cells h to x (d its move;
    x alone when it does not move) inside the intervals of its own state and of every state whose moving contacts are
    up to ``cells`` cells behind their own, against their moves (a slide that lags its plan); a state off the grid
    allows nothing."""
    shape = (lo.shape[0], *sizes)
    for k, move in enumerate(np.asarray(moves, dtype=int)):
        if not move.any():
            continue
        footprint = np.zeros((1,) + tuple(2 * cells + 1 for _ in sizes), dtype=bool)
        index = [0]
        for d in move[:-1]:  # (offset -d .. -d cells: behind; 0 when held)
            index.append(slice(cells, cells + 1) if d == 0 else slice(0, cells + 1) if d > 0 else
                         slice(cells, 2 * cells + 1))
        footprint[tuple(index)] = True
        column_lo, column_hi = lo[:, :, k].reshape(shape), hi[:, :, k].reshape(shape)
        lo[:, :, k] = maximum_filter(column_lo, footprint=footprint, mode="constant", cval=np.inf).reshape(lo.shape[:2])
        hi[:, :, k] = minimum_filter(column_hi, footprint=footprint, mode="constant", cval=-np.inf).reshape(
            hi.shape[:2])
        if move[-1] > 0:
            lo[:, :, k] += cells * h
        elif move[-1] < 0:
            hi[:, :, k] -= cells * h

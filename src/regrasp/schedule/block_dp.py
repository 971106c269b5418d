r"""The decomposition planner's block program: the exact dynamic program of one or two contacts, the others frozen.

:mod:`regrasp.schedule.decomposition` plans m contacts by block-coordinate descent: it freezes all contacts but a block
of two (or one) along their current paths and solves the block's program exactly. A block state at layer k is the
block's cells (c_i, c_j) and its move vector b over the interval [t_{k-1}, t_k] (nine for a pair, three for a single
contact, whose second contact is a dummy with one cell that never moves). The transition rules are the exact lattice's
(:mod:`regrasp.schedule.lattice`): a contact moves one cell per interval, a move ±1 follows a move ±1 of the same sign
or a rest (slides do not reverse without a rest), the layers of ``adm`` False are closed to a move vector (the
first and last intervals at rest, and modes with more sliders than allowed once the frozen contacts' moves are
added), a start costs ``K`` (one slide), and a state costs its envelope proximity and ``move_cost`` per moving block
contact.

The force constraints, with the frozen contacts substituted, arrive as boolean tables over the block's cells (built by
:mod:`regrasp.schedule.decomposition`): ``new_ok[k, b]`` over the new cells (the mode at t_k and, with two sliders, at
the interval's middle), ``old_ok[k, b]`` over the previous cells (the mode at t_{k-1}), ``trans_tab[trans_idx[k, b',
b]]`` over the previous cells (the union move and the break-aways of the slides starting at t_{k-1}; index -1: no
check, -2: the transition is not allowed), and ``init_ok`` at layer 0 (all at rest). A failed check does not close a
state: it costs ``big`` (more than any number of slides), so that a path with force failures can still be improved;
a path without failures costs exactly the lattice's objective (slides, then proximity and moves).

:func:`block_dp` is the compiled program; :func:`block_dp_reference` the same in plain Python (the tests compare them).
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["PAIR_MOVES", "SINGLE_MOVES", "block_dp", "block_dp_reference", "block_path"]

#: The block move vectors of a pair and of a single contact (its second entry the dummy's, always 0); row 0 at rest.
PAIR_MOVES = np.array([(0, 0), (1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (1, -1), (-1, 1), (-1, -1)], dtype=np.int64)
SINGLE_MOVES = PAIR_MOVES[:3].copy()


@numba.njit(cache=True)
def _compatible(d_new: int, d_old: int) -> bool:
    return d_new == 0 or d_old == 0 or d_old == d_new


@numba.njit(cache=True)
def block_dp(env_ok: np.ndarray, prox: np.ndarray, moves: np.ndarray, adm: np.ndarray, new_ok: np.ndarray,
             old_ok: np.ndarray, trans_idx: np.ndarray, trans_tab: np.ndarray, init_ok: np.ndarray, start: np.ndarray,
             end: np.ndarray, K: float, move_cost: float, big: float) -> tuple:
    """The block program (module docstring). ``env_ok``/``prox``: (N + 1, 2, n_max) per layer, block contact and
    cell; ``start``/``end`` (2,) cells, -1 free. Returns (values of the last layer (n_i, n_j,
    nb), back pointers (N + 1, n_i, n_j, nb) int8: the previous move, the last layer with a finite value)."""
    L = env_ok.shape[0]
    nb = moves.shape[0]
    ni, nj = new_ok.shape[2], new_ok.shape[3]
    inf = np.inf
    V = np.full((ni, nj, nb), inf)
    back = np.full((L, ni, nj, nb), -1, dtype=np.int8)
    for ci in range(ni):
        if not env_ok[0, 0, ci] or (start[0] >= 0 and ci != start[0]):
            continue
        for cj in range(nj):
            if not env_ok[0, 1, cj] or (start[1] >= 0 and cj != start[1]):
                continue
            V[ci, cj, 0] = prox[0, 0, ci] + prox[0, 1, cj] + (0.0 if init_ok[ci, cj] else big)
    last = 0
    for k in range(1, L):
        W = np.full((ni, nj, nb), inf)
        slack = L - 1 - k
        any_finite = False
        for ci in range(ni):
            if not env_ok[k, 0, ci] or (end[0] >= 0 and abs(ci - end[0]) > slack):
                continue
            for cj in range(nj):
                if not env_ok[k, 1, cj] or (end[1] >= 0 and abs(cj - end[1]) > slack):
                    continue
                base = prox[k, 0, ci] + prox[k, 1, cj]
                for b in range(nb):
                    if not adm[k, b]:
                        continue
                    oi, oj = ci - moves[b, 0], cj - moves[b, 1]
                    if oi < 0 or oi >= ni or oj < 0 or oj >= nj:
                        continue
                    fail_new = not (new_ok[k, b, ci, cj] and old_ok[k, b, oi, oj])
                    best, arg = inf, -1
                    for a in range(nb):
                        v = V[oi, oj, a]
                        if v == inf:
                            continue
                        if not (_compatible(moves[b, 0], moves[a, 0]) and _compatible(moves[b, 1], moves[a, 1])):
                            continue
                        t = trans_idx[k, a, b]
                        if t == -2:
                            continue
                        fail = fail_new or (t >= 0 and not trans_tab[t, oi, oj])
                        starts = 0
                        for s in range(2):
                            if moves[b, s] != 0 and moves[a, s] == 0:
                                starts += 1
                        value = v + K * starts + (big if fail else 0.0)
                        if value < best:
                            best, arg = value, a
                    if arg >= 0:
                        moving = (moves[b, 0] != 0) + (moves[b, 1] != 0)
                        W[ci, cj, b] = best + base + move_cost * moving
                        back[k, ci, cj, b] = arg
                        any_finite = True
        V = W
        if not any_finite:
            return V, back, last
        last = k
    return V, back, last


def block_dp_reference(env_ok: np.ndarray, prox: np.ndarray, moves: np.ndarray, adm: np.ndarray, new_ok: np.ndarray,
                       old_ok: np.ndarray, trans_idx: np.ndarray, trans_tab: np.ndarray, init_ok: np.ndarray,
                       start: np.ndarray, end: np.ndarray, K: float, move_cost: float, big: float) -> tuple:
    """:func:`block_dp` in plain Python: a forward relaxation over a dictionary of reached states (the values only;
    the last layer's as an (n_i, n_j, nb) array, and the last layer with a finite value)."""
    L, nb = env_ok.shape[0], len(moves)
    ni, nj = new_ok.shape[2], new_ok.shape[3]
    values = {(ci, cj, 0): float(prox[0, 0, ci] + prox[0, 1, cj] + (0.0 if init_ok[ci, cj] else big))
              for ci in range(ni) for cj in range(nj)
              if env_ok[0, 0, ci] and env_ok[0, 1, cj] and all(s < 0 or c == s for c, s in zip((ci, cj), start))}
    last = 0
    for k in range(1, L):
        new: dict = {}
        for (oi, oj, a), v in values.items():
            for b, (di, dj) in enumerate(moves.tolist()):
                ci, cj = oi + di, oj + dj
                if not (0 <= ci < ni and 0 <= cj < nj and adm[k, b] and env_ok[k, 0, ci] and env_ok[k, 1, cj]):
                    continue
                if any(e >= 0 and abs(c - e) > L - 1 - k for c, e in zip((ci, cj), end)):
                    continue
                if any(d != 0 and p != 0 and p != d for d, p in zip((di, dj), moves[a])):
                    continue
                t = int(trans_idx[k, a, b])
                if t == -2:
                    continue
                fail = not (new_ok[k, b, ci, cj] and old_ok[k, b, oi, oj]) or (t >= 0 and not trans_tab[t, oi, oj])
                starts = sum(1 for d, p in zip((di, dj), moves[a]) if d != 0 and p == 0)
                value = v + K * starts + (big if fail else 0.0)
                value = value + (prox[k, 0, ci] + prox[k, 1, cj]) + move_cost * ((di != 0) + (dj != 0))
                if value < new.get((ci, cj, b), np.inf):
                    new[(ci, cj, b)] = value
        if not new:
            break
        values, last = new, k
    out = np.full((ni, nj, nb), np.inf)
    if last == L - 1:
        for (ci, cj, b), v in values.items():
            out[ci, cj, b] = v
    return out, last


def block_path(moves: np.ndarray, back: np.ndarray, ci: int, cj: int, b: int) -> tuple[np.ndarray, np.ndarray]:
    """Back-track from the last layer's state (c_i, c_j, b): (cells (N + 1, 2), moves (N + 1, 2))."""
    L = back.shape[0]
    cells = np.zeros((L, 2), dtype=np.int64)
    out = np.zeros((L, 2), dtype=np.int64)
    for k in range(L - 1, -1, -1):
        cells[k] = ci, cj
        out[k] = moves[b]
        if k == 0:
            break
        a = int(back[k, ci, cj, b])
        ci, cj, b = ci - int(moves[b, 0]), cj - int(moves[b, 1]), a
    return cells, out

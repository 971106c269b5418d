r"""The decomposition planner: regrasp schedules for many contacts, by block-coordinate descent over pairs.

The exact planner (:mod:`regrasp.schedule.lattice`) runs one dynamic program over every contact's cell and move at
once: its states, and its force tables, grow as :math:`n^{m}` with m contacts of n cells. This planner keeps the
lattice, its transition rules and its objective, but optimises two contacts at a time:

1. **Initial path.** Each contact alone, a one-dimensional program over (layer, cell, move) under its own envelope:
   the fewest slides, then the least proximity to the envelope's bounds. When it has no path, the contact's feasible
   set empties, or moves faster than a slide can follow: a physical reason (:class:`ScheduleLimit.ENVELOPE
   <regrasp.schedule.schedule.ScheduleLimit>`, ``SPEED`` or ``PERIODIC``, with the time and the contact).
2. **Block updates.** Freeze all contacts but a pair along their current paths and solve the pair's program exactly
   (:mod:`regrasp.schedule.block_dp`) with the frozen contacts' positions and modes substituted into the force checks
   (:mod:`regrasp.schedule.block_tables`). Its objective is lexicographic: the number of intervals whose force checks
   fail (a penalty, not a prohibition, so that an infeasible start can improve), the slides, the proximity and moves.
   The program is exact given the others and the current path is among its candidates, so **the objective never
   increases**. Each step solves every pair's program and takes the best one's path (best improvement: the first
   improving pair taken at once stops at more slides); the descent stops when no pair improves the objective.
3. **Periodic trajectories.** Each pair's program ends where it starts: it is run from the pair's current start cells
   and, when a free-start program shows it could do better, from that program's start and end cells and from the
   middle of its best free path over two periods (the steady regime).
4. **Verification.** A path without failures goes through the exact planner's schedule and verification; a violation
   bans the path's states around it (counted as failures) and the descent goes on.
5. **Honest failure.** When the descent stalls with failures, the planner tries to prove at each failing time that
   no positions inside the contacts' envelope intervals admit a force system in any admissible mode (a linear
   program per mode, :mod:`regrasp.schedule.force_proof`): ``FORCES``; else it says that its search found none
   (``SEARCH``), which is not a proof that none exists.

**Cost.** A pair's program has :math:`n^2 \cdot 9` states per layer and nine predecessors each; its tables take
:math:`O(N \cdot M_{pair} \cdot V \cdot n)` (V vertices of the polytope, :math:`M_{pair}` ≤ 81 move pairs); one step
of the :math:`\binom{m}{2}` pairs costs :math:`O(m^2 N n^2)`: polynomial in m, where the exact program's
:math:`O(N n^m 3^m)` is not. The modes are capped at ``max_sliders`` (2 by default) sliders, :math:`O(m^2)` of them.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from .block_dp import PAIR_MOVES, SINGLE_MOVES, block_dp, block_path
from .block_tables import ModeVertices, block_tables
from .force_proof import positions_admit_forces
from .problem import slide_ratios
from .schedule import NoScheduleError, ScheduleLimit, verification_limit

if TYPE_CHECKING:
    from .problem import Problem

__all__ = ["DescentReport", "block_solve", "initial_path", "path_value", "plan_decomposed", "prove_no_forces"]

#: A verification callback: the violations (time [s], what, contact index or None) of a path (cells, moves)
Check = Callable[[np.ndarray, np.ndarray], list]

#: Most improvements before the descent stops anyway
MAX_IMPROVEMENTS = 100


@dataclass
class DescentReport:
    """What the decomposition planner did: block programs solved, improvements, re-plans, seconds."""

    block_solves: int = 0
    improvements: int = 0
    repairs: int = 0
    seconds: float = 0.0
    values: list = field(default_factory=list)


def _big(problem: Problem) -> float:
    """The penalty of one failing interval: more than any number of slides and secondary costs."""
    lat = problem.lattice
    return 4.0 * lat.slide_cost * lat.layers * len(problem.grids)


def _p_max(problem: Problem) -> int:
    return int(np.count_nonzero(problem.lattice.combos, axis=1).max())


def _when(problem: Problem, k: int) -> float:
    return float(problem.times[min(max(k, 0), len(problem.times) - 1)])


def initial_path(problem: Problem, i: int) -> tuple[np.ndarray, np.ndarray]:
    """Contact i's best path (cells (N + 1,), moves (N + 1,)) under its own envelope alone (module docstring, step 1),
    or raise :class:`~regrasp.schedule.schedule.NoScheduleError` with why none exists."""
    lat = problem.lattice
    L, n = lat.layers, len(problem.grids[i])
    env = np.zeros((L, 2, n), dtype=bool)
    env[:, 0], env[:, 1, 0] = lat.env_ok[:, i, :n], True
    prox = np.zeros((L, 2, n))
    prox[:, 0] = lat.proximity[:, i, :n]
    adm = np.ones((L, 3), dtype=bool)
    adm[lat.rest_only, 1:] = False
    ones = np.ones((L, 3, n, 1), dtype=bool)
    trans = np.full((L, 3, 3), -1, dtype=np.int64)
    given = -1 if problem.start_cells is None else int(problem.start_cells[i])
    name = problem.names[i]
    if given >= 0 and not lat.env_ok[0, i, given]:
        raise NoScheduleError(_when(problem, 0), ScheduleLimit.ENVELOPE, (name,),
                              f"{name}'s start position is outside its feasible set (less the margins) at t = "
                              f"{_when(problem, 0):.3f} s")

    def solve(start: int, end: int):
        return block_dp(env, prox, SINGLE_MOVES, adm, ones, ones, trans, np.ones((1, n, 1), dtype=bool),
                        np.ones((n, 1), dtype=bool), np.array([start, 0]), np.array([end, -1 if end < 0 else 0]),
                        lat.slide_cost, lat.move_cost, 0.0)

    V, back, last = solve(given, given if problem.periodic else -1)
    if last < L - 1:
        k = last + 1
        if not lat.env_ok[k, i].any():
            raise NoScheduleError(_when(problem, k), ScheduleLimit.ENVELOPE, (name,),
                                  f"{name}'s feasible set, less the margins, is empty at t = {_when(problem, k):.3f} s")
        if problem.periodic and given >= 0 and solve(given, -1)[2] == L - 1:
            raise NoScheduleError(_when(problem, L - 1), ScheduleLimit.PERIODIC, (name,),
                                  f"no path of {name} from its start position ends the period where it starts")
        raise NoScheduleError(_when(problem, k), ScheduleLimit.SPEED, (name,),
                              f"{name}'s feasible set moves faster than it can slide at t = {_when(problem, k):.3f} s")
    if problem.periodic and given < 0:  # the free program's best start and end, each held to the end
        c = int(np.argmin(V[:, 0, 0]))
        cells, _ = block_path(SINGLE_MOVES, back, c, 0, 0)
        best = None
        for start in dict.fromkeys((int(cells[0, 0]), int(cells[-1, 0]))):
            W, back_w, last_w = solve(start, start)
            if last_w == L - 1 and np.isfinite(W[start, 0, 0]) and (best is None or W[start, 0, 0] < best[0]):
                best = (W[start, 0, 0], back_w, start)
        if best is None:
            raise NoScheduleError(_when(problem, L - 1), ScheduleLimit.PERIODIC, (name,),
                                  f"no path of {name} inside its feasible set ends the period where it starts")
        _, back, c = best
    elif problem.periodic:
        c = given
    else:
        c = int(np.argmin(V[:, 0, 0]))
    cells, moves = block_path(SINGLE_MOVES, back, c, 0, 0)
    return cells[:, 0].copy(), moves[:, 0].copy()


def path_value(problem: Problem, cells: np.ndarray, moves: np.ndarray, fails: list) -> float:
    """The descent's objective of a path (cells, moves) (N + 1, m) with the failing intervals ``fails`` (module
    docstring): the penalty per failure, then ``K`` per slide, the proximity and the moves."""
    lat = problem.lattice
    L = len(cells)
    starts = np.count_nonzero((moves[1:] != 0) & (moves[:-1] == 0))
    proximity = sum(lat.proximity[np.arange(L), c, cells[:, c]].sum() for c in range(cells.shape[1]))
    return _big(problem) * len(fails) + lat.slide_cost * starts + proximity + lat.move_cost * np.count_nonzero(moves)


def path_failures(problem: Problem, verts: ModeVertices, cells: np.ndarray, moves: np.ndarray, bans: dict) -> list:
    """The layers k of a path whose checks fail (0: the start at rest; k ≥ 1: the interval ending at k)."""
    tables = block_tables(problem, verts, cells, moves, (0, 1), _p_max(problem), bans)
    index = {tuple(d): b for b, d in enumerate(PAIR_MOVES.tolist())}
    fails = [] if tables.init_ok[cells[0, 0], cells[0, 1]] else [0]
    for k in range(1, len(cells)):
        a, b = index[(moves[k - 1, 0], moves[k - 1, 1])], index[(moves[k, 0], moves[k, 1])]
        (ci, cj), (oi, oj) = cells[k, :2], cells[k - 1, :2]
        t = tables.trans_idx[k, a, b]
        ok = tables.adm[k, b] and tables.new_ok[k, b, ci, cj] and tables.old_ok[k, b, oi, oj] and t != -2 and (
            t < 0 or tables.trans_tab[t, oi, oj])
        if not ok:
            fails.append(k)
    return fails


def block_solve(problem: Problem, verts: ModeVertices, cells: np.ndarray, moves: np.ndarray, block: tuple[int, int],
                bans: dict) -> tuple[float, np.ndarray, np.ndarray]:
    """The best path of the pair ``block`` with the other contacts frozen on (``cells``, ``moves``): (its objective,
    the whole path's cells and moves). The current path is a candidate: the objective never exceeds its own."""
    lat = problem.lattice
    tables = block_tables(problem, verts, cells, moves, block, _p_max(problem), bans)
    big = _big(problem)
    L = len(cells)

    def solve(start, end):
        return block_dp(tables.env_ok, tables.prox, PAIR_MOVES, tables.adm, tables.new_ok, tables.old_ok,
                        tables.trans_idx, tables.trans_tab, tables.init_ok, np.asarray(start, dtype=np.int64),
                        np.asarray(end, dtype=np.int64), lat.slide_cost, lat.move_cost, big)

    given = None if problem.start_cells is None else problem.start_cells[list(block)]
    best = None
    if problem.periodic:
        candidates = [cells[0, list(block)]] if given is None else [given]
        tried = set()
        while candidates:
            start = tuple(int(c) for c in candidates.pop(0))
            if start in tried or min(start) < 0:
                continue
            tried.add(start)
            V, back, last = solve(start, start)
            if last == L - 1 and np.isfinite(V[start + (0,)]) and (best is None or V[start + (0,)] < best[0]):
                best = (float(V[start + (0,)]), back, start)
            if given is None and len(tried) == 1:  # a free start's program: a bound, and its ends as candidates
                W, back_w, last_w = solve((-1, -1), (-1, -1))
                if last_w == L - 1 and (best is None or W[:, :, 0].min() < best[0] - 1e-6):
                    p = np.unravel_index(int(np.argmin(W[:, :, 0])), W.shape[:2])
                    free, _ = block_path(PAIR_MOVES, back_w, int(p[0]), int(p[1]), 0)
                    candidates += [_steady_start(tables, lat, big), free[0], free[-1]]
    else:
        V, back, last = solve((-1, -1) if given is None else given, (-1, -1))
        if last == L - 1:
            p = np.unravel_index(int(np.argmin(V[:, :, 0])), V.shape[:2])
            best = (float(V[p + (0,)]), back, tuple(int(c) for c in p))
    new_cells, new_moves = cells.copy(), moves.copy()
    if best is None:  # (the current path is always a candidate: only an inadmissible current path gets here)
        return np.inf, new_cells, new_moves
    value, back, end = best
    pc, pm = block_path(PAIR_MOVES, back, end[0], end[1], 0)
    new_cells[:, list(block)], new_moves[:, list(block)] = pc, pm
    return value + tables.frozen_cost, new_cells, new_moves


def _steady_start(tables, lat, big: float) -> np.ndarray:
    """The pair's cells in the middle of its best free path over two periods (the frozen paths and the trajectory
    repeat): a start in the steady regime, as the exact planner's second period finds one."""
    L = len(tables.adm)

    def twice(a: np.ndarray) -> np.ndarray:
        return np.concatenate([a, a[1:]])

    V, back, last = block_dp(twice(tables.env_ok), twice(tables.prox), PAIR_MOVES, twice(tables.adm),
                             twice(tables.new_ok), twice(tables.old_ok), twice(tables.trans_idx), tables.trans_tab,
                             tables.init_ok, np.array([-1, -1]), np.array([-1, -1]), lat.slide_cost, lat.move_cost,
                             big)
    if last < 2 * (L - 1):
        return np.array([-1, -1])
    p = np.unravel_index(int(np.argmin(V[:, :, 0])), V.shape[:2])
    cells, _ = block_path(PAIR_MOVES, back, int(p[0]), int(p[1]), 0)
    return cells[L - 1]


def _descend(problem: Problem, verts: ModeVertices, cells: np.ndarray, moves: np.ndarray, bans: dict,
             report: DescentReport) -> tuple[np.ndarray, np.ndarray, float]:
    """Pair updates, the best of all pairs each time, until none improves the objective (module docstring, step 2)."""
    m = cells.shape[1]
    pairs = list(itertools.combinations(range(m), 2))
    value = path_value(problem, cells, moves, path_failures(problem, verts, cells, moves, bans))
    report.values.append(value)
    for _ in range(MAX_IMPROVEMENTS):
        # every pair's program on the current path; the best one's path is taken (best improvement: the first
        # improving pair taken at once gets stuck in more slides, measured in docs/derivations.md)
        found = [block_solve(problem, verts, cells, moves, block, bans) for block in pairs]
        report.block_solves += len(pairs)
        best, new_cells, new_moves = min(found, key=lambda f: f[0])
        if not best < value - 1e-6:
            break
        cells, moves, value = new_cells, new_moves, best
        report.improvements += 1
        report.values.append(value)
    return cells, moves, value


def _intervals(problem: Problem, k: int) -> list:
    """Per contact the hull [m] of its feasible set less the envelope margin at layer k (None: empty)."""
    q, margin = problem.settings.envelope_substeps, problem.settings.envelope_margin
    out = []
    for i in range(len(problem.grids)):
        parts = [(lo + margin, hi - margin) for lo, hi in problem.sub_samples[i][k * q].feasible
                 if hi - lo >= 2 * margin]
        out.append((min(p[0] for p in parts), max(p[1] for p in parts)) if parts else None)
    return out


def prove_no_forces(problem: Problem, k: int) -> bool:
    """Whether no positions inside the contacts' envelope intervals (less the margin) at layer k admit a force system
    in any admissible mode, with the required margins (:mod:`regrasp.schedule.force_proof`)."""
    intervals = _intervals(problem, k)
    if any(iv is None for iv in intervals):
        return True
    traj = problem.scenario.trajectory
    smp = traj.sample(np.clip(problem.times[k:k + 1], traj.t_start, traj.t_end))
    mu_s = [f.static for f in problem.friction]
    limits = problem.settings.force_limits()
    for d in problem.lattice.combos.tolist():
        if positions_admit_forces(problem.geometry, float(smp.pose[0, 2]), smp.acceleration[0], intervals,
                                  slide_ratios(d, problem.friction), mu_s, limits) is not None:
            return False
    return True


def _failure(problem: Problem, fails: list, report: DescentReport) -> NoScheduleError:
    """Why the descent found no schedule: a proof where one applies (module docstring, step 5)."""
    for k in fails[:12]:
        for layer in dict.fromkeys((k, max(k - 1, 0))):
            intervals = _intervals(problem, layer)
            empty = [problem.names[i] for i, iv in enumerate(intervals) if iv is None]
            t = _when(problem, layer)
            if empty:
                return NoScheduleError(t, ScheduleLimit.ENVELOPE, tuple(empty),
                                       f"at t = {t:.3f} s the feasible set of {', '.join(empty)}, less the envelope "
                                       "margin, is empty")
            if prove_no_forces(problem, layer):
                return NoScheduleError(t, ScheduleLimit.FORCES, problem.names,
                                       f"at t = {t:.3f} s no positions inside the contacts' feasible sets admit a "
                                       "force system with the required margins, in any mode of at most "
                                       f"{_p_max(problem)} sliders (a linear program per mode)")
    t = _when(problem, fails[0])
    if len(problem.names) == 2:  # (the one pair's program is the whole problem's: exact)
        return NoScheduleError(t, ScheduleLimit.FORCES, problem.names,
                               f"no path of the two contacts keeps a force system at every layer (their program is "
                               f"exact; its best path fails the force checks at {len(fails)} layer(s), the first at "
                               f"t = {t:.3f} s)")
    return NoScheduleError(t, ScheduleLimit.SEARCH, problem.names,
                           f"the decomposition planner's search found no schedule (its best path still fails the force "
                           f"checks at {len(fails)} layer(s), the first at t = {t:.3f} s, after {report.block_solves} "
                           "pair program(s)); this is not a proof that none exists: try method = 'exact' where it "
                           "fits, or other margins")


def plan_decomposed(problem: Problem, check: Check) -> tuple[np.ndarray, np.ndarray, DescentReport]:
    """A path (cells, moves) (N + 1, m) whose schedule ``check`` accepts (no violations), by the descent of the module
    docstring, and what it did; or raise :class:`~regrasp.schedule.schedule.NoScheduleError`."""
    start = time.perf_counter()
    report = DescentReport()
    verts = ModeVertices(problem)
    paths, errors = [], []
    for i in range(len(problem.grids)):
        try:
            paths.append(initial_path(problem, i))
        except NoScheduleError as e:
            errors.append(e)
    if errors:  # the earliest reason
        raise min(errors, key=lambda e: e.latest_time)
    cells = np.stack([p[0] for p in paths], axis=1)
    moves = np.stack([p[1] for p in paths], axis=1)
    bans: dict = {}
    violations: list = []
    for attempt in range(problem.settings.max_repairs + 1):
        cells, moves, value = _descend(problem, verts, cells, moves, bans, report)
        # (the objective counts the failures: only then list them)
        fails = path_failures(problem, verts, cells, moves, bans) if value >= _big(problem) else []
        if fails:
            report.seconds = time.perf_counter() - start
            raise _failure(problem, fails, report)
        violations = check(cells, moves)
        if not violations:
            report.seconds = time.perf_counter() - start
            return cells, moves, report
        report.repairs += 1
        for t, _, _ in violations:
            k = int((t - problem.times[0]) / problem.dt)
            for j in (k, k + 1):
                if 0 <= j < len(cells):
                    bans.setdefault(j, []).append((tuple(cells[j].tolist()), tuple(moves[j].tolist())))
    t, what, i = violations[0]
    raise NoScheduleError(t, verification_limit(what), problem.names if i is None else (problem.names[i],),
                          f"the schedule still fails its verification after {problem.settings.max_repairs} re-plans "
                          f"({len(violations)} violations, the first: {what} at t = {t:.3f} s)")

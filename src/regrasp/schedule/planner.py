r"""The regrasp schedule planner: the slides of every contact, planned jointly over the trajectory.

The object trajectory is fixed and known before manipulation begins (paper §4), so the regrasps
are planned ahead, offline like the envelope of §2, with the physics as constraints. At every time
the schedule keeps

* each contact inside its feasible envelope (Definition 2.2) with ``envelope_margin``;
* a force system that moves the object along the trajectory (Newton–Euler with its acceleration):
  every slider on its **kinetic** cone edge in its direction, every fixed contact inside its
  **static** cone with ``cone_margin``, ``f_min`` ≤ f_n ≤ ``f_max`` (:mod:`regrasp.schedule.force_polytope`),
  and a starting slider able to break away on its static edge;
* at most ``max_sliders`` = min(m - 1, 2m - 3) contacts sliding at once (p < m, 2m ≥ 3 + p);
* slides at most ``max_slide_speed`` and ``max_slide_acceleration``, each from rest to rest in one
  direction with the smooth profile of :mod:`regrasp.schedule.schedule`.

**Method.** A dynamic program over a lattice of time layers (step
Δt = ``xi_resolution`` / ``max_slide_speed``) and contact cells (``xi_resolution``)
(:mod:`regrasp.schedule.lattice`). The lattice path moves a slider one cell per step; its slides
become smooth profiles that accelerate over ``ramp`` = v / ``max_slide_acceleration`` centred on the
path's corners, so they deviate from it by at most v·ramp/8 (covered by a planning buffer on the
envelope margin). The envelope is checked on a window of sub-samples around each layer, the forces
at the layers. The planner then **verifies** its schedule on a finer time grid (envelopes at the
schedule's exact positions, forces in the exact modes, break-away at each slide's start, all with
the exact margins) and re-plans around any violation (``max_repairs`` times). With more contacts than the lattice's
force tables hold (four on the default lattice), or ``settings.method = "decomposition"``, the decomposition planner
searches the same lattice two contacts at a time instead, at a cost polynomial in their number
(:mod:`regrasp.schedule.decomposition`), with the same objective and verification.

**Objective**, in this order: (1) every constraint above, at the required margins; (2) the fewest
slides; (3) the least time near the envelope's bounds: the sum over layers and contacts of
max(0, ``comfort_margin`` - margin) / (``comfort_margin`` - ``envelope_margin``), plus 0.05 per
moving contact and step (less sliding). Larger required margins cost slides: plan with several to
see the trade-off.

**Periodic trajectories** get a periodic schedule over one period (the same contacts at its end as
at its start). A free-start program over one period gives a lower bound on the slides; a second
period, started from the first's end values, gives the best two-period path, whose middle state is
in the steady regime; the program then runs from that state with the end held to it (and from up to
``period_candidates`` such states). ``slides_lower_bound`` = max(free, ⌈two periods / 2⌉): a
periodic schedule with as many slides is optimal.

When no schedule exists, :class:`~regrasp.schedule.schedule.NoScheduleError` says until when one survives
and which constraint ran out (:mod:`regrasp.schedule.diagnosis`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from ..core.exceptions import InvalidParameterError
from ..model.scenario import Scenario
from .decomposition import plan_decomposed
from .diagnosis import diagnose
from .force_polytope import force_system
from .lattice import cells_of, flat_index, move_runs, path, run
from .problem import Problem, RegraspSettings, build_problem, slide_ratios, window_margin
from .schedule import (
    NoScheduleError,
    RegraspSchedule,
    ScheduleLimit,
    Slide,
    first_minimum,
    slides_at,
    verification_limit,
)
from .verification import schedule_torques, verify

__all__ = ["RegraspSettings", "plan_regrasps"]

Progress = Callable[[int, int], None]


def _slides(problem: Problem, cells: np.ndarray, moves: np.ndarray) -> tuple[Slide, ...]:
    """The lattice path's runs of moves as smooth slides (module docstring)."""
    times, ramp = problem.times, problem.settings.ramp
    out = [Slide(i, problem.names[i], d, float(times[first - 1] - ramp / 2), float(times[last] + ramp / 2),
                 float(problem.grids[i][cells[first - 1, i]]), float(problem.grids[i][cells[last, i]]), ramp)
           for first, i, d, last in move_runs(moves)]
    return tuple(sorted(out, key=lambda s: (s.start, s.contact)))


def _schedule(problem: Problem, cells, moves, seconds: float, lower_bound, verified_min, *,
              forces: bool = True) -> RegraspSchedule:
    """The schedule of a lattice path, sampled at the layers with its force systems (without them,
    NaN, when not ``forces``: a draft to verify)."""
    slides = _slides(problem, cells, moves)
    m = len(problem.names)
    times = problem.times[:len(cells)]
    xi_start = np.array([problem.grids[i][cells[0, i]] for i in range(m)])
    periodic = problem.periodic and len(cells) == len(problem.times)
    at = slides_at(xi_start, slides, times)
    q = problem.settings.envelope_substeps
    envelope_margin = np.array([[problem.sub_samples[i][k * q].margin(float(at.xi[k, i])) for i in range(m)]
                                for k in range(len(times))])
    traj = problem.scenario.trajectory
    sample = traj.sample(np.clip(times, traj.t_start, traj.t_end))
    limits = problem.settings.force_limits()
    mu_s = [f.static for f in problem.friction]
    normal, cone = np.full((len(times), m), np.nan), np.full((len(times), m), np.nan)
    torque = problem.torque if forces and problem.torque is not None and problem.torque.limited else None
    torques = schedule_torques(torque, sample, at) if torque is not None else None
    for k in range(len(times) if forces else 0):
        system = force_system(problem.geometry_at(at.xi[k]), sample.pose[k, 2], sample.acceleration[k], at.xi[k],
                              slide_ratios(at.direction[k], problem.friction), mu_s, limits,
                              *((torques[k], torque.effort) if torque is not None else ()))
        normal[k] = system.normal
        cone[k] = np.where(at.direction[k] == 0, system.cone_margins, np.nan)
    env_min, env_at = verified_min if verified_min is not None else first_minimum(envelope_margin, times,
                                                                                 problem.names)
    cone_min, cone_at = first_minimum(cone, times, problem.names)
    return RegraspSchedule(
        names=problem.names, edges=tuple(c.edge for c in problem.scenario.contacts), t_start=float(times[0]),
        t_end=float(times[-1]), periodic=periodic,
        xi_start=xi_start, slides=slides, times=times, xi=at.xi, xi_dot=at.xi_dot, xi_ddot=at.xi_ddot,
        sliding=at.direction, envelope_margin=envelope_margin, cone_margin=cone, normal_force=normal,
        required_envelope_margin=problem.settings.envelope_margin, required_cone_margin=problem.settings.cone_margin,
        min_envelope_margin=env_min, min_envelope_margin_at=env_at, min_cone_margin=cone_min,
        min_cone_margin_at=cone_at, planning_seconds=seconds, slides_lower_bound=lower_bound)


def _bans(problem: Problem, violations, cells, moves, width: int = 0) -> dict:
    """The path's states at the layers around each violation, to exclude when re-planning; and where the forces fail
    between two layers while contacts slide (the lattice checks the forces at the layers and, for two sliders, at the
    interval's middle: a thin set of positions without forces can lie between), that move vector at every position
    over the ``width`` layers on either side (the same slides a layer later cross the same set). A slide that is not
    well-posed (Painlevé) likewise: the move vector of the named contact's slide (the one that starts within two
    layers: a slide's ramp starts before its first layer), wherever the lattice's sampled check missed it."""
    index = {tuple(d): mu for mu, d in enumerate(problem.lattice.combos.tolist())}
    bans: dict[int, list] = {}
    for t, what, i in violations:
        at = (t - problem.times[0]) / problem.dt
        k = int(at)
        for j in (k, k + 1):
            if 0 <= j < len(cells):
                bans.setdefault(j, []).append((index[tuple(moves[j].tolist())], cells[j].copy()))
        between = abs(at - round(at)) > 1e-6
        if what.startswith("painleve") and i is not None:
            at_slide = [j for j in (k, k + 1, k + 2) if 0 <= j < len(moves) and moves[j, i] != 0]
            centre = at_slide[0] if at_slide else None
        else:
            centre = k + 1 if what == "forces" and between and k + 1 < len(moves) and moves[k + 1].any() else None
        if width and centre is not None:
            mu = index[tuple(moves[centre].tolist())]
            for j in range(max(1, centre - width), min(len(cells), centre + 1 + width)):
                bans.setdefault(j, []).append((mu, None))
    return bans


def _merge(a: dict, b: dict) -> dict:
    out = {k: list(v) for k, v in a.items()}
    for k, v in b.items():
        out.setdefault(k, []).extend(v)
    return out


def _periodic_from(problem: Problem, start, bans: dict):
    """The cheapest periodic path through ``start`` (global cells): (value, cells, moves), or None."""
    lat = problem.lattice
    N = lat.layers - 1
    periodic = run(lat, start=start, bans=bans, end=start)
    value = periodic.value(start) if periodic.last_layer == N else math.inf
    if not math.isfinite(value):
        return None
    return (value, *path(lat, periodic, N, 0, flat_index(start, periodic.boxes[N])))


def _when(problem: Problem, t: float) -> str:
    """" at t = ..." for a refusal's time ``t`` [s] other than the start, saying so where a periodic schedule is back at
    its start."""
    if abs(t - problem.times[0]) < 1e-9:
        return ""
    back = " (where the periodic schedule is back at its start)" if t > problem.times[1] + 1e-9 else ""
    return f" at t = {t:.3f} s{back}"


def _bad_start(problem: Problem) -> NoScheduleError:
    """Why the given start positions are not admissible at the first layer."""
    t0 = float(problem.times[0])
    start = [float(problem.grids[i][c]) for i, c in enumerate(problem.start_cells)]
    low = [(i, x, *window_margin(problem, 0, i, x)) for i, x in enumerate(start)
           if not problem.lattice.env_ok[0, i, problem.start_cells[i]]]
    if low:  # (the margin the lattice's envelope tables take: the least over the first layer's window)
        where = [f"{problem.names[i]} at xi = {x * 1e3:.2f} mm is " + (
                 f"{-m * 1e3:.2f} mm outside its feasible set" if m < 0 else f"only {m * 1e3:.2f} mm inside its "
                 "feasible set") + _when(problem, tm) for i, x, m, tm in low]
        need = problem.settings.envelope_margin + problem.envelope_buffer
        return NoScheduleError(t0, ScheduleLimit.ENVELOPE, tuple(problem.names[i] for i, *_ in low),
                               f"starting at t = {t0:.3f} s, {'; '.join(where)} (a contact must keep "
                               f"{need * 1e3:.2f} mm: the envelope margin {problem.settings.envelope_margin * 1e3:.2f}"
                               f" mm and {problem.envelope_buffer * 1e3:.2f} mm for a slide's ramp)", partial=None)
    return NoScheduleError(t0, ScheduleLimit.FORCES, problem.names,
                           f"no force system holds the object at rest at the start positions "
                           f"({', '.join(f'{x * 1e3:.1f}' for x in start)} mm) with the required margins", partial=None)


def _solve(problem: Problem, bans: dict, hint=None) -> tuple:
    """(cells, moves, lower bound on the slides or None) of the best schedule, or raise; ``hint``: the
    start of the last periodic schedule, tried first when re-planning around ``bans``."""
    lat = problem.lattice
    N = lat.layers - 1
    K = lat.slide_cost
    if hint is not None and problem.start_cells is None:
        found = _periodic_from(problem, hint, bans)
        if found is not None:
            return found[1], found[2], None
    given = problem.start_cells
    # (a periodic plan from a free start traces no path back through the free run)
    keep = not problem.periodic or given is not None
    free = run(lat, start=given, bans=bans, end=given if problem.periodic else None, keep_backs=keep)
    if free.last_layer < 0 and given is not None:
        raise _bad_start(problem)
    if free.last_layer < N:
        if not keep:  # the partial schedule traces back through it after all
            free = run(lat, start=given, bans=bans, keep_backs=True)
        partial = None
        if free.last_layer >= 0:
            _, mu, p = free.best()
            partial = _schedule(problem, *path(lat, free, free.last_layer, mu, p), 0.0, None, None)
        raise diagnose(problem, free, partial)
    if problem.periodic and given is not None:
        if not math.isfinite(free.value(given)):
            raise NoScheduleError(float(problem.times[-1]), ScheduleLimit.PERIODIC, problem.names,
                                  "no schedule from the given start positions ends the period where it starts")
        return (*path(lat, free, N, 0, flat_index(given, free.boxes[N])), None)
    value, mu, p = free.best()
    lower = None if given is not None else int(value // K)
    if not problem.periodic:
        return (*path(lat, free, N, mu, p), lower)
    # a second period started from the first's end values: its best path's start (the middle of the
    # best two-period path) is in the steady regime, a good start for a periodic schedule
    second = run(lat, bans=bans, init=free)
    candidates = []
    free_end = cells_of(p, free.boxes[N])
    del free  # (each run keeps a back pointer per state: let the next ones reuse the memory)
    if second.last_layer == N:
        two, mu2, p2 = second.best()
        lower = max(lower, math.ceil(int(two // K) / 2))
        cells2, moves2 = path(lat, second, N, mu2, p2)
        if np.array_equal(cells2[0], cells2[-1]) and len(move_runs(moves2)) <= lower:
            return cells2, moves2, lower  # the best two-period path repeats its second period
        candidates += [cells2[0], cells2[-1]]
        candidates += _best_rest_states(second, problem.settings.period_candidates)
    else:  # a periodic schedule run twice is a two-period path from one of the first period's end states: none is
        raise _no_periodic(problem, second, 2, lower)
    del second
    candidates.insert(2, free_end)
    best, tried = None, []
    for start in candidates:
        if tuple(start) in tried:
            continue
        if len(tried) == problem.settings.period_candidates:
            break
        tried.append(tuple(start))
        found = _periodic_from(problem, start, bans)
        if found is not None and (best is None or found[0] < best[0]):
            best = found
            if int(found[0] // K) <= lower:
                break  # as few slides as any schedule: optimal
    if best is None:  # a periodic schedule run k times is a k-period path: where none exists, a proof
        chain = run(lat, bans=bans, init=run(lat, bans=bans, keep_backs=False), keep_backs=False)
        for periods in range(3, _PROOF_PERIODS + 1):
            chain = run(lat, bans=bans, init=chain, keep_backs=False)
            if chain.last_layer < N:
                raise _no_periodic(problem, chain, periods, lower)
        # (not a proof: the program tried these starts, not every one)
        raise NoScheduleError(float(problem.times[-1]), ScheduleLimit.SEARCH, problem.names,
                              f"no schedule from the {len(tried)} start states tried ends a period where it starts "
                              f"(not a proof that none does; a non-periodic one with {lower} slide(s) exists: "
                              "settings.periodic = False)")
    return best[1], best[2], lower


#: The most periods in a row the planner runs its program over to prove that no periodic schedule exists.
_PROOF_PERIODS = 8


def _no_periodic(problem: Problem, dead, periods: int, lower) -> NoScheduleError:
    """The proof that no periodic schedule exists: the program run over ``periods`` periods in a row died (``dead``:
    the last period's run), so a periodic schedule, run that many times, would be a path it lacks."""
    t0, period = float(problem.times[0]), float(problem.times[-1] - problem.times[0])
    into = float(problem.times[max(dead.last_layer, 0)]) - t0
    words = {2: "two", 3: "three", 4: "four", 5: "five", 6: "six", 7: "seven", 8: "eight"}
    return NoScheduleError(t0 + (periods - 1) * period + into, ScheduleLimit.PERIODIC, problem.names,
                           f"no schedule runs {words.get(periods, periods)} periods in a row: from every state "
                           + ("the first period" if periods == 2 else f"the first {words.get(periods - 1)} periods")
                           + f" can end in, period {periods} dies by {into:.3f} s into it (a non-periodic one over "
                           f"one period exists, with {lower} slide(s): settings.periodic = False)")


def _best_rest_states(result, count: int) -> list:
    """The global cells of up to ``count`` of the cheapest states at rest in ``result``'s last layer, cheapest first
    (starts a periodic schedule may try: the end of a second period is in the steady regime)."""
    V = result.values[:, 0]
    order = np.argsort(V, kind="stable")[:count]
    box = result.boxes[result.last_layer]
    return [cells_of(int(p), box) for p in order if np.isfinite(V[p])]


def _plan_decomposed(problem: Problem, start: float, progress: Progress | None, total: int) -> RegraspSchedule:
    """The decomposition planner's schedule (:mod:`regrasp.schedule.decomposition`), verified as the exact one's."""
    verified: list = []

    def check(cells: np.ndarray, moves: np.ndarray) -> list:
        draft = _schedule(problem, cells, moves, 0.0, None, None, forces=False)
        violations, least = verify(problem, draft, problem.settings.verify_substeps)
        verified[:] = [least]
        return violations

    cells, moves, _ = plan_decomposed(problem, check)
    schedule = _schedule(problem, cells, moves, time.perf_counter() - start, None, verified[0])
    if progress is not None:
        progress(total, total)
    return schedule


def plan_regrasps(scenario: Scenario, settings: RegraspSettings | None = None, *,
                  start_time: float | None = None, xi0: ArrayLike | None = None, t_end: float | None = None,
                  progress: Progress | None = None) -> RegraspSchedule:
    """Plan the slides of every contact over the scenario's trajectory (module docstring).

    Args:
        scenario: Fingers, edges, object, trajectory, gravity and friction.
        settings: Margins, limits and resolution (default: :meth:`RegraspSettings.of` the scenario).
        start_time: Start of the horizon [s] (default: the trajectory's start).
        xi0: The contacts' positions at ``start_time`` [m] (default: chosen by the planner).
        t_end: End of the horizon [s] (default: the trajectory's end, or one period).
        progress: Called as ``progress(done, total)`` as the stages finish.

    Raises:
        NoScheduleError: no schedule satisfies the constraints (with the diagnosis).
    """
    if not isinstance(scenario, Scenario):
        raise InvalidParameterError("scenario", scenario, "a Scenario (regrasp.load_scenario)")
    if settings is None:
        settings = RegraspSettings.of(scenario)
    if not isinstance(settings, RegraspSettings):
        raise InvalidParameterError("settings", settings, "a RegraspSettings")
    start = time.perf_counter()
    total = 3 + settings.max_repairs
    problem = build_problem(scenario, settings, start_time=start_time, xi0=xi0, t_end=t_end,
                            force_tables={"exact": True, "decomposition": False, None: None}[settings.method])
    if progress is not None:
        progress(1, total)
    if not problem.exact:
        return _plan_decomposed(problem, start, progress, total)
    bans: dict = {}
    hint = lower = None
    for attempt in range(settings.max_repairs + 1):
        cells, moves, bound = _solve(problem, bans, hint)
        lower = bound if attempt == 0 else lower
        hint = cells[0] if problem.periodic else None
        if progress is not None:
            progress(2 + attempt, total)
        draft = _schedule(problem, cells, moves, 0.0, lower, None, forces=False)
        violations, verified = verify(problem, draft, settings.verify_substeps)
        if not violations:
            schedule = _schedule(problem, cells, moves, time.perf_counter() - start, lower, verified)
            if progress is not None:
                progress(total, total)
            return schedule
        bans = _merge(bans, _bans(problem, violations, cells, moves, width=attempt + 1))
    t, what, i = violations[0]
    raise NoScheduleError(t, verification_limit(what), problem.names if i is None else (problem.names[i],),
                          f"the schedule still fails its verification after {settings.max_repairs} re-plans "
                          f"({len(violations)} violations, the first: {what} at t = {t:.3f} s)")


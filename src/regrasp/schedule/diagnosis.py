r"""Why no regrasp schedule exists: the diagnosis in :class:`~regrasp.schedule.schedule.NoScheduleError`.

When the planner's dynamic program dies at some layer, the latest time any admissible state
survives is known. Which constraint ran out is found by relaxing them in turn:

1. **envelope**: some contact's feasible set, less the margin, is empty over a layer's window
   (e.g. condition I of paper §2.1, or a set narrower than twice the margin);
2. **speed**: without the force constraints the program dies as early: the feasible sets move
   faster than slides can follow (per contact, a one-dimensional reachability check names it);
3. **torque**: where the joints' torque limits cut the force tables (:mod:`regrasp.schedule.torque`) and the
   program with the uncut tables survives longer, the limits ran out: the finger, the joint and the time, with
   the least torque it needs at any admissible position;
4. **forces**: otherwise. The relaxed program's path shows the slide the envelopes need next; for
   two fingers on parallel edges the two-finger slide rule (:mod:`regrasp.schedule.slide_rule`) says why
   that slide is impossible.

The best schedule up to the latest time is attached as ``partial``.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np

from .lattice import move_runs, path, run
from .schedule import NoScheduleError, ScheduleLimit
from .slide_rule import two_finger_slide_range

if TYPE_CHECKING:
    from .lattice import LatticeRun
    from .problem import Problem
    from .schedule import RegraspSchedule

__all__ = ["diagnose"]


def _speed_limited(problem, last: int) -> int | None:
    """The contact whose own envelope, followed at the lattice speed, dies first (None if none dies
    by layer last + 1)."""
    lat = problem.lattice
    worst, worst_k = None, last + 2
    for i, grid in enumerate(problem.grids):
        n = len(grid)
        reach = lat.env_ok[0, i, :n].copy()
        for k in range(1, lat.layers):
            grown = reach.copy()
            if not lat.rest_only[k]:
                grown[1:] |= reach[:-1]
                grown[:-1] |= reach[1:]
            reach = grown & lat.env_ok[k, i, :n]
            if not reach.any():
                if k < worst_k:
                    worst, worst_k = i, k
                break
    return worst


def _rule(problem, slider: int, direction: int, when: float) -> str | None:
    """The two-finger slide rule for contact ``slider`` sliding ``direction`` (None unless two
    contacts on parallel edges; a curve has none)."""
    if len(problem.names) != 2 or problem.curved:
        return None
    geo = problem.geometry
    n0, n1 = geo.normals
    if abs(n0 @ n1 + 1.0) > 1e-9:
        return None
    traj = problem.scenario.trajectory
    smp = traj.sample(float(np.clip(when, traj.t_start, traj.t_end)))
    c, s = np.cos(smp.pose[2]), np.sin(smp.pose[2])
    rot = np.array([[c, -s], [s, c]])
    g_eff = geo.gravity - smp.acceleration[:2]  # the object's weight per unit mass, with its inertia
    tangent = rot @ geo.tangents[slider]
    along = float(tangent @ g_eff)
    if abs(along) < 1e-9:
        return None
    holder = 1 - slider
    width = float(abs((problem.scenario.polygon.edge(problem.scenario.contacts[holder].edge).xi_origin
                       - problem.scenario.polygon.edge(problem.scenario.contacts[slider].edge).xi_origin)
                      @ geo.normals[0]))
    with_gravity = direction * along > 0
    rng = two_finger_slide_range(width, problem.friction[slider], problem.friction[holder], upward=not with_gravity)
    fs, fh = problem.friction[slider], problem.friction[holder]
    name = problem.names[slider]
    mm = 1e3
    what = "with gravity (down)" if with_gravity else "against gravity (up)"
    bounds = (f"w mu_k = {rng.low * mm:.1f} mm < Delta <= (w/2)(mu_s + mu_k) = {rng.high * mm:.1f} mm" if with_gravity
              else f"{rng.low * mm:.1f} mm < Delta <= (w/2)(mu_s - mu_k) = {rng.high * mm:.1f} mm")
    up = -g_eff / np.linalg.norm(g_eff)
    heights = []
    for j in (slider, holder):
        edge = problem.scenario.polygon.edge(problem.scenario.contacts[j].edge)
        heights.append([float((rot @ edge.point(x)) @ up) for x in edge.xi_range])
    reach = (min(heights[0]) - max(heights[1]), max(heights[0]) - min(heights[1]))  # Δ the edges allow
    if rng.empty:
        verdict = "an empty range: no position allows it"
    elif rng.low >= reach[1] or rng.high < reach[0]:
        verdict = (f"but the edges allow only {reach[0] * mm:.1f} mm <= Delta <= {reach[1] * mm:.1f} mm: "
                   "no position allows it")
    else:
        verdict = "so only a slider that far above the holder can do it"
    lower = " (the lower contact can never slide down)" if with_gravity else ""
    return (f"two-finger slide rule: {name} must slide {what}, which for two fingers on parallel edges "
            f"w = {width * mm:.1f} mm apart needs {bounds}, Delta the slider's height above the holder "
            f"(slider mu_k = {fs.kinetic:g}, holder mu_s = {fh.static:g}): {verdict}{lower}")


def _along_gravity(problem, when: float, xi: np.ndarray) -> str:
    """Which contacts, at ``xi`` [m], push the object the way gravity pulls it (their normal force adds to the
    weight instead of carrying it), as a clause, or ''."""
    geo = problem.geometry_at(xi)
    g = np.asarray(geo.gravity, dtype=float)
    if not np.linalg.norm(g) > 0:
        return ""
    traj = problem.scenario.trajectory
    beta = float(traj.pose(float(np.clip(when, traj.t_start, traj.t_end)))[2])
    c, s = np.cos(beta), np.sin(beta)
    normals = geo.normals @ np.array([[c, s], [-s, c]])  # rows R(β) n°_i
    along = [problem.names[i] for i, n in enumerate(normals) if n @ g / np.linalg.norm(g) > 0.5]
    if not along:
        return ""
    return (f"; {', '.join(along)} push{'es' if len(along) == 1 else ''} along gravity (its normal force adds to "
            f"the weight instead of carrying it, so friction at the other contacts must carry both)")


def diagnose(problem: Problem, free: LatticeRun, partial: RegraspSchedule | None = None) -> NoScheduleError:
    """The :class:`NoScheduleError` for a dynamic program ``free`` that did not reach the last layer
    (``problem``: the planner's :class:`~regrasp.schedule.planner.Problem`; ``partial``: the best
    schedule up to its last layer, attached to the error)."""
    lat = problem.lattice
    names = problem.names
    times = problem.times
    last = free.last_layer
    latest = float(times[max(last, 0)])
    em = problem.settings.envelope_margin * 1e3
    for k in range(0, min(last + 2, lat.layers)):
        empty = [i for i in range(len(names)) if not lat.env_ok[k, i, :len(problem.grids[i])].any()]
        if empty:
            q = problem.settings.envelope_substeps
            why = []
            for i in empty:
                samples = problem.sub_samples[i]
                window = samples[max(0, (k - 1) * q):(k + 1) * q + 1]
                width = min(sum(hi - lo for lo, hi in s.feasible) for s in window) * 1e3
                later = next((s for s in samples[max(0, (k - 1) * q):] if s.reason), None)
                why.append(f"{names[i]} (its feasible set narrows to {width:.2f} mm"
                           + (f" and is empty from t = {later.time:.3f} s: {later.reason}" if later else "") + ")")
            return NoScheduleError(latest, ScheduleLimit.ENVELOPE, tuple(names[i] for i in empty),
                                   f"at t = {times[k]:.3f} s no position of {', '.join(why)} keeps the envelope "
                                   f"margin of {em:.2f} mm (the latest admissible time is t = {latest:.3f} s)",
                                   partial=partial)
    torque = _torque_limited(problem, last)
    if torque is not None:
        return NoScheduleError(latest, ScheduleLimit.TORQUE, (torque[0],), torque[1],
                               partial=partial if last >= 0 else None)
    posed = _painleve_limited(problem, last)
    if posed is not None:
        return NoScheduleError(latest, ScheduleLimit.PAINLEVE, (posed[0],), posed[1],
                               partial=partial if last >= 0 else None)
    if last < 0:
        return NoScheduleError(latest, ScheduleLimit.FORCES, names,
                               f"no start state at t = {latest:.3f} s has a force system with the required margins",
                               partial=None)
    relaxed_lat = dataclasses.replace(lat, lo=np.full_like(lat.lo, -np.inf), hi=np.full_like(lat.hi, np.inf),
                                      mid_lo=np.full_like(lat.lo, -np.inf), mid_hi=np.full_like(lat.hi, np.inf),
                                      break_lo=None, break_hi=None)
    relaxed = run(relaxed_lat, start=problem.start_cells)
    if relaxed.last_layer <= last + 1:
        i = _speed_limited(problem, last)
        who = names if i is None else (names[i],)
        speed = problem.settings.max_slide_speed * 1e3
        return NoScheduleError(latest, ScheduleLimit.SPEED, who,
                               f"after t = {latest:.3f} s {' and '.join(who)} cannot follow the feasible set "
                               f"at slides of at most {speed:.0f} mm/s", partial=partial)
    # forces: the slides the envelopes need next (the relaxed program's path), and among them one that
    # no admissible position allows at all
    N = relaxed.last_layer
    _, mu, p = relaxed.best()
    cells, moves = path(relaxed_lat, relaxed, N, mu, p)
    needed = move_runs(moves, first=last + 1)
    if not needed:
        return NoScheduleError(latest, ScheduleLimit.FORCES, names,
                               f"after t = {latest:.3f} s no force system holds the object with the required "
                               f"margins at any admissible position", partial=partial)
    needed.sort()
    blocked = [n for n in needed if _never_allowed(problem, n[1], n[2], n[0], n[3])]
    first, i, d, end = (blocked or needed)[0]
    sign = "+" if d > 0 else "-"
    when = float(times[end])
    how = ("no admissible position allows that slide with the required margins" if blocked else
           "no force system allows it together with the other contacts' slides")
    rule = _rule(problem, i, d, when)
    return NoScheduleError(latest, ScheduleLimit.FORCES, (names[i],),
                           f"after t = {latest:.3f} s the envelopes need {names[i]} to slide {sign}xi "
                           f"(in [{times[max(first - 1, 0)]:.3f}, {when:.3f}] s), and {how}"
                           + _along_gravity(problem, when, np.array([g[c] for g, c in zip(problem.grids, cells[end])])),
                           rule=rule, partial=partial)


def _outlives(problem, tables: tuple | None, last: int) -> tuple | None:
    """(the lattice with the force tables ``tables`` (lo, hi) as they were before a cut, its run) when that run
    survives beyond layer ``last`` (the cut is what ran out), else None (also without ``tables``: nothing was cut)."""
    if tables is None:
        return None
    uncut = dataclasses.replace(problem.lattice, lo=tables[0], hi=tables[1])
    result = run(uncut, start=problem.start_cells)
    return (uncut, result) if result.last_layer > last else None


def _torque_limited(problem, last: int) -> tuple[str, str] | None:
    """(the finger, the reason) where the joint torque limits are what ran out: the program on the force tables
    as they were before the limits cut them (``problem.free_tables``) survives beyond layer ``last``; else None.
    The reason names the joint and the time (the first layer no state survives), and the least torque that joint
    needs over its contact's envelope-admissible positions (the lattice's necessary condition,
    ``problem.torque_excess``), against its limit."""
    found = _outlives(problem, problem.free_tables, last)
    if found is None:
        return None
    lat, (_, free) = problem.lattice, found
    k = min(last + 1, lat.layers - 1)
    effort = problem.torque.effort
    best = None  # (least excess over the admissible cells, contact, joint)
    for i, grid in enumerate(problem.grids):
        cells = lat.env_ok[k, i, :len(grid)]
        for j in range(2):
            if not np.isfinite(effort[i, j]) or not cells.any():
                continue
            excess = problem.torque_excess[k, :, i, :len(grid), j][:, cells]  # (modes, admissible cells)
            with np.errstate(all="ignore"):
                least = float(np.nanmin(excess)) if np.isfinite(excess).any() else np.nan
            worst = float(np.nanmax(excess)) if np.isfinite(excess).any() else np.nan
            key = (least, worst)
            if np.isfinite(least) and (best is None or key > best[0]):
                best = (key, i, j)
    when = float(problem.times[k])
    if best is None:
        return problem.names[0], f"at t = {when:.3f} s the joint torque limits leave no force system"
    (least, worst), i, j = best
    name, limit = problem.names[i], float(effort[i, j])
    if least > 0.0:
        what = (f"at t = {when:.3f} s no envelope-admissible position of {name} keeps its joint {j + 1} within its "
                f"torque limit of {limit:.4f} N m: it needs at least {limit + least:.4f} N m "
                f"({least:.4f} N m more)")
    else:
        what = (f"at t = {when:.3f} s the joint torque limits leave no force system for the admissible positions: "
                f"{name} joint {j + 1} (limit {limit:.4f} N m) would need up to {limit + worst:.4f} N m at some")
    latest = float(problem.times[max(last, 0)])
    return name, (f"{what} (joint torque limit; the latest admissible time is t = {latest:.3f} s, and without the "
                  f"limits a schedule survives until t = {float(problem.times[free.last_layer]):.3f} s)")


def _painleve_limited(problem, last: int) -> tuple[str, str] | None:
    """(the contact, the reason) where the slides' well-posedness is what ran out (:mod:`regrasp.schedule.well_posed`):
    the program on the force tables before its cut (``problem.posed_tables``) survives beyond layer ``last``; the
    reason names the first slide of that program's path after ``last`` that the cut excludes; else None."""
    found = _outlives(problem, problem.posed_tables, last)
    if found is None:
        return None
    lat, (uncut_lat, uncut) = problem.lattice, found
    _, mu, p = uncut.best()
    cells, moves = path(uncut_lat, uncut, uncut.last_layer, mu, p)
    index = {tuple(d): j for j, d in enumerate(lat.combos.tolist())}
    times, factor = problem.times, problem.settings.sliding_friction_factor
    latest = float(times[max(last, 0)])
    mask, pairs = problem.posed_mask

    def excluded(k: int, i: int) -> bool:
        mu = index[tuple(moves[k].tolist())]
        a, b, ok = pairs.get(mu, (0, 0, None))
        return not mask[k, mu, i, cells[k, i]] or (ok is not None and not ok[k, cells[k, a], cells[k, b]])

    for first, i, d, end in sorted(move_runs(moves, first=max(last, 0) + 1)):
        bad = [k for k in range(first, end + 1) if excluded(k, i)]
        if bad:
            name, f = problem.names[i], problem.friction[i]
            return name, (f"after t = {latest:.3f} s the envelopes need {name} to slide {'+' if d > 0 else '-'}xi "
                          f"(in [{times[max(first - 1, 0)]:.3f}, {times[end]:.3f}] s), and where they allow it, from "
                          f"t = {times[bad[0]]:.3f} s, friction ({factor:g} x its mu_k = {f.kinetic:g}) would make "
                          "that slide's contact problem ill-posed (Painleve's paradox: its normal force would need "
                          "torques known to a vanishing precision, or the finger jams or lifts off; "
                          "RegraspSettings.sliding_friction_factor)")
    return problem.names[0], (f"after t = {latest:.3f} s no slide the envelopes need is well-posed "
                              f"at {factor:g} x the kinetic friction (Painleve's paradox)")


def _never_allowed(problem, i: int, d: int, k0: int, k1: int) -> bool:
    """Whether no envelope-admissible positions at layers k0..k1 have a force system with contact i
    sliding ``d`` and the others fixed (the lattice's force tables)."""
    lat = problem.lattice
    m = len(problem.names)
    move = [d if j == i else 0 for j in range(m)]
    mu = [tuple(r) for r in lat.combos.tolist()].index(tuple(move))
    others = [j for j in range(m) if j != lat.axis]
    for k in range(k0, k1 + 1):
        masks = [lat.env_ok[k, j, :len(problem.grids[j])] for j in others]
        ok_other = np.ones(1, dtype=bool)
        for mask in masks:
            ok_other = np.outer(ok_other, mask).reshape(-1)
        axis_cells = problem.grids[lat.axis][lat.env_ok[k, lat.axis, :len(problem.grids[lat.axis])]]
        if not axis_cells.size or not ok_other.any():
            continue
        lo, hi = lat.lo[k, ok_other, mu], lat.hi[k, ok_other, mu]
        if np.any((axis_cells[None, :] >= lo[:, None] - 1e-8) & (axis_cells[None, :] <= hi[:, None] + 1e-8)):
            return False
    return True

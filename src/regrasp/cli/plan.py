"""``regrasp plan``: a trajectory's feasibility and each finger's feasible-contact envelope (paper §2), and with
``--regrasp`` the regrasp schedule (paper §4).

``regrasp plan SCENARIO [--json] [--plot DIR] [--samples N] [--geometry ideal|urdf]
[--regrasp [--envelope-margin M] [--cone-margin N]]``

Exit status: 0 when the trajectory is feasible (and, with ``--regrasp``, a regrasp schedule
exists), 1 when it is not (the result is still printed, with the reason), 2 on bad input (a typed
error, printed as one line on stderr).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from ..core.contact import DEFAULT_CONE_MARGIN
from ..core.validation import MAX_SAMPLES
from .common import ProgressBar, nonnegative, number_argument, output_directory

__all__ = ["configure"]

_samples = number_argument(int, f"an integer in [2, {MAX_SAMPLES}]", lambda v: 2 <= v <= MAX_SAMPLES)


def configure(p: argparse.ArgumentParser) -> None:
    """``regrasp plan``'s arguments, on its parser."""
    p.add_argument("scenario", help="scenario file (TOML), e.g. examples/scenarios/paper_trajectory_2.toml")
    p.add_argument("--json", action="store_true", help="print one JSON document on stdout")
    p.add_argument("--plot", metavar="DIR", help="write d.png, reachable.png and feasible.png into DIR")
    p.add_argument("--samples", type=_samples, help="number of time samples (default: the scenario's)")
    p.add_argument("--geometry", choices=("ideal", "urdf"), help="link collision model (default: the scenario's)")
    p.add_argument("--regrasp", action="store_true",
                   help="also plan the regrasp schedule: every contact's slides over the trajectory (paper §4); "
                        "with --json a 'schedule' object, with --plot regrasp.png (paper Fig. 4.3)")
    p.add_argument("--envelope-margin", type=nonnegative, metavar="M",
                   help="with --regrasp: the envelope margin [m] every contact keeps (default 0.001)")
    p.add_argument("--cone-margin", type=nonnegative, metavar="N",
                   help="with --regrasp: the cone margin [N] every fixed contact keeps (default "
                        f"{DEFAULT_CONE_MARGIN})")
    p.set_defaults(func=_cmd_plan)


def _condition_runs(times, finger) -> str:
    parts, start = [], 0
    conds = [s.condition.value for s in finger.samples]
    for k in range(1, len(conds) + 1):
        if k == len(conds) or conds[k] != conds[start]:
            parts.append(f"{conds[start]} [{times[start]:.2f}, {times[k - 1]:.2f}]")
            start = k
    if len(parts) > 6:
        parts = parts[:3] + [f"... ({len(parts) - 5} more) ..."] + parts[-2:]
    return " ".join(parts)


def _summary(plan, scenario, figures) -> str:
    times = plan.times
    mm = 1000.0
    lines = [
        f"regrasp plan: {plan.scenario}" + (f" ({scenario.path})" if scenario.path else ""),
        f"  object: {plan.polygon.label}, {plan.polygon.mass:.3g} kg; trajectory t in "
        f"[{times[0]:.4g}, {times[-1]:.4g}] s, {len(times)} samples; geometry: {plan.geometry.value}",
        "",
        "  verdict: " + ("FEASIBLE - every finger has a feasible contact at every sample" if plan.feasible
                         else "INFEASIBLE - some finger has no feasible contact at some samples"),
        "",
    ]
    for f in plan.fingers:
        widths = np.array([sum(hi - lo for lo, hi in s.feasible) for s in f.samples]) * mm
        l1, l2 = f.link_lengths
        face = "the boundary" if getattr(plan.polygon.edge(f.edge), "curved", False) else f"edge {f.edge}"
        lines.append(f"  {f.name}: {face}, {f.configuration} configuration, l1 = {l1 * mm:.1f} mm, "
                     f"l2 = {l2 * mm:.1f} mm")
        lines.append(f"    conditions: {_condition_runs(times, f)}")
        lines.append(f"    feasible width [mm]: min {widths.min():.2f}, median {np.median(widths):.2f}, "
                     f"max {widths.max():.2f} ({'perimeter' if face == 'the boundary' else 'edge length'} "
                     f"{(f.samples[0].edge_range[1] - f.samples[0].edge_range[0]) * mm:.1f})")
        for iv in f.infeasible_intervals:
            lines.append(f"    infeasible: t in [{iv.start:.3f}, {iv.end:.3f}] s - {iv.reason}")
        if f.initial_xi is None:
            lines.append("    initial contact: none (infeasible at the first sample)")
        else:
            safe = ("inside a danger zone at the start (the feasible set has no width there)"
                    if f.initial_xi_safe_until is None else
                    f"outside the danger zones until t = {f.initial_xi_safe_until:.3f} s")
            lines.append(f"    initial contact: xi = {f.initial_xi * mm:.2f} mm, {safe}, feasible until "
                         f"t = {f.initial_xi_feasible_until:.3f} s")
            if f.fixed_grasp:
                ivs = ", ".join(f"[{lo * mm:.2f}, {hi * mm:.2f}]" for lo, hi in f.fixed_grasp)
                lines.append(f"    fixed grasp possible for the whole trajectory: xi in {ivs} mm")
            else:
                lines.append("    no fixed grasp survives the whole trajectory: the finger must regrasp (slide)")
        lines.append("")
    lines.append(f"  planner: {plan.seconds_per_sample * 1e6:.0f} us per finger per sample (median)")
    if figures:
        lines.append("  figures: " + ", ".join(str(p) for p in figures))
    return "\n".join(lines)


def _piece(obj, xi: float) -> str:
    """Which piece of a rounded polygon ``obj`` ξ [m] falls on ("edge k" or "arc k"), or '' on other objects."""
    piece = getattr(obj, "piece", None)
    return "" if piece is None else "{} {}".format(*piece(xi))


def _schedule_summary(schedule, error, obj=None) -> str:
    """The ``--regrasp`` lines of the summary (on a rounded polygon ``obj``, the piece each slide starts and ends
    on)."""
    mm = 1000.0
    if error is not None:
        lines = [f"  regrasp schedule: NONE ({error.limit.value}) - {error.reason}"]
        if error.rule:
            lines.append(f"    {error.rule}")
        lines.append(f"    the latest time any admissible state survives: t = {error.latest_time:.3f} s")
        return "\n".join(lines)
    per = " per period" if schedule.periodic else ""
    bound = schedule.slides_lower_bound
    lines = [f"  regrasp schedule: {'periodic' if schedule.periodic else 'not periodic'}, t in "
             f"[{schedule.t_start:.3f}, {schedule.t_end:.3f}] s, {len(schedule.slides)} slides{per}"
             + (f" (no schedule has fewer than {bound})" if bound is not None else "")
             + f", planned in {schedule.planning_seconds:.2f} s"]
    for i, name in enumerate(schedule.names):
        ours = [s for s in schedule.slides if s.contact == i]
        if not ours:
            on = _piece(obj, schedule.xi_start[i])
            lines.append(f"    {name}: no slide (fixed at xi = {schedule.xi_start[i] * mm:.1f} mm"
                         + (f", {on})" if on else ")"))
            continue
        parts = []
        for s in ours:
            pieces = (_piece(obj, s.start_xi), _piece(obj, s.end_xi))
            parts.append(f"{'+' if s.direction > 0 else '-'}xi {s.start_xi * mm:.1f} -> {s.end_xi * mm:.1f} mm "
                         + (f"({' -> '.join(dict.fromkeys(pieces))}) " if pieces[0] else "")
                         + f"in [{s.start:.3f}, {s.end:.3f}] s")
        lines.append(f"    {name}: {len(ours)} slide{'s' if len(ours) != 1 else ''}: " + "; ".join(parts))
    t, who = schedule.min_envelope_margin_at
    lines.append(f"    smallest envelope margin {schedule.min_envelope_margin * mm:.2f} mm ({who}, t = {t:.3f} s; "
                 f"required {schedule.required_envelope_margin * mm:.2f} mm)")
    t, who = schedule.min_cone_margin_at
    lines.append(f"    smallest cone margin {schedule.min_cone_margin:.3f} N ({who}, t = {t:.3f} s; "
                 f"required {schedule.required_cone_margin:.3f} N)")
    return "\n".join(lines)


def _cmd_plan(args) -> int:
    from ..envelope.planner import plan_scenario
    from ..model.scenario import load_scenario

    scenario = load_scenario(args.scenario)
    if args.plot is not None:  # before the work, not after it
        output_directory("--plot", args.plot)
    progress = ProgressBar(f"planning {scenario.name}") if not args.json else None
    result = plan_scenario(scenario, samples=args.samples, geometry=args.geometry, progress=progress)
    if result.sampling_warning is not None:
        print(f"regrasp plan: warning: {result.sampling_warning}", file=sys.stderr)
    schedule = error = None
    if args.regrasp:
        from ..schedule.planner import RegraspSettings, plan_regrasps
        from ..schedule.schedule import NoScheduleError

        options = {k: v for k, v in (("envelope_margin", args.envelope_margin), ("cone_margin", args.cone_margin),
                                     ("geometry", args.geometry)) if v is not None}
        try:
            schedule = plan_regrasps(scenario, RegraspSettings.of(scenario, **options),
                                     progress=ProgressBar("planning regrasps") if not args.json else None)
        except NoScheduleError as exc:
            error = exc
    figures = []
    if args.plot is not None:
        from ..envelope.plotting import write_plan_figures
        from ..schedule.plotting import plot_schedule

        figures = write_plan_figures(result, args.plot)
        if schedule is not None:
            figures.append(plot_schedule(result, schedule, Path(args.plot) / "regrasp.png"))
        elif error is not None and error.partial is not None:
            figures.append(plot_schedule(result, error.partial, Path(args.plot) / "regrasp.png", failure=error))
    if args.json:
        doc = result.to_json_dict()
        if args.regrasp:
            doc["schedule"] = schedule.to_json_dict() if schedule is not None else error.to_json_dict()
        doc["figures"] = [str(p) for p in figures]
        json.dump(doc, sys.stdout)
        sys.stdout.write("\n")
    else:
        text = _summary(result, scenario, figures)
        if args.regrasp:
            text += "\n\n" + _schedule_summary(schedule, error, scenario.polygon)
        print(text)
    return 0 if result.feasible and error is None else 1

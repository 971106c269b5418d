"""``regrasp simulate``: run a regrasping rollout on the plant, print what happened, record it.

``regrasp simulate [SCENARIO] [--periods N | --duration T] [--policy scheduled|paper|none]
[--plant project|mujoco|drake [--tip-radius MM]] [--rrd FILE] [--decimate K] [--spawn | --connect ADDR] [--json]
[--plant-mass-scale S] [--plant-mu-scale S] [--envelope-margin M] [--cone-margin N] [--plot DIR]``

Default: the shipped three-finger trajectory-2 scenario, the scheduled policy, the scenario's
duration. Exit status: 0 the rollout succeeded, 1 it failed or no schedule exists (the result is
still printed, with the reason), 2 bad input. Ctrl-C ends the run with a partial result (exit 1)
and a complete recording.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from ..core.capture import captured_fd
from ..core.contact import DEFAULT_CONE_MARGIN
from ..core.events import EventKind, FailureKind
from ..core.exceptions import InvalidParameterError
from ..core.validation import MAX_COUNT
from .common import (
    DEFAULT_SCENARIO,
    STARTED,
    KernelLoad,
    ProgressBar,
    add_plant_arguments,
    count_argument,
    nonnegative,
    output_directory,
    output_file,
    plant_spec,
    positive,
)

if TYPE_CHECKING:
    from ..model.scenario import Scenario
    from ..plants.simulation import PlantLike
    from ..rollout.result import RolloutResult

__all__ = ["configure", "plant_text", "rollout_summary"]


def configure(p: argparse.ArgumentParser) -> None:
    """``regrasp simulate``'s arguments, on its parser."""
    p.add_argument("scenario", nargs="?", default=None,
                   help=f"scenario file (TOML); default: {DEFAULT_SCENARIO.name} from examples/scenarios")
    span = p.add_mutually_exclusive_group()
    span.add_argument("--periods", type=count_argument(1, MAX_COUNT), metavar="N",
                      help="run N periods of a periodic trajectory (past the scenario's t_end)")
    span.add_argument("--duration", type=positive(float), metavar="T", help="simulated time [s]")
    p.add_argument("--policy", choices=("scheduled", "paper", "none"), default="scheduled",
                   help="scheduled: plan the slides ahead, follow and re-plan them (default); paper: the paper's "
                        "danger-zone heuristic; none: never slide")
    add_plant_arguments(p)
    p.add_argument("--rrd", metavar="FILE", help="write a rerun recording to FILE")
    p.add_argument("--decimate", type=count_argument(1, MAX_COUNT), default=10, metavar="K",
                   help="record every K-th step (events at every step); default 10, a 10 ms row at 1 kHz, about "
                        "0.17 MB per simulated second; 1 records every step (about 1.5 MB per second)")
    view = p.add_mutually_exclusive_group()
    view.add_argument("--spawn", action="store_true", help="stream to a rerun viewer it starts")
    view.add_argument("--connect", metavar="ADDR", help="stream to a running rerun viewer at this gRPC address")
    p.add_argument("--json", action="store_true", help="print one JSON document on stdout")
    p.add_argument("--plant-mass-scale", type=positive(float), default=1.0, metavar="S",
                   help="the plant's object mass and inertia are S times the model's (the controllers keep the model)")
    p.add_argument("--plant-mu-scale", type=positive(float), default=1.0, metavar="S",
                   help="the plant's friction coefficients are S times the model's")
    p.add_argument("--envelope-margin", type=nonnegative, metavar="M",
                   help="scheduled: the envelope margin [m] the schedule keeps (default 0.001)")
    p.add_argument("--cone-margin", type=nonnegative, metavar="N",
                   help="scheduled: the cone margin [N] the schedule and the controllers keep (default 0.2)")
    p.add_argument("--plot", metavar="DIR", help="write regrasp_rollout.png (per finger: band, planned and actual "
                                                 "contact against time) into DIR")
    p.set_defaults(func=_cmd_simulate)


def plant_text(name: str, plant: PlantLike) -> str:
    """One line on the plant ``name`` (``"project"``, ``"mujoco"`` or ``"drake"``) built as ``plant``."""
    if name == "mujoco":
        s = plant.settings
        return (f"mujoco (sphere tips r = {s.tip_radius * 1e3:g} mm, soft contacts, MuJoCo step "
                f"{s.timestep * 1e3:g} ms)")
    if name == "drake":
        s = plant.settings
        return (f"drake (sphere tips r = {s.tip_radius * 1e3:g} mm, compliant point contacts k = "
                f"{s.point_contact_stiffness:g} N/m, d = {s.hunt_crossley_dissipation:g} s/m, {s.approximation} "
                f"approximation, Drake step {s.time_step * 1e3:g} ms)")
    pad = getattr(plant, "pad", None)
    if pad is not None:
        return (f"project (point contacts on compliant pads k = {pad.stiffness:g} N/m, c = {pad.damping:g} N s/m, "
                f"preload {pad.preload:g} N; the reference path)")
    return "project (point contacts, rigid)"


def rollout_summary(result: RolloutResult, scenario: Scenario, plant_line: str, started: float | None = None) -> str:
    """A rollout's result as ``regrasp simulate`` prints it (``plant_line``: :func:`plant_text`'s; ``started``: when
    the command started, ``time.monotonic()``, for the wall time in all, with imports, planning and compiling)."""
    mm = 1e3
    lines = [f"regrasp simulate: {scenario.name}" + (f" ({scenario.path})" if scenario.path else ""),
             f"  plant: {plant_line}",
             f"  policy: {result.policy}; simulated {result.simulated_seconds:.3f} of {result.duration:.3f} s "
             f"({result.steps} steps)"]
    sch = result.schedule
    if sch is not None:
        end = scenario.trajectory.t_start + result.duration
        kind = ("periodic" if sch.periodic else "not periodic") if sch.periodic or sch.t_end >= end - 1e-9 else \
            f"PARTIAL, until t = {sch.t_end:.3f} s (no schedule goes further)"
        lines.append(f"  schedule: {kind}, {len(sch.slides)} slides"
                     + (" per period" if sch.periodic else "") + (f" (no fewer possible than {sch.slides_lower_bound})"
                                                                  if sch.slides_lower_bound is not None else "")
                     + f"; planned smallest margins {sch.min_envelope_margin * mm:.2f} mm (envelope), "
                       f"{sch.min_cone_margin:.3f} N (cone)"
                     + (f"; planned in {sch.planning_seconds:.2f} s" if sch.planning_seconds > 0 else ""))
    if result.success:
        lines.append("  result: SUCCESS")
    else:
        f = result.failure
        lines.append(f"  result: FAILURE at t = {f.time:.3f} s ({f.kind.value}): {f.reason}")
    width = result.object_width
    err, rot = result.max_object_error_after_transient, result.max_orientation_error_after_transient
    rows = [
        ("object error after 0.5 s", "-" if err != err else f"{err * mm:.4f} mm max ({err / width:.2e} of the "
                                                              f"object's width), orientation {rot * 1e3:.3f} mrad"),
        ("slides", ", ".join(f"{n} {c}" for n, c in result.regrasps.items())),
        ("re-plans", str(result.replans)),
        ("smallest envelope margin", _smallest(result.min_envelope_margin, result.min_envelope_margin_at, mm,
                                               ".2f mm")),
        ("smallest cone margin (fixed)", _smallest(result.min_cone_margin, result.min_cone_margin_at, 1.0, ".3f N")),
        ("plant events", ", ".join(f"{k} {v}" for k, v in sorted(result.plant_event_counts().items())) or "none"),
        ("wall time", f"{result.wall_seconds:.2f} s for the run" + (f" ({result.realtime_factor:.2f}x real time)"
                                                                    if math.isfinite(result.realtime_factor) else "")
         + ("" if started is None else f"; {time.monotonic() - started:.1f} s in all, with the imports, planning "
                                       "and compiling kernels")),
    ]
    w = max(len(k) for k, _ in rows)
    lines += [f"  {k:<{w}}  {v}" for k, v in rows]
    lines += _health_lines(result)
    replans = [e for e in result.events if e.kind in (EventKind.REPLAN, EventKind.REPLAN_FAILED)]
    for e in replans[:5]:
        lines.append(f"  {e.kind.value} at t = {e.time:.3f} s: {e.detail}")
    if result.rrd:
        lines.append(f"  recording: {result.rrd} - open it with `rerun {result.rrd}` "
                     f"(or `rerun --web-viewer {result.rrd}` on a machine without a display)")
    return "\n".join(lines)


def _smallest(value: float, at: tuple[float, str], scale: float, form: str) -> str:
    """A smallest margin and where (``form``: its format and unit, ``".2f mm"``), or ``n/a`` when no step had one (no
    contact held fixed, a run of no step): never an inf or a NaN."""
    if not math.isfinite(value):
        return "n/a (no step measured one)"
    spec, unit = form.split(" ")
    return f"{value * scale:{spec}} {unit} ({at[1]}, t = {at[0]:.3f} s)"


def _health_lines(result) -> list[str]:
    """Each contact's health (:class:`~regrasp.core.health.ContactHealth`) as a small table."""
    if not result.health:
        return []

    def force(value: float, at: float) -> str:
        return "-" if value == float("inf") else f"{value:.3f} N (t = {at:.3f} s)"

    rows = [("contact", "least force held", "least force sliding (avg)", "longest without force", "largest slip held")]
    for h in result.health:
        zero = (f"{h.longest_zero_force * 1e3:.0f} ms (t = {h.longest_zero_force_at:.3f} s)" if h.longest_zero_force
                else "0 ms")
        rows.append((h.contact, force(h.least_held_force, h.least_held_force_at),
                     force(h.least_slider_force, h.least_slider_force_at), zero,
                     f"{h.largest_held_slip * 1e3:.4f} mm"))
    widths = [max(len(r[j]) for r in rows) for j in range(len(rows[0]))]
    return ["  contact health:"] + ["    " + "  ".join(f"{c:<{w}}" for c, w in zip(r, widths)).rstrip() for r in rows]


def _no_schedule_text(error, scenario) -> str:
    lines = [f"regrasp simulate: {scenario.name}" + (f" ({scenario.path})" if scenario.path else ""),
             f"  result: NO SCHEDULE ({error.limit.value}) - {error.reason}"]
    if error.rule:
        lines.append(f"    {error.rule}")
    lines.append(f"  the latest time any admissible state survives: t = {error.latest_time:.3f} s; "
                 "try --policy paper or --policy none to run anyway")
    return "\n".join(lines)


def _cmd_simulate(args: argparse.Namespace) -> int:
    from ..model.scenario import load_scenario
    from ..plants.spec import ModelErrors
    from ..rollout.spec import RunSpec
    from ..schedule.planner import RegraspSettings
    from ..supervisor.settings import SupervisorSettings

    path = args.scenario if args.scenario is not None else DEFAULT_SCENARIO
    if args.scenario is None and not DEFAULT_SCENARIO.is_file():
        raise InvalidParameterError("scenario", None, f"a scenario file (the default {DEFAULT_SCENARIO} is not "
                                    "here: regrasp is not installed from its source tree)")
    scenario = load_scenario(path)
    output_file("--rrd", args.rrd)  # (the outputs before any work: a run is never lost to its file)
    if args.connect is not None:
        from ..rollout.recording.options import as_viewer_url

        as_viewer_url("--connect", args.connect)
    if args.plot is not None:
        output_directory("--plot", args.plot)
    plant = replace(plant_spec(args), errors=ModelErrors(mass_scale=args.plant_mass_scale,
                                                         mu_scale=args.plant_mu_scale))
    cone = DEFAULT_CONE_MARGIN if args.cone_margin is None else args.cone_margin
    options = {"cone_margin": cone}
    if args.envelope_margin is not None:
        options["envelope_margin"] = args.envelope_margin
    # (the laws know the tips' radius)
    settings = SupervisorSettings.robust(scenario.geometry, cone, tip_radius=plant.tip_radius)
    common = dict(settings=settings, regrasp_settings=RegraspSettings.of(scenario, **options), plant=plant)
    run = RunSpec(periods=args.periods, duration=args.duration)
    run.resolve(scenario)  # (a run of no step, or past what the trajectory allows: refused before the plan)
    # (a machine's first run compiles them, in worker processes while this one plans: said, with progress)
    kernels = KernelLoad(quiet=args.json)
    # OSQP's C library prints "Polishing not needed" on fd 1 even with verbose=False: keep stdout for the result
    with captured_fd(1):
        code, output = _simulate(args, scenario, run, common, kernels)
    sys.stdout.write(output + "\n")
    return code


def _simulate(args, scenario, run, common, kernels: KernelLoad) -> tuple[int, str]:
    """Run the rollout (``kernels`` loaded before it): (exit status, what to print on stdout)."""
    from ..plants.simulation import InterruptAtStepEnd
    from ..rollout.build import build_rollout
    from ..schedule.schedule import NoScheduleError, ScheduleLimit

    quiet = args.json
    try:
        rollout = build_rollout(scenario, run, policy=args.policy, **common,
                                plan_progress=None if quiet else ProgressBar("planning regrasps"))
    except NoScheduleError as exc:
        if exc.limit is not ScheduleLimit.ENVELOPE or exc.partial is None:
            if args.json:
                return 1, json.dumps({"success": False, "policy": args.policy, "schedule": exc.to_json_dict(),
                                      "failure": {"time": exc.latest_time, "kind": FailureKind.NO_SCHEDULE.value,
                                                  "reason": str(exc), "contact": ", ".join(exc.contacts)}})
            return 1, _no_schedule_text(exc, scenario)
        # the envelope empties: run the best schedule up to then, and fail where the physics says so
        if not quiet:
            print(f"no schedule beyond t = {exc.latest_time:.3f} s ({exc.reason}); running the partial schedule",
                  file=sys.stderr)
        rollout = build_rollout(scenario, run, policy=args.policy, schedule=exc.partial, **common)
    kernels.finish(stretches=False)  # (the plant's constructor waited for them already, if it runs them)
    # Ctrl-C from here until the recording is closed ends the run at a step's end (never inside the recorder)
    with InterruptAtStepEnd():
        recorder = None
        if args.rrd is not None or args.spawn or args.connect:
            from ..rollout.recording.recorder import RolloutRecorder

            recorder = RolloutRecorder(rollout.plant, rrd_path=args.rrd, spawn=args.spawn, connect=args.connect,
                                       decimation=args.decimate, envelope_geometry=scenario.geometry,
                                       recording_name=f"{scenario.name} ({args.policy})")
        try:
            result = rollout.run(recorder=recorder, progress=None if quiet else ProgressBar("simulating"))
        finally:
            if recorder is not None:
                recorder.close()
    figures = []
    if args.plot is not None:
        from ..rollout.plots import plot_rollout

        figures.append(str(plot_rollout(result, Path(args.plot) / "regrasp_rollout.png", scenario=scenario,
                                        plant=args.plant)))
    code = 0 if result.success else 1
    if args.json:
        doc = result.to_json_dict()
        doc["plant"] = args.plant
        doc["figures"] = figures
        return code, json.dumps(doc)
    lines = ([rollout_summary(result, scenario, plant_text(args.plant, rollout.plant), STARTED)]
             + [f"  figure: {f}" for f in figures])
    if result.failure is not None and result.failure.kind is FailureKind.INTERRUPTED:
        lines.append("  (interrupted: the result and the recording cover the run so far)")
    return code, "\n".join(lines)


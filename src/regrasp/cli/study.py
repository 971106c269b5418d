"""``regrasp study``: many seeded rollouts under model errors and noise; the success rate and why runs failed.

``regrasp study [SCENARIO] --runs N [--seed S] [--workers K] [--ray [ADDRESS]] [--plant project|mujoco|drake]
[--periods P | --duration T] [--mass H] [--mu H] ... [--delay STEPS] [--json] [--plot DIR | --resume DIR]
[--sweep NAME=V1,V2,... | --replay I [--rrd FILE]]``

The perturbations default to the scenario's ``[study]`` table; a flag overrides its key.
Exit status: 0 the study ran (whatever its success rate), 2 bad input, 130 Ctrl-C (after the runs that finished
are summarised and, with ``--plot``, written: study.json and the figures); with ``--replay``, 0 or 1 as the run
succeeded or failed.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from ..core.exceptions import InvalidParameterError
from ..core.validation import MAX_COUNT, MAX_RUNS, MAX_SEED, MAX_WORKERS
from ..model.noise import MAX_DELAY_STEPS
from .common import (
    DEFAULT_SCENARIO,
    ProgressBar,
    add_plant_arguments,
    compile_kernels,
    count_argument,
    number_argument,
    output_directory,
    output_file,
    plant_spec,
    ray_address_argument,
)

if TYPE_CHECKING:
    from ..plants.spec import PlantSpec
    from ..study.study import StudyResult

__all__ = ["configure"]


def _at_most(limit: float, unit: str) -> Callable[[str], float]:
    return number_argument(float, f"a number in [0, {limit:g}] [{unit}]", lambda v: 0.0 <= v <= limit)


_half_width = number_argument(float, "a relative half-width in [0, 1)", lambda v: 0.0 <= v < 1.0)
_seconds = number_argument(float, "a finite duration > 0 [s]", lambda v: 0.0 < v < float("inf"))
#: Default runs of a study.
RUNS = 20


#: Each perturbation's flag: (metavar, help, argument type); the bounds are the library's.
_FLAGS = {
    "mass": ("H", "the plant's object mass: the model's times U(1-H, 1+H)", _half_width),
    "inertia": ("H", "the plant's object inertia: the model's times U(1-H, 1+H), drawn on its own", _half_width),
    "mu": ("H", "the plant's mu_s and mu_k: the model's times U(1-H, 1+H)", _half_width),
    "mu_kinetic": ("H", "the plant's mu_k alone, times U(1-H, 1+H) more (at most the plant's mu_s)", _half_width),
    "link_mass": ("H", "the plant's finger link masses and inertias: the URDFs' times U(1-H, 1+H)", _half_width),
    "contact_position": ("M", "each fingertip placed U(-M, M) [m] off its planned xi (the supervisor believes the "
                              "plan)", _at_most(0.01, "m")),
    "position_noise": ("M", "object position sensing noise, standard deviation [m]", _at_most(0.1, "m")),
    "angle_noise": ("RAD", "object angle sensing noise [rad]", _at_most(3.2, "rad")),
    "velocity_noise": ("M/S", "object velocity sensing noise [m/s]", _at_most(10.0, "m/s")),
    "angular_velocity_noise": ("RAD/S", "object angular velocity sensing noise [rad/s]", _at_most(100.0, "rad/s")),
    "xi_noise": ("M", "contact position (xi) sensing noise [m]", _at_most(0.1, "m")),
    "xi_dot_noise": ("M/S", "contact rate sensing noise [m/s]", _at_most(10.0, "m/s")),
    "force_noise": ("N", "contact force sensing noise [N]", _at_most(100.0, "N")),
    "slip_threshold": ("M/S", "the slip sensor reports sliding above this |xi_dot| [m/s] (default: a perfect "
                              "slip sensor)", _at_most(10.0, "m/s")),
    "slip_delay": ("STEPS", "the slip sensor's delay [control steps]", count_argument(0, MAX_DELAY_STEPS)),
    "torque_noise": ("NM", "joint torque noise, standard deviation [N m]", _at_most(10.0, "N m")),
    "delay": ("STEPS", "actuation delay: each torque is applied STEPS control steps late",
              count_argument(0, MAX_DELAY_STEPS)),
}


def _sweep(text: str) -> tuple[str, tuple[float, ...]]:
    """``NAME=V1,V2,...`` as (the Perturbation field, the sizes); argparse turns an error into exit 2."""
    name, _, values = text.partition("=")
    name = name.strip().lstrip("-").replace("-", "_")
    if name not in _FLAGS or not values:
        raise argparse.ArgumentTypeError(f"expected NAME=V1,V2,... with NAME one of {', '.join(_FLAGS)}, got {text!r}")
    _, _, kind = _FLAGS[name]
    try:
        sizes = tuple(kind(v.strip()) for v in values.split(","))
    except argparse.ArgumentTypeError as exc:
        raise argparse.ArgumentTypeError(f"--sweep {name}: {exc}") from None
    if len(sizes) > 100:
        raise argparse.ArgumentTypeError(f"expected at most 100 sizes, got {len(sizes)}")
    return name, sizes


def configure(p: argparse.ArgumentParser) -> None:
    """``regrasp study``'s arguments, on its parser."""
    p.add_argument("scenario", nargs="?", default=None,
                   help=f"scenario file (TOML); default: {DEFAULT_SCENARIO.name} from examples/scenarios")
    p.add_argument("--runs", type=count_argument(1, MAX_RUNS), default=None, metavar="N",
                   help=f"number of runs (default {RUNS})")
    p.add_argument("--seed", type=count_argument(0, MAX_SEED), default=0, metavar="S",
                   help="the study's seed (default 0)")
    p.add_argument("--workers", type=count_argument(1, MAX_WORKERS), default=None, metavar="K",
                   help="worker processes (default: one per core); the results do not depend on it")
    p.add_argument("--ray", nargs="?", const="local", default=None, metavar="ADDRESS", type=ray_address_argument,
                   help="run on Ray: a local cluster of --workers CPUs, or the cluster at ADDRESS ('auto', HOST:PORT "
                        "or ray://HOST[:PORT], reached within seconds before the plan); the results are the same as "
                        "on processes")
    add_plant_arguments(p)
    p.add_argument("--fixed-softness", action="store_true",
                   help="--plant mujoco: keep MuJoCo's default contact softness in every run (default: each run draws "
                        "its solref time constant 0.25-2 ms, solimp width 0.05-0.5 mm and tip radius 0.1-1 mm; "
                        "--tip-radius fixes the radius)")
    span = p.add_mutually_exclusive_group()
    span.add_argument("--periods", type=count_argument(1, MAX_COUNT), metavar="P",
                      help="each run: P periods of the trajectory")
    span.add_argument("--duration", type=_seconds, metavar="T", help="each run: T seconds")
    for name, (metavar, text, kind) in _FLAGS.items():
        p.add_argument("--" + name.replace("_", "-"), dest=name, type=kind, default=None, metavar=metavar, help=text)
    p.add_argument("--json", action="store_true", help="print one JSON document on stdout")
    p.add_argument("--plot", metavar="DIR", help="write the study's figures (PNG) and study.json into DIR")
    p.add_argument("--sweep", type=_sweep, metavar="NAME=V1,V2,...",
                   help="one study per size of one perturbation (a flag's name, e.g. xi-noise=0,1e-4,2e-4), the others "
                        "as given: the success rate against that size (--plot: study_sweep.png)")
    p.add_argument("--replay", type=count_argument(0, MAX_RUNS - 1), metavar="I",
                   help="run only run I of this study (the same seed and perturbations; I < --runs if given) and print "
                        "its rollout; exit status 0 if it succeeds, 1 if it fails (not with --workers, --ray, --plot "
                        "or --sweep)")
    p.add_argument("--rrd", metavar="FILE", help="with --replay: write the run to a rerun recording")
    p.add_argument("--resume", metavar="DIR",
                   help="go on with the study whose study.json is in DIR (one Ctrl-C stopped, or one of fewer --runs): "
                        "the same command and flags, its finished runs kept and the others run, written back into DIR "
                        "(--runs defaults to the runs it was asked for)")
    p.set_defaults(func=_cmd_study)


def _summary(result: StudyResult) -> str:
    import numpy as np

    lo, hi = result.interval
    runs = result.runs
    counted = f"{len(runs)} of {result.requested_runs} runs" if result.interrupted else f"{len(runs)} runs"
    lines = [f"regrasp study: {Path(result.scenario).name} on the {result.plant} plant, {counted} of "
             f"{result.duration:.4g} s, seed "
             f"{result.seed}: {result.perturbation.describe()}"
             + ("" if result.softness is None else f"; {result.softness.describe()}")]
    if result.interrupted:
        lines.append(f"  interrupted (Ctrl-C): {len(runs)} of {result.requested_runs} runs had finished; the runs "
                     "under way were dropped, and the numbers below are over the finished ones")
    if not runs:
        return "\n".join(lines)
    lines.append(f"  success: {result.successes}/{len(runs)} = {result.success_rate:.1%} (Wilson 95 %: "
                 f"[{lo:.1%}, {hi:.1%}])")
    for kind, count in sorted(result.failures.items()):
        times = sorted(r.failure_time for r in runs if r.failure_kind == kind)
        lines.append(f"  failed, {kind}: {count} (at t = {', '.join(f'{t:.3f}' for t in times[:8])}"
                     f"{', ...' if len(times) > 8 else ''} s)")
    errors = np.array([r.max_object_error for r in runs if r.max_object_error is not None]) * 1e3
    turns = np.array([r.max_orientation_error for r in runs if r.max_orientation_error is not None]) * 1e3
    lines.append("  smallest cone margin [N]: " + _spread([r.min_cone_margin for r in runs], 1.0, ".3f"))
    lines.append("  smallest envelope margin [mm]: " + _spread([r.min_envelope_margin for r in runs], 1e3, ".2f"))
    if errors.size:
        turned = f"; orientation [mrad]: median {np.median(turns):.1f}, max {turns.max():.1f}" if turns.size else ""
        lines.append(f"  largest object error after 0.5 s [mm]: median {np.median(errors):.3f}, max {errors.max():.3f}"
                     + turned)
    lines.append(f"  wall time: {result.wall_seconds:.1f} s ({result.plan_seconds:.1f} s planning) on "
                 f"{result.workers} {'Ray CPU' if result.backend == 'ray' else 'worker'}(s)")
    return "\n".join(lines)


def _spread(values: list[float | None], scale: float, form: str) -> str:
    """``min M, 5 % Q, median D`` of the runs' values that were measured (None: a run with no step that measured one),
    with how many were not; ``n/a`` when none was."""
    import numpy as np

    measured = np.array([v for v in values if v is not None], dtype=float) * scale
    missing = len(values) - measured.size
    if not measured.size:
        return "n/a (no run measured one)"
    return (f"min {measured.min():{form}}, 5 % {np.percentile(measured, 5):{form}}, median {np.median(measured):{form}}"
            + (f" ({missing} run(s) measured none)" if missing else ""))


def _softness(args: argparse.Namespace):
    """The ranges the runs draw their contact softness from: on MuJoCo unless ``--fixed-softness`` (a
    ``--tip-radius`` fixes the radius), else None."""
    if args.plant != "mujoco" or args.fixed_softness:
        return None
    from ..model.softness import SoftnessRanges

    if args.tip_radius is None:
        return SoftnessRanges()
    radius = args.tip_radius * 1e-3
    return SoftnessRanges(tip_radius=(radius, radius))


def _replay(args: argparse.Namespace, scenario, perturbation, plant: PlantSpec) -> int:
    """``--replay I``: run I of the study alone, printed as ``regrasp simulate`` prints a rollout (and recorded)."""
    from ..rollout.spec import RunSpec
    from ..schedule.planner import plan_regrasps
    from ..study.draws import draw_runs
    from ..study.study import build_run
    from .simulate import plant_text, rollout_summary

    draw = draw_runs(args.replay + 1, args.seed, perturbation, len(scenario.contacts), _softness(args))[args.replay]
    _, duration = RunSpec(duration=args.duration, periods=args.periods).resolve(scenario)  # (before the plan)
    schedule = plan_regrasps(scenario, progress=None if args.json else ProgressBar("planning regrasps"))
    rollout = build_run(scenario, draw, schedule, duration, perturbation, plant=plant)
    recorder = None
    if args.rrd is not None:
        from ..rollout.recording.recorder import RolloutRecorder

        recorder = RolloutRecorder(rollout.plant, rrd_path=args.rrd, envelope_geometry=scenario.geometry,
                                   recording_name=f"{scenario.name}, study seed {args.seed}, run {args.replay}")
    try:
        result = rollout.run(recorder=recorder, progress=None if args.json else ProgressBar("simulating"))
    finally:
        if recorder is not None:
            recorder.close()
    if args.json:
        doc = result.to_json_dict()
        doc.update(plant=plant.kind, run=args.replay, seed=args.seed, draw=draw.to_json_dict())
        json.dump(doc, sys.stdout)
        sys.stdout.write("\n")
    else:
        e = draw.errors
        factors = (f"mass x{e.mass_scale:.3f}, inertia x{e.object_inertia_scale:.3f}, mu x{e.mu_scale:.3f}, "
                   f"placement {', '.join(f'{x * 1e3:+.3f}' for x in e.xi_offset)} mm")
        if draw.softness is not None:
            soft = draw.softness
            factors += (f", solref {soft.time_constant * 1e3:.3f} ms, solimp width {soft.solimp_width * 1e3:.3f} mm, "
                        f"tip radius {soft.tip_radius * 1e3:.3f} mm")
        print(f"run {args.replay} of seed {args.seed} ({perturbation.describe()}): {factors}")
        print(rollout_summary(result, scenario, plant_text(plant.kind, rollout.plant)))
    return 0 if result.success else 1


def _sweep_study(args: argparse.Namespace, scenario, perturbation, plant: PlantSpec) -> int:
    """``--sweep NAME=V1,...``: one study per size, a line each (and study_sweep.png, study_sweep.json)."""
    from ..study.plots import plot_sweep
    from ..study.study import sweep_study

    name, values = args.sweep
    directory = output_directory("--plot", args.plot) if args.plot is not None else None
    workers = args.workers if args.workers is not None else (os.cpu_count() or 1)
    results = sweep_study(scenario, args.runs, name, values, perturbation=perturbation, seed=args.seed,
                          duration=args.duration, periods=args.periods, workers=min(workers, args.runs),
                          ray_address=args.ray, plant=plant, softness=_softness(args), interruptible=True,
                          progress=None if args.json else
                          ProgressBar(f"regrasp study: {len(values)} x {args.runs} runs", lines=True))
    interrupted = len(results) < len(values) or results[-1].interrupted
    doc = {"sweep": name, "values": list(values), "studies": [r.to_json_dict() for r in results]}
    if directory is not None:
        (directory / "study_sweep.json").write_text(json.dumps(doc) + "\n", encoding="utf-8")  # results first
        doc["figures"] = [str(plot_sweep(name, results, directory / "study_sweep.png",
                                               gravity=scenario.gravity_in_hand))]
        (directory / "study_sweep.json").write_text(json.dumps(doc) + "\n", encoding="utf-8")
    if args.json:
        json.dump(doc, sys.stdout)
        sys.stdout.write("\n")
        return 130 if interrupted else 0
    print(f"regrasp study --sweep {name}: {len(values)} studies of {args.runs} runs, seed {args.seed}; besides "
          f"{name}: "
          f"{replace(perturbation, **{name: type(perturbation).__dataclass_fields__[name].default}).describe()}")
    for value, r in zip(values, results):
        lo, hi = r.interval
        failures = ", ".join(f"{k} {v}" for k, v in sorted(r.failures.items())) or "none"
        cut = f" (interrupted: {len(r.runs)} of {r.requested_runs} runs finished)" if r.interrupted else ""
        print(f"  {name} = {value:<10g} success {r.successes}/{len(r.runs)} (Wilson 95 %: [{lo:.1%}, {hi:.1%}]); "
              f"failures: {failures}{cut}")
    if interrupted:
        print(f"  interrupted (Ctrl-C) after {len(results)} of {len(values)} sizes")
    for f in doc.get("figures", []):
        print(f"  figure: {f}")
    return 130 if interrupted else 0


def _perturbation(args: argparse.Namespace, scenario) -> object:
    """The scenario's [study] perturbation with the flags given on the command line."""
    given = {name: getattr(args, name) for name in _FLAGS if getattr(args, name) is not None}
    return replace(scenario.study, **given)


def _check_combination(args: argparse.Namespace) -> None:
    """The flags that mean nothing together, refused before any work: ``--rrd`` without ``--replay``; with
    ``--replay``, a study's own flags (``--sweep``, ``--workers``, ``--ray``, ``--plot``: a replay is one run, here)
    and a run past ``--runs``; ``--fixed-softness`` off MuJoCo."""
    if args.fixed_softness and args.plant != "mujoco":
        raise InvalidParameterError("--fixed-softness", True, f"--plant mujoco (only MuJoCo's contacts have a softness "
                                    f"to draw; the {args.plant} plant's is fixed)")
    if args.resume is not None and (args.sweep is not None or args.replay is not None):
        raise InvalidParameterError("--resume", args.resume, "a study to go on with (not with --sweep or --replay)")
    if args.resume is not None and args.plot is not None and Path(args.plot).resolve() != Path(args.resume).resolve():
        raise InvalidParameterError("--plot", args.plot, f"the directory --resume writes back into ({args.resume}), "
                                    "or no --plot")
    if args.replay is None:
        if args.rrd is not None:
            raise InvalidParameterError("--rrd", args.rrd, "--replay I (a study records no run; replay one)")
        return
    for flag, value in (("--sweep", args.sweep), ("--workers", args.workers), ("--ray", args.ray),
                        ("--plot", args.plot)):
        if value is not None:
            raise InvalidParameterError("--replay", args.replay, f"a run of one study, alone in this process (not with "
                                        f"{flag})")
    if args.runs is not None and args.replay >= args.runs:
        raise InvalidParameterError("--replay", args.replay, f"a run of this study's {args.runs} (0 to "
                                    f"{args.runs - 1})")


def _cmd_study(args: argparse.Namespace) -> int:
    from ..core.validation import as_count
    from ..model.scenario import load_scenario
    from ..rollout.spec import RunSpec
    from ..study.plots import plot_study
    from ..study.resume import finished_runs, read_study
    from ..study.study import run_study

    path = Path(args.scenario) if args.scenario is not None else DEFAULT_SCENARIO
    scenario = load_scenario(path)  # a bad file is exit 2 before any work
    perturbation = _perturbation(args, scenario)
    plant = plant_spec(args)
    _check_combination(args)
    compile_kernels(quiet=args.json)  # (a machine's first run compiles them: said, not a silent minute)
    if args.replay is not None:
        output_file("--rrd", args.rrd)
        return _replay(args, scenario, perturbation, plant)
    doc = None if args.resume is None else read_study(args.resume, "--resume")
    if args.runs is None:
        args.runs = RUNS if doc is None else as_count("--runs", doc.get("requested_runs", doc.get("runs")), 1,
                                                      MAX_RUNS)
    if args.sweep is not None:
        return _sweep_study(args, scenario, perturbation, plant)
    finished = ()
    if doc is not None:
        _, duration = RunSpec(periods=args.periods, duration=args.duration).resolve(scenario)
        finished = finished_runs(doc, scenario=str(path), contacts=len(scenario.contacts), plant=plant.kind,
                                 duration=duration, seed=args.seed, runs=args.runs, perturbation=perturbation,
                                 softness=_softness(args), option="--resume")
        args.plot = args.resume
    directory = output_directory("--plot", args.plot) if args.plot is not None else None
    workers = args.workers if args.workers is not None else (os.cpu_count() or 1)
    result = run_study(scenario, args.runs, seed=args.seed, perturbation=perturbation, duration=args.duration,
                       periods=args.periods, workers=min(workers, args.runs), ray_address=args.ray, plant=plant,
                       softness=_softness(args), interruptible=True, finished=finished,
                       progress=None if args.json else ProgressBar(f"regrasp study: {args.runs} runs", lines=True))
    resumed = ""
    if doc is not None:  # (the wall time of every session the study took)
        result = replace(result, wall_seconds=result.wall_seconds + float(doc.get("wall_seconds") or 0.0),
                         plan_seconds=result.plan_seconds + float(doc.get("plan_seconds") or 0.0))
        resumed = (f"\n  resumed: {len(finished)} runs read from {Path(args.resume) / 'study.json'}, "
                   f"{len(result.runs) - len(finished)} run now (wall times: every session's)")
    doc = result.to_json_dict()
    figures = []
    if directory is not None:
        # the results first: a long study is never lost to a figure
        (directory / "study.json").write_text(json.dumps(doc) + "\n", encoding="utf-8")
        figures = plot_study(result, directory, gravity=scenario.gravity_in_hand)
        doc["figures"] = [str(f) for f in figures]
        (directory / "study.json").write_text(json.dumps(doc) + "\n", encoding="utf-8")
    if args.json:
        json.dump(doc, sys.stdout)
        sys.stdout.write("\n")
    else:
        print(_summary(result) + resumed + "".join(f"\n  figure: {f}" for f in figures)
              + (f"\n  results: {directory / 'study.json'}" if directory is not None else ""))
    return 130 if result.interrupted else 0

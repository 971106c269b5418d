"""``regrasp study``: many seeded rollouts under drawn model errors; the success rate and why runs failed.

``regrasp study [SCENARIO] --runs N [--seed S] [--workers K] [--periods P | --duration T] [--mass H] [--mu H]
[--json] [--plot DIR]``

Exit status: 0 the study ran (whatever its success rate), 2 bad input.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from ._cli_args import number_argument

if TYPE_CHECKING:
    from .study import StudyResult

__all__ = ["add_study_parser"]


def _count(least: int) -> Callable[[str], int]:
    return number_argument(int, f"an integer >= {least}", lambda v: v >= least)


_half_width = number_argument(float, "a relative half-width in [0, 1)", lambda v: 0.0 <= v < 1.0)
_seconds = number_argument(float, "a finite duration > 0 [s]", lambda v: 0.0 < v < float("inf"))


def add_study_parser(sub: argparse._SubParsersAction,
                     progress_bar: Callable[[str], Callable[[int, int], None]]) -> None:
    """Register ``study`` on the ``regrasp`` parser's subparsers."""
    from .cli_simulate import DEFAULT_SCENARIO

    p = sub.add_parser("study", help="a robustness study: many seeded rollouts under drawn model errors",
                       description="Plan the regrasp schedule once, then run seeded rollouts whose plant's object mass "
                                   "and friction are drawn around the model's. Prints the success rate with a Wilson "
                                   "95 % interval and the failures by kind. Exit status 0: the study ran, "
                                   "2: bad input.")
    p.add_argument("scenario", nargs="?", default=None,
                   help=f"scenario file (TOML); default: {DEFAULT_SCENARIO.name} from examples/scenarios")
    p.add_argument("--runs", type=_count(1), default=20, metavar="N", help="number of runs (default 20)")
    p.add_argument("--seed", type=_count(0), default=0, metavar="S", help="the study's seed (default 0)")
    p.add_argument("--workers", type=_count(1), default=None, metavar="K",
                   help="worker processes (default: one per core); the results do not depend on it")
    span = p.add_mutually_exclusive_group()
    span.add_argument("--periods", type=_count(1), metavar="P", help="each run: P periods of the trajectory")
    span.add_argument("--duration", type=_seconds, metavar="T", help="each run: T seconds")
    p.add_argument("--mass", type=_half_width, default=0.0, metavar="H",
                   help="the plant's object mass and inertia: the model's times U(1-H, 1+H) (default 0)")
    p.add_argument("--mu", type=_half_width, default=0.0, metavar="H",
                   help="the plant's friction coefficients: the model's times U(1-H, 1+H) (default 0)")
    p.add_argument("--inertia", type=_half_width, default=0.0, metavar="H",
                   help="the plant's object inertia: the model's times U(1-H, 1+H), drawn on its own (default 0)")
    p.add_argument("--link-mass", type=_half_width, default=0.0, metavar="H",
                   help="the plant's finger link masses and inertias: the URDFs' times U(1-H, 1+H) (default 0)")
    p.add_argument("--json", action="store_true", help="print one JSON document on stdout")
    p.add_argument("--plot", metavar="DIR", help="write study_outcomes.png and study_failure_times.png into DIR")
    p.set_defaults(func=lambda args: _cmd_study(args, progress_bar))


def _summary(result: StudyResult) -> str:
    from dataclasses import asdict

    import numpy as np

    lo, hi = result.interval
    runs = result.runs
    lines = [f"regrasp study: {Path(result.scenario).name}, {len(runs)} runs of {result.duration:.4g} s, seed "
             f"{result.seed}, " + ", ".join(f"{k} ±{v:.0%}" for k, v in asdict(result.perturbation).items()),
             f"  success: {result.successes}/{len(runs)} = {result.success_rate:.1%} (Wilson 95 %: "
             f"[{lo:.1%}, {hi:.1%}])"]
    for kind, count in sorted(result.failures.items()):
        times = sorted(r.failure_time for r in runs if r.failure_kind == kind)
        lines.append(f"  failed, {kind}: {count} (at t = {', '.join(f'{t:.3f}' for t in times[:8])}"
                     f"{', ...' if len(times) > 8 else ''} s)")
    cone = np.array([r.min_cone_margin for r in runs])
    env = np.array([r.min_envelope_margin for r in runs]) * 1e3
    lines.append(f"  smallest cone margin [N]: min {cone.min():.3f}, median {np.median(cone):.3f}")
    lines.append(f"  smallest envelope margin [mm]: min {env.min():.2f}, median {np.median(env):.2f}")
    lines.append(f"  wall time: {result.wall_seconds:.1f} s on {result.workers} worker(s)")
    return "\n".join(lines)


def _plots(result: StudyResult, directory: Path) -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = [r for r in result.runs if r.success]
    bad = [r for r in result.runs if not r.success]
    fig, ax = plt.subplots(figsize=(5.5, 4.5))
    ax.scatter([r.draw.mass_scale for r in ok], [r.draw.mu_scale for r in ok], marker="o", label="success")
    ax.scatter([r.draw.mass_scale for r in bad], [r.draw.mu_scale for r in bad], marker="x", color="C3",
               label="failure")
    ax.set_xlabel("plant mass / model mass [-]")
    ax.set_ylabel("plant μ / model μ [-]")
    ax.set_title(f"{result.successes}/{len(result.runs)} succeeded")
    ax.legend()
    outcomes = directory / "study_outcomes.png"
    fig.savefig(outcomes, dpi=120, bbox_inches="tight")
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(5.5, 3.5))
    ax.hist([r.failure_time for r in bad], bins=20, range=(0.0, result.duration))
    ax.set_xlabel("failure time [s]")
    ax.set_ylabel("runs")
    ax.yaxis.set_major_locator(matplotlib.ticker.MaxNLocator(integer=True))
    ax.set_title(f"{len(bad)} failures")
    times = directory / "study_failure_times.png"
    fig.savefig(times, dpi=120, bbox_inches="tight")
    plt.close(fig)
    return [outcomes, times]


def _cmd_study(args: argparse.Namespace, progress_bar: Callable[[str], Callable[[int, int], None]]) -> int:
    from .cli import output_directory
    from .cli_simulate import DEFAULT_SCENARIO
    from .scenario import load_scenario
    from .study import Perturbation, run_study

    path = Path(args.scenario) if args.scenario is not None else DEFAULT_SCENARIO
    load_scenario(path)  # a bad file is exit 2 before any work
    directory = output_directory("--plot", args.plot) if args.plot else None
    workers = args.workers if args.workers is not None else (os.cpu_count() or 1)
    result = run_study(path, args.runs, seed=args.seed, perturbation=Perturbation(args.mass, args.mu, args.inertia, args.link_mass),
                       duration=args.duration, periods=args.periods, workers=min(workers, args.runs),
                       progress=None if args.json else progress_bar(f"{args.runs} runs"))
    figures = _plots(result, directory) if directory is not None else []
    if args.json:
        doc = result.to_json_dict()
        doc["figures"] = [str(f) for f in figures]
        json.dump(doc, sys.stdout)
        sys.stdout.write("\n")
    else:
        print(_summary(result) + "".join(f"\n  figure: {f}" for f in figures))
    return 0

"""``regrasp suite``: variants of a scenario drawn from a spec's ranges, each planned and run on the plant; the
fraction with a schedule, why the others have none, success given a schedule, the planning time and memory.

``regrasp suite [SPEC] [--variants N] [--seed S] [--workers K] [--ray [ADDRESS]] [--plant project|mujoco|drake]
[--periods P] [--plan-only] [--json] [--plot DIR]``

Default SPEC: the shipped ``examples/suites/default.toml``. Exit status: 0 the suite ran (whatever its results),
2 bad input (a spec's bad key names it), 130 Ctrl-C (after the variants that finished are summarised and, with
``--plot``, written: suite.json and the figures).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from ..core.exceptions import InvalidParameterError
from ..core.validation import MAX_COUNT, MAX_RUNS, MAX_SEED, MAX_WORKERS
from .common import (
    DEFAULT_SUITE,
    ProgressBar,
    add_plant_arguments,
    compile_kernels,
    count_argument,
    output_directory,
    plant_spec,
    ray_address_argument,
)

if TYPE_CHECKING:
    from ..suite.result import SuiteResult
    from ..suite.spec import SuiteSpec

__all__ = ["configure", "suite_summary"]


def configure(p: argparse.ArgumentParser) -> None:
    """``regrasp suite``'s arguments, on its parser."""
    p.add_argument("spec", nargs="?", default=None,
                   help=f"suite spec (TOML); default: {DEFAULT_SUITE.name} from examples/suites")
    p.add_argument("--variants", type=count_argument(1, MAX_RUNS), default=None, metavar="N",
                   help="draw N variants (default: the spec's 'variants'); variant i is the same whatever N")
    p.add_argument("--seed", type=count_argument(0, MAX_SEED), default=None, metavar="S",
                   help="the suite's seed (default: the spec's 'seed')")
    p.add_argument("--workers", type=count_argument(1, MAX_WORKERS), default=None, metavar="K",
                   help="worker processes (default: one per core); the results but the timings do not depend on it")
    p.add_argument("--ray", nargs="?", const="local", default=None, metavar="ADDRESS", type=ray_address_argument,
                   help="run on Ray: a local cluster of --workers CPUs, or the cluster at ADDRESS ('auto', HOST:PORT "
                        "or ray://HOST[:PORT], reached within seconds first; its workers need the spec's files at the "
                        "same paths)")
    add_plant_arguments(p)
    p.add_argument("--periods", type=count_argument(1, MAX_COUNT), default=2, metavar="P",
                   help="each scheduled variant runs P periods of its trajectory (default 2; a trajectory that is not "
                        "periodic: its whole domain)")
    p.add_argument("--plan-only", action="store_true", help="plan every variant, run none on the plant")
    p.add_argument("--json", action="store_true", help="print one JSON document on stdout")
    p.add_argument("--plot", metavar="DIR", help="write suite.json and the suite's figures (PNG) into DIR")
    p.set_defaults(func=_cmd_suite)


def _spread(stats: dict[str, float] | None, scale: float, form: str) -> str:
    if stats is None:
        return "n/a (no variant was planned)"
    return ", ".join(f"{label} {value * scale:{form}}" for label, value in stats.items())


def _indices(indices: tuple[int, ...] | list[int]) -> str:
    shown = ", ".join(str(i) for i in indices[:12])
    return f"variant{'s' if len(indices) > 1 else ''} {shown}{', ...' if len(indices) > 12 else ''}"


def _shown(path: str) -> str:
    """``path`` relative to the working directory when it is under it, else as it is."""
    try:
        return str(Path(path).resolve().relative_to(Path.cwd()))
    except (ValueError, OSError):
        return path


def suite_summary(result: SuiteResult, spec: SuiteSpec | None = None) -> str:
    """A suite's result as ``regrasp suite`` prints it (``spec``: the drawn ranges too)."""
    n = len(result.outcomes)
    counted = f"{n} of {result.requested} variants" if result.interrupted else f"{n} variants"
    where = "planned only" if result.plan_only else f"{result.periods} period(s) each on the {result.plant} plant"
    lines = [f"regrasp suite: {result.name} ({_shown(result.spec)}): {counted} of {Path(result.scenario).name}, seed "
             f"{result.seed}, {where}"]
    if spec is not None and spec.varied:
        lines.append("  varied: " + "; ".join(f"{v.key} {v.describe()}" for v in spec.varied))
    if result.interrupted:
        lines.append(f"  interrupted (Ctrl-C): {n} of {result.requested} variants had finished; those under way were "
                     "dropped, and the numbers below are over the finished ones")
    if not n:
        return "\n".join(lines)
    scheduled = len(result.scheduled)
    lo, hi = result.schedule_interval
    lines.append(f"  with a schedule: {scheduled}/{n} = {scheduled / n:.1%} (Wilson 95 %: [{lo:.1%}, {hi:.1%}])")
    for status, limit, contacts, indices in result.reasons:
        what = "no schedule" if status == "no_schedule" else "refused"
        names = f" ({', '.join(contacts)})" if contacts else ""
        lines.append(f"    {what}, {limit}{names}: {len(indices)} ({_indices(indices)})")
    unexplained = [o.index for o in result.unexplained]
    lines.append("  without a schedule and without a physical reason: "
                 + (f"{len(unexplained)} ({_indices(unexplained)})" if unexplained else "none"))
    ran = result.ran
    if ran:
        slo, shi = result.success_interval
        lines.append(f"  success given a schedule: {result.successes}/{len(ran)} = {result.successes / len(ran):.1%} "
                     f"(Wilson 95 %: [{slo:.1%}, {shi:.1%}])")
        for kind, count in sorted(result.failures.items()):
            failed = [o for o in ran if not o.success and str(o.failure_kind) == kind]
            times = ", ".join(f"{o.index} at t = {o.failure_time:.3f} s" if o.failure_time is not None else
                              str(o.index) for o in failed[:8])
            lines.append(f"    failed, {kind}: {count} (variant{'s' if count > 1 else ''} {times}"
                         f"{', ...' if len(failed) > 8 else ''})")
    elif not result.plan_only and scheduled:
        lines.append("  success given a schedule: n/a (no rollout finished)")
    cold = sum(o.cold for o in result.outcomes if o.plan_seconds is not None)
    lines.append(f"  planning time [s] (envelope and schedule): {_spread(result.plan_seconds, 1.0, '.2f')}"
                 + (f" ({cold} the first plan in its process)" if cold else ""))
    bound = any(o.memory_upper_bound for o in result.outcomes)
    lines.append(f"  peak memory while planning [MiB] (the worker's peak RSS{', an upper bound' if bound else ''}): "
                 f"{_spread(result.peak_memory, 2.0**-20, '.0f')}")
    lines.append(f"  wall time: {result.wall_seconds:.1f} s on {result.workers} "
                 f"{'Ray CPU' if result.backend == 'ray' else 'worker'}(s)")
    return "\n".join(lines)


def _cmd_suite(args: argparse.Namespace) -> int:
    from ..suite.plots import plot_suite
    from ..suite.run import run_suite
    from ..suite.spec import load_suite_spec

    path = Path(args.spec) if args.spec is not None else DEFAULT_SUITE
    if args.spec is None and not DEFAULT_SUITE.is_file():
        raise InvalidParameterError("spec", None, f"a suite spec (the default {DEFAULT_SUITE} is not here: regrasp "
                                    "is not installed from its source tree)")
    spec = load_suite_spec(path)  # a bad spec is exit 2 before any work
    changes = {k: v for k, v in (("variants", args.variants), ("seed", args.seed)) if v is not None}
    spec = replace(spec, **changes) if changes else spec
    plant = plant_spec(args)
    directory = output_directory("--plot", args.plot) if args.plot is not None else None
    compile_kernels(quiet=args.json)  # (a machine's first run compiles them: said, not a silent minute)
    workers = args.workers if args.workers is not None else (os.cpu_count() or 1)
    result = run_suite(spec, workers=min(workers, spec.variants), ray_address=args.ray, plant=plant,
                       periods=args.periods, plan_only=args.plan_only, interruptible=True,
                       progress=None if args.json else ProgressBar(f"regrasp suite: {spec.variants} variants",
                                                                   lines=True))
    doc = result.to_json_dict()
    figures = []
    if directory is not None:  # (the results first: a long suite is never lost to a figure)
        (directory / "suite.json").write_text(json.dumps(doc) + "\n", encoding="utf-8")
        figures = plot_suite(result, directory)
        doc["figures"] = [str(f) for f in figures]
        (directory / "suite.json").write_text(json.dumps(doc) + "\n", encoding="utf-8")
    if args.json:
        json.dump(doc, sys.stdout)
        sys.stdout.write("\n")
    else:
        print(suite_summary(result, spec) + "".join(f"\n  figure: {f}" for f in figures)
              + (f"\n  results: {directory / 'suite.json'}" if directory is not None else ""))
    return 130 if result.interrupted else 0

r"""Benchmark: the planning time and peak memory of a suite's variants (issue 27, item 4's target: three fingers
within 10 s at the 95th percentile).

What is measured
----------------
The variants of a suite spec (default: ``examples/suites/default.toml``, the first ``--variants N`` of them) are
planned, not run: ``run_suite(spec, plan_only=True, workers=K)`` (:mod:`regrasp.suite.run`). Each variant's planning
is the envelope plan and the regrasp schedule, timed with ``time.perf_counter`` around both; its peak memory is the
worker process's peak resident set size while it plans (the high-water mark reset first; :mod:`regrasp.suite.memory`).
The rollout kernels are loaded before the first variant (as ``regrasp suite`` does); the first plan in each process
also loads the planner's compiled kernels from numba's cache (counted: ``cold``).

Reported: the median, 95th percentile and largest planning time [s] and peak memory [MiB] over the variants, and the
count with a schedule. With ``--workers K`` each process plans with its share of the cores (numba's threads; the
lattice is parallel): a variant's time is then its share's, longer than ``--workers 1``'s, and the wall time shorter.
A benchmark, not a test: nothing is asserted.

Run (from any directory)::

    python benchmarks/bench_suite_planning.py                 # the default spec's 120 variants, 1 worker
    python benchmarks/bench_suite_planning.py --variants 6    # a quick run
    python benchmarks/bench_suite_planning.py --workers 2 --json
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEFAULT = ROOT / "examples" / "suites" / "default.toml"
TARGET_P95 = 10.0  # [s] three fingers, issue 27 item 4


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("spec", nargs="?", default=str(DEFAULT), help="suite spec (default: examples/suites/"
                                                                      "default.toml)")
    parser.add_argument("--variants", type=int, default=None, metavar="N",
                        help="plan the first N variants (default: the spec's)")
    parser.add_argument("--workers", type=int, default=1, metavar="K", help="worker processes (default 1)")
    parser.add_argument("--json", action="store_true", help="one JSON document on stdout")
    args = parser.parse_args()
    if args.variants is not None and args.variants < 1:
        parser.error("--variants must be at least 1")
    if args.workers < 1:
        parser.error("--workers must be at least 1")
    sys.path.insert(0, str(ROOT / "src"))  # (this checkout's regrasp)
    from regrasp.suite.run import run_suite
    from regrasp.suite.spec import load_suite_spec

    spec = load_suite_spec(args.spec)
    if args.variants is not None:
        spec = replace(spec, variants=args.variants)
    result = run_suite(spec, workers=min(args.workers, spec.variants), plan_only=True)
    seconds, memory = result.plan_seconds or {}, result.peak_memory or {}
    doc = {"spec": str(spec.path), "variants": len(result.outcomes), "workers": result.workers,
           "cpus": os.cpu_count(), "scheduled": len(result.scheduled),
           "unexplained": [o.index for o in result.unexplained],
           "cold": sum(o.cold for o in result.outcomes if o.plan_seconds is not None),
           "plan_seconds": seconds, "peak_memory_mib": {k: v / 2**20 for k, v in memory.items()},
           "memory_upper_bound": any(o.memory_upper_bound for o in result.outcomes),
           "target_p95_seconds": TARGET_P95, "wall_seconds": result.wall_seconds}
    if args.json:
        print(json.dumps(doc))
        return 0
    mib = doc["peak_memory_mib"]
    print(f"suite planning: {doc['variants']} variants of {Path(args.spec).name} on {doc['workers']} worker(s) "
          f"({doc['cpus']} CPUs), {doc['scheduled']} with a schedule, {doc['cold']} cold (the first plan in its "
          f"process)")
    if seconds:
        verdict = "within" if seconds["p95"] <= TARGET_P95 else "OVER"
        print(f"  planning time [s]: median {seconds['p50']:.2f}, p95 {seconds['p95']:.2f}, max {seconds['max']:.2f} "
              f"({verdict} the {TARGET_P95:g} s target at the 95th percentile)")
        print(f"  peak memory [MiB] (the worker's peak RSS while planning"
              f"{', an upper bound' if doc['memory_upper_bound'] else ''}): median {mib['p50']:.0f}, "
              f"p95 {mib['p95']:.0f}, max {mib['max']:.0f}")
    if doc["unexplained"]:
        print(f"  without a schedule and without a physical reason: variants {doc['unexplained']}")
    print(f"  wall time: {result.wall_seconds:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())

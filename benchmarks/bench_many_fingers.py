r"""Benchmark: planning regrasp schedules for many fingers (issue 27), time and peak memory.

What is measured
----------------
Each plan runs in a fresh process (``python benchmarks/bench_many_fingers.py --child SCENARIO METHOD``): it loads the
scenario, calls :func:`regrasp.plan_regrasps` with default settings (``method`` forced where given) and reports the
call's wall time (``time.perf_counter``: the envelope samples, the problem, the descent or the lattice program, the
verification; numba's kernels load from its cache, compiled once beforehand by a warm-up process) and the process's
peak resident memory (``resource.getrusage(RUSAGE_SELF).ru_maxrss``, with the interpreter and the imports). The parent
prints per case the MEDIAN over ``--repeats`` processes (default 3), the slides per period and the planner used:

* ``four_fingers.toml`` and ``five_fingers.toml`` (the decomposition planner: the exact lattice's force tables would
  not fit in memory); targets: four fingers in ≤ 60 s and ≤ 4 GiB, five in ≤ 3 min;
* ``paper_trajectory_2_three_fingers.toml`` with the exact planner and with the decomposition planner (the same
  problem both ways: their times and slides);
* ``four_fingers.toml`` on a coarser lattice the exact planner can hold (3 mm cells, at most two sliders) with forces
  that couple the fingers (f_max 3 N, cone margin 1 N), with both planners ("four_fingers/coarse": their slides).

Run (from any directory)::

    python benchmarks/bench_many_fingers.py              # 3 processes per case: about 7 min on a 2-core machine
    python benchmarks/bench_many_fingers.py --repeats 1  # about 1 min
    python benchmarks/bench_many_fingers.py --json       # one JSON document on stdout
    python benchmarks/bench_many_fingers.py --cases many --repeats 1  # four and five fingers once (benchmarks/run.py)
    python benchmarks/bench_many_fingers.py --cases quick  # four fingers once (the CI smoke run)
"""

from __future__ import annotations

import argparse
import json
import resource
import time
from pathlib import Path

import numpy as np
from common import child_json

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "examples" / "scenarios"
#: A four-finger lattice the exact planner can hold (3 mm cells, at most two sliders) with forces that couple the
#: fingers (f_max 3 N, cone margin 1 N): the two planners' slides compared
COARSE = {"xi_resolution": 3e-3, "envelope_margin": 1.5e-3, "max_sliders": 2, "f_max": 3.0, "cone_margin": 1.0}
CASES = [("four_fingers", None, {}), ("five_fingers", None, {}), ("paper_trajectory_2_three_fingers", "exact", {}),
         ("paper_trajectory_2_three_fingers", "decomposition", {}), ("four_fingers", "exact", COARSE),
         ("four_fingers", "decomposition", COARSE)]


def child(scenario: str, method: str, options: str) -> None:
    """Plan once in this process (``options``: more settings, JSON); print one JSON line."""
    from regrasp import load_scenario, plan_regrasps
    from regrasp.schedule.problem import RegraspSettings

    sc = load_scenario(SCENARIOS / f"{scenario}.toml")
    settings = RegraspSettings(method=None if method == "default" else method, **json.loads(options))
    t0 = time.perf_counter()
    schedule = plan_regrasps(sc, settings)
    seconds = time.perf_counter() - t0
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # (kB on Linux)
    print(json.dumps({"seconds": seconds, "peak_bytes": peak, "slides": len(schedule.slides),
                      "lower_bound": schedule.slides_lower_bound, "fingers": len(sc.contacts)}))


def run_child(scenario: str, method: str | None, options: dict) -> dict:
    return child_json(__file__, scenario, method or "default", json.dumps(options))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="fresh processes per case (default 3)")
    parser.add_argument("--json", action="store_true", help="print one JSON document")
    parser.add_argument("--cases", choices=("all", "many", "quick"), default="all",
                        help="all (default); many: four and five fingers only; quick: four fingers, one process")
    parser.add_argument("--child", nargs=3, metavar=("SCENARIO", "METHOD", "OPTIONS"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(*args.child)
        return
    run_child("paper_trajectory_2_three_fingers", "decomposition", {})  # warm-up: numba compiles its kernels once
    results = {}
    cases = CASES if args.cases == "all" else CASES[:2] if args.cases == "many" else CASES[:1]
    repeats = 1 if args.cases == "quick" else max(1, args.repeats)
    for scenario, method, options in cases:
        runs = [run_child(scenario, method, options) for _ in range(repeats)]
        results[f"{scenario}{'/coarse' if options else ''}/{method or 'default'}"] = {
            "median_s": float(np.median([r["seconds"] for r in runs])),
            "median_peak_mib": float(np.median([r["peak_bytes"] for r in runs])) / 2**20,
            "runs_s": [r["seconds"] for r in runs], "slides": runs[0]["slides"], "fingers": runs[0]["fingers"],
            "planner": method or ("exact" if runs[0]["fingers"] <= 3 else "decomposition")}
    if args.json:
        print(json.dumps(results))
        return
    print(f"{'scenario':40s} {'planner':>13s} {'fingers':>7s} {'median [s]':>10s} {'peak [MiB]':>10s} {'slides':>6s}")
    for key, r in results.items():
        print(f"{key.rsplit('/', 1)[0]:40s} {r['planner']:>13s} {r['fingers']:7d} {r['median_s']:10.2f} "
              f"{r['median_peak_mib']:10.0f} {r['slides']:6d}")
    print(f"(median of {repeats} fresh process(es) each; targets: four fingers <= 60 s and <= 4 GiB, "
          "five <= 180 s)")


if __name__ == "__main__":
    main()

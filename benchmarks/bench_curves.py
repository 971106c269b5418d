r"""Benchmark: planning regrasp schedules on curved objects (issue 28), wall time.

What is measured
----------------
Each plan runs in a fresh process (``python benchmarks/bench_curves.py --child SCENARIO RESOLUTION``): it loads the
scenario and times (``time.perf_counter``) one :func:`regrasp.plan_regrasps` call with default settings but the
lattice's cell ``RESOLUTION`` [m] (the envelope samples, the force tables, whose cost on a curve is one exact test per
cell of every contact (docs/derivations.md, "§4 on curves"), the lattice program and the verification; numba's
kernels load from its cache, compiled once beforehand by a warm-up process). The parent prints per case the MEDIAN
over ``--repeats`` processes (default 3) and the slides per period:

* ``disc.toml`` and ``rounded_box.toml`` at their own 2 mm cells (``regrasp plan --regrasp``'s plan);
* both at 4 mm and 3 mm (the examples' defaults: ``examples/15_turn_a_disc.py``, ``16_rounded_box_corner.py``).

Run (from any directory)::

    python benchmarks/bench_curves.py              # 3 processes per case: about 10 min on a 2-core machine
    python benchmarks/bench_curves.py --repeats 1  # about 3 min
    python benchmarks/bench_curves.py --json       # one JSON document on stdout
    python benchmarks/bench_curves.py --quick      # the disc at 4 mm over one swing, once (the CI smoke run)
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from common import child_json

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "examples" / "scenarios"
CASES = [("disc", 2e-3), ("rounded_box", 2e-3), ("disc", 4e-3), ("rounded_box", 3e-3)]


def child(scenario: str, resolution: str, swing: str) -> None:
    """Plan once in this process (``swing``: "1" plans one swing only, t in [0.7, 2.45] s, not periodic); print one JSON
    line."""
    from regrasp import load_scenario, plan_regrasps
    from regrasp.schedule.problem import RegraspSettings

    sc = load_scenario(SCENARIOS / f"{scenario}.toml")
    h = float(resolution)
    settings = RegraspSettings(xi_resolution=h, envelope_margin=max(1e-3, 0.5 * h), periodic=False if swing == "1"
                               else None)
    span = {"start_time": 0.7, "t_end": 2.45} if swing == "1" else {}  # (one swing: beta from +0.79 to -0.76 rad)
    t0 = time.perf_counter()
    schedule = plan_regrasps(sc, settings, **span)
    seconds = time.perf_counter() - t0
    print(json.dumps({"seconds": seconds, "slides": len(schedule.slides)}))


def run_child(scenario: str, resolution: float, swing: bool = False) -> dict:
    return child_json(__file__, scenario, repr(resolution), "1" if swing else "0")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="fresh processes per case (default 3)")
    parser.add_argument("--json", action="store_true", help="print one JSON document")
    parser.add_argument("--quick", action="store_true", help="the disc at 4 mm over one swing, once")
    parser.add_argument("--child", nargs=3, metavar=("SCENARIO", "RESOLUTION", "SWING"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(*args.child)
        return
    run_child("disc", 4e-3, swing=True)  # warm-up: numba compiles its kernels once
    cases = [("disc", 4e-3)] if args.quick else CASES
    repeats = 1 if args.quick else max(1, args.repeats)
    results = {}
    for scenario, h in cases:
        runs = [run_child(scenario, h, swing=args.quick) for _ in range(repeats)]
        results[f"{scenario}/{h * 1e3:g} mm"] = {"median_s": float(np.median([r["seconds"] for r in runs])),
                                                  "runs_s": [r["seconds"] for r in runs], "slides": runs[0]["slides"]}
    if args.json:
        print(json.dumps(results))
        return
    print(f"{'scenario':24s} {'median [s]':>10s} {'slides':>6s}")
    for key, r in results.items():
        print(f"{key:24s} {r['median_s']:10.2f} {r['slides']:6d}")
    print(f"(median of {repeats} fresh process(es) each; {'one swing' if args.quick else 'periodic plans'})")


if __name__ == "__main__":
    main()

"""Wall time of ``--help`` of every command and every example, each in a fresh process (issue 26: ≤ 1 s).

Run: python benchmarks/bench_help.py [--repeat N] [--json]

Timed, each ``N`` times (default 5) in a fresh subprocess (``time.perf_counter`` around
``subprocess.run``: the interpreter's start, the imports before argparse answers, the output):
* ``python -m regrasp.cli.main --help`` and ``... plan --help``, ``... simulate --help``, ``... study --help``,
  ``... suite --help``;
* ``python examples/NN_*.py --help`` for every numbered example.
The processes import the regrasp of this checkout (``src`` first on ``PYTHONPATH``). Reports the median and the
largest time of each command in seconds and marks those over the 1 s target; a command that fails or does not
print a usage is reported as such. A benchmark, not a test: nothing is asserted about the times.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

# (not benchmarks/common.py: it imports regrasp, and this script's own --help answers at once)
ROOT = Path(__file__).resolve().parents[1]
TARGET = 1.0  # [s], issue 26


def commands() -> list[tuple[str, list[str]]]:
    """(label, argv after the interpreter) of every command timed."""
    cli = [(" ".join(["regrasp", *sub, "--help"]), ["-m", "regrasp.cli.main", *sub, "--help"])
           for sub in ([], ["plan"], ["simulate"], ["study"], ["suite"])]
    examples = sorted((ROOT / "examples").glob("[0-9][0-9]_*.py"))
    return cli + [(f"examples/{p.name} --help", [str(p), "--help"]) for p in examples]


def time_once(argv: list[str], env: dict[str, str]) -> tuple[float, str | None]:
    """(wall time [s], None or why the command failed) of one fresh process."""
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, *argv], capture_output=True, text=True, cwd=ROOT, env=env, check=False)
    seconds = time.perf_counter() - start
    if proc.returncode != 0:
        return seconds, f"exit status {proc.returncode}: {(proc.stderr.strip().splitlines() or [''])[-1]}"
    if not proc.stdout.startswith("usage:"):
        return seconds, "no usage printed"
    return seconds, None


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5, metavar="N", help="fresh processes per command (default 5)")
    parser.add_argument("--json", action="store_true", help="one JSON document on stdout")
    args = parser.parse_args()
    if args.repeat < 1:
        parser.error("--repeat must be at least 1")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT / "src"),
                                                         *filter(None, [os.environ.get("PYTHONPATH")])])}
    results = {}
    for label, argv in commands():
        samples, errors = [], []
        for _ in range(args.repeat):
            seconds, error = time_once(argv, env)
            samples.append(seconds)
            if error is not None:
                errors.append(error)
        results[label] = {"median_s": statistics.median(samples), "max_s": max(samples),
                          "error": errors[0] if errors else None}
    if args.json:
        print(json.dumps(results))
        return
    width = max(len(label) for label in results)
    print(f"--help in a fresh process, {args.repeat} run(s) each (this machine); * = over {TARGET:g} s")
    print(f"  {'command':{width}s} {'median':>9s} {'max':>9s}")
    for label, r in results.items():
        cells = " ".join(f"{r[k]:6.2f} s{'*' if r[k] > TARGET else ' '}" for k in ("median_s", "max_s"))
        print(f"  {label:{width}s} {cells}" + (f"  FAILED: {r['error']}" if r["error"] else ""))
    over = [label for label, r in results.items() if r["median_s"] > TARGET]
    print(f"{len(over)} of {len(results)} over {TARGET:g} s (median)")


if __name__ == "__main__":
    main()

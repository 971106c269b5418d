"""The first run on a fresh clone: ``pip install -e`` and the main command, timed (issue 26: ≤ 45 s on 2 cores).

Run: python benchmarks/first_run.py [REPO] [--rev REV] [--keep] [--json]

What it does, in a temporary directory:
1. ``git clone REPO`` (default: the repository this script is in; its committed HEAD, not uncommitted changes, or
   ``--rev``): a fresh clone has no numba cache (numba caches next to each kernel's source, in ``__pycache__``) and
   no Python bytecode;
2. ``python -m venv --system-site-packages``: the dependencies come from this machine's Python (numpy, pinocchio,
   coal, numba, rerun, ...), as they would from a warm pip cache, not downloaded: what is timed is regrasp's own
   install and first run, not the network;
3. times ``pip install -e CLONE`` and then the main command in the clone, ``regrasp simulate --periods 3 --rrd
   rollout.rrd``, separately and in total (wall time, ``time.perf_counter`` around each subprocess); then, 15 s
   later (a worker may go on compiling the stretch kernel after a short first run), ``regrasp [plan|simulate|study]
   --help`` and a second, warm run of the main command;
4. checks the rollout succeeded (exit status 0, ``result: SUCCESS``, the recording written), and that the
   ``regrasp`` it ran imported the clone's package, not another install.

NUMBA_CACHE_DIR is removed from the environment (else numba would cache elsewhere, perhaps warm). A benchmark,
not a test: nothing is asserted about the times; exit status 1 when a step fails.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TARGET = 45.0  # [s], issue 26: install plus the first run, 2 cores
COMMAND = ["simulate", "--periods", "3", "--rrd", "rollout.rrd"]


def run(argv: list[str], cwd: Path, env: dict[str, str]) -> tuple[float, subprocess.CompletedProcess]:
    """(wall time [s], the finished process) of ``argv``."""
    start = time.perf_counter()
    proc = subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True, check=False)
    return time.perf_counter() - start, proc


def fail(step: str, proc: subprocess.CompletedProcess) -> None:
    print(f"first_run: {step} failed (exit status {proc.returncode})", file=sys.stderr)
    print(proc.stdout[-3000:], proc.stderr[-3000:], sep="\n", file=sys.stderr)
    sys.exit(1)


def load() -> str:
    try:
        return " ".join(f"{v:.2f}" for v in os.getloadavg())
    except OSError:
        return "unknown"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("repo", nargs="?", default=str(ROOT), help="the repository to clone (default: this one)")
    parser.add_argument("--rev", help="check this revision out in the clone (default: its HEAD)")
    parser.add_argument("--keep", action="store_true", help="keep the temporary directory (its path is printed)")
    parser.add_argument("--json", action="store_true", help="one JSON document on stdout")
    args = parser.parse_args()

    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "PYTHONPATH")}
    work = Path(tempfile.mkdtemp(prefix="regrasp-first-run-"))
    try:
        clone, venv = work / "regrasp", work / "venv"
        seconds, proc = run(["git", "clone", "--quiet", args.repo, str(clone)], work, env)
        if proc.returncode:
            fail("git clone", proc)
        if args.rev is not None:
            seconds, proc = run(["git", "checkout", "--quiet", args.rev], clone, env)
            if proc.returncode:
                fail("git checkout", proc)
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=clone, capture_output=True, text=True,
                              check=False).stdout.strip()
        seconds, proc = run([sys.executable, "-m", "venv", "--system-site-packages", str(venv)], work, env)
        if proc.returncode:
            fail("python -m venv", proc)
        bindir = venv / ("Scripts" if os.name == "nt" else "bin")
        load_before = load()
        install, proc = run([str(bindir / "python"), "-m", "pip", "install", "--quiet", "-e", str(clone)], clone, env)
        if proc.returncode:
            fail("pip install -e", proc)
        probe = subprocess.run([str(bindir / "python"), "-c", "import regrasp; print(regrasp.__file__)"], cwd=work,
                               env=env, capture_output=True, text=True, check=False).stdout.strip()
        if not Path(probe).resolve().is_relative_to(clone.resolve()):
            print(f"first_run: the venv imports regrasp from {probe}, not from the clone {clone}", file=sys.stderr)
            sys.exit(1)
        regrasp = str(bindir / "regrasp")
        first, proc = run([regrasp, *COMMAND], clone, env)
        if proc.returncode or "result: SUCCESS" not in proc.stdout or not (clone / "rollout.rrd").is_file():
            fail("the first run", proc)
        first_stderr = proc.stderr
        summary = next((line.strip() for line in proc.stdout.splitlines() if "wall time" in line), "")
        time.sleep(15.0)  # (a worker that goes on compiling the stretch kernel after a short first run: let it end)
        helps = {}
        for sub in ([], ["plan"], ["simulate"], ["study"]):
            seconds, proc = run([regrasp, *sub, "--help"], clone, env)
            if proc.returncode or not proc.stdout.startswith("usage:"):
                fail(f"regrasp {' '.join(sub)} --help", proc)
            helps[" ".join(["regrasp", *sub, "--help"])] = seconds
        warm, proc = run([regrasp, *COMMAND], clone, env)
        if proc.returncode:
            fail("the warm run", proc)
        warm_summary = next((line.strip() for line in proc.stdout.splitlines() if "wall time" in line), "")
        result = {"commit": head, "cores": os.cpu_count(), "load_before": load_before, "load_after": load(),
                  "install_s": install, "first_run_s": first, "total_s": install + first, "warm_run_s": warm,
                  "target_s": TARGET, "help_s": helps, "first_run_summary": summary, "warm_run_summary": warm_summary,
                  "first_run_stderr": first_stderr.strip().splitlines()}
    finally:
        if args.keep:
            print(f"first_run: kept {work}", file=sys.stderr)
        else:
            shutil.rmtree(work, ignore_errors=True)
    if args.json:
        print(json.dumps(result))
        return
    print(f"first run of regrasp {result['commit']} from a fresh clone ({result['cores']} cores; load average "
          f"{result['load_before']} before, {result['load_after']} after; dependencies from this machine's Python)")
    print(f"  pip install -e             {install:6.1f} s")
    print(f"  regrasp {' '.join(COMMAND)}  {first:6.1f} s  (compiles the kernels)")
    print(f"  total                      {install + first:6.1f} s  (target {TARGET:g} s"
          f"{', met' if install + first <= TARGET else ', NOT met'})")
    print(f"  the same command, warm     {warm:6.1f} s")
    for label, seconds in helps.items():
        print(f"  {label:26s} {seconds:6.2f} s")
    print(f"  first run's summary: {summary}")
    print(f"  warm run's summary:  {warm_summary}")
    for line in result["first_run_stderr"]:
        print(f"  stderr: {line}")


if __name__ == "__main__":
    main()

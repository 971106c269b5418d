"""The benchmarks run (quick mode) and their built-in correctness check passes. No timing assertions."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

from hang_guard import HANG_SECONDS

pytestmark = pytest.mark.slow  # (rollouts, subprocesses: `pytest -m "not slow"` leaves them out)

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"


def test_planner_benchmark_quick_smoke():
    proc = subprocess.run([sys.executable, str(BENCH / "bench_planner.py"), "--quick", "--json"],
                          capture_output=True, text=True, timeout=HANG_SECONDS, check=False)
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    for mode in ("ideal", "urdf", "brute_force"):
        assert doc[mode]["median_us"] > 0
    assert set(doc["ratios"]) == {"brute_over_urdf", "brute_over_ideal", "urdf_over_ideal"}
    assert doc["check"]["ok"] is True and doc["check"]["max_diff_steps"] <= doc["check"]["allowed_steps"]


def test_dynamics_benchmark_quick_smoke():
    proc = subprocess.run([sys.executable, str(BENCH / "bench_dynamics.py"), "--quick", "--json"],
                          capture_output=True, text=True, timeout=HANG_SECONDS, check=False)
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    for key in ("plant_step", "plant_accelerations", "reduced_state", "reduced_forward_dynamics",
                "control_step_qp", "control_step_no_qp", "control_step_m3_qp"):
        assert doc[key]["median_us"] > 0


def test_benchmark_table_quick_smoke():
    """benchmarks/run.py --quick --json: every measured item has a positive median, and the
    Pinocchio/OSQP floors are measured in the same run (no timing assertions)."""
    proc = subprocess.run([sys.executable, str(BENCH / "run.py"), "--quick", "--json"],
                          capture_output=True, text=True, timeout=HANG_SECONDS, check=False)
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    for key in ("control_fixed_qp", "control_fixed_no_qp", "control_sliding_m3_qp", "control_sliding_m3_no_qp",
                "plant_step"):
        assert doc[key]["median_us"] > 0 and doc[key]["floor_us"] > 0
    assert doc["control_fixed_qp"]["floor_us"] > doc["control_fixed_no_qp"]["floor_us"]
    assert doc["planner_sample_ideal"]["median_us"] > 0 and doc["planner_sample_ideal"]["floor_us"] is None
    for key in ("supervisor_step_urdf", "supervisor_step_ideal", "supervisor_step_urdf_tracked"):
        assert doc[key]["median_us"] > 0 and doc[key]["floor_us"] > 0
    rollout = doc["rollout_realtime_factor"]
    assert set(rollout) >= {"recording_off", "recording_on"}
    assert rollout["recording_off"] > 0 and rollout["recording_on"] > 0
    assert 0 < rollout["simulated_s"] <= rollout["requested_s"] + 1e-9
    plan = doc["regrasp_plan"]
    assert plan["median_s"] > 0 and plan["periodic"] is True and plan["slides"] >= plan["slides_lower_bound"] > 0
    assert [v["fingers"] for v in doc["many_fingers"].values()] == [4]  # (--quick: four fingers only)


def test_first_run_benchmark_answers_its_help():
    """benchmarks/first_run.py clones, installs and runs for a minute: only its --help here (no timing)."""
    proc = subprocess.run([sys.executable, str(BENCH / "first_run.py"), "--help"], capture_output=True, text=True,
                          timeout=HANG_SECONDS, check=False)
    assert proc.returncode == 0 and proc.stdout.startswith("usage:") and "--json" in proc.stdout


def test_suite_planning_benchmark_quick_smoke():
    """benchmarks/bench_suite_planning.py --variants 1: one variant planned, its time and memory (no timing
    assertions)."""
    proc = subprocess.run([sys.executable, str(BENCH / "bench_suite_planning.py"), "--variants", "1", "--json"],
                          capture_output=True, text=True, timeout=HANG_SECONDS, check=False)
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    assert doc["variants"] == 1 and doc["plan_seconds"]["p95"] > 0 and doc["peak_memory_mib"]["p95"] > 0


def test_many_fingers_benchmark_quick_smoke():
    """benchmarks/bench_many_fingers.py --cases quick --json: four fingers planned in a fresh process, its time and
    peak memory reported (no timing assertions)."""
    proc = subprocess.run([sys.executable, str(BENCH / "bench_many_fingers.py"), "--cases", "quick", "--json"],
                          capture_output=True, text=True, timeout=HANG_SECONDS, check=False)
    assert proc.returncode == 0, proc.stderr
    (four,) = json.loads(proc.stdout).values()
    assert four["fingers"] == 4 and four["planner"] == "decomposition" and four["slides"] > 0
    assert four["median_s"] > 0 and four["median_peak_mib"] > 0


def test_curves_benchmark_quick_smoke():
    """benchmarks/bench_curves.py --quick --json: the disc planned over one swing in a fresh process, its slides
    and time reported (no timing assertions)."""
    proc = subprocess.run([sys.executable, str(BENCH / "bench_curves.py"), "--quick", "--json"],
                          capture_output=True, text=True, timeout=HANG_SECONDS, check=False)
    assert proc.returncode == 0, proc.stderr
    (disc,) = json.loads(proc.stdout).values()
    assert disc["slides"] > 0 and disc["median_s"] > 0

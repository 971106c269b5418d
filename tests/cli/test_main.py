"""The ``regrasp`` command line: verdicts, JSON, figures, exit codes and errors."""

import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from hang_guard import HANG_SECONDS, interrupted_run
from regrasp import load_scenario, plan_scenario
from regrasp.cli.main import main

pytestmark = pytest.mark.slow  # (rollouts, subprocesses: `pytest -m "not slow"` leaves them out)

ROOT = Path(__file__).resolve().parents[2]
T1 = str(ROOT / "examples" / "scenarios" / "paper_trajectory_1.toml")
T2 = str(ROOT / "examples" / "scenarios" / "paper_trajectory_2.toml")


def run_json(capsys, *args):
    code = main(["plan", *args, "--json"])
    out = capsys.readouterr().out
    return code, json.loads(out)


@pytest.mark.parametrize("geometry", ["ideal", "urdf"])
def test_plan_json_verdicts(capsys, geometry):
    code, doc = run_json(capsys, T1, "--geometry", geometry, "--samples", "101")
    assert code == 1 and doc["feasible"] is False
    reasons = [iv["reason"] for f in doc["fingers"] for iv in f["infeasible_intervals"]]
    assert "condition I" in reasons
    code, doc = run_json(capsys, T2, "--geometry", geometry, "--samples", "101")
    assert code == 0 and doc["feasible"] is True
    assert doc["geometry"] == geometry
    assert all(f["initial_xi"] is not None for f in doc["fingers"])


def test_plan_summary_and_plots(capsys, tmp_path):
    code = main(["plan", T2, "--plot", str(tmp_path / "figs"), "--samples", "51"])
    out = capsys.readouterr().out
    assert code == 0
    assert "FEASIBLE" in out and "initial contact" in out and "finger1" in out
    for name in ("d.png", "reachable.png", "feasible.png"):
        data = (tmp_path / "figs" / name).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000


def test_bad_input_exits_2_with_a_clear_message(capsys, tmp_path):
    bad = tmp_path / "bad.toml"
    urdf = ROOT / "urdf" / "planar_2r_finger.urdf"
    text = Path(T2).read_text().replace("../../urdf/planar_2r_finger.urdf", str(urdf))
    bad.write_text(text.replace("edge = 1", "edge = 9"))
    assert main(["plan", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "fingers[0].edge" in err and str(bad) in err and "Traceback" not in err
    with pytest.raises(SystemExit) as exc:
        main(["plan", T2, "--samples", "1"])
    assert exc.value.code == 2


def test_console_script_runs():
    proc = subprocess.run([sys.executable, "-m", "regrasp.cli.main", "plan", T2, "--samples", "21", "--json"],
                          capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["feasible"] is True


T3 = str(ROOT / "examples" / "scenarios" / "paper_trajectory_2_three_fingers.toml")


def test_plan_regrasp_json_has_the_schedule(capsys, tmp_path):
    code = main(["plan", T3, "--regrasp", "--json", "--samples", "201", "--plot", str(tmp_path / "figs")])
    doc = json.loads(capsys.readouterr().out)
    assert code == 0
    s = doc["schedule"]
    assert s["found"] is True and s["reason"] is None and s["periodic"] is True
    assert len(s["times"]) == len(s["xi"]) == len(s["sliding"]) and len(s["xi"][0]) == 3
    assert s["min_envelope_margin"] >= 1e-3 and s["min_cone_margin"] >= 0.1
    assert {sl["contact"] for sl in s["slides"]} >= {"finger1", "finger2"}
    for sl in s["slides"]:
        assert set(sl) == {"contact", "direction", "start", "end", "from", "to"}
        assert sl["direction"] in (-1, 1) and sl["start"] < sl["end"]
    assert s["planning_seconds"] > 0
    # the xi rows are in the planner's parametrization: inside each finger's feasible set there
    times = np.array(doc["times"])
    for i, finger in enumerate(doc["fingers"]):
        k = int(np.argmin(np.abs(times - s["times"][40])))
        assert any(lo - 2e-3 <= s["xi"][40][i] <= hi + 2e-3 for lo, hi in finger["feasible"][k])
    png = (tmp_path / "figs" / "regrasp.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and str(tmp_path / "figs" / "regrasp.png") in doc["figures"]


def test_plan_regrasp_without_a_schedule_exits_1_with_the_reason(capsys):
    code = main(["plan", T2, "--regrasp"])
    out = capsys.readouterr().out
    assert code == 1
    assert "regrasp schedule: NONE (forces)" in out and "two-finger slide rule" in out
    code, doc = run_json(capsys, T2, "--regrasp")
    assert code == 1 and doc["feasible"] is True
    assert doc["schedule"]["found"] is False and "two-finger slide rule" in doc["schedule"]["reason"]


def test_plan_regrasp_bad_margin_exits_2(capsys):
    assert main(["plan", T3, "--regrasp", "--envelope-margin", "0.0001"]) == 2
    err = capsys.readouterr().err
    assert "envelope_margin" in err and "Traceback" not in err
    with pytest.raises(SystemExit) as exc:
        main(["plan", T3, "--regrasp", "--cone-margin", "-1"])
    assert exc.value.code == 2


# ---------------------------------------------------------------- regrasp simulate
def simulate(*args, cwd, timeout=HANG_SECONDS):
    return subprocess.run([sys.executable, "-m", "regrasp.cli.main", "simulate", *args], capture_output=True, text=True,
                          cwd=cwd, timeout=timeout, check=False)


def verify_rrd(path):
    proc = subprocess.run(["rerun", "rrd", "verify", str(path)], capture_output=True, text=True, timeout=HANG_SECONDS)
    assert proc.returncode == 0, proc.stderr


def test_simulate_json_and_recording_of_the_default_scenario(tmp_path):
    """The default scenario (three fingers, scheduled): one JSON document on stdout and nothing else
    (OSQP's C-level prints are kept off it), the rollout's keys, the schedule's summary, a verified .rrd."""
    proc = simulate("--duration", "1.0", "--json", "--rrd", "out.rrd", "--decimate", "5", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    assert doc["success"] is True and doc["policy"] == "scheduled" and doc["steps"] == 1000
    assert {"failure", "max_object_error_after_transient", "regrasps", "events", "min_cone_margin",
            "min_envelope_margin", "replans", "plant_events", "realtime_factor", "rrd", "contact_health"} <= set(doc)
    health = {h["contact"]: h for h in doc["contact_health"]}
    assert set(health) == {"finger1", "finger2", "palm"}
    assert all(h["least_held_force"] >= 0.05 and h["longest_zero_force"] == 0.0 for h in health.values())
    assert doc["schedule"]["periodic"] is True and len(doc["schedule"]["slides"]) == 4
    assert any(e["kind"] == "prime" and e["source"] == "supervisor" for e in doc["events"])  # the slides at 0.815 s
    verify_rrd(tmp_path / "out.rrd")


def test_simulate_says_at_once_that_two_fingers_have_no_schedule_and_why(tmp_path):
    proc = simulate(T2, cwd=tmp_path)
    assert proc.returncode == 1, proc.stderr
    assert "NO SCHEDULE (forces)" in proc.stdout and "lower contact can never slide down" in proc.stdout
    proc = simulate(T2, "--json", cwd=tmp_path)
    doc = json.loads(proc.stdout)
    assert proc.returncode == 1 and doc["success"] is False and doc["failure"]["kind"] == "no_schedule"


def test_simulate_without_regrasps_fails_with_when_and_why(tmp_path):
    proc = simulate("--policy", "none", "--duration", "1.5", "--plot", "figs", cwd=tmp_path)
    assert proc.returncode == 1, proc.stderr
    found = re.search(r"FAILURE at t = ([0-9.]+) s \(collision\): collision of finger1", proc.stdout)
    assert found, proc.stdout
    # where the plan said the start contact leaves its feasible set (one planner sample spacing either side)
    plan = plan_scenario(load_scenario(ROOT / "examples" / "scenarios" / "paper_trajectory_2_three_fingers.toml"))
    spacing = float(plan.times[1] - plan.times[0])
    assert abs(float(found.group(1)) - plan.fingers[0].initial_xi_feasible_until) <= spacing
    assert (tmp_path / "figs" / "regrasp_rollout.png").stat().st_size > 10_000


@pytest.mark.parametrize("args", [["--periods", "0"], ["--periods", "2", "--duration", "1"], ["--policy", "greedy"],
                                  ["--plant-mass-scale", "-1"], ["--decimate", "0"], [str(ROOT / "nowhere.toml")],
                                  ["--spawn", "--connect", "rerun+http://127.0.0.1:9876/proxy"]])
def test_simulate_bad_input_exits_2_with_one_line(tmp_path, args):
    proc = simulate(*args, cwd=tmp_path)
    assert proc.returncode == 2, (proc.stdout, proc.stderr)
    # one error line (argparse's follows its usage lines), no traceback, nothing on stdout
    last = proc.stderr.strip().splitlines()[-1]
    assert last.startswith(("regrasp: error:", "regrasp simulate: error:")) and "Traceback" not in proc.stderr
    assert proc.stdout == ""


def test_ctrl_c_ends_a_simulation_with_a_partial_result_and_a_complete_recording(tmp_path):
    import signal
    import time

    proc = subprocess.Popen([sys.executable, "-m", "regrasp.cli.main", "simulate", "--duration", "600",
                             "--rrd", "run.rrd"], cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    # the recording is opened once the plan is done, just before the run starts (imports and planning take
    # seconds; the run, ten minutes of the trajectory with the scheduled policy, minutes): interrupt it 3 s after
    # (the recorder's set-up, under a loaded machine, takes up to a second or two of that)
    deadline = time.monotonic() + 120.0
    while not (tmp_path / "run.rrd").exists() and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.1)
    time.sleep(3.0)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=HANG_SECONDS)
    assert proc.returncode == 1, err
    assert "interrupted" in out and "FAILURE" in out and "Traceback" not in err
    verify_rrd(tmp_path / "run.rrd")


def test_ctrl_c_ends_a_study_keeping_the_runs_it_finished(tmp_path):
    """Ctrl-C once a tenth of the runs finished (the progress line on stderr says so, through a pipe too): exit
    130, the finished runs summarised and written (study.json, the figures), the workers stopped, no traceback."""

    code, out, err = interrupted_run(["study", "--runs", "100", "--workers", "2", "--duration", "0.5", "--seed", "3",
                                      "--plot", "out"], tmp_path)
    assert code == 130, (out, err)
    assert "regrasp study: 100 runs: 0/100 (0%)" in err and "Traceback" not in err
    doc = json.loads((tmp_path / "out" / "study.json").read_text())
    assert doc["interrupted"] and doc["requested_runs"] == 100 and 10 <= doc["runs"] < 100
    assert doc["runs"] == len(doc["outcomes"]) and len(doc["figures"]) == 3
    assert f"interrupted (Ctrl-C): {doc['runs']} of 100 runs had finished" in out
    assert f"success: {doc['successes']}/{doc['runs']}" in out


def test_a_partial_schedule_is_called_partial_and_the_wall_time_counts_everything(capsys):
    """Trajectory 1 has no schedule past t = 0.060 s: the summary says so, not "not periodic" as if it were whole;
    and its wall time counts the run and, in all, the imports, the plan and the compiling."""
    assert main(["simulate", T1]) == 1
    out = capsys.readouterr().out
    assert "schedule: PARTIAL, until t = 0.060 s" in out and "not periodic" not in out
    run, total = re.search(r"wall time +([0-9.]+) s for the run .*; ([0-9.]+) s in all, with the imports", out).groups()
    assert float(total) >= float(run)

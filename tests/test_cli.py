"""The ``regrasp`` command line: verdicts, JSON, figures, exit codes and errors."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from regrasp.cli import main

ROOT = Path(__file__).resolve().parents[1]
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
    proc = subprocess.run([sys.executable, "-m", "regrasp.cli", "plan", T2, "--samples", "21", "--json"],
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

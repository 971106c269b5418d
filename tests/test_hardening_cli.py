"""Issue 13's examples through the command line and the scenario reader: each ends in exit 2 with exactly
one error line naming the file and the key (or a valid result, with a warning where one is due).

The number in each case's id is the issue's class.
"""

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from hang_guard import HANG_SECONDS
from regrasp.cli.main import main

ROOT = Path(__file__).resolve().parents[1]
URDF = ROOT / "urdf" / "planar_2r_finger.urdf"
BASE = (ROOT / "examples" / "scenarios" / "paper_trajectory_2.toml").read_text().replace(
    '"../../urdf/', f'"{ROOT / "urdf"}/')


def edited(old: str, new: str, text: str = BASE) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


def sphere_tipped(tmp_path: Path) -> Path:
    """The shipped finger with a sphere as its distal collision shape (fine for 'ideal', not for 'urdf')."""
    path = tmp_path / "sphere.urdf"
    text = URDF.read_text()
    i = text.rindex('<cylinder radius="0.005" length="0.045"/>')
    path.write_text(text[:i] + '<sphere radius="0.01"/>' + text[i + len('<cylinder radius="0.005" length="0.045"/>'):])
    return path


# (id, scenario text or a function of tmp_path giving it, extra arguments, the key the error must name)
ERRORS = [
    ("2 samples = 2**63 - 1", edited('geometry = "ideal"', 'geometry = "ideal"\nsamples = 9223372036854775807'
                                     ).replace("samples = 401\n", ""), [], "planner.samples"),
    ("2 t_end = 1e9", edited("beta_a = 0.0", "beta_a = 0.0\nt_end = 1e9"), [], "trajectory.t_end"),
    ("2 omega = 1e-300 (a period of 6e300 s)", edited("omega = 2.0 ", "omega = 1e-300 "), [], "trajectory.omega"),
    ("3 hand = 5", "hand = 5\n" + BASE.replace("[hand]", "[hand_]"), [], "'hand'"),
    ("3 hand = 'abc'", 'hand = "abc"\n' + BASE.replace("[hand]", "[hand_]"), [], "'hand'"),
    ("4 omega = 1e-308", edited("omega = 2.0 ", "omega = 1e-308 "), [], "trajectory.omega"),
    ("5 a waypoint of 1.8e308", BASE.split("[trajectory]")[0] + '[trajectory]\ntype = "waypoints"\n'
     'times = [0.0, 1.0, 2.0]\nposes = [[0, 0.12, 0], [1.8e308, 0.12, 0], [0, 0.12, 0]]\n\n[hand]'
     + BASE.split("[hand]")[1], [], "trajectory.poses"),
    ("6 a width of 1e200", edited("width = 0.10", "width = 1e200"), [], "object.width"),
    ("9 a 300-character URDF name", edited("planar_2r_finger.urdf", "x" * 300 + ".urdf"), [], "fingers[0].urdf"),
    ("10 a 2000-gon in the urdf geometry", edited("width = 0.10\nheight = 0.04", "vertices = VERTS").replace(
        'geometry = "ideal"', 'geometry = "urdf"'), [], "object"),
    ("13 a boolean in the base", edited("base = [-0.05, 0.0, 1.5707963267948966]", "base = [-0.05, 0.0, true]"), [],
     "fingers[0].base"),
    ("15 a typo key", edited("omega = 2.0 ", "omgea = 2.0 "), [], "the table has 'omgea': a typo?"),
    ("15 a sphere tip in the urdf geometry", lambda tmp: edited(f'"{URDF}"\nbase = [0.05', f'"{sphere_tipped(tmp)}"'
                                                               f'\nbase = [0.05').replace('geometry = "ideal"',
                                                                                          'geometry = "urdf"'),
     [], "fingers[1].urdf"),
    ("15 a sphere tip with --geometry urdf", lambda tmp: edited(f'"{URDF}"\nbase = [0.05', f'"{sphere_tipped(tmp)}"'
                                                               f'\nbase = [0.05'), ["--geometry", "urdf"],
     "fingers[1].urdf"),
]
_A = np.linspace(0.0, 2.0 * np.pi, 2000, endpoint=False)
VERTS = str([[round(0.03 * float(np.cos(a)), 9), round(0.03 * float(np.sin(a)), 9)] for a in _A])


@pytest.mark.parametrize("text, extra, key", [e[1:] for e in ERRORS], ids=[e[0] for e in ERRORS])
def test_a_bad_scenario_exits_2_with_one_line_naming_the_file_and_key(tmp_path, capfd, text, extra, key):
    text = text(tmp_path) if callable(text) else text
    path = tmp_path / "s.toml"
    path.write_text(text.replace("VERTS", VERTS))
    code = main(["plan", str(path), "--samples", "101", *extra])
    out, err = capfd.readouterr()
    lines = err.strip().splitlines()
    assert code == 2, (out, err)
    assert len(lines) == 1 and lines[0].startswith(f"regrasp: error: {path}: key "), lines
    assert key in lines[0], lines[0]


def test_too_few_samples_for_the_motion_are_a_warning_in_the_result_and_on_stderr(tmp_path, capfd):
    path = tmp_path / "s.toml"
    path.write_text(edited("beta_a = 0.0", "beta_a = 0.0\nt_end = 3000.0"))  # 401 samples over 3000 s
    assert main(["plan", str(path)]) in (0, 1)
    err = capfd.readouterr().err.strip().splitlines()
    assert len(err) == 1 and re.match(r"regrasp plan: warning: 401 samples over 3000 s are too few: the object may "
                                      r"move [0-9.]+ mm between two", err[0]), err
    assert main(["plan", str(ROOT / "examples" / "scenarios" / "paper_trajectory_2.toml")]) == 0
    assert capfd.readouterr().err == ""  # the shipped 401 samples see the motion: no warning


@pytest.mark.parametrize("where", ["a file", "under a file", "unwritable"])
def test_plot_into_a_bad_place_is_exit_2_before_any_work(tmp_path, capfd, where):
    afile = tmp_path / "afile"
    afile.write_text("x")
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    target = {"a file": afile, "under a file": afile / "figs", "unwritable": locked / "figs"}[where]
    if where == "unwritable" and os.access(locked, os.W_OK):
        pytest.skip("running as a user who can write anywhere (root)")
    code = main(["plan", str(ROOT / "examples" / "scenarios" / "paper_trajectory_2.toml"), "--plot", str(target)])
    err = capfd.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "--plot" in err[0] and str(target) in err[0], err


def test_plot_into_a_place_root_cannot_write_either(tmp_path, capfd):
    """Where the tests run as root (CI containers), a read-only file system stands in for permissions."""
    code = main(["plan", str(ROOT / "examples" / "scenarios" / "paper_trajectory_2.toml"), "--plot",
                 "/proc/regrasp-figures"])
    err = capfd.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "invalid --plot = '/proc/regrasp-figures'" in err[0], err


@pytest.mark.slow
def test_version_and_ctrl_c():
    version = subprocess.run([sys.executable, "-m", "regrasp.cli.main", "--version"], capture_output=True, text=True,
                             timeout=HANG_SECONDS)
    assert version.returncode == 0 and re.fullmatch(r"regrasp \d+\.\d+\.\d+\S*\n", version.stdout)
    proc = subprocess.Popen([sys.executable, "-m", "regrasp.cli.main", "plan",
                             str(ROOT / "examples" / "scenarios" / "paper_trajectory_2_three_fingers.toml"),
                             "--samples", "100000", "--geometry", "ideal", "--regrasp"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    # past the imports (about 2 s), well inside the plan: 300 000 envelopes in Python (the ideal geometry; the
    # compiled urdf ones take 2 s) and the regrasp schedule, about 9 s here
    time.sleep(5.0)
    assert proc.poll() is None, proc.communicate()
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=HANG_SECONDS)
    lines = err.strip().splitlines()
    assert proc.returncode == 130, err
    assert lines[-1] == "regrasp: interrupted" and not any("Traceback" in line for line in lines), lines


# ---------------------------------------------------------------- issue 25: the new surfaces' reproducers
T3 = str(ROOT / "examples" / "scenarios" / "paper_trajectory_2_three_fingers.toml")
RUN = ["simulate", T3, "--policy", "none", "--duration", "0.05"]
STUDY = ["study", T3, "--runs", "1", "--workers", "1", "--duration", "0.05"]


def one_error_line(capfd, argv: list[str]) -> str:
    """``main(argv)``: exit 2 and the one error line it prints (argparse's follows its usage lines), no traceback."""
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse
        code = exc.code
    out, err = capfd.readouterr()
    lines = err.strip().splitlines()
    assert code == 2 and lines and out == "", (argv, out, err)
    assert "Traceback" not in err and re.match(r"regrasp( \w+)?: error: ", lines[-1]), lines
    if lines[-1].startswith("regrasp: error:"):
        assert len(lines) == 1, lines
    return lines[-1]


def unused_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.parametrize("argv, says", [
    (RUN + ["--rrd", "/proc/x.rrd"], "invalid --rrd = '/proc/x.rrd': expected a writable file path"),
    (RUN + ["--rrd", "a\0b.rrd"], "a NUL byte in the name"),
    (RUN + ["--rrd", "x" * 300 + ".rrd"], "a name of 304 bytes"),
    (RUN + ["--rrd", ""], "an empty path"),
    (RUN + ["--plot", "/proc/figs"], "invalid --plot = '/proc/figs'"),
    (RUN + ["--plot", ""], "invalid --plot = ''"),
    (RUN + ["--connect", "localhost:9876"], "invalid --connect"),
    (STUDY + ["--plot", "/proc/figs"], "invalid --plot = '/proc/figs'"),
    (["study", T3, "--replay", "0", "--duration", "0.05", "--rrd", "/proc/x.rrd"], "invalid --rrd = '/proc/x.rrd'"),
    (RUN + ["--decimate", "1000000000000000000000"], "argument --decimate: expected an integer in [1, 1000000]"),
    (["simulate", T3, "--periods", "1" + "0" * 400], "argument --periods: expected an integer in [1, 1000000]"),
    (STUDY + ["--seed", "1" + "0" * 60], "argument --seed: expected an integer in [0, "),
    (STUDY + ["--workers", "100000"], "argument --workers: expected an integer in [1, 1024]"),
    (STUDY + ["--delay", "11"], "argument --delay: expected an integer in [0, 10]"),
    (["simulate", T3, "--policy", "none", "--duration", "1e-5"], "invalid duration = 1e-05: expected a run of at "
                                                                  "least one control step (0.001 s)"),
    (["study", T3, "--runs", "1", "--duration", "1e-300"], "invalid duration = 1e-300"),
    (RUN + ["--plant", "mujoco", "--tip-radius", "1e300"], "argument --tip-radius: expected a radius in (0, 50] mm"),
    (["study", T3, "--replay", "100000"], "argument --replay: expected an integer in [0, 99999]"),
    (["study", T3, "--runs", "5", "--replay", "7"], "invalid --replay = 7: expected a run of this study's 5"),
    (["study", T3, "--replay", "1", "--workers", "2"], "(not with --workers)"),
    (["study", T3, "--replay", "1", "--ray"], "(not with --ray)"),
    (["study", T3, "--replay", "1", "--plot", "figs"], "(not with --plot)"),
    (STUDY + ["--fixed-softness"], "invalid --fixed-softness = True: expected --plant mujoco"),
    (STUDY + ["--ray", "1.2.3"], "argument --ray: expected 'local', 'auto', a Ray cluster's HOST:PORT"),
], ids=["1 rrd in /proc", "1 rrd with NUL", "1 rrd of 300 characters", "1 rrd empty", "1 plot in /proc",
        "1 plot empty", "1 connect", "1 study plot in /proc", "1 replay rrd in /proc", "3 decimate 1e21",
        "3 periods 1e400", "3 seed 1e60", "3 workers 1e5", "3 delay 11", "4 simulate 1e-5 s", "4 study 1e-300 s",
        "5 tip radius 1e300", "5 replay 100000", "5 replay past runs", "5 replay workers", "5 replay ray",
        "5 replay plot", "5 fixed softness off mujoco", "2 ray address"])
def test_issue_25_command_lines_exit_2_with_one_line_before_any_work(capfd, tmp_path, monkeypatch, argv, says):
    monkeypatch.chdir(tmp_path)
    line = one_error_line(capfd, argv)
    assert says in line, line
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_issue_25_a_study_on_an_unreachable_ray_cluster_ends_at_once(capfd):
    start = time.monotonic()
    port = unused_port()
    line = one_error_line(capfd, STUDY + ["--ray", f"127.0.0.1:{port}"])
    assert line == f"regrasp: error: no Ray cluster at '127.0.0.1:{port}': cannot connect to 127.0.0.1:{port} " \
                   "(Connection refused)"
    assert time.monotonic() - start < 5.0


def strict_json(text: str):
    """``text`` as JSON with no NaN or Infinity (``json.dumps(..., allow_nan=False)`` holds for it)."""
    import json

    def refuse(constant):
        raise AssertionError(f"{constant} in a JSON document")
    return json.loads(text, parse_constant=refuse)


def test_issue_25_summaries_of_runs_that_measured_nothing_say_so(capsys, monkeypatch):
    """Runs that failed at their first step measured no margin: 'n/a', null in JSON, never inf or NaN."""
    import dataclasses

    from regrasp.cli.simulate import rollout_summary
    from regrasp.model.perturbation import Perturbation
    from regrasp.study import study as study_module
    from regrasp.study.draws import draw_runs
    from regrasp.study.study import RunOutcome, StudyResult

    draws = draw_runs(2, 0, Perturbation())
    outcomes = tuple(RunOutcome(d, False, "collision", 0.0, "finger1", None, None, None, None, 0, 0, 0.01)
                     for d in draws)
    result = StudyResult(T3, outcomes, Perturbation(), 0, 0.05, 1, "process", 0.1, 0.05)
    monkeypatch.setattr(study_module, "run_study", lambda *args, **kwargs: result)
    assert main(["study", T3, "--runs", "2", "--workers", "1"]) == 0
    out = capsys.readouterr().out
    assert "smallest cone margin [N]: n/a" in out and "smallest envelope margin [mm]: n/a" in out
    assert "inf" not in out and "nan" not in out, out
    assert main(["study", T3, "--runs", "2", "--workers", "1", "--json"]) == 0
    doc = strict_json(capsys.readouterr().out)
    assert doc["outcomes"][0]["min_cone_margin"] is None

    assert main(["simulate", T3, "--policy", "none", "--duration", "0.01", "--json"]) == 0
    doc = strict_json(capsys.readouterr().out)
    assert doc["steps"] == 10 and doc["success"] is True
    from regrasp import RunSpec, build_rollout, load_scenario

    sc = load_scenario(T3)
    run = build_rollout(sc, RunSpec(duration=0.002), policy="none").run()
    blank = dataclasses.replace(run, min_cone_margin=float("inf"), min_cone_margin_at=(float("nan"), ""),
                                min_envelope_margin=float("inf"), min_envelope_margin_at=(float("nan"), ""))
    text = rollout_summary(blank, sc, "project")
    assert re.search(r"smallest envelope margin +n/a", text) and "inf" not in text and "nan" not in text, text
    strict_json(__import__("json").dumps(blank.to_json_dict()))

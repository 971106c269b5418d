"""``regrasp suite``: its help answers at once; a bad spec is exit 2 with one line naming the key; a small suite
prints its summary, writes suite.json and the figures; --json; Ctrl-C keeps what finished (exit 130)."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

from hang_guard import HANG_SECONDS, interrupted_run
from regrasp.cli.main import main

ROOT = Path(__file__).resolve().parents[2]
SCENARIOS = ROOT / "examples" / "scenarios"
PNG = b"\x89PNG\r\n\x1a\n"


def spec_file(tmp_path: Path, scenario: str, variants: int, body: str = "") -> Path:
    path = tmp_path / "spec.toml"
    path.write_text(f'name = "small"\nscenario = "{SCENARIOS / scenario}"\nvariants = {variants}\nseed = 2\n[vary]\n'
                    + body)
    return path


def test_help_answers_without_importing_the_work():
    proc = subprocess.run([sys.executable, "-m", "regrasp.cli.main", "suite", "--help"], capture_output=True,
                          text=True, timeout=HANG_SECONDS, check=False)
    assert proc.returncode == 0 and proc.stdout.startswith("usage: regrasp suite")
    for flag in ("--variants", "--seed", "--workers", "--ray", "--plant", "--periods", "--plan-only", "--json",
                 "--plot"):
        assert flag in proc.stdout
    code = ("import sys; import regrasp.cli.main; "
            "print(sorted(m for m in ('numba', 'pinocchio', 'matplotlib', 'ray') if m in sys.modules))")
    probe = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=HANG_SECONDS,
                           check=False)
    assert probe.stdout.strip() == "[]", probe.stderr


@pytest.mark.parametrize("body, key", [('"object.mass" = [0.2, 0.1]\n', "vary.object.mass"),
                                       ('"trajectory.kind" = {choices = ["ellipse"]}\n', "vary.trajectory.kind")])
def test_a_bad_spec_exits_2_with_one_line_naming_the_key(tmp_path, capsys, body, key):
    assert main(["suite", str(spec_file(tmp_path, "paper_trajectory_2.toml", 2, body))]) == 2
    out, err = capsys.readouterr()
    assert out == "" and len(err.strip().splitlines()) == 1 and f"key '{key}'" in err


def test_bad_flags_exit_2(tmp_path, capsys):
    spec = str(spec_file(tmp_path, "paper_trajectory_2.toml", 2))
    for args in (["--variants", "0"], ["--periods", "-1"], ["--workers", "x"], ["--ray", "no address"]):
        with pytest.raises(SystemExit) as info:
            main(["suite", spec, *args])
        assert info.value.code == 2
    assert main(["suite", str(tmp_path / "missing.toml")]) == 2


def test_a_small_suite_prints_its_summary_and_writes_its_results_and_figures(tmp_path, capsys):
    spec = spec_file(tmp_path, "paper_trajectory_2_three_fingers.toml", 5, '"object.mass" = [0.075, 0.085]\n')
    assert main(["suite", str(spec), "--variants", "1", "--periods", "1", "--workers", "1",
                 "--plot", str(tmp_path / "out")]) == 0
    out = capsys.readouterr().out
    assert out.startswith("regrasp suite: small (") and "1 variants of paper_trajectory_2_three_fingers.toml" in out
    assert "with a schedule: 1/1 = 100.0%" in out and "success given a schedule: 1/1" in out
    assert "without a schedule and without a physical reason: none" in out and "planning time [s]" in out
    doc = json.loads((tmp_path / "out" / "suite.json").read_text())
    assert doc["variants"] == doc["requested"] == 1 and doc["successes"] == 1 and len(doc["figures"]) == 3
    for name in doc["figures"]:
        data = Path(name).read_bytes()
        assert data.startswith(PNG) and len(data) > 5000


def test_json_has_the_reasons(tmp_path, capsys):
    spec = spec_file(tmp_path, "paper_trajectory_2.toml", 2, '"object.mass" = [0.09, 0.11]\n')
    assert main(["suite", str(spec), "--workers", "1", "--json", "--seed", "9"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["seed"] == 9 and doc["scheduled"] == 0 and doc["unexplained"] == [] and doc["ran"] == 0
    assert doc["reasons"] == [{"status": "no_schedule", "limit": "forces", "contacts": ["finger1"],
                               "variants": [0, 1]}]


@pytest.mark.slow
def test_ctrl_c_ends_a_suite_keeping_the_variants_it_finished(tmp_path):

    spec = spec_file(tmp_path, "paper_trajectory_2.toml", 40, '"object.mass" = [0.09, 0.11]\n')
    code, out, err = interrupted_run(["suite", str(spec), "--workers", "2", "--plot", "out"], tmp_path)
    assert code == 130, (out, err)
    assert "Traceback" not in err
    doc = json.loads((tmp_path / "out" / "suite.json").read_text())
    assert doc["interrupted"] and doc["requested"] == 40 and 4 <= doc["variants"] < 40
    assert f"interrupted (Ctrl-C): {doc['variants']} of 40 variants had finished" in out

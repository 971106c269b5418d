"""Every numbered example runs headless, terminates and prints something (CI smoke test); each answers
--help without doing its work, and its docstring says how to run it."""

import ast
import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import pytest

import regrasp
from hang_guard import HANG_SECONDS

pytestmark = pytest.mark.slow  # (rollouts, subprocesses: `pytest -m "not slow"` leaves them out)

#: The examples run in a temporary directory against the regrasp these tests import (a relative PYTHONPATH, such
#: as ``PYTHONPATH=src`` in a worktree, would no longer point there).
ENV = {**os.environ, "MPLBACKEND": "Agg",
       "PYTHONPATH": os.pathsep.join([str(Path(regrasp.__file__).resolve().parents[1]),
                                      *filter(None, [os.environ.get("PYTHONPATH")])])}
#: Examples that need an extra: their file name and the package.
NEEDS = {"10_mujoco_plant.py": "mujoco"}
EXAMPLES = [pytest.param(p, marks=pytest.mark.skipif(importlib.util.find_spec(NEEDS[p.name]) is None,
                                                     reason=f"needs the {NEEDS[p.name]} extra"))
            if p.name in NEEDS else p
            for p in sorted((Path(__file__).resolve().parents[1] / "examples").glob("[0-9][0-9]_*.py"))]
IDS = [getattr(p, "values", (p,))[0].name for p in EXAMPLES]


def test_there_are_examples():
    assert len(EXAMPLES) >= 2


@pytest.mark.parametrize("path", EXAMPLES, ids=IDS)
def test_example_runs(path, tmp_path):
    proc = subprocess.run([sys.executable, str(path)], capture_output=True, text=True, timeout=HANG_SECONDS,
                          cwd=tmp_path, env=ENV, check=False)
    assert proc.returncode == 0, proc.stderr
    assert len(proc.stdout.splitlines()) >= 3


@pytest.mark.parametrize("path", EXAMPLES, ids=IDS)
def test_example_help(path, tmp_path):
    proc = subprocess.run([sys.executable, str(path), "--help"], capture_output=True, text=True, timeout=HANG_SECONDS,
                          cwd=tmp_path, env=ENV, check=False)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith("usage:")
    assert path.name in proc.stdout
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("path", EXAMPLES, ids=IDS)
def test_example_docstring_names_its_file(path):
    doc = ast.get_docstring(ast.parse(path.read_text(encoding="utf-8")))
    assert doc is not None
    assert f"Run: python examples/{path.name}" in doc

"""The validation layer's output side (issue 25, items 1, 4 and 5): a path to write (``output_path_problem``,
``as_output_path``, ``as_output_directory``), a run's step count (``step_count``) and a tip radius
(``as_tip_radius``)."""

import math
import os
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from regrasp.core.exceptions import InvalidParameterError
from regrasp.core.validation import (
    MAX_TIP_RADIUS,
    as_output_directory,
    as_output_path,
    as_tip_radius,
    output_path_problem,
    step_count,
)


@pytest.fixture
def places(tmp_path):
    afile = tmp_path / "afile"
    afile.write_text("x")
    return tmp_path, afile


@pytest.mark.parametrize("value, says", [
    ("/proc/x.rrd", "no file can be made in /proc"), ("/proc/self/x.rrd", "no file can be made in /proc"),
    ("a\0b.rrd", "a NUL byte"), ("x" * 300 + ".rrd", "a name of 304 bytes"), ("", "an empty path"),
    (5, "not a path"), (None, "not a path"), (b"x.rrd", "not a path"), (3.5, "not a path"), (object(), "not a path"),
    ("/" + "d/" * 3000 + "x.rrd", "a path longer than"),
], ids=["proc", "proc self", "NUL", "300 characters", "empty", "int", "None", "bytes", "float", "object", "too long"])
def test_a_file_that_cannot_be_written_is_named_before_any_work(value, says):
    assert says in output_path_problem(value)
    with pytest.raises(InvalidParameterError) as info:
        as_output_path("rrd_path", value)
    assert info.value.name == "rrd_path" and says in str(info.value) and "\n" not in str(info.value)


def test_a_file_in_a_missing_or_unusable_place(places):
    tmp, afile = places
    assert output_path_problem(tmp) == "it is a directory"
    assert output_path_problem(tmp / "missing" / "x.rrd") == f"its directory {tmp / 'missing'} does not exist"
    assert output_path_problem(afile / "x.rrd") == f"{afile} is not a directory"
    assert not list(tmp.glob(".regrasp-write-check-*"))  # (the write check leaves nothing behind)


def test_a_file_that_can_be_written(places, monkeypatch):
    tmp, afile = places
    monkeypatch.chdir(tmp)
    for value in (tmp / "x.rrd", str(tmp / "x.rrd"), "x.rrd", afile):
        assert output_path_problem(value) is None, value
        assert as_output_path("rrd_path", value) == Path(value)
    assert sorted(p.name for p in tmp.iterdir()) == ["afile"]  # nothing made


def test_a_read_only_directory_or_file(places):
    tmp, afile = places
    locked = tmp / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    afile.chmod(0o400)
    try:
        if os.access(locked, os.W_OK):
            pytest.skip("running as a user who can write anywhere (root): /proc stands in above")
        assert "no file can be made in" in output_path_problem(locked / "x.rrd")
        assert "no file can be made in" in output_path_problem(locked / "figs", directory=True)
        assert output_path_problem(afile) == "an existing file that cannot be written"
    finally:
        locked.chmod(0o700)


def test_a_directory_to_write_into(places):
    tmp, afile = places
    assert output_path_problem(tmp, directory=True) is None
    assert output_path_problem(tmp / "new" / "deeper", directory=True) is None  # (made later, by the caller)
    assert not (tmp / "new").exists()
    assert output_path_problem(afile, directory=True) == "it is a file"
    assert output_path_problem(afile / "figs", directory=True) == f"{afile} is not a directory"
    for value, says in (("/proc/figs", "no file can be made in /proc"), ("a\0b", "NUL"), ("", "empty"),
                        (7, "not a path"), ("d" * 256, "a name of 256 bytes")):
        with pytest.raises(InvalidParameterError, match="invalid --plot") as info:
            as_output_directory("--plot", value)
        assert says in str(info.value), str(info.value)
    assert as_output_directory("--plot", tmp) == tmp


names = st.one_of(st.text(max_size=12), st.text(alphabet="ab\0/.", max_size=6),
                  st.integers(250, 300).map(lambda n: "n" * n), st.sampled_from(["..", ".", "/", "//", "~", " "]))


@settings(derandomize=True, database=None, max_examples=150, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.lists(names, min_size=1, max_size=3), st.booleans())
def test_a_generated_path_is_a_problem_or_can_be_written(tmp_path, parts, directory):
    """Under a fresh directory: either a problem in one line, or the path really takes a file (or a directory that
    takes a file)."""
    root = tmp_path / "gen"
    root.mkdir(exist_ok=True)
    path = f"{root}/" + "/".join(part.replace("..", "..x") for part in parts)  # (never above the fresh directory)
    problem = output_path_problem(path, directory=directory)
    if problem is not None:
        assert isinstance(problem, str) and "\n" not in problem
        return
    target = Path(os.path.abspath(path))
    if directory:
        target.mkdir(parents=True, exist_ok=True)
        target = target / "probe.txt"
    existed = target.exists()
    with open(target, "a", encoding="utf-8"):
        pass
    if not existed:
        target.unlink()


def test_a_run_of_no_step_is_refused_naming_its_length():
    assert step_count("duration", 1.0, 1e-3) == 1000
    assert step_count("duration", 1e-3, 1e-3) == 1
    assert step_count("duration", 1e-3 * (1 - 1e-12), 1e-3) == 1  # (a rounding's worth short is one step)
    for short in (0.0, 1e-5, 1e-300, 9.99e-4, math.nan):
        with pytest.raises(InvalidParameterError, match="at least one control step") as info:
            step_count("duration", short, 1e-3)
        assert info.value.name == "duration"


def test_a_tip_radius_is_a_radius_of_at_most_5_cm():
    assert as_tip_radius("tip_radius", 2.5e-4) == 2.5e-4
    assert as_tip_radius("tip_radius", np.float64(MAX_TIP_RADIUS)) == MAX_TIP_RADIUS
    assert as_tip_radius("tip_radius", 0.0, allow_zero=True) == 0.0
    for bad in (1e300, 0.051, 0.0, -1e-3, math.inf, math.nan, "1", True, 10**400):
        with pytest.raises(InvalidParameterError) as info:
            as_tip_radius("tip_radius", bad)
        assert info.value.name == "tip_radius"

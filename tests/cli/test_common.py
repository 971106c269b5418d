"""The command line's shared plant options (``regrasp.cli.common``): ``--plant``, ``--tip-radius`` and the pad's."""

from __future__ import annotations

import argparse

import pytest

from regrasp.cli.common import add_plant_arguments, plant_spec
from regrasp.core.exceptions import InvalidParameterError
from regrasp.core.pad import DEFAULT_PAD_PRELOAD, Pad


def parse(*argv: str) -> argparse.Namespace:
    p = argparse.ArgumentParser()
    add_plant_arguments(p)
    return p.parse_args(list(argv))


def test_pad_options_make_a_soft_project_plant():
    assert plant_spec(parse()).pad is None
    assert plant_spec(parse("--pad-stiffness", "1e5")).pad == Pad(1e5, 0.0, DEFAULT_PAD_PRELOAD)
    spec = plant_spec(parse("--pad-stiffness", "2e4", "--pad-damping", "28.3", "--pad-preload", "1"))
    assert spec.kind == "project" and spec.pad == Pad(2e4, 28.3, 1.0)


@pytest.mark.parametrize("argv", [("--pad-damping", "10"), ("--pad-preload", "1"),
                                  ("--plant", "mujoco", "--pad-stiffness", "1e5")])
def test_pad_options_need_a_stiffness_and_the_project_plant(argv):
    with pytest.raises(InvalidParameterError):
        plant_spec(parse(*argv))


@pytest.mark.parametrize("argv", [("--pad-stiffness", "0"), ("--pad-stiffness", "-1"), ("--pad-damping", "-1")])
def test_bad_pad_values_are_refused_by_the_parser(argv):
    with pytest.raises(SystemExit):
        parse(*argv)


def test_loading_cached_kernels_says_nothing_and_compiling_them_says_so(monkeypatch):
    import io
    import time

    import regrasp.cli.common as common
    import regrasp.kernels as kernels
    from regrasp.kernels import WARM_UP_STEPS

    quiet = io.StringIO()
    common.compile_kernels(stream=quiet)  # (the session's kernels are loaded: at once, nothing said)
    assert quiet.getvalue() == ""

    def slow_warm_up(progress=None, groups=None):  # a cold machine of one core: still compiling at the notice
        deadline = time.monotonic() + 60.0
        while "compiling" not in loud.getvalue() and time.monotonic() < deadline:
            time.sleep(0.01)
        for k in range(1, WARM_UP_STEPS + 1):
            progress(k, WARM_UP_STEPS)

    loud = io.StringIO()
    monkeypatch.setattr(kernels, "warm_up", slow_warm_up)
    monkeypatch.setattr(kernels.warm, "compile_in_background", lambda groups: [])
    monkeypatch.setattr(common, "COMPILE_NOTICE_AFTER", 0.01)
    seconds = common.compile_kernels(stream=loud)
    lines = loud.getvalue().splitlines()
    assert lines[0].startswith("regrasp: compiling the numba kernels: once per machine")
    assert lines[-1] == f"regrasp: kernels compiled in {seconds:.0f} s"


def test_a_cold_cache_is_said_at_once_and_its_workers_progress_is_shown(monkeypatch):
    """On a cold cache the kernels compile in worker processes: said when the command starts (its planning goes on),
    then a progress line while it waits for them, then the seconds it took."""
    import io

    import regrasp.cli.common as common
    import regrasp.kernels as kernels
    import regrasp.kernels.warm as warm

    def waiting_warm_up(progress=None, groups=None):
        for k in range(1, 5):
            progress(k, 4)

    monkeypatch.setattr(warm, "compile_in_background", lambda groups: ["force", "control"])
    monkeypatch.setattr(kernels, "warm_up", waiting_warm_up)
    loud = io.StringIO()
    load = common.KernelLoad(stream=loud)
    assert loud.getvalue().startswith("regrasp: compiling the numba kernels once per machine")
    assert "worker processes" in loud.getvalue()
    seconds = load.finish()
    lines = loud.getvalue().splitlines()
    assert any(line.startswith(f"{common.COMPILING}: 2/4") for line in lines)
    assert lines[-1] == f"regrasp: kernels compiled in {seconds:.0f} s"
    quiet = io.StringIO()
    common.KernelLoad(stream=quiet, quiet=True).finish()
    assert quiet.getvalue() == ""

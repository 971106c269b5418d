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

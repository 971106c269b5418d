"""Which plant a rollout runs on (``regrasp.plants.spec``): a soft project plant, from the spec or the scenario."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from regrasp import Hand, load_scenario
from regrasp.core.exceptions import InvalidParameterError
from regrasp.core.pad import Pad
from regrasp.plants.spec import PlantSpec

ROOT = Path(__file__).resolve().parents[2]
SCENARIO = ROOT / "examples" / "scenarios" / "paper_trajectory_2.toml"


def build(spec: PlantSpec, scenario):
    hand = Hand([c.finger for c in scenario.contacts], gravity_in_hand=scenario.gravity_in_hand)
    return spec.build(scenario, hand, [0.005, -0.008], [0.0, 0.12, 0.0], np.zeros(3), 0.0, 1e-3)


def test_a_pad_from_the_spec_or_the_scenario_and_rigid_by_default():
    scenario = load_scenario(SCENARIO)
    assert scenario.pad is None
    rigid = build(PlantSpec(), scenario)
    assert rigid.pad is None
    pad = Pad(1e5, 60.0)
    soft = build(PlantSpec(pad=pad), scenario)
    assert soft.pad is pad and not soft.compiled
    padded = dataclasses.replace(scenario, pad=Pad(2e4))
    assert build(PlantSpec(), padded).pad == Pad(2e4)
    assert build(PlantSpec(pad=pad), padded).pad is pad  # the spec's wins
    # the same state, the tips on the edges' lines: the pads carry their preload
    np.testing.assert_allclose(soft.state.q, rigid.state.q)
    assert soft.pad_energy() == pytest.approx(2 * pad.energy(pad.preload_depth))


@pytest.mark.parametrize("make", [lambda: PlantSpec(pad=1e5), lambda: PlantSpec("mujoco", pad=Pad(1e5))])
def test_a_pad_is_a_pad_on_the_project_plant(make):
    pytest.importorskip("mujoco")
    with pytest.raises(InvalidParameterError):
        make()


@pytest.mark.parametrize("friction", [[False, []], [0.5, [1, [2]]], {1: 2}, {0.5}, np.array([[0.5]])])
def test_a_plant_spec_refuses_a_friction_that_is_no_coefficient_per_finger(friction):
    """Ragged lists (numpy's ndim raises on them), mappings and sets are typed errors (the generated-argument test
    of tests/test_entry_points.py found [False, []])."""
    with pytest.raises(InvalidParameterError):
        PlantSpec(friction=friction)

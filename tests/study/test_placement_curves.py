"""A study's placement errors (``contact_position``) on a curved object: every ξ is on the object, so a placement is
checked against the finger's feasible envelope at the start instead of an edge's ends (:func:`check_placement`);
on a polygon it is still checked against the edge."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from regrasp import load_scenario
from regrasp.core.exceptions import InvalidParameterError
from regrasp.envelope.planner import plan_scenario
from regrasp.study.study import check_placement

ROOT = Path(__file__).resolve().parents[2]
THREE = ROOT / "examples" / "scenarios" / "paper_trajectory_2_three_fingers.toml"


def disc_case(tmp: Path):
    """The three-finger scenario on a disc of radius 50 mm (each finger on its one face), and its envelope plan
    (3 samples, ideal geometry)."""
    text = THREE.read_text().replace("width = 0.10\nheight = 0.04", 'shape = "disc"\nradius = 0.05')
    text = text.replace("../../urdf", str(ROOT / "urdf"))
    for edge in ("edge = 1", "edge = 2", "edge = 3"):
        text = text.replace(edge, "edge = 0")
    path = tmp / "disc.toml"
    path.write_text(text)
    scenario = load_scenario(path)
    return scenario, plan_scenario(scenario, samples=3, geometry="ideal")


def test_a_placement_on_a_curve_stays_inside_the_fingers_envelope(tmp_path):
    scenario, plan = disc_case(tmp_path)
    perimeter = scenario.polygon.perimeter
    xi0 = np.array([f.initial_xi for f in plan.fingers])
    holding = [next(iv for iv in f.samples[0].feasible if iv[0] <= x <= iv[1]) for f, x in zip(plan.fingers, xi0)]
    room = min(min(x - lo, hi - x) for x, (lo, hi) in zip(xi0, holding))
    assert room > 1e-3
    check_placement(scenario, xi0, 0.9 * room, plan)
    check_placement(scenario, xi0 + np.array([perimeter, -perimeter, 2 * perimeter]), 0.9 * room, plan)  # any turn
    check_placement(scenario, xi0, 0.0, plan)
    check_placement(scenario, None, 0.9 * room, plan)
    check_placement(scenario, xi0, 1.0, None)  # (no plan: every ξ is on the object, nothing to check)
    with pytest.raises(InvalidParameterError, match="inside its feasible envelope at the start"):
        check_placement(scenario, xi0, 1.1 * max(hi - lo for lo, hi in holding), plan)
    outside = xi0.copy()
    gaps = [(a[1], b[0]) for a, b in zip(plan.fingers[0].samples[0].feasible,
                                        plan.fingers[0].samples[0].feasible[1:])]
    if gaps:  # a ξ between two feasible intervals: no placement around it
        outside[0] = 0.5 * sum(gaps[0])
        with pytest.raises(InvalidParameterError, match="in none of its feasible intervals"):
            check_placement(scenario, outside, 1e-4, plan)
    outside[0] = xi0[0] + 0.5 * perimeter  # the disc's far side
    with pytest.raises(InvalidParameterError, match="finger1"):
        check_placement(scenario, outside, 1e-4, plan)


def test_a_placement_on_a_polygon_stays_on_its_edge():
    scenario = load_scenario(THREE)
    xi0 = np.zeros(3)
    ends = [scenario.polygon.edge(c.edge).xi_range for c in scenario.contacts]
    room = min(min(-lo, hi) for lo, hi in ends)
    check_placement(scenario, xi0, 0.99 * room)
    check_placement(scenario, xi0, 0.99 * room, plan_scenario(scenario, samples=2, geometry="ideal"))  # (the plan
    # does not matter on a polygon)
    with pytest.raises(InvalidParameterError, match="on its edge"):
        check_placement(scenario, xi0, 1.01 * room)

"""A suite's variants: seeded per index (the same whatever the count, the order or the worker), inside their
ranges, set on the base scenario's document and built by the scenario's own validation."""

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from regrasp.core.exceptions import InvalidParameterError
from regrasp.core.trajectory import EllipseTrajectory, WaypointTrajectory
from regrasp.suite.spec import load_suite_spec
from regrasp.suite.variants import draw_variant, variant_scenario

ROOT = Path(__file__).resolve().parents[2]
DEFAULT = load_suite_spec(ROOT / "examples" / "suites" / "default.toml")
VARIETY = load_suite_spec(ROOT / "examples" / "suites" / "variety.toml")


def test_a_variant_depends_only_on_the_seed_and_its_index():
    forwards = [draw_variant(DEFAULT, i) for i in range(6)]
    backwards = [draw_variant(DEFAULT, i) for i in reversed(range(6))][::-1]
    assert forwards == backwards
    more = replace(DEFAULT, variants=500)
    assert [draw_variant(more, i) for i in range(6)] == forwards  # (not on how many variants there are)
    child = np.random.SeedSequence(DEFAULT.seed).spawn(DEFAULT.variants)[4]
    rng = np.random.default_rng(child)
    assert [x for _, x in forwards[4].values] == [float(rng.uniform(v.low, v.high)) for v in DEFAULT.varied]
    assert forwards[4].entropy == tuple(int(w) for w in child.generate_state(4))
    other = replace(DEFAULT, seed=DEFAULT.seed + 1)
    assert draw_variant(other, 4).values != forwards[4].values
    with pytest.raises(InvalidParameterError, match="index"):
        draw_variant(DEFAULT, DEFAULT.variants)


def test_drawn_values_are_inside_their_ranges_and_land_in_the_scenario():
    for i in range(5):
        variant = draw_variant(DEFAULT, i)
        p = variant.parameters
        for v in DEFAULT.varied:
            assert v.low <= p[v.key] <= v.high
        scenario = variant_scenario(DEFAULT, variant)
        traj = scenario.trajectory
        assert isinstance(traj, EllipseTrajectory)
        assert (traj.omega, traj.a, traj.b) == (p["trajectory.omega"], p["trajectory.a"], p["trajectory.b"])
        assert scenario.polygon.mass == p["object.mass"]
        assert np.isclose(np.ptp(scenario.polygon.vertices[:, 0]), p["object.width"])
        assert all(f.static == f.kinetic == p["hand.mu"] for f in scenario.friction)
        palm = scenario.contacts[2].finger
        assert palm.name == "palm" and palm.base_in_hand[0] == p["fingers.palm.base.0"]
        assert palm.base_in_hand[1] == -0.06  # (the rest of the base kept)
        assert scenario.name.endswith(f"variant {i}") and len(scenario.contacts) == 3


def test_whole_tables_are_chosen_with_their_own_ranges_and_gravity_turns():
    kinds, fingers, shapes = set(), set(), set()
    for i in range(VARIETY.variants):
        variant = draw_variant(VARIETY, i)
        scenario = variant_scenario(VARIETY, variant)
        traj = scenario.trajectory
        kinds.add(type(traj).__name__ + ("/" + traj.boundary if isinstance(traj, WaypointTrajectory) else ""))
        if isinstance(traj, EllipseTrajectory):
            assert 1.5 <= traj.omega <= 2.5
        fingers.add(len(scenario.contacts))
        shapes.add(round(float(scenario.polygon.vertices[0][0]), 3))
        angle = variant.parameters["hand.gravity_angle"]
        g = scenario.gravity_in_hand
        assert np.isclose(np.hypot(*g), 9.81) and np.isclose(math.atan2(g[1], g[0]), -math.pi / 2 + angle)
    assert kinds == {"EllipseTrajectory", "WaypointTrajectory/periodic", "WaypointTrajectory/natural"}
    assert fingers == {2, 3} and shapes == {0.05, 0.055}


def test_a_key_inside_a_chosen_table_is_set_after_the_table(tmp_path):
    base = ROOT / "examples" / "scenarios" / "paper_trajectory_2_three_fingers.toml"
    spec_path = tmp_path / "spec.toml"
    spec_path.write_text(f'scenario = "{base}"\nvariants = 4\n[vary]\n"trajectory.omega" = [2.5, 2.6]\n'
                         '"trajectory" = {choices = [{type = "ellipse", cx = 0.0, cy = 0.12, a = 0.08, b = 0.04, '
                         'omega = 1.0}]}\n')
    spec = load_suite_spec(spec_path)
    scenario = variant_scenario(spec, draw_variant(spec, 0))
    assert scenario.trajectory.a == 0.08 and 2.5 <= scenario.trajectory.omega <= 2.6

"""The planner on the paper's examples (Examples 2.1 and 2.2), its initial-grasp rule and a URDF swap."""

from pathlib import Path

import numpy as np
import pytest

from regrasp import EllipseTrajectory, Finger, load_scenario, plan, plan_scenario
from regrasp.core.exceptions import InvalidParameterError
from regrasp.core.intervals import DANGER_FRACTION, contains
from regrasp.model import FingerContact

ROOT = Path(__file__).resolve().parents[2]
SCENARIOS = ROOT / "examples" / "scenarios"


@pytest.fixture(scope="module")
def trajectory_1():
    return load_scenario(SCENARIOS / "paper_trajectory_1.toml")


@pytest.fixture(scope="module")
def trajectory_2():
    return load_scenario(SCENARIOS / "paper_trajectory_2.toml")


@pytest.mark.parametrize("geometry", ["ideal", "urdf"])
def test_trajectory_1_is_infeasible_with_a_condition_I_interval(trajectory_1, geometry):
    result = plan_scenario(trajectory_1, geometry=geometry, samples=201)
    assert not result.feasible
    reasons = {iv.reason for f in result.fingers for iv in f.infeasible_intervals}
    assert "condition I" in reasons
    for f in result.fingers:
        for iv in f.infeasible_intervals:
            if iv.reason == "condition I":  # every sample inside is really condition I, with an empty envelope
                inside = [s for s in f.samples if iv.start <= s.time <= iv.end]
                assert inside and all(s.condition.value == "I" and not s.reachable for s in inside)
                assert all(s.d < -f.link_lengths[0] for s in inside)


@pytest.mark.parametrize("geometry", ["ideal", "urdf"])
def test_trajectory_2_is_feasible_alternating_conditions_III_and_IV(trajectory_2, geometry):
    result = plan_scenario(trajectory_2, geometry=geometry)
    assert result.feasible
    for f in result.fingers:
        conds = [s.condition.value for s in f.samples]
        assert set(conds) == {"III", "IV"}
        switches = sum(a != b for a, b in zip(conds, conds[1:]))
        assert switches >= 1
        assert all(s.feasible for s in f.samples)
        # No fixed contact survives the period: a regrasp (slide) is needed, as in paper §4.
        assert f.fixed_grasp == ()
        assert f.initial_xi_feasible_until < result.times[-1]
    # d of the two fingers are equal and opposite (paper §4: symmetric set-up)
    d1 = np.array([s.d for s in result.fingers[0].samples])
    d2 = np.array([s.d for s in result.fingers[1].samples])
    np.testing.assert_allclose(d1, -d2, atol=1e-15)


@pytest.mark.parametrize("fraction", [DANGER_FRACTION, 0.25])
def test_initial_grasp_stays_outside_the_danger_zones_longest(trajectory_2, fraction):
    """Brute force over 2001 contacts: none stays outside the danger zones longer than the suggested one, which
    starts outside them; its reported times are where it leaves them and its feasible set."""
    result = plan_scenario(trajectory_2, samples=201, danger_fraction=fraction)
    for f in result.fingers:
        grid = np.linspace(*f.samples[0].edge_range, 2001)

        def survival(xi, safe):  # index of the last sample up to which xi is in every (safe) set
            last = -1
            for k, s in enumerate(f.samples):
                keep = [(lo + fraction * (hi - lo), hi - fraction * (hi - lo)) for lo, hi in s.feasible] if safe \
                    else s.feasible
                if not contains(keep, xi):
                    break
                last = k
            return last

        best = max(survival(x, True) for x in grid)
        k_safe = survival(f.initial_xi, True)
        assert k_safe >= best > 0  # no sampled contact keeps out of the danger zones longer
        assert result.times[k_safe] == pytest.approx(f.initial_xi_safe_until)
        assert result.times[survival(f.initial_xi, False)] == pytest.approx(f.initial_xi_feasible_until)
        lo, hi = next(iv for iv in f.samples[0].feasible if iv[0] <= f.initial_xi <= iv[1])
        assert min(f.initial_xi - lo, hi - f.initial_xi) > fraction * (hi - lo)


def test_danger_fraction_is_validated(trajectory_2):
    for bad in (0.0, 0.5, -0.1, True, "0.1"):
        with pytest.raises(InvalidParameterError):
            plan_scenario(trajectory_2, samples=11, danger_fraction=bad)


def test_a_gentle_trajectory_needs_no_regrasp(trajectory_2):
    gentle = EllipseTrajectory(0.0, 0.12, 0.01, 0.005, 2.0)
    result = plan(trajectory_2.contacts, trajectory_2.polygon, gentle, samples=101)
    assert result.feasible
    for f in result.fingers:
        assert f.fixed_grasp
        assert f.initial_xi_feasible_until == pytest.approx(result.times[-1])
        assert all(contains(s.feasible, f.initial_xi) for s in f.samples)


def test_swapping_the_finger_urdf_changes_the_envelope(trajectory_2):
    other = ROOT / "urdf" / "planar_2r_finger_long_distal.urdf"
    swapped = []
    for c in trajectory_2.contacts:
        finger = Finger.from_urdf(other, base_in_hand=c.finger.base_in_hand,
                                  configuration=c.finger.configuration, name=c.finger.name)
        swapped.append(FingerContact(finger, c.edge))
    a = plan_scenario(trajectory_2, samples=101)
    b = plan(swapped, trajectory_2.polygon, trajectory_2.trajectory, samples=101)
    assert b.fingers[0].link_lengths != a.fingers[0].link_lengths
    diffs = [
        max(abs(x - y) for x, y in zip(np.ravel(sa.reachable), np.ravel(sb.reachable)))
        if len(sa.reachable) == len(sb.reachable) else np.inf
        for sa, sb in zip(a.fingers[0].samples, b.fingers[0].samples)
    ]
    assert max(diffs) > 1e-3  # metres: the reachable set moves by millimetres at least
    assert any(sa.feasible != sb.feasible for sa, sb in zip(a.fingers[0].samples, b.fingers[0].samples))


def test_infeasible_intervals_group_consecutive_samples(trajectory_1):
    result = plan_scenario(trajectory_1, samples=101)
    for f in result.fingers:
        bad = [s for s in f.samples if not s.feasible]
        covered = [s for s in f.samples if any(iv.start <= s.time <= iv.end for iv in f.infeasible_intervals)]
        assert [s.time for s in bad] == [s.time for s in covered]
        for iv in f.infeasible_intervals:
            assert all(s.reason == iv.reason for s in f.samples if iv.start <= s.time <= iv.end)


def test_json_document_has_the_documented_keys(trajectory_2):
    doc = plan_scenario(trajectory_2, samples=11).to_json_dict()
    assert {"feasible", "times", "object", "poses", "fingers"} <= set(doc)
    assert len(doc["times"]) == len(doc["poses"]) == 11
    f = doc["fingers"][0]
    for key in ("name", "edge", "configuration", "base_in_hand", "link_lengths", "xi_origin_in_object",
                "xi_direction_in_object", "d", "condition", "reachable", "feasible", "infeasible_intervals",
                "initial_xi"):
        assert key in f
    # the documented meaning of xi: origin + xi * direction in the object frame lies on edge `edge`
    verts = np.array(doc["object"]["vertices_in_object"])
    a, b = verts[f["edge"]], verts[(f["edge"] + 1) % len(verts)]
    for lo, hi in f["feasible"][0]:
        for xi in (lo, hi):
            p = np.array(f["xi_origin_in_object"]) + xi * np.array(f["xi_direction_in_object"])
            e, r = b - a, p - a
            assert abs(e[0] * r[1] - e[1] * r[0]) < 1e-12
            assert -1e-12 <= np.dot(p - a, b - a) <= np.dot(b - a, b - a) + 1e-12


def test_motion_between_samples_is_the_worst_vertex_path_between_two_samples():
    from regrasp import ConvexPolygon, EllipseTrajectory
    from regrasp.envelope.planner import motion_between_samples

    box = ConvexPolygon.rectangle(0.1, 0.04, mass=0.08)
    traj = EllipseTrajectory(0.0, 0.1, 0.1, 0.05, 2.0, beta_a=1.0)
    times = traj.times(401)
    estimate = motion_between_samples(traj, box, times)
    # independent: each vertex's path length between consecutive samples, from dense poses
    dense = np.linspace(times[0], times[-1], 400 * 50 + 1)
    vertices = np.array([box.vertices_in(q) for q in traj.pose(dense)])  # (time, vertex, xy)
    steps = np.linalg.norm(np.diff(vertices, axis=0), axis=-1)  # (time - 1, vertex)
    worst = steps.reshape(400, 50, -1).sum(axis=1).max()
    # the estimate bounds every vertex's path (|v| + |omega| r >= a vertex's speed) and is close to it
    assert worst <= estimate <= 1.5 * worst
    assert motion_between_samples(traj, box, times[:1]) == 0.0

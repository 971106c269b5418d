"""Scenario loading: the shipped scenarios, and every malformed input names file, key and expectation."""

from pathlib import Path

import numpy as np
import pytest

from regrasp import Friction, Scenario, ScenarioError, load_scenario
from regrasp.core.exceptions import InvalidParameterError
from regrasp.model.geometry import Geometry

ROOT = Path(__file__).resolve().parents[2]
SCENARIOS = ROOT / "examples" / "scenarios"
URDF = ROOT / "urdf" / "planar_2r_finger.urdf"

VALID = f"""
name = "t"
[object]
width = 0.1
height = 0.04
mass = 0.08
[trajectory]
type = "ellipse"
cx = 0.0
cy = 0.12
a = 0.09
b = 0.05
omega = 2.0
[[fingers]]
name = "f1"
urdf = "{URDF}"
base = [-0.05, 0.0, 1.5707963267948966]
configuration = "left"
edge = 1
[[fingers]]
name = "f2"
urdf = "{URDF}"
base = [0.05, 0.0, 1.5707963267948966]
configuration = "right"
edge = 3
"""


def write(tmp_path, text, name="s.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_shipped_scenarios_load():
    for name in ("paper_trajectory_1", "paper_trajectory_2"):
        sc = load_scenario(ROOT / "examples" / "scenarios" / f"{name}.toml")
        assert sc.name == name
        assert [c.edge for c in sc.contacts] == [1, 3]
        assert [c.finger.configuration.value for c in sc.contacts] == ["left", "right"]
        # the bases are as far apart as the rectangle is wide (paper Example 2.1)
        width = np.ptp(sc.polygon.vertices[:, 0])
        assert abs(sc.contacts[1].finger.base_in_hand[0]
                   - sc.contacts[0].finger.base_in_hand[0]) == pytest.approx(width)
        assert sc.geometry is Geometry.IDEAL and sc.samples == 401


def test_valid_minimal_and_defaults(tmp_path):
    sc = load_scenario(write(tmp_path, VALID))
    np.testing.assert_allclose(sc.gravity_in_hand, [0.0, -9.81])
    assert sc.trajectory.t_end == pytest.approx(np.pi)
    assert sc.polygon.mass == pytest.approx(0.08)


def test_waypoint_trajectory_and_vertices(tmp_path):
    text = VALID.replace("width = 0.1\nheight = 0.04",
                         "vertices = [[0.05, 0.02], [-0.05, 0.02], [-0.05, -0.02], [0.05, -0.02]]")
    text = text.replace('type = "ellipse"\ncx = 0.0\ncy = 0.12\na = 0.09\nb = 0.05\nomega = 2.0',
                        'type = "waypoints"\ntimes = [0.0, 1.0, 2.0]\n'
                        'poses = [[0, 0.12, 0], [0.02, 0.13, 0.1], [0, 0.12, 0]]\nboundary = "clamped"')
    sc = load_scenario(write(tmp_path, text))
    np.testing.assert_allclose(sc.trajectory.pose(1.0), [0.02, 0.13, 0.1])


CASES = [
    # (replace old, by new, expected key in the error, words expected in the message)
    ("edge = 1", "edge = 7", "fingers[0].edge", "does not exist"),
    ("edge = 1", 'edge = "left"', "fingers[0].edge", "integer"),
    ('configuration = "left"', 'configuration = "up"', "fingers[0].configuration", "'left', 'right'"),
    ("mass = 0.08", "mass = -1.0", "object.mass", "mass"),
    ("omega = 2.0", "omega = 2.0\nomgea = 3.0", "trajectory.omgea", "unknown key"),
    ("a = 0.09", "", "trajectory.a", "required"),
    ('type = "ellipse"', 'type = "circle"', "trajectory.type", "'ellipse', 'waypoints'"),
    ("base = [-0.05, 0.0, 1.5707963267948966]", "base = [-0.05, 0.0]", "fingers[0].base", "shape (3)"),
    ('urdf = "' + str(URDF) + '"\nbase = [-0.05', 'urdf = "missing.urdf"\nbase = [-0.05', "fingers[0].urdf",
     "not found"),
    ('name = "f2"', 'name = "f1"', "fingers[1].name", "unique"),
    ("width = 0.1\nheight = 0.04", "vertices = [[0, 0], [1, 0], [0.2, 0.2], [0, 1]]", "object.vertices", "convex"),
    ("width = 0.1\nheight = 0.04", "vertices = [[0, 0], [1, 0]]", "object.vertices", "3"),
    # issue 25: the key at fault, not its partner
    ("height = 0.04", "height = 1e-300", "object.height", "a length in [1e-06, 1000] m"),
    ("width = 0.1", "width = 1e-300", "object.width", "a length in [1e-06, 1000] m"),
    ("width = 0.1\nheight = 0.04", "width = 2.0\nheight = 1e-6", "object.height", "at least 1/1e+06 of the width"),
    ("omega = 2.0", "omega = 2.0\nt_start = -1e6\nt_end = -999999.0", "trajectory.t_start", "within ±3600 s of 0"),
]


@pytest.mark.parametrize("old,new,key,words", CASES)
def test_malformed_scenarios_name_file_key_and_expectation(tmp_path, old, new, key, words):
    assert old in VALID
    path = write(tmp_path, VALID.replace(old, new, 1))
    with pytest.raises(ScenarioError) as err:
        load_scenario(path)
    assert err.value.key == key
    msg = str(err.value)
    assert str(path) in msg and key in msg
    assert words.lower() in msg.lower()


WAYPOINTS = 'type = "waypoints"\ntimes = TIMES\nposes = POSES'
ELLIPSE = 'type = "ellipse"\ncx = 0.0\ncy = 0.12\na = 0.09\nb = 0.05\nomega = 2.0'


@pytest.mark.parametrize("times, poses, key, words", [
    ("[-1.7e308, 0.0, 1.7e308]", "[[0, 0.12, 0], [0.01, 0.12, 0], [0, 0.12, 0]]", "trajectory.times",
     "a domain of at most 3600 s"),
    ("[0.0, 1e-300, 2e-300, 3e-300]", "[[0, 0.12, 0], [0.01, 0.12, 0], [0, 0.12, 0], [0.01, 0.12, 0]]",
     "trajectory.times", "at least 1e-06 s apart"),
    ("[0.0, 2.0, 1.0]", "[[0, 0.12, 0], [0.01, 0.12, 0], [0, 0.12, 0]]", "trajectory.times", "strictly increasing"),
    ("[5000.0, 5001.0]", "[[0, 0.12, 0], [0.01, 0.12, 0]]", "trajectory.times", "within ±3600 s of 0"),
    ("[0.0, 1e-6, 2e-6]", "[[0, 0.12, 0], [1e200, 0.12, 0], [0, 0.12, 0]]", "trajectory.poses", "exceeds 1e+150"),
], ids=["span ±1.7e308", "1e-300 apart", "decreasing", "at 5000 s", "overflowing spline"])
def test_waypoint_errors_name_the_times_or_the_poses(tmp_path, times, poses, key, words):
    """Issue 25: waypoint times spanning ±1.7e308 (a scipy traceback before) or 1e-300 s apart (a NaN pose in
    ``plan`` before) are one-line errors at the key at fault."""
    path = write(tmp_path, VALID.replace(ELLIPSE, WAYPOINTS.replace("TIMES", times).replace("POSES", poses)))
    with pytest.raises(ScenarioError) as err:
        load_scenario(path)
    assert err.value.key == key and words in str(err.value) and "\n" not in str(err.value), str(err.value)


@pytest.mark.parametrize("absolute", [False, True])
def test_a_urdf_path_that_is_a_symlink_loop_is_no_file(tmp_path, absolute):
    """Issue 25: a relative URDF path that is a symlink loop was a ``RuntimeError: Symlink loop`` traceback."""
    loop = tmp_path / "loop.urdf"
    loop.symlink_to(loop)
    path = write(tmp_path, VALID.replace(f'urdf = "{URDF}"', f'urdf = "{loop if absolute else "loop.urdf"}"', 1))
    with pytest.raises(ScenarioError, match="URDF file not found") as err:
        load_scenario(path)
    assert err.value.key == "fingers[0].urdf" and str(loop) in str(err.value)


def test_a_relative_urdf_path_is_resolved(tmp_path):
    (tmp_path / "urdf").mkdir()
    (tmp_path / "urdf" / "f.urdf").symlink_to(URDF)
    sc = load_scenario(write(tmp_path, VALID.replace(f'urdf = "{URDF}"', 'urdf = "./urdf/../urdf/f.urdf"', 1)))
    assert sc.contacts[0].finger.source == str(URDF)


def test_not_toml_and_missing_file(tmp_path):
    with pytest.raises(ScenarioError, match="not valid TOML"):
        load_scenario(write(tmp_path, "[object\nwidth = 1"))
    with pytest.raises(ScenarioError, match="not found"):
        load_scenario(tmp_path / "nope.toml")
    with pytest.raises(ScenarioError, match="fingers"):
        load_scenario(write(tmp_path, VALID.split("[[fingers]]")[0]))


def test_planner_section(tmp_path):
    sc = load_scenario(write(tmp_path, VALID + '\n[planner]\nsamples = 11\ngeometry = "urdf"\n'))
    assert sc.samples == 11 and sc.geometry is Geometry.URDF
    with pytest.raises(ScenarioError, match="planner.samples"):
        load_scenario(write(tmp_path, VALID + "\n[planner]\nsamples = 1\n", "b.toml"))


# ---------------------------------------------------------------------------- friction keys
def with_friction(finger1: str = "", hand: str = "", finger2: str = "") -> str:
    """VALID with friction keys (TOML lines) in finger f1's table, finger f2's and a [hand] table."""
    text = VALID.replace("edge = 1\n", f"edge = 1\n{finger1}\n", 1).replace("edge = 3\n", f"edge = 3\n{finger2}\n", 1)
    return text + ("\n[hand]\n" + hand + "\n" if hand else "")


@pytest.mark.parametrize("finger1,hand,finger2,expected", [
    ("", "", "", (Friction(0.5), Friction(0.5))),  # today's default, μ_s = μ_k = 0.5
    ("mu = 0.8", "", "", (Friction(0.8), Friction(0.5))),
    ("mu_static = 0.8\nmu_kinetic = 0.4", "", "", (Friction(0.8, 0.4), Friction(0.5))),
    ("mu_static = 0.6\nmu_kinetic = 0.6", "", "mu = 0", (Friction(0.6), Friction(0.0))),
    ("", "mu = 0.7", "", (Friction(0.7), Friction(0.7))),
    ("", "mu_static = 0.9\nmu_kinetic = 0.3", "", (Friction(0.9, 0.3), Friction(0.9, 0.3))),
    # a finger's own keys override the hand's, whichever form either uses
    ("mu = 0.2", "mu_static = 0.9\nmu_kinetic = 0.3", "", (Friction(0.2), Friction(0.9, 0.3))),
    ("mu_static = 1.2\nmu_kinetic = 1", "mu = 0.4", "", (Friction(1.2, 1.0), Friction(0.4))),
])
def test_friction_keys_per_finger_and_for_the_hand(tmp_path, finger1, hand, finger2, expected):
    sc = load_scenario(write(tmp_path, with_friction(finger1, hand, finger2)))
    assert sc.friction == expected
    assert tuple(c.friction for c in sc.contacts) == expected
    assert all(isinstance(f, Friction) for f in sc.friction)


@pytest.mark.parametrize("where", ["finger", "hand"])
@pytest.mark.parametrize("keys,name,words", [
    ("mu = 0.5\nmu_static = 0.6", "mu", "not both"),
    ("mu = 0.5\nmu_kinetic = 0.4", "mu", "not both"),
    ("mu = 0.5\nmu_static = 0.6\nmu_kinetic = 0.4", "mu", "not both"),
    ("mu_static = 0.6", "mu_static", "together"),
    ("mu_kinetic = 0.4", "mu_kinetic", "together"),
    ("mu = -0.2", "mu", ">= 0"),
    ("mu_static = -0.1\nmu_kinetic = -0.2", "mu_static", ">= 0"),
    ("mu_static = 0.5\nmu_kinetic = -0.1", "mu_kinetic", ">= 0"),
    ("mu = inf", "mu", "finite"),
    ("mu = nan", "mu", "finite"),
    ("mu_static = inf\nmu_kinetic = 0.4", "mu_static", "finite"),
    ("mu_static = 0.5\nmu_kinetic = nan", "mu_kinetic", "finite"),
    ('mu = "high"', "mu", "number"),
    ("mu_static = 0.4\nmu_kinetic = 0.6", "mu_kinetic", "<= mu_static"),
])
def test_bad_friction_keys_name_the_key(tmp_path, where, keys, name, words):
    text = with_friction(finger1=keys) if where == "finger" else with_friction(hand=keys)
    with pytest.raises(ScenarioError) as err:
        load_scenario(write(tmp_path, text))
    key = ("fingers[0]." if where == "finger" else "hand.") + name
    assert err.value.key == key
    assert key in str(err.value) and words in str(err.value)


@pytest.mark.parametrize("finger1,hand,finger2,expected", [
    ("", "", "", ([5.0, 5.0], [5.0, 5.0])),  # the URDF's effort
    ("effort = 0.3", "", "", ([0.3, 0.3], [5.0, 5.0])),
    ("effort = [0.3, 0.2]", "effort = 0.4", "", ([0.3, 0.2], [0.4, 0.4])),
    ("", "effort = [0.4, 0.1]", "effort = inf", ([0.4, 0.1], [np.inf, np.inf])),
])
def test_effort_keys_per_finger_and_for_the_hand(tmp_path, finger1, hand, finger2, expected):
    sc = load_scenario(write(tmp_path, with_friction(finger1, hand, finger2)))
    assert [c.finger.effort_limit.tolist() for c in sc.contacts] == list(expected)
    from regrasp.model.hand import Hand
    assert Hand([c.finger for c in sc.contacts]).effort_limit.tolist() == expected[0] + expected[1]


@pytest.mark.parametrize("where", ["finger", "hand"])
@pytest.mark.parametrize("value", ["0", "-0.1", "nan", "[0.3]", "[0.3, 0.2, 0.1]", '"strong"', "true", "[[0.3, 0.2]]",
                                   "[0.3, -1]"])
def test_bad_effort_keys_name_the_key(tmp_path, where, value):
    text = with_friction(**{"finger1" if where == "finger" else "hand": f"effort = {value}"})
    with pytest.raises(ScenarioError) as err:
        load_scenario(write(tmp_path, text))
    key = ("fingers[0]." if where == "finger" else "hand.") + "effort"
    assert err.value.key == key and "torque limit > 0 [N m]" in str(err.value)


# ---------------------------------------------------------------------------- the fingertips' pad
def test_pad_table(tmp_path):
    """No [pad]: rigid contacts (None); a [pad] table: a Pad with its keys, the rest the defaults."""
    from regrasp.core.pad import DEFAULT_PAD_PRELOAD, Pad

    assert load_scenario(write(tmp_path, VALID)).pad is None
    sc = load_scenario(write(tmp_path, VALID + "\n[pad]\nstiffness = 1e5\ndamping = 60\n", "a.toml"))
    assert sc.pad == Pad(1e5, 60.0, DEFAULT_PAD_PRELOAD)
    sc = load_scenario(write(tmp_path, VALID + "\n[pad]\nstiffness = 2e4\npreload = 1\nsubsteps = 4\n", "b.toml"))
    assert sc.pad == Pad(2e4, 0.0, 1.0, substeps=4)


@pytest.mark.parametrize("body,key", [("damping = 1", "pad.stiffness"), ("stiffness = 0", "pad.stiffness"),
                                      ("stiffness = 1e5\ndamping = -1", "pad.damping"),
                                      ('stiffness = "soft"', "pad.stiffness"),
                                      ("stiffness = 1e5\nsubsteps = 0.5", "pad.substeps"),
                                      ("stiffness = 1e5\nsubsteps = 0", "pad.substeps"),
                                      ("stiffness = 1e5\nstifness = 1", "pad.stifness")])
def test_bad_pad_keys_name_the_key(tmp_path, body, key):
    with pytest.raises(ScenarioError) as err:
        load_scenario(write(tmp_path, VALID + f"\n[pad]\n{body}\n"))
    assert err.value.key == key


def test_a_scenario_built_in_code_needs_only_its_four_nouns():
    sc = load_scenario(SCENARIOS / "paper_trajectory_2_three_fingers.toml")
    built = Scenario(name="in code", polygon=sc.polygon, trajectory=sc.trajectory, contacts=list(sc.contacts))
    assert built.path is None and built.description == "" and built.contacts == sc.contacts
    assert built.geometry is Geometry.IDEAL and built.samples == 401
    np.testing.assert_array_equal(built.gravity_in_hand, [0.0, -9.81])


@pytest.mark.parametrize("bad", [dict(name=""), dict(polygon="box"), dict(trajectory=None), dict(contacts=[]),
                                 dict(contacts=["finger"]), dict(gravity_in_hand=[0.0, np.nan]), dict(samples=1),
                                 dict(geometry="mesh"), dict(path=3), dict(description=None)])
def test_a_scenario_built_in_code_is_validated(bad):
    sc = load_scenario(SCENARIOS / "paper_trajectory_2_three_fingers.toml")
    fields = dict(name="in code", polygon=sc.polygon, trajectory=sc.trajectory, contacts=sc.contacts) | bad
    with pytest.raises(InvalidParameterError):
        Scenario(**fields)

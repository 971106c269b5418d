"""Generated bad inputs (hypothesis, seeded): the validation layer, the scenario reader and the CLI.

Each property: a typed error whose message names the parameter or key, or a valid value with no
NaN or inf; for the CLI, exit 2 with one error line on stderr. ``derandomize`` makes the examples
the same on every run.
"""

import math
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from regrasp import load_scenario
from regrasp.cli.main import main
from regrasp.core.exceptions import InvalidParameterError, ScenarioError
from regrasp.core.validation import as_finite_array, as_finite_float

ROOT = Path(__file__).resolve().parents[1]
BASE = (ROOT / "examples" / "scenarios" / "paper_trajectory_2.toml").read_text().replace(
    '"../../urdf/', f'"{ROOT / "urdf"}/')
SETTINGS = settings(derandomize=True, database=None, max_examples=150, deadline=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])

scalars = st.one_of(
    st.booleans(), st.none(), st.text(max_size=5), st.binary(max_size=3), st.complex_numbers(allow_nan=True),
    st.floats(allow_nan=True, allow_infinity=True), st.integers(min_value=-(10**400), max_value=10**400),
    st.sampled_from([10**309, -(10**309), 1e308, 5e-324, np.float32("nan"), np.int64(3), np.bool_(True)]))
values = st.recursive(scalars, lambda children: st.lists(children, max_size=4), max_leaves=8)


def is_number(v) -> bool:
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, (bool, np.bool_))


@SETTINGS
@given(values)
def test_as_finite_float_gives_a_finite_float_or_names_the_parameter(value):
    try:
        out = as_finite_float("mass", value)
    except InvalidParameterError as exc:
        assert exc.name == "mass" and str(exc).startswith("invalid mass = ") and "\n" not in str(exc)
        assert len(str(exc)) < 250
        return
    assert is_number(value) and isinstance(out, float) and math.isfinite(out)


def leaves(value):
    if isinstance(value, list):
        for v in value:
            yield from leaves(v)
    else:
        yield value


@SETTINGS
@given(values)
def test_as_finite_array_gives_finite_floats_or_names_the_parameter(value):
    try:
        arr = as_finite_array("base", value)
    except InvalidParameterError as exc:
        assert exc.name == "base" and "\n" not in str(exc) and len(str(exc)) < 300
        return
    assert arr.dtype == float and np.isfinite(arr).all()
    assert all(is_number(v) for v in leaves(value))


# the scenario's numeric keys, as (TOML key line's start, its key for the error)
KEYS = [("mass = 0.08", "object.mass"), ("omega = 2.0", "trajectory.omega"), ("a = 0.09", "trajectory.a"),
        ("gravity = [0.0, -9.81]", "hand.gravity"), ("samples = 401", "planner.samples"),
        ("base = [-0.05, 0.0, 1.5707963267948966]", "fingers[0].base"), ("edge = 1", "fingers[0].edge")]

toml_values = st.one_of(
    st.integers(min_value=-(10**400), max_value=10**400).map(str),
    st.floats(allow_nan=True, allow_infinity=True).map(lambda f: {math.inf: "inf", -math.inf: "-inf"}.get(f, "nan")
                                                        if not math.isfinite(f) else repr(f)),
    st.sampled_from(['"abc"', "true", "[]", "[1, 2]", '[0.05, 0.0, true]', '["1", 2, 3]', "{ x = 1 }", "1e308",
                     "-1e308", "0", "-1", "1e-308", '[1e309, 0, 0]', "[[1, 2], [3]]"]))


@SETTINGS
@given(st.sampled_from(KEYS), toml_values)
def test_a_bad_scenario_value_is_an_error_naming_its_key_or_a_valid_scenario(tmp_path_factory, key, literal):
    line, name = key
    assert line in BASE
    path = tmp_path_factory.mktemp("sc") / "s.toml"
    path.write_text(BASE.replace(line, line.split(" = ")[0] + " = " + literal, 1))
    try:
        sc = load_scenario(path)
    except ScenarioError as exc:
        text = str(exc)
        assert "\n" not in text and len(text) < 600, text
        assert exc.key is None or exc.key == name or exc.key.startswith(name.split(".")[0]), (name, text)
        return
    # accepted: every number that came from it is finite
    assert np.isfinite(sc.gravity_in_hand).all() and math.isfinite(sc.polygon.mass)
    t = sc.trajectory.times(7)
    assert np.isfinite(sc.trajectory.pose(t)).all() and np.isfinite(sc.trajectory.acceleration(t)).all()


flags = st.lists(st.sampled_from(["--samples", "0", "-5", "1e9", "abc", "--geometry", "mesh", "--plot", "",
                                  "--json", "--regrasp", "--envelope-margin", "-1", "nan", "--cone-margin", "inf",
                                  "--periods", "--duration", "--policy", "greedy", "--decimate",
                                  "--plant-mass-scale", "--nope"]), min_size=1, max_size=4)


@settings(derandomize=True, database=None, max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.sampled_from(["plan", "simulate"]), flags)
def test_bad_command_lines_exit_2_with_one_error_line(capsys, command, extra):
    args = [command, str(ROOT / "nowhere.toml"), *extra]
    try:
        code = main(args)
    except SystemExit as exc:  # argparse
        code = exc.code
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2, (args, err)
    assert err and re.match(r"regrasp( \w+)?: error: ", err[-1]), err
    assert not any(line.startswith("Traceback") for line in err)


@pytest.mark.parametrize("name", ["x" * 300 + ".toml", "a\0b.toml", ""])
def test_unusable_scenario_paths_are_scenario_errors(name):
    with pytest.raises(ScenarioError):
        load_scenario(name)


URDF_TEXT = (ROOT / "urdf" / "planar_2r_finger.urdf").read_text()
# every attribute value of the shipped finger, by (element, attribute): what a generated URDF may break
URDF_SLOTS = sorted({(element, attribute) for element, attributes in re.findall(r"<(\w+)\s([^>]*)>", URDF_TEXT)
                     for attribute in re.findall(r"(\w+)=\"", attributes)})
urdf_values = st.one_of(
    st.sampled_from(["nan", "inf", "-inf", "-1", "0", "1e300", "-1e300", "1e-300", "1e400", "0 0 1e300", "nan 0 0",
                     "0.1 0 0", "0 0 -1", "1 0 0", "0 0 0", "0 0.1 0", "0 1.5707963267948966 0", "0.5 0 0"]),
    st.sampled_from(["abc", "", "1 2", "prismatic", "fixed", "continuous", "floating", "planar", "revolute", "link1",
                     "tip", "base", "nowhere"]),
    st.floats(allow_nan=True, allow_infinity=True, width=32).map(repr),
    st.floats(min_value=1e-4, max_value=1.0).map(repr))
# structural edits, as (regular expression, replacement) applied once at the i-th match
structural = st.sampled_from([
    (r"<inertial>.*?</inertial>", ""), (r"<collision>.*?</collision>", ""), (r"<visual>.*?</visual>", ""),
    (r'<link name="tip"/>', ""), (r'name="tip"', 'name="tip2"'), (r'<joint name="joint2"', '<joint name="joint1"'),
    (r"<cylinder", "<capsule"), (r"<cylinder [^>]*>", '<sphere radius="0.01"/>'),
    (r"<cylinder [^>]*>", '<box size="0.12 0.01 0.01"/>'), (r"</robot>", ""), (r'type="fixed"', 'type="revolute"'),
    (r"<parent", "<parent_"), (r'<link name="base"/>', '<link name="base"/><link name="base"/>'),
    (r"<axis [^>]*>", ""), (r"<limit [^>]*>", ""), (r"<origin [^>]*>", "")])


def mutated_urdf(text: str, edits) -> str:
    for kind, a, b in edits:
        if kind == "attr":
            matches = [m for m in re.finditer(rf"<{a[0]}\b[^>]*?\s{a[1]}=\"([^\"]*)\"", text)]
            if matches:
                m = matches[b[1] % len(matches)]
                text = text[:m.start(1)] + b[0] + text[m.end(1):]
        else:
            matches = list(re.finditer(a[0], text, re.S))
            if matches:
                m = matches[b % len(matches)]
                text = text[:m.start()] + a[1] + text[m.end():]
    return text


urdf_edits = st.lists(st.one_of(
    st.tuples(st.just("attr"), st.sampled_from(URDF_SLOTS), st.tuples(urdf_values, st.integers(0, 7))),
    st.tuples(st.just("text"), structural, st.integers(0, 7))), min_size=1, max_size=3)


@settings(derandomize=True, database=None, max_examples=200, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(urdf_edits)
def test_a_generated_urdf_is_a_one_line_finger_error_or_a_finite_finger(tmp_path_factory, capfd, edits):
    """A mutated finger URDF (attribute values and structure) either loads as a finger whose model is finite
    (lengths, mass matrix positive definite, tip Jacobian) or raises a FingerModelError naming the file in one
    line, with urdfdom's own output kept off stderr."""
    import pinocchio as pin

    from regrasp import Finger
    from regrasp.core.exceptions import FingerModelError, RegraspError
    from regrasp.model.collision import checked_link_shapes, default_tip_clearance

    path = tmp_path_factory.mktemp("urdf") / "finger.urdf"
    path.write_text(mutated_urdf(URDF_TEXT, edits))
    capfd.readouterr()
    try:
        finger = Finger.from_urdf(path)
    except RegraspError as exc:
        assert isinstance(exc, FingerModelError) and str(path) in str(exc), exc
        assert "\n" not in str(exc) and len(str(exc)) < 1200, str(exc)
        assert capfd.readouterr().err == ""
        return
    assert capfd.readouterr().err == ""
    assert all(1e-6 <= length <= 10.0 for length in finger.link_lengths)
    data = finger.model.createData()
    for q in np.random.default_rng(0).uniform(-3.0, 3.0, (3, finger.model.nq)):
        mass = pin.crba(finger.model, data, q)
        assert np.isfinite(mass).all() and np.linalg.eigvalsh(0.5 * (mass + mass.T)).min() > 0.0
        assert np.isfinite(finger.tip_jacobian(q)).all() and np.isfinite(finger.forward_kinematics(q)).all()
    try:  # the 'urdf' geometry's shapes: usable, or a one-line FingerModelError
        checked_link_shapes(finger, default_tip_clearance(finger))
    except FingerModelError as exc:
        assert "\n" not in str(exc)

"""Generated bad inputs (hypothesis, seeded): the validation layer, the scenario reader and the CLI.

Each property: a typed error whose message names the parameter or key, or a valid value with no
NaN or inf; for the CLI, exit 2 with one error line on stderr. ``derandomize`` makes the examples
the same on every run. Every flag of ``simulate`` and ``study`` (issue 25): one to three flags with generated
values either exit 2 with one error line before any work, or reach the work (replaced here by :class:`Reached`), and
a value that must be refused (a count out of its bounds, an unwritable path, a run of no step, an address where no
Ray cluster answers) never reaches it.
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


# ---------------------------------------------------------------- every flag of simulate and study (issue 25)
class Reached(Exception):
    """The command got past its checks to its work (the plan, the rollout): its input was taken."""


def reached(*args, **kwargs):
    raise Reached


class FlagRecorder:
    """Stands in for a command's parser in its ``configure``: the flags it adds, each with its options."""

    def __init__(self, configure):
        self.flags: dict[str, dict] = {}
        configure(self)

    def add_argument(self, *names, **options):
        self.flags.update({n: options for n in names if n.startswith("--")})

    def add_mutually_exclusive_group(self, **options):
        return self

    def set_defaults(self, **defaults):
        pass


def count_bounds():
    from regrasp.core.validation import MAX_COUNT, MAX_RUNS, MAX_SEED, MAX_WORKERS
    from regrasp.model.noise import MAX_DELAY_STEPS

    return {"simulate": {"--periods": (1, MAX_COUNT), "--decimate": (1, MAX_COUNT)},
            "study": {"--periods": (1, MAX_COUNT), "--runs": (1, MAX_RUNS), "--seed": (0, MAX_SEED),
                      "--workers": (1, MAX_WORKERS), "--replay": (0, MAX_RUNS - 1), "--delay": (0, MAX_DELAY_STEPS),
                      "--slip-delay": (0, MAX_DELAY_STEPS)}}


T3 = str(ROOT / "examples" / "scenarios" / "paper_trajectory_2_three_fingers.toml")
BAD_PATHS = ["", "/proc/x", "a\0b", "x" * 300]
# values no flag's work is slow for (no run count or replay index in the thousands, no host name to look up)
flag_values = st.one_of(
    st.sampled_from(["abc", "nan", "inf", "-inf", "-1", "0", "1", "2", "0.5", "1.5", "1e-5", "1e-300", "1e300",
                     "-1e-300", "0.0002", "1" + "0" * 21, "9" * 5000, "0x10", "1_0", " 3 ", "\u0663", "11", "100001",
                     "1025", "1000001", "mass=0.1,0.2", "delay=1,2", "bogus=1", "xi-noise=", "mujoco", "drake",
                     "project", "none", "paper", "rerun+http://127.0.0.1:1/proxy", "figs", "out.rrd", *BAD_PATHS]),
    st.sampled_from(["0", "1", "2", "0.1", "0.01", "0.001", "0.2", "0.25", "5", "10"]),  # (values most flags take)
    st.integers(-3, 12).map(str), st.floats(allow_nan=True, allow_infinity=True).map(repr), st.text(max_size=6))
ray_values = st.sampled_from(["", "local", "auto", "127.0.0.1:1", "127.0.0.1:0", "[::1]:1", "ray://127.0.0.1", "1.2.3",
                              "x y:1", "h:99999", "-1"])
path_values = st.sampled_from([*BAD_PATHS, "figs", "out.rrd", "sub/out.rrd", ".", "/proc", "/proc/self/x"])


def values_for(command: str, flag: str):
    """What a flag is given: a generated value, or one aimed at it (a path, a Ray address, a count at its bounds)."""
    aimed = {"--rrd": path_values, "--plot": path_values, "--ray": ray_values,
             "--connect": st.sampled_from(["rerun+http://127.0.0.1:1/proxy", "localhost:9876", "", "rerun://"])}
    bounds = count_bounds()[command].get(flag)
    if bounds is not None:  # (not the largest run counts: their draws take seconds)
        lo, hi = bounds
        aimed[flag] = st.sampled_from([str(lo - 1), str(lo), str(lo + 1), str(hi + 1), "1" + "0" * 400, "1.0", "1e3"])
    if flag == "--ray":  # (only these: a generated host name would be looked up)
        return ray_values
    return st.one_of(aimed[flag], flag_values) if flag in aimed else flag_values


def command_line(command: str, chosen: dict) -> list[str]:
    flags = FlagRecorder(configure_of(command)).flags
    argv = [command, T3]
    for flag, value in chosen.items():
        argv.append(flag)
        if flags[flag].get("action") != "store_true":
            argv.append(value)
    return argv


def configure_of(command: str):
    from regrasp.cli import simulate, study

    return {"simulate": simulate.configure, "study": study.configure}[command]


def number(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        return math.nan


def must_refuse(command: str, chosen: dict) -> str | None:
    """Why the command line must be refused (a count out of its bounds, a path no file can be written to, a run of
    no step, an address where no Ray cluster answers, no viewer's URL), or None."""
    for flag, value in chosen.items():
        if (flag == "--duration" and not 1e-3 <= number(value) <= 3600.0) \
                or (flag == "--ray" and value not in ("local", "auto")) \
                or (flag == "--connect" and value != "rerun+http://127.0.0.1:1/proxy"):
            return f"{flag} {value[:40]!r}"
        bounds = count_bounds()[command].get(flag)
        if bounds is not None:
            try:
                ok = bounds[0] <= int(value) <= bounds[1]
            except ValueError:
                ok = False
            if not ok:
                return f"{flag} {value[:40]!r}"
        if flag in ("--rrd", "--plot") and value in BAD_PATHS:
            return f"{flag} {value[:40]!r}"
    return None


def test_the_count_table_names_every_count_flag():
    for command, bounds in count_bounds().items():
        flags = FlagRecorder(configure_of(command)).flags
        counts = {f for f, o in flags.items()
                  if getattr(o.get("type"), "__qualname__", "").startswith("count_argument")}
        assert counts == set(bounds), command


def generated_command_lines(command: str):
    """One to three of the command's flags, each with a value (:func:`values_for`)."""
    flags = sorted(FlagRecorder(configure_of(command)).flags)
    return st.lists(st.sampled_from(flags), min_size=1, max_size=3, unique=True).flatmap(
        lambda chosen: st.tuples(*(values_for(command, f) for f in chosen)).map(lambda vs: dict(zip(chosen, vs))))


def check_command_line(capsys, command: str, chosen: dict) -> None:
    argv = command_line(command, chosen)
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse
        code = exc.code
    except Reached:
        code = None
    out, err = capsys.readouterr()
    lines = err.strip().splitlines()
    if code is None:  # taken: then nothing said it was bad
        assert must_refuse(command, chosen) is None, (argv, must_refuse(command, chosen))
        assert "error" not in err, err
        return
    assert code == 2, (argv, code, out, err)
    assert lines and re.match(r"regrasp( \w+)?: error: ", lines[-1]), (argv, lines)
    assert "\n" not in lines[-1] and not any("Traceback" in line for line in lines), lines
    if lines[-1].startswith("regrasp: error: "):  # (a typed error: its one line, nothing else)
        assert len(lines) == 1, lines


FLAG_SETTINGS = settings(derandomize=True, database=None, max_examples=200, deadline=None,
                         suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


@pytest.fixture
def before_any_work(tmp_path, monkeypatch):
    """The commands' work replaced by :class:`Reached` (the checks are what is tested), in a fresh directory."""
    import regrasp.rollout.build
    import regrasp.schedule.planner

    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("RAY_ADDRESS", raising=False)
    monkeypatch.setattr(regrasp.rollout.build, "build_rollout", reached)
    monkeypatch.setattr(regrasp.schedule.planner, "plan_regrasps", reached)


@FLAG_SETTINGS
@given(chosen=generated_command_lines("simulate"))
def test_every_simulate_flag_takes_a_value_or_exits_2_with_one_line(capsys, before_any_work, chosen):
    check_command_line(capsys, "simulate", chosen)


@FLAG_SETTINGS
@given(chosen=generated_command_lines("study"))
def test_every_study_flag_takes_a_value_or_exits_2_with_one_line(capsys, before_any_work, chosen):
    check_command_line(capsys, "study", chosen)

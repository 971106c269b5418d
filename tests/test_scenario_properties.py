"""Generated bad values (hypothesis, seeded) for every ``[study]`` key and every friction key of a scenario file
(issue 25): ``mu``, ``mu_static`` and ``mu_kinetic`` in ``[hand]`` and in each ``[[fingers]]`` table, and every
:class:`~regrasp.model.perturbation.Perturbation` field in ``[study]``.

Each example ends in a one-line :class:`~regrasp.core.exceptions.ScenarioError` naming one of the keys it set (or no
key when the file is not TOML at all), or in a valid scenario whose values are the ones written, finite and within
their documented bounds. ``derandomize`` makes the examples the same on every run.
"""

import math
from dataclasses import fields
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from regrasp import load_scenario
from regrasp.core.contact import DEFAULT_FRICTION
from regrasp.core.exceptions import ScenarioError
from regrasp.model.perturbation import MAX_CONTACT_POSITION, RELATIVE, Perturbation

ROOT = Path(__file__).resolve().parents[1]
BASE = (ROOT / "examples" / "scenarios" / "paper_trajectory_2.toml").read_text().replace(
    '"../../urdf/', f'"{ROOT / "urdf"}/')
SETTINGS = settings(derandomize=True, database=None, max_examples=60, deadline=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])

# bad values of every kind, as TOML literals (and a few good ones, so that acceptance is exercised too)
BAD = ["nan", "-nan", "inf", "-inf", '"abc"', '"0.5"', "''", "true", "false", "[]", "[0.5]", "[0.5, 0.4]",
       "{ x = 1 }", "1979-05-27", "-1", "-0.0", "-1e-300", "1e308", "-1e308", "1e400", "5e-324",
       str(10**400), str(-(10**400)), "9223372036854775807", "0", "1", "2", "0.999999", "1.0", "0.01", "1e-300",
       "3.5", "1e6", ""]  # ("": no value at all, not TOML)
literals = st.one_of(st.sampled_from(BAD), st.floats(allow_nan=False, allow_infinity=False, width=32).map(repr),
                     st.integers(min_value=-3, max_value=3).map(str))

STUDY_KEYS = [f.name for f in fields(Perturbation)]
FRICTION_KEYS = ["mu", "mu_static", "mu_kinetic"]
# where each table's keys go: after a line the table has (the [[fingers]] tables by their edge)
TABLES = {"hand": "gravity = [0.0, -9.81]\n", "fingers[0]": "edge = 1\n", "fingers[1]": "edge = 3\n"}


def with_keys(entries: dict[str, dict[str, str]]) -> str:
    """BASE with ``{table: {key: literal}}`` written into its [hand] and [[fingers]] tables and a [study] table."""
    text = BASE
    for table, line in TABLES.items():
        assert text.count(line) == 1, line
        text = text.replace(line, line + "".join(f"{k} = {v}\n" for k, v in entries.get(table, {}).items()))
    if "study" in entries:
        text += "\n[study]\n" + "".join(f"{k} = {v}\n" for k, v in entries["study"].items())
    return text


def written_file(tmp_path_factory, entries) -> Path:
    path = tmp_path_factory.mktemp("sc") / "s.toml"
    path.write_text(with_keys(entries))
    return path


def check_error(exc: ScenarioError, path: Path, entries: dict[str, dict[str, str]]) -> None:
    """A one-line error naming the file and one of the keys written (or none: a file that is not TOML)."""
    text = str(exc)
    assert "\n" not in text and len(text) < 600 and text.startswith(str(path)), text
    written = {f"{table}.{key}" for table, keys in entries.items() for key in keys}
    if exc.key is None:
        assert "not valid TOML" in text, text
    else:
        assert exc.key in written, (exc.key, written, text)
    assert not any(word in text for word in ("Traceback", "TypeError", "OverflowError")), text


@SETTINGS
@given(st.dictionaries(st.sampled_from(STUDY_KEYS), literals, min_size=1, max_size=3))
def test_a_bad_study_value_is_an_error_naming_its_key_or_the_perturbation_written(tmp_path_factory, study):
    path = written_file(tmp_path_factory, {"study": study})
    try:
        sc = load_scenario(path)
    except ScenarioError as exc:
        check_error(exc, path, {"study": study})
        return
    p = sc.study
    for name in STUDY_KEYS:  # every key written is taken as written; the others keep their defaults
        value = getattr(p, name)
        if name not in study:
            assert value == getattr(Perturbation(), name), name
            continue
        written = float(study[name]) if study[name] not in ("true", "false") else None
        assert written is not None and value == written, (name, study[name], value)
        if name in ("delay", "slip_delay"):
            assert type(value) is int and value >= 0, (name, value)
        else:
            assert type(value) is float and math.isfinite(value) and value >= 0.0, (name, value)
        if name in RELATIVE:
            assert value < 1.0, (name, value)
        if name == "contact_position":
            assert value <= MAX_CONTACT_POSITION


friction_entries = st.dictionaries(
    st.sampled_from(list(TABLES)), st.dictionaries(st.sampled_from(FRICTION_KEYS), literals, min_size=1, max_size=3),
    min_size=1, max_size=2)


@SETTINGS
@given(friction_entries)
def test_a_bad_friction_value_is_an_error_naming_its_key_or_the_friction_written(tmp_path_factory, entries):
    path = written_file(tmp_path_factory, entries)
    try:
        sc = load_scenario(path)
    except ScenarioError as exc:
        check_error(exc, path, entries)
        return

    def written(table: str):
        keys = entries.get(table, {})
        if "mu" in keys:
            assert set(keys) == {"mu"}, keys  # (mu with mu_static or mu_kinetic is an error)
            return float(keys["mu"]), float(keys["mu"])
        if keys:
            assert set(keys) == {"mu_static", "mu_kinetic"}, keys  # (one without the other is an error)
            return float(keys["mu_static"]), float(keys["mu_kinetic"])
        return None

    hand = written("hand") or (DEFAULT_FRICTION.static, DEFAULT_FRICTION.kinetic)
    for i, friction in enumerate(sc.friction):  # a finger's own keys override [hand]'s
        static, kinetic = written(f"fingers[{i}]") or hand
        assert (friction.static, friction.kinetic) == (static, kinetic), (i, friction, entries)
        assert math.isfinite(friction.static) and 0.0 <= friction.kinetic <= friction.static, friction


@pytest.mark.parametrize("key", STUDY_KEYS)
@pytest.mark.parametrize("literal", ["nan", "inf", '"0.1"', "-1", "1e308", "[0.1]", "true", str(10**400)])
def test_every_study_key_refuses_each_kind_of_bad_value_at_its_key(tmp_path, key, literal):
    """The generated cases above draw from all keys; this one crosses every key with every kind of bad value once
    (1e308 is accepted only where a size has no upper bound: then it is taken as written, a finite float)."""
    path = tmp_path / "s.toml"
    path.write_text(with_keys({"study": {key: literal}}))
    try:
        sc = load_scenario(path)
    except ScenarioError as exc:
        check_error(exc, path, {"study": {key: literal}})
        assert exc.key == f"study.{key}"
        return
    assert literal == "1e308" and getattr(sc.study, key) == 1e308 and key not in (*RELATIVE, "contact_position")


@pytest.mark.parametrize("table", list(TABLES))
@pytest.mark.parametrize("key", FRICTION_KEYS)
@pytest.mark.parametrize("literal", ["nan", "-inf", '"0.5"', "-0.1", "[0.5]", "false", str(10**400), "{ x = 1 }"])
def test_every_friction_key_refuses_each_kind_of_bad_value_at_its_key(tmp_path, table, key, literal):
    """Every friction key of every table with every kind of bad value (the pair written with a good partner)."""
    keys = {key: literal} if key == "mu" else {"mu_static": "0.8", "mu_kinetic": "0.4", key: literal}
    path = tmp_path / "s.toml"
    path.write_text(with_keys({table: keys}))
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    check_error(info.value, path, {table: keys})
    assert info.value.key == f"{table}.{key}"


WAYPOINTS = '[trajectory]\ntype = "waypoints"\ntimes = TIMES\nposes = POSES\n\n[hand]'


@pytest.mark.parametrize("times, poses, key", [
    ("[-1.7e308, 0.0, 1.7e308]", "[[0, 0.12, 0], [0.01, 0.12, 0], [0, 0.12, 0]]", "trajectory.times"),
    ("[0.0, 1e-300, 2e-300, 3e-300]", "[[0, 0.12, 0], [0.01, 0.12, 0], [0, 0.12, 0], [0.01, 0.12, 0]]",
     "trajectory.times"),
    ("[0.0, 1e-6, 2e-6]", "[[0, 0.12, 0], [1e200, 0.12, 0], [0, 0.12, 0]]", "trajectory.poses"),
], ids=["span ±1.7e308", "1e-300 apart", "overflowing spline"])
def test_plan_with_extreme_waypoint_times_exits_2_with_one_line_and_no_warning(tmp_path, capfd, times, poses, key):
    """Issue 25: `plan` printed a scipy traceback (times spanning ±1.7e308), or 3 scipy RuntimeWarnings and
    ``invalid pose_object_in_hand = array([nan, nan, 0.])`` (times 1e-300 s apart)."""
    import warnings

    from regrasp.cli.main import main

    path = tmp_path / "s.toml"
    path.write_text(BASE.split("[trajectory]")[0] + WAYPOINTS.replace("TIMES", times).replace("POSES", poses)
                    + BASE.split("[hand]")[1])
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # (a RuntimeWarning would fail the test)
        code = main(["plan", str(path), "--samples", "11"])
    out, err = capfd.readouterr()
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and lines[0].startswith(f"regrasp: error: {path}: key '{key}'"), (out, err)

"""A suite's spec: the shipped ones load; every mistake is a ScenarioError naming the spec's file and key, raised
before any work."""

from pathlib import Path

import pytest

from regrasp.core.exceptions import ScenarioError
from regrasp.suite.spec import SuiteSpec, Varied, load_suite_spec

ROOT = Path(__file__).resolve().parents[2]
BASE = ROOT / "examples" / "scenarios" / "paper_trajectory_2_three_fingers.toml"


def write(tmp_path: Path, body: str, head: str | None = None) -> Path:
    path = tmp_path / "spec.toml"
    head = f'scenario = "{BASE}"\nvariants = 3\n' if head is None else head
    path.write_text(head + body)
    return path


def test_the_default_spec_draws_at_least_100_three_finger_variants_around_the_shipped_scenario():
    spec = load_suite_spec(ROOT / "examples" / "suites" / "default.toml")
    assert spec.name == "default" and spec.variants >= 100 and spec.scenario == BASE
    ranges = {v.key: (v.low, v.high) for v in spec.varied}
    assert ranges["trajectory.omega"] == (1.5, 3.0) and ranges["object.mass"] == (0.04, 0.2)
    assert ranges["hand.mu"] == (0.4, 0.8) and ranges["fingers.palm.base.0"] == (0.02, 0.04)
    assert len(spec.base["fingers"]) == 3


def test_the_variety_spec_uses_every_kind_of_entry():
    spec = load_suite_spec(ROOT / "examples" / "suites" / "variety.toml")
    kinds = {v.key: v for v in spec.varied}
    assert kinds["trajectory"].choices is not None and len(kinds["trajectory"].choices) == 3
    assert [len(c) for c in kinds["fingers"].choices] == [3, 2]
    assert kinds["hand.gravity_angle"].low == -0.2
    assert all(Path(f["urdf"]).is_absolute() for c in kinds["fingers"].choices for f in c)  # (from the spec's folder)


def test_nested_tables_and_spelled_out_forms_are_the_same_keys(tmp_path):
    spec = load_suite_spec(write(tmp_path, '[vary.object]\nmass = {uniform = [0.05, 0.1]}\nwidth = [0.09, 0.1]\n'
                                           '[vary.fingers.palm]\nedge = {choices = [2]}\n'))
    assert [(v.key, v.low, v.high, v.choices) for v in spec.varied] == [
        ("object.mass", 0.05, 0.1, None), ("object.width", 0.09, 0.1, None), ("fingers.palm.edge", None, None, (2,))]
    assert spec.varied[2].path == ("fingers", "palm", "edge")


@pytest.mark.parametrize("body, key, words", [
    ('[vary]\n"object.mass" = [0.1, 0.05]\n', "vary.object.mass", "lo <= hi"),
    ('[vary]\n"object.mass" = []\n', "vary.object.mass", "two finite numbers"),
    ('[vary]\n"object.mass" = [0.05]\n', "vary.object.mass", "two finite numbers"),
    ('[vary]\n"object.mass" = [0.05, nan]\n', "vary.object.mass", "two finite numbers"),
    ('[vary]\n"object.mass" = 0.05\n', "vary.object.mass", "{choices = [value, ...]}"),
    ('[vary]\n"object.mass" = {choices = []}\n', "vary.object.mass.choices", "non-empty list"),
    ('[vary]\n"object.mass" = {uniform = [0.05, 0.1], scale = 2}\n', "vary.object.mass.scale", "unknown key"),
    ('[vary]\n"objekt.mass" = [0.05, 0.1]\n', "vary.objekt.mass", "'object': a typo?"),
    ('[vary]\n"object..mass" = [0.05, 0.1]\n', "vary.object..mass", "an empty part"),
    ('[vary]\n"trajectory.omegaa" = [1.5, 3.0]\n', "vary.trajectory.omegaa", "trajectory.omegaa"),
    ('[vary]\n"trajectory.type" = {choices = ["spiral"]}\n', "vary.trajectory.type", "'ellipse', 'waypoints'"),
    ('[vary]\n"object.mass" = [-0.1, 0.1]\n', "vary.object.mass", "object.mass"),
    ('[vary]\n"fingers.palm.urdf" = {choices = ["no_such.urdf"]}\n', "vary.fingers.palm.urdf.choices[0]",
     "no_such.urdf"),
    ('[vary]\n"fingers.thumb.edge" = {choices = [1]}\n', "vary.fingers.thumb.edge", "no finger 'thumb'"),
    ('[vary]\n"fingers.palm.base.3" = [0.0, 0.1]\n', "vary.fingers.palm.base.3", "an index 0..2"),
    ('[vary]\n"fingers.palm.edge" = {choices = [7]}\n', "vary.fingers.palm.edge", "edge 7 does not exist"),
    ('[vary]\n"hand.gravity_angle" = {choices = [0.1]}\n', "vary.hand.gravity_angle", "a range of angles"),
    ('[vary]\n"object.vertices" = {choices = [1979-05-27]}\n', "vary.object.vertices.choices[0]", "numbers, strings"),
    ('vary = 3\n', "vary", "a table [vary]"),
    ('variant = 3\n', "variant", "'variants': a typo?"),
])
def test_a_bad_entry_names_the_key(tmp_path, body, key, words):
    with pytest.raises(ScenarioError) as info:
        load_suite_spec(write(tmp_path, body))
    assert info.value.key == key and words in str(info.value), str(info.value)
    assert str(tmp_path / "spec.toml") in str(info.value)


@pytest.mark.parametrize("head, key, words", [
    ("variants = 3\n", "scenario", "required"),
    ('scenario = "nowhere.toml"\nvariants = 3\n', "scenario", "nowhere.toml"),
    (f'scenario = "{BASE}"\n', "variants", "required"),
    (f'scenario = "{BASE}"\nvariants = 0\n', "variants", "an integer in [1, "),
    (f'scenario = "{BASE}"\nvariants = 2.5\n', "variants", "an integer in [1, "),
    (f'scenario = "{BASE}"\nvariants = 3\nseed = -1\n', "seed", "an integer in [0, "),
    (f'scenario = "{BASE}"\nvariants = 3\nname = ""\n', "name", "non-empty string"),
    ('scenario = 3\nvariants = 3\n', "scenario", "a scenario file's path"),
])
def test_a_bad_top_level_key_names_it(tmp_path, head, key, words):
    with pytest.raises(ScenarioError) as info:
        load_suite_spec(write(tmp_path, "", head))
    assert info.value.key == key and words in str(info.value), str(info.value)


def test_a_file_that_is_no_spec_is_said(tmp_path):
    with pytest.raises(ScenarioError, match="not valid TOML"):
        load_suite_spec(write(tmp_path, "[vary\n"))
    with pytest.raises(ScenarioError, match="does not exist|no such|not found"):
        load_suite_spec(tmp_path / "missing.toml")


def test_a_spec_built_in_code_is_checked():
    base = {"name": "x"}
    with pytest.raises(Exception, match="variants"):
        SuiteSpec("s", BASE, base, (), 0)
    with pytest.raises(Exception, match="varied"):
        SuiteSpec("s", BASE, base, ("object.mass",), 1)
    spec = SuiteSpec("s", BASE, base, (Varied("object.mass", ("object", "mass"), 0.05, 0.1),), 2, seed=3)
    assert spec.where == "<suite s>" and spec.varied[0].describe() == "U(0.05, 0.1)"


def test_the_modules_example_is_a_valid_spec(tmp_path):
    """The spec module's docstring example reads (its scenario's path made this checkout's)."""
    import re

    from regrasp.suite import spec as module

    example = re.search(r"code-block:: toml\n\n(.*?)\n\n[A-Z]", module.__doc__, re.S).group(1)
    text = "\n".join(line[4:] for line in example.splitlines())
    text = text.replace('"../scenarios/paper_trajectory_2_three_fingers.toml"', f'"{BASE}"')
    (tmp_path / "spec.toml").write_text(text)
    spec = load_suite_spec(tmp_path / "spec.toml")
    assert [v.key for v in spec.varied][:3] == ["object.width", "trajectory.omega", "fingers.palm.base.0"]
    assert spec.varied[-1].key == "trajectory" and spec.variants == 120

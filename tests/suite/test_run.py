"""Running a suite: a variant without a schedule says why (a physical reason), one its scenario refuses is an
outcome too, a scheduled one runs on the plant; Ctrl-C keeps what finished; the outcomes do not depend on the
workers."""

from dataclasses import fields, replace
from pathlib import Path

import pytest

from regrasp.core.exceptions import InvalidParameterError
from regrasp.plants.spec import ModelErrors, PlantSpec
from regrasp.suite.run import run_suite, run_variant
from regrasp.suite.spec import Varied, load_suite_spec

ROOT = Path(__file__).resolve().parents[2]
SCENARIOS = ROOT / "examples" / "scenarios"
#: Outcome fields that are measured (wall times, memory), not results.
MEASURED = {"plan_seconds", "envelope_seconds", "peak_memory", "memory_upper_bound", "cold", "run_seconds"}


def spec_file(tmp_path: Path, scenario: str, variants: int, body: str = "") -> Path:
    path = tmp_path / f"{Path(scenario).stem}.toml"
    path.write_text(f'scenario = "{SCENARIOS / scenario}"\nvariants = {variants}\nseed = 4\n[vary]\n{body}')
    return path


@pytest.fixture(scope="module")
def two_fingers(tmp_path_factory):
    """Two fingers on trajectory 2: no schedule, quickly (the two-finger slide rule)."""
    return load_suite_spec(spec_file(tmp_path_factory.mktemp("two"), "paper_trajectory_2.toml", 2,
                                     '"object.mass" = [0.09, 0.11]\n'))


@pytest.fixture(scope="module")
def three_fingers(tmp_path_factory):
    return load_suite_spec(spec_file(tmp_path_factory.mktemp("three"), "paper_trajectory_2_three_fingers.toml", 2,
                                     '"object.mass" = [0.075, 0.085]\n"hand.mu" = [0.5, 0.55]\n'))


def results(outcomes) -> list[dict]:
    return [{f.name: getattr(o, f.name) for f in fields(o) if f.name not in MEASURED} for o in outcomes]


def test_a_variant_without_a_schedule_says_why(two_fingers):
    o = run_variant(two_fingers, 1)
    assert o.status == "no_schedule" and o.limit == "forces" and o.contacts == ("finger1",) and o.physical
    assert "two-finger slide rule" in o.reason and o.latest_time > 0 and o.fingers == 2
    assert o.plan_seconds > o.envelope_seconds > 0 and o.peak_memory > 2**20 and o.success is None
    assert o.parameters == (("object.mass", pytest.approx(o.parameters[0][1])),)


def test_a_variant_its_scenario_refuses_is_an_outcome(two_fingers):
    bad = replace(two_fingers, varied=(Varied("object.mass", ("object", "mass"), -2.0, -1.0),))
    o = run_variant(bad, 0)
    assert o.status == "refused" and o.limit == "ScenarioError" and "object.mass" in o.reason
    assert o.fingers == 0 and o.plan_seconds is None and not o.physical


def test_a_scheduled_variant_runs_on_the_plant_and_ctrl_c_keeps_what_finished(three_fingers):
    def press(done: int, total: int) -> None:
        if done == 1:
            raise KeyboardInterrupt

    r = run_suite(three_fingers, periods=1, progress=press, interruptible=True)
    assert r.interrupted and r.requested == 2 and [o.index for o in r.outcomes] == [0]
    o = r.outcomes[0]
    assert o.scheduled and o.slides >= 1 and o.success and o.run_seconds > 0 and o.failure_kind is None
    assert r.successes == 1 and r.varied == ("object.mass", "hand.mu") and r.periods == 1


def test_ctrl_c_before_any_variant():
    def press(done: int, total: int) -> None:
        raise KeyboardInterrupt

    spec = ROOT / "examples" / "suites" / "default.toml"
    r = run_suite(spec, progress=press, interruptible=True)
    assert r.outcomes == () and r.interrupted
    with pytest.raises(KeyboardInterrupt):
        run_suite(spec, progress=press)


def test_plan_only_runs_nothing(two_fingers):
    r = run_suite(two_fingers, plan_only=True)
    assert r.plan_only and len(r.outcomes) == 2 and not r.ran and r.reasons[0][:3] == ("no_schedule", "forces",
                                                                                         ("finger1",))
    assert not r.unexplained and r.plan_seconds["max"] > 0


@pytest.mark.parametrize("options, words", [
    (dict(workers=0), "workers"), (dict(periods=0), "periods"), (dict(plan_only="yes"), "plan_only"),
    (dict(plant=PlantSpec(errors=ModelErrors(mass_scale=1.1))), "without model errors"),
    (dict(ray_address="not an address"), "ray_address"), (dict(plant="bullet"), "plant"),
])
def test_bad_options_are_refused_before_any_work(two_fingers, options, words):
    with pytest.raises(InvalidParameterError, match=words):
        run_suite(two_fingers, **options)


@pytest.mark.slow
def test_the_outcomes_do_not_depend_on_the_workers(two_fingers, three_fingers):
    spec = replace(two_fingers, variants=3)
    one, two = run_suite(spec, workers=1), run_suite(spec, workers=2)
    assert results(one.outcomes) == results(two.outcomes) and two.workers == 2
    planned = run_suite(three_fingers, workers=2, plan_only=True)
    assert [o.index for o in planned.outcomes] == [0, 1] and all(o.scheduled for o in planned.outcomes)


@pytest.mark.slow
def test_the_outcomes_are_the_same_on_a_local_ray(two_fingers):
    pytest.importorskip("ray")
    here = run_suite(two_fingers, workers=1)
    on_ray = run_suite(two_fingers, workers=2, ray_address="local")
    assert on_ray.backend == "ray" and results(on_ray.outcomes) == results(here.outcomes)

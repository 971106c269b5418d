"""A suite's summary: fractions with Wilson intervals, the reasons grouped, the failures counted, the percentiles;
JSON and back."""

import json

import pytest

from regrasp.study.study import wilson_interval
from regrasp.suite.result import SuiteResult, VariantOutcome, percentiles
from suite_results import made_result


def test_the_summary_counts_every_kind_of_outcome():
    r = made_result()
    assert len(r.scheduled) == 15 and r.schedule_interval == wilson_interval(15, 20)
    assert r.reasons == [("no_schedule", "forces", ("finger1",), (3, 4, 9)),
                         ("no_schedule", "verification", ("palm",), (5,)),
                         ("refused", "ScenarioError", (), (6,))]
    assert [o.index for o in r.unexplained] == [5, 6]
    assert len(r.ran) == 15 and r.successes == 13 and r.success_interval == wilson_interval(13, 15)
    assert r.failures == {"separation": 1, "unplanned_slip": 1}
    assert not r.interrupted and made_result(requested=30).interrupted
    assert r.outcomes[7].outcome == "separation" and r.outcomes[3].outcome == "no_schedule: forces"
    assert r.outcomes[0].outcome == "success" and r.outcomes[6].outcome == "refused: ScenarioError"
    planned = [o.plan_seconds for o in r.outcomes if o.plan_seconds is not None]
    assert len(planned) == 19 and r.plan_seconds == percentiles(planned)
    assert r.plan_seconds["max"] == max(planned) and r.plan_seconds["p50"] <= r.plan_seconds["p95"]


def test_percentiles_and_an_empty_suite():
    assert percentiles([]) is None
    assert percentiles([1.0, 2.0, 3.0, 4.0, 5.0]) == {"p50": 3.0, "p90": 4.6, "p95": 4.8, "max": 5.0}
    empty = made_result(0, requested=4)
    assert empty.interrupted and empty.schedule_interval == (0.0, 1.0) and empty.success_interval == (0.0, 1.0)
    assert empty.plan_seconds is None and empty.peak_memory is None and empty.reasons == []
    doc = empty.to_json_dict()
    assert doc["schedule_fraction"] is None and doc["success_rate"] is None


def test_json_round_trip():
    r = made_result()
    doc = json.loads(json.dumps(r.to_json_dict(), allow_nan=False))
    assert SuiteResult.from_json_dict(doc) == r
    assert doc["reasons"][0] == {"status": "no_schedule", "limit": "forces", "contacts": ["finger1"],
                                 "variants": [3, 4, 9]}
    assert doc["unexplained"] == [5, 6] and doc["failures"] == {"separation": 1, "unplanned_slip": 1}
    assert doc["outcomes"][0]["parameters"] == dict(r.outcomes[0].parameters)
    one = r.outcomes[7]
    assert VariantOutcome.from_json_dict(json.loads(json.dumps(one.to_json_dict()))) == one


@pytest.mark.parametrize("values", [[{"a": [1, 2]}], [[0.1, 0.2]], ["a string"]])
def test_drawn_values_of_any_toml_kind_survive_json(values):
    o = VariantOutcome(0, (1,), (("k", values[0]),), 3, "scheduled")
    assert VariantOutcome.from_json_dict(json.loads(json.dumps(o.to_json_dict()))) == o

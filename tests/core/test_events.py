"""Events and failures as values: kinds are enums equal to their strings, values are read-only numbers."""

import json

import pytest

from regrasp.core.events import Event, EventKind, EventSource, Failure, FailureKind


def test_an_event_is_a_value_with_read_only_numbers_and_a_json_form():
    e = Event(1.5, "finger1", "slip", "|f_t| > mu_s f_n", "plant", {"normal_force": 0.3})
    assert e.kind is EventKind.SLIP and e.source is EventSource.PLANT and e.kind == "slip"
    with pytest.raises(TypeError):
        e.values["normal_force"] = 1.0
    doc = json.loads(json.dumps(e.to_json_dict()))
    assert doc == {"time": 1.5, "contact": "finger1", "kind": "slip", "detail": "|f_t| > mu_s f_n",
                   "source": "plant", "values": {"normal_force": 0.3}}


def test_unknown_kinds_are_refused():
    with pytest.raises(ValueError):
        Event(0.0, "a", "wobble", "")
    with pytest.raises(ValueError):
        Failure(0.0, "broken", "")


def test_a_failure_says_when_what_and_who():
    f = Failure(2.0, FailureKind.COLLISION, "link 2 penetrates", "finger1")
    assert f.to_json_dict() == {"time": 2.0, "kind": "collision", "reason": "link 2 penetrates", "contact": "finger1"}

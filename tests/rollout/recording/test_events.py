"""The recording's event lines: who, what and when, for a finger's event and for one of no finger."""

from regrasp.core.events import Event, EventKind, EventSource
from regrasp.rollout.recording.events import event_line


def text(log):
    return str(log.text.as_arrow_array()[0])


def test_an_event_names_its_finger_and_one_of_no_finger_names_only_its_source():
    slip = event_line(Event(1.25, "finger2", EventKind.SLIP, "slip velocity 3 mm/s", source=EventSource.PLANT))
    replan = event_line(Event(0.08, "", EventKind.REPLAN_FAILED, "no regrasp schedule", source=EventSource.SUPERVISOR))
    assert text(slip) == "t = 1.2500 s  plant finger2: slip (slip velocity 3 mm/s)"
    assert text(replan) == "t = 0.0800 s  supervisor: replan_failed (no regrasp schedule)"

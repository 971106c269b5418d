"""The recording's ``events`` text log: one line per event (the plant's or the supervisor's) at its own time, one
ERROR line per failure, and which of a plant's events are logged already (:class:`PlantEventCursor`)."""

from __future__ import annotations

from collections.abc import Sequence

import rerun as rr

from ...core.events import Event, EventKind, Failure, FailureKind

__all__ = ["WARN_KINDS", "PlantEventCursor", "event_line", "failure_line"]

#: The event kinds logged at level WARN (the others at INFO).
WARN_KINDS = frozenset({EventKind.SLIP, EventKind.SEPARATION, EventKind.COLLISION, EventKind.LEFT_EDGE,
                        EventKind.SINGULAR, EventKind.LEFT_ENVELOPE, EventKind.SLIDE_REJECTED,
                        EventKind.SLIDE_ABORTED, EventKind.REPLAN_FAILED})


def event_line(ev: Event) -> rr.TextLog:
    """``t = … s  <source> <finger>: <kind> (<detail>)`` (an event of no one finger, such as a re-plan:
    ``<source>: <kind> (<detail>)``), WARN for the kinds in :data:`WARN_KINDS`, else INFO."""
    level = "WARN" if ev.kind in WARN_KINDS else "INFO"
    who = f"{ev.source.value} {ev.contact}" if ev.contact else ev.source.value
    return rr.TextLog(f"t = {ev.time:.4f} s  {who}: {ev.kind.value} ({ev.detail})", level=level)


def failure_line(failure: Failure) -> rr.TextLog:
    """``FAILURE (<kind>): <reason>``, level ERROR."""
    return rr.TextLog(f"FAILURE ({FailureKind(failure.kind).value}): {failure.reason}", level="ERROR")


class PlantEventCursor:
    """Where a recording is in a plant's event list (a new list, after ``plant.reset()``, starts again at 0)."""

    def __init__(self) -> None:
        self.events: Sequence[Event] | None = None
        self.seen = 0

    def new(self, events: Sequence[Event]) -> Sequence[Event]:
        """The events of ``events`` not returned before; all of them are seen after this."""
        seen = self.seen if events is self.events else 0
        self.skip(events)
        return events[seen:]

    def skip(self, events: Sequence[Event]) -> None:
        """Mark every event of ``events`` seen (they are logged by other means: a record's)."""
        self.events, self.seen = events, len(events)

"""What happens during a rollout, as values: event kinds, failure kinds, one event type.

The plant reports physical events (:class:`EventKind` ``SLIP`` … ``SINGULAR``); the supervisor
reports its decisions (``DANGER`` … ``REPLAN_FAILED``). Both end up in one time-ordered log of
:class:`Event`, whose ``values`` hold the numbers (positions [m], margins [m] or [N], times [s]) a
program reads; ``detail`` is the same in words for a person. A rollout that fails says why with a
:class:`Failure` of a :class:`FailureKind`. Code branches on kinds and values, never on text.

The enums mix in ``str``: ``EventKind.SLIP == "slip"``, so a kind prints and serialises as its value.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import Enum
from types import MappingProxyType
from typing import Mapping

__all__ = ["Event", "EventKind", "EventSource", "Failure", "FailureKind"]


class EventKind(str, Enum):
    """What an :class:`Event` reports."""

    # the plant (regrasp.plants.project.plant)
    SLIP = "slip"                      #: a fixed contact's force left its static cone
    STICK = "stick"                    #: a sliding contact stopped, its force inside the static cone
    SEPARATION = "separation"          #: a contact's normal force went negative
    LEFT_EDGE = "left_edge"            #: a contact left its edge
    COLLISION = "collision"            #: a finger link penetrates the object
    SINGULAR = "singular"              #: a finger's Jacobian became singular
    SATURATION = "saturation"          #: a commanded joint torque exceeded its limit: the motor applies the limit
    # the supervisor (regrasp.supervisor.supervisor and its policies)
    DANGER = "danger"                  #: a contact entered its danger zone (or will, by the plan)
    SLIDE_REJECTED = "slide_rejected"  #: the sliding predicate refused a slide; the policy waits
    PRIME = "prime"                    #: a slide starts: the contact is put just past its static cone
    SLIDE = "slide"                    #: the sliding law took over
    ARRIVED = "arrived"                #: a slide reached its target
    STUCK = "stuck"                    #: a slide stuck before its target
    TIMED_OUT = "timed_out"            #: a slide ran out of time
    SLIDE_ABORTED = "slide_aborted"    #: no internal force kept a slide going
    SETTLED = "settled"                #: a slid contact is fixed again
    LEFT_ENVELOPE = "left_envelope"    #: a fixed contact is outside its feasible envelope
    REPLAN = "replan"                  #: the schedule was re-planned from the measured state
    REPLAN_FAILED = "replan_failed"    #: a re-plan found no schedule (the old one is kept)


class EventSource(str, Enum):
    """Who reported an :class:`Event`."""

    PLANT = "plant"
    SUPERVISOR = "supervisor"


@dataclass(frozen=True)
class Event:
    """A plant event or a supervisor decision.

    Attributes:
        time: [s].
        contact: Finger name ("" when the event concerns no one contact).
        kind: :class:`EventKind`.
        detail: The numbers and the reason, in words.
        source: :class:`EventSource`.
        values: The numbers, by name (SI units: ``xi`` [m], ``target`` [m], ``margin`` [m],
            ``direction`` ±1, ``planned_end`` [s], ...), read-only.
    """

    time: float
    contact: str
    kind: EventKind
    detail: str
    source: EventSource = EventSource.SUPERVISOR
    values: Mapping[str, float] = field(default_factory=dict)

    def __post_init__(self):
        object.__setattr__(self, "kind", EventKind(self.kind))
        object.__setattr__(self, "source", EventSource(self.source))
        if not isinstance(self.values, MappingProxyType):
            object.__setattr__(self, "values", MappingProxyType(dict(self.values)))

    def to_json_dict(self) -> dict:
        """The event as plain JSON types (a value that is NaN or infinite is null: JSON has neither)."""
        return {"time": self.time, "contact": self.contact, "kind": self.kind.value, "detail": self.detail,
                "source": self.source.value,
                "values": {k: float(v) if math.isfinite(v) else None for k, v in self.values.items()}}


class FailureKind(str, Enum):
    """Why a rollout failed."""

    UNPLANNED_SLIP = "unplanned_slip"  #: a contact slipped that the supervisor held fixed
    SEPARATION = "separation"          #: a contact lost touch
    LEFT_EDGE = "left_edge"            #: a contact slid off its edge
    COLLISION = "collision"            #: a finger link hit the object
    SINGULAR = "singular"              #: a finger reached a singular posture
    LEFT_ENVELOPE = "left_envelope"    #: a fixed contact left its feasible envelope
    CONTROL = "control"                #: the control law had no solution (no internal force, singular model)
    NO_SCHEDULE = "no_schedule"        #: no regrasp schedule exists (the planner's reason)
    INTERRUPTED = "interrupted"        #: the user stopped the run (Ctrl-C)


#: The failure a plant event that stops the plant means.
PLANT_FAILURES = {EventKind.SEPARATION: FailureKind.SEPARATION, EventKind.LEFT_EDGE: FailureKind.LEFT_EDGE,
                  EventKind.COLLISION: FailureKind.COLLISION, EventKind.SINGULAR: FailureKind.SINGULAR}


@dataclass(frozen=True)
class Failure:
    """When and why a rollout failed.

    Attributes:
        time: [s].
        kind: :class:`FailureKind`.
        reason: In words, with the numbers.
        contact: The finger concerned, or "".
    """

    time: float
    kind: FailureKind
    reason: str
    contact: str = ""

    def __post_init__(self):
        object.__setattr__(self, "kind", FailureKind(self.kind))

    def to_json_dict(self) -> dict:
        return {"time": self.time, "kind": self.kind.value, "reason": self.reason, "contact": self.contact}

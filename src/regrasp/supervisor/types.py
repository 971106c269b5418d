"""The value types of slides: a contact's phase, a slide order (what a policy asks for) and a slide's end.

They are shared by the policies (:mod:`regrasp.supervisor.policies.scheduled`), which propose :class:`SlideOrder` s and
learn how they ended (:class:`SlideEnd`), and the executor (:mod:`regrasp.supervisor.executor`), which runs them.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any
from enum import Enum

from ..core.events import EventKind
from ..core.exceptions import InvalidParameterError

__all__ = ["SLIPPING_PHASES", "ContactPhase", "Reference", "SlideEnd", "SlideOrder", "SlideProfile"]

#: t [s] -> (ξ_d [m], ξ̇_d [m/s], ξ̈_d [m/s²])
Reference = Callable[[float], tuple[float, float, float]]


class ContactPhase(str, Enum):
    """What the supervisor is doing with a contact."""

    FIXED = "fixed"
    PRIMING = "priming"
    SLIDING = "sliding"
    SETTLING = "settling"


#: The phases in which a contact slips on purpose.
SLIPPING_PHASES = frozenset({ContactPhase.PRIMING, ContactPhase.SLIDING, ContactPhase.SETTLING})


@dataclass(frozen=True)
class SlideProfile:
    """A planned slide's profile as a :data:`Reference`: t [s] -> (ξ, ξ̇, ξ̈) of ``slide``
    (:class:`~regrasp.schedule.schedule.Slide`) at t - ``offset`` [s] (a periodic schedule's later periods). Compiled
    stretches (:mod:`regrasp.rollout.stretch`) read its fields."""

    slide: Any
    offset: float = 0.0

    def __call__(self, t: float) -> tuple[float, float, float]:
        return self.slide.profile_at(float(t) - self.offset)


@dataclass(frozen=True)
class SlideOrder:
    """A slide a policy asks for.

    Attributes:
        contact: The contact's index.
        direction: +1 (along the edge's ξ) or -1.
        target: ξ* [m].
        reference: t [s] -> (ξ_d [m], ξ̇_d [m/s], ξ̈_d [m/s²]) for the sliding phase, or None (the filter).
        planned_start, planned_end: When the slide is planned to start and end [s] (None: unplanned).
        why: Why the slide is ordered, in words.
    """

    contact: int
    direction: int
    target: float
    reference: Reference | None = None
    planned_start: float | None = None
    planned_end: float | None = None
    why: str = ""

    def __post_init__(self):
        if self.direction not in (-1, 1):
            raise InvalidParameterError("direction", self.direction, "+1 or -1")
        if not math.isfinite(self.target):
            raise InvalidParameterError("target", self.target, "a finite position [m]")


@dataclass(frozen=True)
class SlideEnd:
    """How an ordered slide ended.

    Attributes:
        order: The order.
        kind: ``ARRIVED``, ``STUCK``, ``TIMED_OUT`` or ``SLIDE_ABORTED`` (:class:`~regrasp.core.events.EventKind`).
        time: When its sliding phase ended [s].
        xi: Where the contact was then [m].
    """

    order: SlideOrder
    kind: EventKind
    time: float
    xi: float

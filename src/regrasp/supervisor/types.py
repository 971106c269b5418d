"""The supervisor's value types: a contact's phase, a slide order (what a policy asks for), a slide's end, what a
policy may know of the task (:class:`SupervisorContext`) and one supervisor step's output (:class:`SupervisorOutput`).

They are shared by the policies (:mod:`regrasp.supervisor.policies.scheduled`), which propose :class:`SlideOrder` s and
learn how they ended (:class:`SlideEnd`), and the executor (:mod:`regrasp.supervisor.executor`), which runs them.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum
from typing import TYPE_CHECKING, Any

import numpy as np

from ..core.events import Event, EventKind
from ..core.exceptions import InvalidParameterError

if TYPE_CHECKING:
    from ..core.polygon import ConvexPolygon
    from ..core.trajectory import Trajectory, TrajectorySample
    from ..dynamics.control import ControlOutput
    from ..dynamics.grasp import Grasp
    from ..envelope.finger_envelope import EnvelopeSample
    from ..envelope.planner import PlanResult
    from ..model.hand import Hand

__all__ = ["SLIPPING_PHASES", "ContactPhase", "Reference", "SlideEnd", "SlideOrder", "SlideProfile",
           "SupervisorContext", "SupervisorOutput"]

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


@dataclass(frozen=True)
class SupervisorOutput:
    """One supervisor step.

    Attributes:
        tau: Joint torques [N m], (2m,).
        control: The control law's output.
        law: The law that ran.
        phases: Each contact's phase.
        envelopes: Each contact's envelope sample (the latest evaluated one).
        margins: Each contact's envelope margin [m] (negative: outside its feasible set).
        bounds: Each contact's feasible interval (lo, hi) holding (or nearest to) ξ [m], (m, 2);
            NaN where the set is empty.
        targets: Each contact's slide target ξ* [m] (NaN when no slide is under way).
        reference_xi: ξ_d the sliding law tracks [m] per contact (NaN when not sliding).
        planned_xi: Where the policy's plan puts each contact now [m] (NaN without a plan).
        desired: The desired object state at the step's start.
        events: Decisions taken at this step.
        supervisor_seconds: Wall time of the supervisor's own work (envelopes and decisions) [s].
        control_seconds: Wall time of the control law [s].
    """

    tau: np.ndarray
    control: ControlOutput
    law: str
    phases: tuple[ContactPhase, ...]
    envelopes: tuple[EnvelopeSample, ...]
    margins: np.ndarray
    bounds: np.ndarray
    targets: np.ndarray
    reference_xi: np.ndarray
    planned_xi: np.ndarray
    desired: TrajectorySample
    events: tuple[Event, ...]
    supervisor_seconds: float
    control_seconds: float


@dataclass(frozen=True, eq=False)
class SupervisorContext:
    """What a policy may know of the task: the hand, the object, the trajectory and what the
    controllers assume (friction, object mass and inertia), and the planner's envelopes."""

    hand: Hand
    polygon: ConvexPolygon
    grasp: Grasp
    trajectory: Trajectory
    friction: tuple
    object_mass: float
    object_inertia: float
    plan: PlanResult | None
    names: tuple[str, ...]

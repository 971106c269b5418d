r"""What a step's law gives up, in turn, when no internal force gives it all
(:class:`~regrasp.supervisor.executor.SlideExecutor`): the contacts' floors above ``f_min``, then the friction
margin's part above ``fallback_friction_margin``, then the feedback's correction, then a settling contact's kinetic
cone edge.

The floors are given up only as far as they must be: where the whole floors leave no forces and ``f_min`` does, the
largest fraction of them that leaves forces is found by bisection (:func:`largest_fraction`, :data:`FLOOR_BISECTIONS`
halvings). Where the internal force has one free direction (two sliders and a holder, or a slider and a contact being
primed), the least squeeze under a floor sits on that floor: taking the floors down to ``f_min`` at once drops every
load to its least in one step, and a compliant contact that carried 1.4 N then leaves its edge.

The held contacts' friction margin is kept before the floors: a floor keeps a load through a handover, the margin
covers the plant's μ being below the model's, and a holder that slips fails the run. While any fraction of the floors
leaves forces within the whole margin, no step takes the smaller ``fallback_friction_margin`` to keep more of them
(a held palm at 0.44 of its load with the plant's μ 0.42 slipped that way at a break-away).

The planned motion and ``f_min`` are the limits: where even they leave no forces, the executor aborts the slides.
Measured on the default scenario's 200-run study (``docs/derivations.md``, "Contact health and keeping the loads").
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, NamedTuple, TypeVar

from ..core.exceptions import InvalidParameterError

if TYPE_CHECKING:
    import numpy as np

    from ..dynamics.control import ComputedTorqueController, ControlOutput

__all__ = ["FEEDBACK_FRACTIONS", "FLOOR_BISECTIONS", "FLOOR_FRACTIONS", "Fallback", "fallbacks", "first_feasible",
           "largest_fraction", "with_feedback"]

T = TypeVar("T")

#: The fractions of the contacts' floors above ``f_min`` (:meth:`~regrasp.supervisor.executor.SlideExecutor.floors`)
#: a step's law tries in turn when the forces cannot meet them all: a contact keeps what load the others' cones allow
#: (a slider whose plant μ is above the model's drags the object harder, and the holders' cones then cap the
#: squeeze), down to ``f_min``; between the two, :func:`largest_fraction` finds the largest that leaves forces.
FLOOR_FRACTIONS = (1.0, 0.0)
#: The halvings of the interval between a fraction of the floors that leaves no forces and one that does
#: (:func:`largest_fraction`): 4 find the largest to 1/16 of the floors above ``f_min``, with at most 4 more QPs.
FLOOR_BISECTIONS = 4
#: The fractions of the object's and the sliders' feedback (the errors S_d - S and Ṡ_d - Ṡ, the integral's shift
#: included) a step's law tries in turn, once its floors are down to ``f_min``, when the forces cannot give the
#: commanded accelerations (before a slide is aborted): the planned (feed-forward) motion is what the plan checked;
#: the correction of an error the plant's model error made (a slider dragging harder than the model's μ turns the
#: object) is a preference the cones cap.
FEEDBACK_FRACTIONS = (1.0, 0.5, 0.0)


class Fallback(NamedTuple):
    """One law a step tries (:func:`fallbacks`).

    Attributes:
        floors: The fraction of the contacts' floors above ``f_min`` kept [-] (0: ``f_min`` alone).
        feedback: The fraction of the feedback's errors kept [-] (1: the targets as given).
        edges: Whether a settling contact still sensed sliding keeps its kinetic cone's edge.
        relaxed: Whether the internal force may take ``fallback_friction_margin`` where no force keeps the whole
            ``friction_margin`` (False: it may not; the same where the settings have no fallback margin).
    """

    floors: float
    feedback: float
    edges: bool
    relaxed: bool


def fallbacks(floored: bool, relaxable: bool, settling: bool) -> list[Fallback]:
    """The laws a step tries in turn (:data:`FLOOR_FRACTIONS`, :data:`FEEDBACK_FRACTIONS`): the floors first
    (``floored``: some contact has a floor above ``f_min``), with the whole feedback and the whole friction margin;
    then the same with the fallback friction margin (``relaxable``: the settings have one); then, on ``f_min`` alone,
    less feedback; then (``settling``: a contact settles on its kinetic cone's edge) the same without the settling
    edges."""
    floors = FLOOR_FRACTIONS if floored else FLOOR_FRACTIONS[:1]
    out = [Fallback(f, FEEDBACK_FRACTIONS[0], True, False) for f in floors] if relaxable else []
    out += [Fallback(f, FEEDBACK_FRACTIONS[0], True, True) for f in floors]
    out += [Fallback(floors[-1], g, True, True) for g in FEEDBACK_FRACTIONS[1:]]
    if settling:
        out += [Fallback(floors[-1], g, False, True) for g in FEEDBACK_FRACTIONS]
    return out


def largest_fraction(solve: Callable[[float], T], feasible: float, infeasible: float, found: T, *,
                     errors: tuple[type[Exception], ...], steps: int = FLOOR_BISECTIONS) -> T:
    """The result of ``solve`` at the largest fraction in [``feasible``, ``infeasible``) found by ``steps`` halvings,
    where ``solve(feasible)`` gave ``found`` and ``solve(infeasible)`` raised one of ``errors`` (a fraction whose
    ``solve`` raises one of them leaves no forces; the fractions that do are an interval, the floors being lower
    bounds)."""
    lo, hi = float(feasible), float(infeasible)
    for _ in range(steps):
        mid = 0.5 * (lo + hi)
        try:
            found = solve(mid)
        except errors:
            hi = mid
            continue
        lo = mid
    return found


def first_feasible(order: list[Fallback], solve: Callable[[float, float, bool, bool], T],
                   error: type[Exception]) -> T:
    """``solve``'s result at the first :class:`Fallback` of ``order`` (:func:`fallbacks`) at which it does not raise
    ``error``; where an entry before it with the rest the same kept more of the floors, at the largest fraction between
    the two (:func:`largest_fraction`). The last entry's ``error`` where every entry raises it."""
    failed: dict[tuple, float] = {}  # (feedback, edges, relaxed): the least fraction of the floors that raised
    for k, entry in enumerate(order):
        try:
            found = solve(*entry)
        except error:
            if k == len(order) - 1:
                raise
            rest = entry[1:]
            failed[rest] = min(failed.get(rest, entry.floors), entry.floors)
            continue
        rest = entry[1:]
        if failed.get(rest, entry.floors) > entry.floors:
            found = largest_fraction(lambda f: solve(f, *rest), entry.floors, failed[rest], found, errors=(error,))
        return found
    raise InvalidParameterError("order", order, "a non-empty list of Fallback (floors, feedback, edges, relaxed)")


def with_feedback(law: ComputedTorqueController, gain: float, S: np.ndarray, S_dot: np.ndarray, S_d: np.ndarray,
                  S_d_dot: np.ndarray, S_d_ddot: np.ndarray) -> ControlOutput:
    """``law``'s output with ``gain`` of the feedback's errors S_d - S, Ṡ_d - Ṡ (1: the targets as given)."""
    if gain == 1.0:
        return law(S, S_dot, S_d, S_d_dot, S_d_ddot)
    return law(S, S_dot, S + gain * (S_d - S), S_dot + gain * (S_d_dot - S_dot), S_d_ddot)

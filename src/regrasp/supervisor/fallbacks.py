r"""What a step's law gives up, in turn, when no internal force gives it all
(:class:`~regrasp.supervisor.executor.SlideExecutor`): the contacts' floors above ``f_min``, then the feedback's
correction, then a settling contact's kinetic cone edge.

The floors are given up only as far as they must be: where the whole floors leave no forces and ``f_min`` does, the
largest fraction of them that leaves forces is found by bisection (:func:`largest_fraction`, :data:`FLOOR_BISECTIONS`
halvings). Where the internal force has one free direction (two sliders and a holder, or a slider and a contact being
primed), the least squeeze under a floor sits on that floor: taking the floors down to ``f_min`` at once drops every
load to its least in one step, and a compliant contact that carried 1.4 N then leaves its edge.

The planned motion and ``f_min`` are the limits: where even they leave no forces, the executor aborts the slides.
Measured on the default scenario's 200-run study (``docs/derivations.md``, "Contact health and keeping the loads").
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, TypeVar

from ..core.exceptions import InvalidParameterError
from ..dynamics.internal_force.settings import InternalForceSettings

if TYPE_CHECKING:
    import numpy as np

    from ..dynamics.control import ComputedTorqueController, ControlOutput

__all__ = ["FEEDBACK_FRACTIONS", "FLOOR_BISECTIONS", "FLOOR_FRACTIONS", "fallbacks", "first_feasible",
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


def fallbacks(internal_force: InternalForceSettings | None, settling: bool) -> list[tuple[float, float, bool]]:
    """The (floor fraction, feedback fraction, settling edges) a step's law tries in turn (:data:`FLOOR_FRACTIONS`,
    :data:`FEEDBACK_FRACTIONS`): the floors first, with the whole feedback; then, on ``f_min`` alone, less feedback;
    then (``settling``: a contact settles on its kinetic cone's edge) the same without the settling edges."""
    floors = FLOOR_FRACTIONS if internal_force is not None and internal_force.floors != () else FLOOR_FRACTIONS[:1]
    out = [(f, FEEDBACK_FRACTIONS[0], True) for f in floors] + [(floors[-1], g, True) for g in FEEDBACK_FRACTIONS[1:]]
    if settling:
        out += [(floors[-1], g, False) for g in FEEDBACK_FRACTIONS]
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


def first_feasible(order: list[tuple[float, float, bool]], solve: Callable[[float, float, bool], T],
                   error: type[Exception]) -> T:
    """``solve``'s result at the first (floor fraction, feedback fraction, settling edges) of ``order``
    (:func:`fallbacks`) at which it does not raise ``error``; where that one gave up floors the entry before kept
    (same feedback and edges), at the largest fraction between the two (:func:`largest_fraction`). The last entry's
    ``error`` where every entry raises it."""
    failed = None
    for k, (fraction, gain, edges) in enumerate(order):
        try:
            found = solve(fraction, gain, edges)
        except error:
            if k == len(order) - 1:
                raise
            failed = (fraction, gain, edges)
            continue
        if failed is not None and failed[1:] == (gain, edges) and failed[0] > fraction:
            found = largest_fraction(lambda f: solve(f, gain, edges), fraction, failed[0], found, errors=(error,))
        return found
    raise InvalidParameterError("order", order, "a non-empty list of (floor fraction, feedback fraction, edges)")


def with_feedback(law: ComputedTorqueController, gain: float, S: np.ndarray, S_dot: np.ndarray, S_d: np.ndarray,
                  S_d_dot: np.ndarray, S_d_ddot: np.ndarray) -> ControlOutput:
    """``law``'s output with ``gain`` of the feedback's errors S_d - S, Ṡ_d - Ṡ (1: the targets as given)."""
    if gain == 1.0:
        return law(S, S_dot, S_d, S_d_dot, S_d_ddot)
    return law(S, S_dot, S + gain * (S_d - S), S_dot + gain * (S_d_dot - S_dot), S_d_ddot)

r"""What a step's law gives up, in turn, when no internal force gives it all
(:class:`~regrasp.supervisor.executor.SlideExecutor`): the contacts' floors above ``f_min``, then the feedback's
correction, then a settling contact's kinetic cone edge.

The planned motion and ``f_min`` are the limits: where even they leave no forces, the executor aborts the slides.
Measured on the default scenario's 200-run study (``docs/derivations.md``, "Contact health and keeping the loads").
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..dynamics.internal_force.settings import InternalForceSettings

if TYPE_CHECKING:
    import numpy as np

    from ..dynamics.control import ComputedTorqueController, ControlOutput

__all__ = ["FEEDBACK_FRACTIONS", "FLOOR_FRACTIONS", "fallbacks", "with_feedback"]

#: The fractions of the contacts' floors above ``f_min`` (:meth:`~regrasp.supervisor.executor.SlideExecutor.floors`)
#: a step's law tries in turn when the forces cannot meet them all: a contact keeps what load the others' cones allow
#: (a slider whose plant μ is above the model's drags the object harder, and the holders' cones then cap the
#: squeeze), down to ``f_min``.
FLOOR_FRACTIONS = (1.0, 0.5, 0.0)
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


def with_feedback(law: ComputedTorqueController, gain: float, S: np.ndarray, S_dot: np.ndarray, S_d: np.ndarray,
                  S_d_dot: np.ndarray, S_d_ddot: np.ndarray) -> ControlOutput:
    """``law``'s output with ``gain`` of the feedback's errors S_d - S, Ṡ_d - Ṡ (1: the targets as given)."""
    if gain == 1.0:
        return law(S, S_dot, S_d, S_d_dot, S_d_ddot)
    return law(S, S_dot, S + gain * (S_d - S), S_dot + gain * (S_d_dot - S_dot), S_d_ddot)

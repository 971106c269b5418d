r"""The motors' torque limits in the plants: saturation, and when it starts.

A motor applies :math:`\mathrm{clip}(\tau, -e, e)` of the commanded torque τ [N m], e the joint's limit
(:attr:`~regrasp.model.hand.Hand.effort_limit`: the URDF's ``effort`` or the scenario's; inf: none). A joint
whose commanded torque starts to exceed its limit (by more than round-off:
:data:`~regrasp.kernels.plant.SATURATION_TOLERANCE` relative to max(1, e), which a controller that keeps the
limit reaches when its torque sits on it) is reported once (a ``saturation`` plant event, with the
``joint`` (1 or 2), the commanded ``torque`` and the ``effort`` [N m]), until it is back within the limit.
Every plant (:class:`~regrasp.plants.project.plant.Plant`, whose compiled kernel clips the same way,
:class:`~regrasp.plants.mujoco.plant.MujocoPlant`, which clips before ``qfrc_applied``, and
:class:`~regrasp.plants.drake.plant.DrakePlant`, before its applied generalized forces) uses :class:`Saturation`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from ..kernels.plant import SATURATION_TOLERANCE

__all__ = ["Saturation"]


class Saturation:
    """The torque limits of 2m joints (``effort`` [N m], inf: none) and which joints saturated at the last step."""

    def __init__(self, effort: Sequence[float]):
        self.effort = tuple(float(e) for e in effort)
        #: Which joints' commanded torques the last step clipped (2m).
        self.saturated: tuple[bool, ...] = (False,) * len(self.effort)

    def clear(self) -> None:
        """No joint saturated (a reset)."""
        self.saturated = (False,) * len(self.effort)

    def clip(self, tau: Sequence[float]) -> tuple[tuple[float, ...], tuple[bool, ...]]:
        """(clip(τ, -effort, effort), which joints saturated: beyond their limits by more than round-off) for
        finite torques ``tau`` [N m] (floats)."""
        applied = tuple(min(max(t, -e), e) for t, e in zip(tau, self.effort))
        return applied, tuple(abs(t) - e > SATURATION_TOLERANCE * max(1.0, e) for t, e in zip(tau, self.effort))

    def onsets(self, tau: Sequence[float], saturated: tuple[bool, ...]) -> list[tuple[int, str, dict[str, float]]]:
        """The joints that start to saturate at this step, as (finger index, detail, values) of the event to log,
        given the commanded torques ``tau`` [N m] and :meth:`clip`'s mask; remembers ``saturated``."""
        out = []
        if any(saturated) or any(self.saturated):
            for j, (now, before) in enumerate(zip(saturated, self.saturated)):
                if now and not before:
                    joint, effort = j % 2 + 1, self.effort[j]
                    out.append((j // 2, f"joint {joint} commanded {tau[j]:+.4f} N m, beyond its limit of "
                                        f"{effort:.4f} N m: the motor applies {math.copysign(effort, tau[j]):+.4f} N m",
                                {"joint": float(joint), "torque": float(tau[j]), "effort": effort}))
            self.saturated = saturated
        return out

"""What a hand senses at one control step (:class:`Measurement`): the value a plant's sensing gives a supervisor
or a control law (:func:`~regrasp.plants.simulation.sense`, :class:`~regrasp.plants.disturbance.Disturbance`) and
the supervisor, its executor and its policies read. It never carries the plant itself."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["Measurement"]


@dataclass(frozen=True)
class Measurement:
    """What the hand senses at one control step.

    Attributes:
        t: Time [s].
        X, V: Object pose (x, y, β) and twist in the hand frame [m, rad], [m/s, rad/s].
        xi, xi_dot: Each contact's position along its edge and its rate [m], [m/s].
        sliding: Whether each contact is sliding (a slip sensor), (m,) bool.
        tangential_force: Tangential contact force on the object at each contact [N], (m,) (a force
            sensor, during the last step).
        normal_force: Normal contact force at each contact [N], (m,), the same sensor; None: not
            sensed. The executor estimates a slider's kinetic friction ratio from the two.
    """

    t: float
    X: np.ndarray
    V: np.ndarray
    xi: np.ndarray
    xi_dot: np.ndarray
    sliding: np.ndarray
    tangential_force: np.ndarray
    normal_force: np.ndarray | None = None

    def force_ratio(self, i: int, min_force: float = 0.0) -> float:
        """Contact i's sensed friction ratio |f_t| / f_n [-]; NaN where the normal force is not sensed or is not
        above ``min_force`` [N]."""
        if self.normal_force is None or not float(self.normal_force[i]) > min_force:
            return math.nan
        return abs(float(self.tangential_force[i])) / float(self.normal_force[i])

r"""The two-finger slide rule: when can one of two fingers on parallel edges slide?

Two contacts push on parallel edges a distance w apart, the weight W = m g acting along the edges
(quasi-statically, or with g the effective gravity g - a). Horizontal balance makes both normal
forces equal, λ; with one contact sliding the forces are unique. Let Δ be the slider's height
above the holder along the edges (against gravity), :math:`\mu_k` the slider's kinetic and
:math:`\mu_s` the holder's static coefficient. The slider's friction is :math:`\pm\mu_k\lambda`
(up when it slides up: the fingertip drags the object along), vertical balance gives the
holder's :math:`f_B = W \mp \mu_k \lambda`, and the moment about the centre of mass
:math:`(w/2)(f_B - f_A) = \lambda \Delta` gives

* sliding **up** (against gravity): :math:`\lambda = \tfrac{w}{2} W / (w\mu_k + \Delta)` and
  :math:`f_B = \lambda(\mu_k + 2\Delta/w)`, so pushing (λ > 0) and the holder inside its cone
  (:math:`|f_B| \le \mu_s \lambda`) need

  .. math:: \max(-w\mu_k, -\tfrac{w}{2}(\mu_s + \mu_k)) < \Delta \le \tfrac{w}{2}(\mu_s - \mu_k);

* sliding **down** (with gravity): :math:`\lambda = \tfrac{w}{2} W / (\Delta - w\mu_k)` and
  :math:`f_B = \lambda(2\Delta/w - \mu_k)`, so

  .. math:: w\mu_k < \Delta \le \tfrac{w}{2}(\mu_s + \mu_k).

Hence the **lower** contact (Δ < 0) can never slide down, whatever :math:`\mu_s \ge \mu_k`, and a
downward slide needs :math:`\mu_k < \mu_s`; with :math:`\mu_s = \mu_k` the upper contact
(Δ > 0) can never slide up. A minimum push :math:`f_{min}` and a maximum :math:`f_{max}` narrow
both ranges further (λ above is the normal force). ``docs/derivations.md`` has the derivation;
``tests/schedule/test_slide_rule.py`` checks it against :func:`~regrasp.dynamics.sliding.sliding_feasibility`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..core.contact import Friction
from ..core.exceptions import InvalidParameterError

__all__ = ["SlideRange", "two_finger_slide_range"]


@dataclass(frozen=True)
class SlideRange:
    """The slider heights Δ [m] above the holder for which a two-finger slide is possible.

    Attributes:
        low: Exclusive lower bound [m] (the normal force is unbounded there).
        high: Inclusive upper bound [m] (the holder reaches its static cone's edge).
        upward: True for a slide against gravity.
        pole: The height [m] where the normal force λ = (w/2) W / (Δ - pole) is unbounded.
    """

    low: float
    high: float
    upward: bool
    pole: float

    @property
    def empty(self) -> bool:
        return not self.low < self.high

    def contains(self, delta: float) -> bool:
        return self.low < delta <= self.high

    def normal_force(self, delta: float, width: float, weight: float) -> float:
        """λ [N] at height Δ for edges ``width`` [m] apart and ``weight`` [N] (inf at the pole)."""
        denominator = delta - self.pole
        return math.inf if denominator <= 0 else 0.5 * width * weight / denominator


def two_finger_slide_range(width: float, slider: Friction, holder: Friction, *, upward: bool) -> SlideRange:
    """The range of the module docstring for edges ``width`` [m] apart (the bare physics: no f_min,
    no f_max, no cone margin)."""
    if not (math.isfinite(width) and width > 0):
        raise InvalidParameterError("width", width, "a distance > 0 [m]")
    mk, ms = slider.kinetic, holder.static
    if upward:
        return SlideRange(max(-width * mk, -0.5 * width * (ms + mk)), 0.5 * width * (ms - mk), True, -width * mk)
    return SlideRange(width * mk, 0.5 * width * (ms + mk), False, width * mk)

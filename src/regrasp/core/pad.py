r"""A compliant fingertip pad (:class:`Pad`): the normal contact law of the project plant's soft contacts.

The pad is a Kelvin–Voigt element between the fingertip point p and the object's edge: with
:math:`\delta` [m] the tip's penetration into the edge's line, shifted by the pad's preload depth
:math:`\delta_0 = f_0 / k`,

.. math::

    \delta = n\cdot(p - x_o) - e + \delta_0, \qquad
    f_n = \begin{cases} \max(0,\ k\,\delta + c\,\dot\delta) & \delta > 0 \\ 0 & \delta \le 0 \end{cases}

(n the edge's inward normal, e its offset: :math:`n\cdot(p - x_o) = e` on the edge's line). A tip placed exactly on
the line carries the preload :math:`f_0 = k\delta_0`; as k grows at a fixed preload :math:`\delta_0 \to 0` and the
contact tends to the rigid one. The force never pulls: a tip off the surface, or leaving it faster than the spring
pushes, carries nothing.

**Why Kelvin–Voigt and not Hunt–Crossley** (:math:`f_n = k\delta(1 + d\dot\delta)_+`, Drake's): a grasp's pads sit
at their loads' depths, and what the damping must do there is damp the tip's oscillation on the pad, a
:math:`\sqrt{k/m}` mode. Kelvin–Voigt's damping c is the same at every depth, so "critically damped for a tip of
mass m", :math:`c = 2\sqrt{k m}`, means one thing (:meth:`Pad.critically_damped`). Hunt–Crossley's is
:math:`k d \delta`, proportional to the load: the rollout's contacts carry 0.2 to 2 N, so no one d damps them all
(a d critical at 2 N leaves a 0.2 N contact at 10 % of critical). Its advantage, no force jump at impact, matters
for impacts, and a grasp's contacts do not impact: they start preloaded.

**Stability of RK4 on a pad.** A tip of mobility w [1/kg] (the inverse of its effective mass along the normal) on a
pad is :math:`\ddot\delta = -w(k\delta + c\dot\delta)`, whose eigenvalues are
:math:`\lambda = (-cw \pm \sqrt{c^2w^2 - 4kw})/2`, so :math:`|\lambda| \le \Lambda(w) = (cw + \sqrt{c^2w^2 +
4kw})/2` (:meth:`Pad.rate_bound`). Classical RK4 is stable for :math:`h|\lambda| \lesssim 2.8`; the plant takes
``substeps`` per control step so that :math:`h\Lambda \le` ``step_rate`` (:meth:`Pad.substeps_for`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .exceptions import InvalidParameterError
from .validation import as_integer, as_positive_float

__all__ = ["DEFAULT_PAD_PRELOAD", "Pad"]

#: The default preload [N]: what a tip placed on its edge's line carries (the rollout's contacts carry 0.3-2 N).
DEFAULT_PAD_PRELOAD = 0.5


@dataclass(frozen=True)
class Pad:
    r"""A compliant normal contact (module docstring), the same for every contact of a plant.

    Attributes:
        stiffness: k [N/m] (> 0).
        damping: c [N s/m] (>= 0); :meth:`critically_damped` for a tip's mass.
        preload: f_0 [N] (>= 0): the force of a tip placed exactly on its edge's line; the pad's preload depth is
            :math:`\delta_0 = f_0/k` [m] (:attr:`preload_depth`).
        substeps: RK4 steps per control step (None: as many as :meth:`substeps_for` asks, every step).
        step_rate: The largest :math:`h\Lambda` [-] a substep of h [s] may take (:meth:`substeps_for`; RK4 is stable
            to about 2.8).
        separation_gap: A touching contact whose pad ends a step more than this [m] off its edge is released (a
            ``separation`` event; within it, the tip may leave and touch again).
    """

    stiffness: float
    damping: float = 0.0
    preload: float = DEFAULT_PAD_PRELOAD
    substeps: int | None = None
    step_rate: float = 2.0
    separation_gap: float = 2.5e-5

    def __post_init__(self) -> None:
        object.__setattr__(self, "stiffness", as_positive_float("stiffness", self.stiffness))
        for name in ("damping", "preload", "separation_gap"):
            object.__setattr__(self, name, as_positive_float(name, getattr(self, name), allow_zero=True))
        rate = as_positive_float("step_rate", self.step_rate)
        if rate > 2.5:
            raise InvalidParameterError("step_rate", self.step_rate, "at most 2.5 (RK4 is stable to about 2.8)")
        object.__setattr__(self, "step_rate", rate)
        if self.substeps is not None:
            object.__setattr__(self, "substeps", as_integer("substeps", self.substeps, least=1))

    @classmethod
    def critically_damped(cls, stiffness: float, mass: float, **kwargs: float | None) -> Pad:
        r"""A pad of ``stiffness`` [N/m] critically damped for a tip of ``mass`` [kg]: :math:`c = 2\sqrt{k m}`."""
        k = as_positive_float("stiffness", stiffness)
        return cls(k, 2.0 * math.sqrt(k * as_positive_float("mass", mass)), **kwargs)

    @property
    def preload_depth(self) -> float:
        r""":math:`\delta_0 = f_0 / k` [m]."""
        return self.preload / self.stiffness

    def normal_force(self, depth: float, rate: float) -> float:
        r"""The pad's normal force [N] at penetration ``depth`` δ [m] and its rate ``rate`` δ̇ [m/s]:
        :math:`\max(0, k\delta + c\dot\delta)` for δ > 0, else 0."""
        if depth <= 0.0:
            return 0.0
        return max(0.0, self.stiffness * depth + self.damping * rate)

    def energy(self, depth: float) -> float:
        r"""The pad's elastic energy [J] at penetration ``depth`` δ [m]: :math:`k\delta_+^2/2`."""
        return 0.5 * self.stiffness * depth * depth if depth > 0.0 else 0.0

    def rate_bound(self, mobility: float) -> float:
        r""":math:`\Lambda(w) = (cw + \sqrt{c^2w^2 + 4kw})/2` [1/s], a bound on the eigenvalues' magnitude of a tip of
        ``mobility`` w [1/kg] on the pad (module docstring)."""
        cw = self.damping * mobility
        return 0.5 * (cw + math.sqrt(cw * cw + 4.0 * self.stiffness * mobility))

    def substeps_for(self, dt: float, mobility: float) -> int:
        r"""RK4 steps per control step of ``dt`` [s] for a largest contact ``mobility`` w [1/kg]: ``substeps`` if
        set, else :math:`\lceil dt\,\Lambda(w) / \text{step\_rate}\rceil` (at least 1)."""
        if self.substeps is not None:
            return self.substeps
        return max(1, math.ceil(dt * self.rate_bound(mobility) / self.step_rate - 1e-12))

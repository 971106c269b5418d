"""The slide executor's settings (:class:`ExecutorSettings`): how it primes, slides, settles and holds, and the
laws it runs (:mod:`regrasp.supervisor.executor` explains the phases)."""

from __future__ import annotations

from dataclasses import dataclass, field

from ..core.exceptions import InvalidParameterError
from ..dynamics.internal_force.solver import InternalForceSettings
from ..core.validation import as_duration, as_flag, as_integer, as_positive_float

__all__ = ["ExecutorSettings"]


@dataclass(frozen=True)
class ExecutorSettings:
    """Tuning of :class:`SlideExecutor` (see the module docstring).

    Attributes:
        omega_n: Natural frequency of the slide filter [rad/s] (orders without a reference).
        zeta: Damping ratio of the slide filter [-].
        prime_time: Longest priming [s].
        prime_overshoot: Priming asks for |f_t| = (μ_s + this) f_n at first [-] ...
        prime_overshoot_max: ... and up to (μ_s + this) f_n at the end of ``prime_time`` [-].
        start_speed: The priming ends when the contact is sensed sliding and moving in the slide's direction
            faster than this [m/s] (None: sensed sliding is enough).
        settle_undershoot: Settling asks for (μ_k - this) f_n [-] (at most μ_k / 2) ...
        settle_margin: ... or for μ_k f_n - this [N] where that is less (with the normal force sensed when the
            slide ends; still at most μ_k / 2 below μ_k).
        arrive_tolerance: A slide has arrived when |ξ - ξ*| is below this [m] ...
        arrive_speed: ... and |ξ̇| below this [m/s].
        max_slide_time: A slide that has not arrived after this long ends where it is [s].
        friction_filter_time: Estimate each slider's kinetic friction ratio |f_t| / f_n from the sensed
            contact forces (:class:`~regrasp.supervisor.supervisor.Measurement` ``normal_force``) with a first-order
            filter of this time constant [s], and let the laws use it instead of the model's μ_k (None:
            the model's). The plant's μ_k may differ from the model's; a slider that carries more friction
            than its law predicts stops and sticks, one that carries less overshoots.
        friction_min_force: The estimate uses only steps with f_n above this [N].
        breakaway_estimate: Start the estimate at the step the contact is sensed breaking away, from the
            force ratio it broke away at (≈ the plant's μ_s ≥ μ_k), so that the sliding law's first steps
            expect no less friction than the plant's (False: from its first step sensed sliding).
        friction_resolution: The laws get the estimate rounded to this [-] (a new law per change).
        control_period: The control period the filter assumes [s].
        max_reprimes: A planned slide (an order with a reference) that sticks before its planned end is
            primed again, at most this many times; then it ends where it stuck.
        actuation_delay: The hand's actuation delay [control steps] (module docstring): a torque computed at
            one step is applied this many steps later.
        control_omega: Bandwidth of the computed-torque laws on the object's coordinates [rad/s]
            (critically damped: K_v = 2ω, K_s = ω²).
        slide_omega: The same on the sliders' ξ [rad/s]. A slider's effective inertia along its edge is
            small, so a friction error (μ_k of the plant ≠ the model's) moves it far at the object's
            bandwidth: 10 % of μ_k is about 6 mm at 20 rad/s on the three-finger scenario.
        integral: Integral action on every coordinate, K_i = ``integral`` · ω³ (0: none) [-]: it removes
            the steady error that a wrong object mass or friction leaves (Δg / ω² = 2.5 mm for 10 % of
            the weight at 20 rad/s). The law stays stable for K_i < K_v K_s = 2ω³, i.e. ``integral`` < 2.
            It acts through the reference: S_d + (K_i / K_s) ∫E dt gives a = S̈_d + K_v Ė + K_s E + K_i ∫E.
        internal_force: The controllers' internal-force QP settings; its ``target_cone_margin`` [N]
            is the margin the fixed contacts are kept inside their cones by (the paper's "γ large").
        hold_resolution: A held contact's position in the laws' model follows the sensed one when the two
            differ by more than this [m] (None: only at phase changes). A rigid point contact stays where it
            is held; a real fingertip of radius r rolls on the edge, r Δθ for a turn Δθ of the distal link
            relative to the object, and a model that keeps the old position puts the contact's normal force
            at the wrong lever arm (``docs/derivations.md``, "A second plant: MuJoCo"). With a plant that
            senses a fixed contact where it is held (the project's), this never triggers.
        hold_filter_time: The held contacts' sensed positions go through a first-order filter of this time
            constant [s] before the model takes them (at ``hold_resolution`` and at every phase change; None:
            unfiltered). A noisy ξ sensor otherwise moves the model's lever arms, and rebuilds the law, at every
            step.
        tip_radius: The fingertips are spheres of this radius [m] (0: points): every law's torque gets the
            couple the sphere's contact point adds on the distal link (:func:`~regrasp.model.sphere_tip.sphere_tip_torque`).
    """

    omega_n: float = 20.0
    zeta: float = 1.0
    prime_time: float = 0.02
    prime_overshoot: float = 0.05
    prime_overshoot_max: float = 0.05
    start_speed: float | None = None
    settle_undershoot: float = 0.05
    settle_margin: float = 0.0
    arrive_tolerance: float = 5e-4
    arrive_speed: float = 5e-3
    max_slide_time: float = 1.5
    max_reprimes: int = 5
    actuation_delay: int = 0
    friction_filter_time: float | None = None
    friction_min_force: float = 0.05
    breakaway_estimate: bool = False
    friction_resolution: float = 0.0025
    control_period: float = 1e-3
    control_omega: float = 20.0
    slide_omega: float = 20.0
    integral: float = 0.0
    internal_force: InternalForceSettings = field(default_factory=lambda: InternalForceSettings(f_min=0.2))
    hold_resolution: float | None = 2e-6
    hold_filter_time: float | None = None
    tip_radius: float = 0.0

    def __post_init__(self):
        for name in ("omega_n", "zeta", "prime_time", "prime_overshoot", "settle_undershoot", "arrive_tolerance",
                     "arrive_speed", "max_slide_time", "control_omega", "slide_omega"):
            as_positive_float(name, getattr(self, name))
        for name in ("omega_n", "control_omega", "slide_omega"):  # (their squares are gains)
            if getattr(self, name) > 1e6:
                raise InvalidParameterError(name, getattr(self, name), "a frequency of at most 1e6 rad/s")
        for name in ("prime_time", "max_slide_time"):
            as_duration(name, getattr(self, name))
        as_positive_float("integral", self.integral, allow_zero=True)
        as_positive_float("settle_margin", self.settle_margin, allow_zero=True)
        if self.start_speed is not None:
            as_positive_float("start_speed", self.start_speed, allow_zero=True)
        if self.friction_filter_time is not None:
            as_positive_float("friction_filter_time", self.friction_filter_time)
        for name in ("friction_min_force", "friction_resolution", "control_period"):
            as_positive_float(name, getattr(self, name))
        as_integer("max_reprimes", self.max_reprimes)
        as_integer("actuation_delay", self.actuation_delay)
        as_flag("breakaway_estimate", self.breakaway_estimate)
        if not self.prime_overshoot_max >= self.prime_overshoot:
            raise InvalidParameterError("prime_overshoot_max", self.prime_overshoot_max,
                                        f"at least prime_overshoot = {self.prime_overshoot}")
        if self.integral >= 2.0:
            raise InvalidParameterError("integral", self.integral, "a gain fraction in [0, 2) (stability)")
        if not isinstance(self.internal_force, InternalForceSettings):
            raise InvalidParameterError("internal_force", self.internal_force, "an InternalForceSettings")
        if self.hold_resolution is not None:
            as_positive_float("hold_resolution", self.hold_resolution)
        if self.hold_filter_time is not None:
            as_duration("hold_filter_time", self.hold_filter_time)
        as_positive_float("tip_radius", self.tip_radius, allow_zero=True)

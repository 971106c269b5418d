"""The supervisor's settings, one tree: :class:`SupervisorSettings` holds its executor's (:class:`ExecutorSettings`:
how a slide is primed, slid, settled and held, and the laws it runs; :mod:`regrasp.supervisor.executor` explains
the phases), its envelope monitor's (:class:`MonitorSettings`) and each policy's (:class:`PaperSettings`,
:class:`ScheduledSettings`), each once. :meth:`SupervisorSettings.robust` is what a rollout uses by default.

Margins have one name per unit: a *friction margin* is a ratio [-] subtracted from μ_s
(``InternalForceSettings.friction_margin``), a *cone margin* is a force [N], μ_s f_n - |f_t|
(``InternalForceSettings.target_cone_margin``, :data:`~regrasp.core.contact.DEFAULT_CONE_MARGIN`)."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from ..core.contact import DEFAULT_CONE_MARGIN
from ..core.exceptions import InvalidParameterError
from ..core.intervals import DANGER_FRACTION
from ..core.validation import (
    as_count,
    as_duration,
    as_finite_float,
    as_flag,
    as_positive_float,
    as_tip_radius,
    check_fields,
    expect_type,
)
from ..dynamics.internal_force.settings import InternalForceSettings
from ..model.geometry import Geometry, as_geometry

__all__ = ["ExecutorSettings", "MonitorSettings", "PaperSettings", "ScheduledSettings", "SupervisorSettings"]


@dataclass(frozen=True)
class ExecutorSettings:
    """Tuning of :class:`~regrasp.supervisor.executor.SlideExecutor` (:mod:`regrasp.supervisor.executor`).

    Attributes:
        omega_n: Natural frequency of the slide filter [rad/s] (orders without a reference).
        zeta: Damping ratio of the slide filter [-].
        prime_time: Longest priming [s]; it ends earlier when the contact is sensed slipping.
        prime_overshoot: Priming asks for |f_t| = (μ_s + this) f_n at first [-], just past the static cone's edge,
            so that the contact starts to slip by itself before the sliding law takes over (switching to the
            sliding law while the contact is still stuck makes the plant redistribute the forces for one step and
            can slip another contact). The excess past the plant's μ_s is what the slip releases in one step: two
            contacts primed together at 0.05 pulled a 1.1 N slider 2.9-4.0 N off its edge (issue 27's ω 2.5 rad/s,
            200 g variant), at 0.01 it kept 0.30 N; so start low and grow ...
        prime_overshoot_max: ... and up to (μ_s + this) f_n at the end of ``prime_time`` [-].
        reprime_overshoot_step: A re-priming (a planned slide stuck on its way, ``max_reprimes``) starts this much
            higher per re-priming so far [-] (at most ``prime_overshoot_max``): a compliant contact primed gently
            breaks away and grips again as its friction builds up (Drake, 1 mm tips: five re-primings at +0.01 and
            the slide given up), so each new try pushes harder.
        start_speed: The priming ends when the contact is sensed sliding and moving in the slide's direction
            faster than this [m/s] (None: sensed sliding is enough).
        settle_undershoot: A slide that ends with the contact still sliding settles with the fixed-contact law
            asking for (μ_k - this) f_n of friction in the sliding direction [-] (at most μ_k / 2), just inside the
            kinetic cone, so the contact slows down gently and sticks ...
        settle_margin: ... or for μ_k f_n - this [N] where that is less (with the normal force sensed when the
            slide ends; still at most μ_k / 2 below μ_k).
        arrive_tolerance: A slide has arrived when |ξ - ξ*| is below this [m] ...
        arrive_speed: ... and |ξ̇| below this [m/s].
        max_slide_time: A slide that has not arrived after this long ends where it is [s].
        friction_filter_time: Estimate each slider's kinetic friction ratio |f_t| / f_n from the sensed
            contact forces (:class:`~regrasp.core.measurement.Measurement` ``normal_force``) with a first-order
            filter of this time constant [s], and let the laws use it instead of the model's μ_k (None:
            the model's). The plant's μ_k may differ from the model's; a slider that carries more friction
            than its law predicts stops and sticks, one that carries less overshoots.
        friction_min_force: The estimate uses only steps with f_n above this [N].
        breakaway_estimate: Start the estimate at the step the contact is sensed breaking away, from the
            force ratio it broke away at or the largest it held while primed, if more (≈ the plant's μ_s ≥ μ_k;
            a compliant contact's friction builds up over its first slipping step), so that the sliding law's
            first steps expect no less friction than the plant's (False: from its first step sensed sliding).
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
        internal_force: The controllers' internal-force QP settings (default: push ≥ 0.2 N, fixed contacts 0.05
            inside their cones in ratio); its ``target_cone_margin`` [N] is the margin the fixed contacts are kept
            inside their cones by where the forces allow (the paper's "γ large"). A larger minimum push squeezes
            harder, which makes some slides infeasible for the torque balance (e.g. the side fingers of
            paper_trajectory_2_three_fingers.toml sliding up at 0.5 N).
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
            couple the sphere's contact point adds on the distal link
            (:func:`~regrasp.model.sphere_tip.sphere_tip_torque`).
        slider_floor: A contact being primed, slid or settled pushes with at least this [N] in the laws (0: the
            internal force's ``f_min``): the least loaded contact is the one whose load a compliant plant loses
            first (``docs/derivations.md``, "Keeping the loads").
        holder_preload: While any contact is primed or slides, every held contact pushes with at least this [N]
            (0: ``f_min``): a neighbour's break-away redistributes the load, and a soft contact's hop takes a
            slider's load away for a moment; the holders carry it.
        reflex_below: A contact whose sensed normal force falls below this [N] (0: never) ...
        reflex_floor: ... pushes with at least this [N] in the laws ...
        reflex_time: ... for this long [s] (the reflex: more internal force at once, before the contact is lost).
        handover_time: At a phase change every contact's predicted load of the step before is a floor released
            linearly over this time [s] (0: none; :mod:`regrasp.supervisor.handover`) ...
        handover_load_max: ... up to this load [N].
    """

    omega_n: float = 20.0
    zeta: float = 1.0
    prime_time: float = 0.02
    prime_overshoot: float = 0.05
    prime_overshoot_max: float = 0.05
    reprime_overshoot_step: float = 0.0
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
    slider_floor: float = 0.0
    holder_preload: float = 0.0
    reflex_below: float = 0.0
    reflex_floor: float = 0.0
    reflex_time: float = 0.01
    handover_time: float = 0.0
    handover_load_max: float = 2.0

    def __post_init__(self):
        check_fields(self, as_positive_float, ("omega_n", "zeta", "prime_overshoot", "prime_overshoot_max",
                                               "settle_undershoot", "arrive_tolerance", "arrive_speed", "control_omega",
                                               "slide_omega", "friction_min_force", "friction_resolution"))
        check_fields(self, as_positive_float, ("reprime_overshoot_step",), allow_zero=True)
        for name in ("omega_n", "control_omega", "slide_omega"):  # (their squares are gains)
            if getattr(self, name) > 1e6:
                raise InvalidParameterError(name, getattr(self, name), "a frequency of at most 1e6 rad/s")
        check_fields(self, as_duration, ("prime_time", "max_slide_time", "control_period", "reflex_time"))
        check_fields(self, as_duration, ("friction_filter_time", "hold_filter_time"), optional=True)
        check_fields(self, as_positive_float, ("integral", "settle_margin", "slider_floor", "holder_preload",
                                               "reflex_below", "reflex_floor", "handover_time"), allow_zero=True)
        check_fields(self, as_positive_float, ("handover_load_max",))
        check_fields(self, as_tip_radius, ("tip_radius",), allow_zero=True)
        check_fields(self, as_positive_float, ("start_speed",), allow_zero=True, optional=True)
        check_fields(self, as_positive_float, ("hold_resolution",), optional=True)
        check_fields(self, as_count, ("max_reprimes", "actuation_delay"))
        check_fields(self, as_flag, ("breakaway_estimate",))
        expect_type("internal_force", self.internal_force, InternalForceSettings, "an InternalForceSettings")
        if not self.prime_overshoot_max >= self.prime_overshoot:
            raise InvalidParameterError("prime_overshoot_max", self.prime_overshoot_max,
                                        f"at least prime_overshoot = {self.prime_overshoot}")
        if self.integral >= 2.0:
            raise InvalidParameterError("integral", self.integral, "a gain fraction in [0, 2) (stability)")
        for name in ("slider_floor", "holder_preload", "reflex_below", "reflex_floor") + \
                (("handover_load_max",) if self.handover_time > 0.0 else ()):
            if getattr(self, name) >= self.internal_force.f_max:
                raise InvalidParameterError(name, getattr(self, name), f"a normal force below the internal "
                                            f"force's f_max ({self.internal_force.f_max:g} N)")


@dataclass(frozen=True)
class MonitorSettings:
    """Tuning of the runtime envelope monitor (:class:`~regrasp.supervisor.monitor.EnvelopeMonitor`).

    Attributes:
        geometry: The envelopes' link geometry, a :class:`~regrasp.model.geometry.Geometry` (or its string).
        every: Evaluate the runtime envelopes every k-th step (1: every step; the monitor evaluates afresh whenever
            the policy decides, too).
        track: Follow each runtime envelope's ``urdf`` collision cuts from the last evaluation
            (:class:`~regrasp.envelope.tracker.EnvelopeTracker`; it falls back to the full evaluation whenever the
            envelope's structure changes) instead of finding them anew. Off by default: it matches a fresh
            evaluation (same pieces, ends within the bisection tolerance) at every step tested on the three-finger
            paper scenario, but on some random fingers it misses, for a few steps, a collision island born inside
            a piece (a thick distal link grazing the edge). No effect with ``ideal``.
    """

    geometry: Geometry = Geometry.IDEAL
    every: int = 1
    track: bool = False

    def __post_init__(self):
        object.__setattr__(self, "geometry", as_geometry("geometry", self.geometry))
        check_fields(self, as_count, ("every",), 1)
        check_fields(self, as_flag, ("track",))


@dataclass(frozen=True)
class PaperSettings:
    """Tuning of the paper's danger-zone policy (:class:`~regrasp.supervisor.policies.paper.PaperPolicy`).

    Attributes:
        danger_fraction: A contact is in danger when its margin is below this fraction of its feasible interval's
            width [-] ...
        reaction_time: ... or when, within this time [s], it would come that close to a bound: by the planned
            envelopes along the desired trajectory (when the supervisor has a plan), or else by the bounds' current
            rates (finite differences of the runtime envelopes). A bound can sweep 100 mm/s near a vertex, faster
            than a slide can start.
        target_horizon: With a plan, a slide's target is the midpoint of the widest piece of the planned feasible
            sets' intersection over the next ``target_horizon`` [s] (or over the longest prefix of it whose
            intersection is not empty), within the current interval.
        recheck_time: After the predicate rejects a slide, ask again after this long [s].
        feasibility: Margins the sliding-direction predicate requires before a slide starts (at least those of
            the executor's ``internal_force``, so that the priming QP is feasible).
        regrasp: False: the policy never slides (every contact stays where it is; danger is still reported).
        path_checks: The predicate is asked at this many points of a slide, evenly from the start to the target,
            each at the desired state of when the filter is expected to pass there (a slide takes about 6/ω_n):
            whether a slide is possible depends on where the contact is (its lever arm), so a slide can be
            possible where it starts and not on the way.
        enabling: When a contact's slide is rejected, look for a slide of another contact that makes it possible
            (e.g. the palm finger moving under the side that must slide down), and do that first.
        enabling_candidates: Candidate targets per other contact, evenly across what the plan keeps feasible for
            it (out of its danger zones), the nearest first.
        enabling_recheck_time: Search for an enabling slide at most this often per contact [s].
    """

    danger_fraction: float = DANGER_FRACTION
    reaction_time: float = 0.4
    target_horizon: float = 0.6
    recheck_time: float = 0.01
    feasibility: InternalForceSettings = field(
        default_factory=lambda: InternalForceSettings(f_min=0.2, friction_margin=0.05, f_max=20.0))
    regrasp: bool = True
    path_checks: int = 3
    enabling: bool = True
    enabling_candidates: int = 9
    enabling_recheck_time: float = 0.05

    def __post_init__(self):
        check_fields(self, as_duration, ("reaction_time", "target_horizon", "recheck_time", "enabling_recheck_time"))
        check_fields(self, as_count, ("path_checks", "enabling_candidates"), 1)
        check_fields(self, as_finite_float, ("danger_fraction",))
        if not 0.0 < self.danger_fraction < 0.5:
            raise InvalidParameterError("danger_fraction", self.danger_fraction, "a fraction in (0, 0.5)")
        expect_type("feasibility", self.feasibility, InternalForceSettings, "an InternalForceSettings")
        check_fields(self, as_flag, ("regrasp", "enabling"))


@dataclass(frozen=True)
class ScheduledSettings:
    """Tuning of :class:`ScheduledPolicy`.

    Attributes:
        prime_lead: Start priming this long before the schedule starts a slide [s] (the executor's
            ``prime_time`` is the longest priming).
        time_tolerance: A slide that ends (arrives, sticks, times out) more than this [s] from its
            planned end triggers a re-plan ...
        xi_tolerance: ... and so does one that ends more than this [m] from its planned end position.
        margin_fraction: A runtime envelope margin below this fraction of the planned one (at the
            nearest planned sample) triggers a re-plan [-].
        replan_cooldown: After a re-plan (or a failed one), no margin-triggered re-plan for this long [s].
        max_replans: At most this many re-plans in a run.
        replan: False: never re-plan (nothing triggers one, nothing is logged).
        decision_period: Decide at least this often [s] (default 10 ms; 0: at every step). Between decisions the policy
            proposes nothing, unless something happened: a slide ended or a contact changed phase (the next
            step decides), or a scheduled slide is due (the policy decides at its start, never late). What a
            longer period delays is only the margin-triggered re-plan, by at most the period.
    """

    prime_lead: float = 0.0
    time_tolerance: float = 0.05
    xi_tolerance: float = 1e-3
    margin_fraction: float = 0.5
    replan_cooldown: float = 0.1
    max_replans: int = 10
    decision_period: float = 0.01
    replan: bool = True

    def __post_init__(self):
        check_fields(self, as_positive_float, ("prime_lead", "time_tolerance", "xi_tolerance", "replan_cooldown",
                                               "decision_period"), allow_zero=True)
        check_fields(self, as_finite_float, ("margin_fraction",))
        if not 0.0 <= self.margin_fraction < 1.0:
            raise InvalidParameterError("margin_fraction", self.margin_fraction, "a fraction in [0, 1)")
        check_fields(self, as_count, ("max_replans",))
        check_fields(self, as_flag, ("replan",))


@dataclass(frozen=True)
class SupervisorSettings:
    """Tuning of :class:`~regrasp.supervisor.supervisor.RegraspSupervisor`: one value per concern, nested.

    Attributes:
        executor: How slides are run and the laws computed (:class:`ExecutorSettings`).
        monitor: How the runtime envelopes are evaluated (:class:`MonitorSettings`).
        paper: The paper's danger-zone policy (:class:`PaperSettings`; the supervisor's default policy).
        scheduled: The schedule-following policy (:class:`ScheduledSettings`; what
            :func:`~regrasp.rollout.build.build_rollout` builds by default).
    """

    executor: ExecutorSettings = field(default_factory=ExecutorSettings)
    monitor: MonitorSettings = field(default_factory=MonitorSettings)
    paper: PaperSettings = field(default_factory=PaperSettings)
    scheduled: ScheduledSettings = field(default_factory=ScheduledSettings)

    def __post_init__(self):
        expect_type("executor", self.executor, ExecutorSettings, "an ExecutorSettings")
        expect_type("monitor", self.monitor, MonitorSettings, "a MonitorSettings")
        expect_type("paper", self.paper, PaperSettings, "a PaperSettings")
        expect_type("scheduled", self.scheduled, ScheduledSettings, "a ScheduledSettings")

    @classmethod
    def robust(cls, geometry: Geometry | str = Geometry.IDEAL, cone_margin: float = DEFAULT_CONE_MARGIN, *,
               actuation_delay: int = 0, tip_radius: float = 0.0,
               hold_resolution: float | None = ExecutorSettings.hold_resolution, slider_floor: float = 0.3,
               holder_preload: float = 0.3) -> SupervisorSettings:
        """Settings for a hand whose plant differs from the model and whose sensors and actuators are not
        perfect (``docs/derivations.md``, "§4, executed" and "Robustness"): the fixed contacts kept 0.1 inside
        their cones in ratio (0.05 where no force allows more, and the model's cone itself where none allows even
        that: what the schedule planner plans, ``RegraspSettings.friction_margin``) and ``cone_margin`` [N] inside
        where the forces allow, the sliders' ξ at 60 rad/s, integral action (0.3 ω³), a priming whose overshoot
        grows from 0.01 to 0.25 over 40 ms (so a contact breaks away about where the plant's μ_s is, with little
        force to spare: ``RegraspSettings.prime_overshoot``; each re-priming of a slide stuck on its way starts 0.04
        higher) and lasts until the contact moves the right way at 1 mm/s, the sliders' kinetic
        friction estimated from the sensed forces (10 ms, from the break-away on), settling with 0.05 N of static
        margin, the held contacts' model positions following their sensed ones through a 20 ms filter, and the
        runtime envelopes evaluated every 10th step (100 Hz at 1 kHz; what a stale reading can miss:
        :mod:`regrasp.supervisor.monitor`), in ``geometry``.

        What the hand itself determines is an argument: its ``actuation_delay`` [control steps], its fingertips'
        sphere ``tip_radius`` [m] and the ``hold_resolution`` [m] its ξ sensor's noise calls for; and what the
        schedule was planned with, its ``slider_floor`` and ``holder_preload`` [N]
        (:class:`~regrasp.schedule.problem.RegraspSettings`): the executor keeps the plan's loads, with a reflex
        (a contact sensed below 0.1 N pushes with at least 0.4 N for 10 ms) and a handover hold (at a phase change
        each contact's load is released over 30 ms, at most 2 N of it). Change anything
        else with :func:`dataclasses.replace` on the branch (e.g. ``replace(s, executor=replace(s.executor,
        prime_overshoot=0.01))``)."""
        executor = ExecutorSettings(
            slide_omega=60.0, integral=0.3, prime_time=0.04, prime_overshoot=0.01, prime_overshoot_max=0.25,
            reprime_overshoot_step=0.04, friction_filter_time=0.01,
            breakaway_estimate=True, settle_margin=0.05, start_speed=1e-3, hold_filter_time=0.02,
            internal_force=InternalForceSettings(f_min=0.2, friction_margin=0.1, target_cone_margin=cone_margin,
                                                 fallback_friction_margin=0.05, last_friction_margin=0.0),
            actuation_delay=actuation_delay, tip_radius=tip_radius, hold_resolution=hold_resolution,
            slider_floor=slider_floor, holder_preload=holder_preload, reflex_below=0.1, reflex_floor=0.4,
            handover_time=0.03)
        return cls(executor=executor, monitor=MonitorSettings(geometry=geometry, every=10))

    def with_executor(self, **changes: object) -> SupervisorSettings:
        """These settings with ``changes`` to the executor's (``dataclasses.replace`` on that branch)."""
        return replace(self, executor=replace(self.executor, **changes))

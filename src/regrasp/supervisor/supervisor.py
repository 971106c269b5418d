r"""The regrasp supervisor (paper §4, Figure 4.1): a monitor watches, a policy proposes, an executor runs.

At every control step :meth:`RegraspSupervisor.step`

1. reads each contact's runtime envelope at the *measured* object pose
   (:class:`~regrasp.supervisor.monitor.EnvelopeMonitor`: margins, bounds and their rates; evaluated afresh at
   least every ``envelope_every`` steps and whenever the policy decides); a fixed contact
   outside its feasible set is logged (``LEFT_ENVELOPE``: the rollout fails there);
2. moves the slides under way on (:meth:`~regrasp.supervisor.executor.SlideExecutor.advance`: priming,
   sliding, settling) and tells the policy how finished slides ended;
3. asks the policy (:mod:`regrasp.supervisor.policies.scheduled`) for new slides and starts them: the schedule-following
   :class:`~regrasp.supervisor.policies.scheduled.ScheduledPolicy`, the paper's heuristic
   :class:`~regrasp.supervisor.policies.paper.PaperPolicy` (the default), or :class:`~regrasp.supervisor.policies.scheduled.NoRegraspPolicy`;
4. computes the torques with the control law of the contacts' phases
   (:meth:`~regrasp.supervisor.executor.SlideExecutor.command`).

The supervisor reads only what a hand could sense (:class:`Measurement`): the object pose and
twist, each contact's position and rate along its edge and whether each contact is stuck or
sliding (a slip sensor). It never sees the plant.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..core.contact import ContactMode, FrictionLike, as_frictions
from ..dynamics.control import ControlOutput
from ..envelope.finger_envelope import EnvelopeSample, FingerEnvelope, Geometry
from ..core.events import Event, EventKind
from ..core.exceptions import InvalidParameterError
from .executor import ContactPhase, ExecutorSettings, SlideExecutor
from ..dynamics.grasp import Grasp
from ..model.hand import Hand
from ..dynamics.internal_force.solver import InternalForceSettings
from .monitor import EnvelopeMonitor, bound_speeds
from ..envelope.planner import PlanResult
from .policies.scheduled import Policy
from .policies.paper import PaperPolicy
from ..core.polygon import ConvexPolygon
from ..core.trajectory import Trajectory, TrajectorySample
from ..core.validation import as_duration, as_finite_array, as_finite_float, as_inertia, as_mass

__all__ = [
    "ContactPhase",
    "Measurement",
    "RegraspSupervisor",
    "SupervisorContext",
    "SupervisorOutput",
    "SupervisorSettings",
]


#: The settings the supervisor passes on to its executor (their defaults are the executor's).
_EXECUTOR_FIELDS = ("omega_n", "zeta", "prime_time", "prime_overshoot", "prime_overshoot_max", "start_speed",
                    "settle_undershoot", "settle_margin", "actuation_delay", "arrive_tolerance", "arrive_speed",
                    "max_slide_time", "control_omega", "slide_omega", "integral", "friction_filter_time",
                    "breakaway_estimate", "internal_force", "hold_resolution", "hold_filter_time",
                    "tip_radius")


@dataclass(frozen=True)
class SupervisorSettings:
    """Tuning of :class:`RegraspSupervisor`: its monitor, executor and the paper's policy.

    Attributes:
        danger_fraction: A contact is in danger when its margin is below this fraction of its
            feasible interval's width [-] ...
        reaction_time: ... or when, within this time [s], it would come that close to a bound:
            by the planned envelopes along the desired trajectory (when the supervisor has a
            plan), or else by the bounds' current rates (finite differences of the runtime
            envelopes). A bound can sweep 100 mm/s near a vertex, faster than a slide can start.
        target_horizon: With a plan, a slide's target is the midpoint of the widest piece of the
            planned feasible sets' intersection over the next ``target_horizon`` [s] (or over
            the longest prefix of it whose intersection is not empty), within the current interval.
        omega_n: Natural frequency of the slide filter [rad/s].
        zeta: Damping ratio of the slide filter [-].
        prime_time: Longest duration of the cone-edge transition before a slide [s]; it ends
            earlier when the contact is sensed slipping.
        prime_overshoot: The transition asks for |f_t| = (μ_s + this) f_n at the contact [-], just
            past the static cone's edge, so that the contact starts to slip by itself (gently: the
            tangential force exceeds the static friction by ``prime_overshoot`` f_n) before the
            sliding law takes over. Switching to the sliding law while the contact is still stuck
            makes the plant redistribute the forces for one step and can slip another contact.
        prime_overshoot_max: The priming's overshoot grows to this over ``prime_time`` [-] (at least
            ``prime_overshoot``; see :class:`~regrasp.supervisor.executor.ExecutorSettings`).
        start_speed: The priming ends when the contact slides in the slide's direction faster than this [m/s]
            (None: when it is sensed sliding; :class:`~regrasp.supervisor.executor.ExecutorSettings`).
        settle_undershoot: A slide that ends with the contact still sliding settles with the
            fixed-contact law asking for (μ_k - this) f_n of friction in the sliding direction [-]
            (this at most μ_k / 2), just inside the kinetic cone: the plant's kinetic friction
            exceeds it by this much f_n, so the contact slows down gently and sticks. The plain
            fixed-contact law would predict static friction of either sign there, which a sliding
            contact cannot give; the plant would redistribute the forces for a step, enough to
            slip another contact when the slider carries much friction (the palm under the object).
        settle_margin: ... or asking for μ_k f_n - this [N] where that is less [N]: a contact that sticks
            before the settling torque arrives (an actuation delay) then holds it with this margin
            (:class:`~regrasp.supervisor.executor.ExecutorSettings`).
        actuation_delay: The hand's actuation delay [control steps]: the executor holds a slide's settling
            until the torques in flight were computed for it (:mod:`regrasp.supervisor.executor`).
        arrive_tolerance: A slide ends when |ξ - ξ*| is below this [m] ...
        arrive_speed: ... and |ξ̇| below this [m/s].
        max_slide_time: A slide that has not arrived after this long ends where it is [s].
        recheck_time: After the predicate rejects a slide, ask again after this long [s].
        control_omega: Bandwidth of the computed-torque laws [rad/s] (critically damped).
        slide_omega: The same on the sliders' ξ [rad/s] (:class:`~regrasp.supervisor.executor.ExecutorSettings`).
        friction_filter_time: Estimate sliders' kinetic friction from the sensed forces with this time
            constant [s] (None: the model's μ_k; :class:`~regrasp.supervisor.executor.ExecutorSettings`).
        breakaway_estimate: Start that estimate at the break-away, from the force ratio it happened at
            (:class:`~regrasp.supervisor.executor.ExecutorSettings`).
        integral: Integral action, K_i = ``integral`` · ω³ on every coordinate (0: none; see
            :class:`~regrasp.supervisor.executor.ExecutorSettings`).
        hold_resolution: A held contact's model position follows the sensed one when they differ by more than
            this [m] (a rolling fingertip; None: only at phase changes; :class:`~regrasp.supervisor.executor.ExecutorSettings`).
        hold_filter_time: The held contacts' sensed positions are filtered with this time constant [s] before the
            model takes them (None: unfiltered; :class:`~regrasp.supervisor.executor.ExecutorSettings`).
        tip_radius: The fingertips' sphere radius [m] the laws' torques account for (0: point contacts;
            :class:`~regrasp.supervisor.executor.ExecutorSettings`).
        envelope_every: Evaluate the runtime envelopes every k-th step (1: every step).
        track_envelopes: Follow each runtime envelope's ``urdf`` collision cuts from the last
            evaluation (:class:`~regrasp.envelope.tracker.EnvelopeTracker`; it falls back to the full
            evaluation whenever the envelope's structure changes) instead of finding them anew
            (about 2x faster per step). Off by default: it matches a fresh evaluation (same pieces,
            ends within the bisection tolerance) at every step tested on the three-finger paper
            scenario, but on some random fingers it misses, for a few steps, a collision island
            born inside a piece (a thick distal link grazing the edge). No effect with ``ideal``.
        geometry: Envelope geometry, ``"ideal"`` or ``"urdf"``.
        internal_force: Margins of the controllers' internal-force QP (default: push ≥ 0.2 N, fixed
            contacts 0.05 inside their cones, and kept at least ``target_cone_margin`` N inside them
            where the forces allow). A larger minimum push squeezes harder, which
            makes some slides infeasible for the torque balance (e.g. the side fingers of
            paper_trajectory_2_three_fingers.toml sliding up at 0.5 N).
        feasibility: Margins the sliding-direction predicate requires before a slide starts (at
            least those of ``internal_force``, so that the priming QP is feasible).
        regrasp: False: the paper's policy never slides (every contact stays where it is).
        path_checks: The predicate is asked at this many points of a slide, evenly from the start
            to the target, each at the desired state of when the filter is expected to pass there
            (a slide takes about 6/ω_n): whether a slide is possible depends on where the contact
            is (its lever arm), so a slide can be possible where it starts and not on the way.
        enabling: When a contact's slide is rejected, look for a slide of another contact that
            makes it possible (e.g. the palm finger moving under the side that must slide down),
            and do that first.
        enabling_candidates: Candidate targets per other contact, evenly across what the plan keeps
            feasible for it (out of its danger zones), the nearest first.
        enabling_recheck_time: Search for an enabling slide at most this often per contact [s].
    """

    danger_fraction: float = 0.1
    reaction_time: float = 0.4
    target_horizon: float = 0.6
    omega_n: float = ExecutorSettings.omega_n
    zeta: float = ExecutorSettings.zeta
    prime_time: float = ExecutorSettings.prime_time
    prime_overshoot: float = ExecutorSettings.prime_overshoot
    prime_overshoot_max: float = ExecutorSettings.prime_overshoot_max
    start_speed: float | None = ExecutorSettings.start_speed
    settle_undershoot: float = ExecutorSettings.settle_undershoot
    settle_margin: float = ExecutorSettings.settle_margin
    actuation_delay: int = ExecutorSettings.actuation_delay
    arrive_tolerance: float = ExecutorSettings.arrive_tolerance
    arrive_speed: float = ExecutorSettings.arrive_speed
    max_slide_time: float = ExecutorSettings.max_slide_time
    recheck_time: float = 0.01
    control_omega: float = ExecutorSettings.control_omega
    slide_omega: float = ExecutorSettings.slide_omega
    integral: float = ExecutorSettings.integral
    friction_filter_time: float | None = ExecutorSettings.friction_filter_time
    breakaway_estimate: bool = ExecutorSettings.breakaway_estimate
    envelope_every: int = 1
    track_envelopes: bool = False
    geometry: str = "ideal"
    internal_force: InternalForceSettings = field(default_factory=lambda: ExecutorSettings().internal_force)
    hold_resolution: float | None = ExecutorSettings.hold_resolution
    hold_filter_time: float | None = ExecutorSettings.hold_filter_time
    tip_radius: float = ExecutorSettings.tip_radius
    feasibility: InternalForceSettings = field(
        default_factory=lambda: InternalForceSettings(f_min=0.2, margin=0.05, f_max=20.0))
    regrasp: bool = True
    path_checks: int = 3
    enabling: bool = True
    enabling_candidates: int = 9
    enabling_recheck_time: float = 0.05

    def __post_init__(self):
        self.executor_settings()  # the executor's fields are checked where they are used
        for name in ("reaction_time", "target_horizon", "recheck_time", "enabling_recheck_time"):
            as_duration(name, getattr(self, name))
        for name, least in (("path_checks", 1), ("enabling_candidates", 1)):
            value = getattr(self, name)
            if isinstance(value, bool) or int(value) != value or value < least:
                raise InvalidParameterError(name, value, f"an integer >= {least}")
        if not 0.0 < as_finite_float("danger_fraction", self.danger_fraction) < 0.5:
            raise InvalidParameterError("danger_fraction", self.danger_fraction, "a fraction in (0, 0.5)")
        if isinstance(self.envelope_every, bool) or int(self.envelope_every) != self.envelope_every \
                or self.envelope_every < 1:
            raise InvalidParameterError("envelope_every", self.envelope_every, "an integer >= 1")
        if not isinstance(self.track_envelopes, bool):
            raise InvalidParameterError("track_envelopes", self.track_envelopes, "True or False")
        try:
            Geometry(self.geometry)
        except ValueError:
            raise InvalidParameterError("geometry", self.geometry, "'ideal' or 'urdf'") from None


    @classmethod
    def robust(cls, geometry: str = "ideal", cone_margin: float = 0.2, **overrides: Any) -> "SupervisorSettings":
        """Settings for a hand whose plant differs from the model and whose sensors and actuators are not
        perfect (``docs/derivations.md``, "§4, executed" and "Robustness"): the fixed contacts kept 0.1 inside
        their cones in ratio (0.05 where no force allows more) and ``cone_margin`` [N] inside where the forces
        allow, the sliders' ξ at 60 rad/s, integral action (0.3 ω³), a priming whose overshoot grows from 0.05
        to 0.25 over 40 ms and lasts until the contact moves the right way at 1 mm/s, the sliders' kinetic
        friction estimated from the sensed forces (10 ms, from the break-away on), settling with 0.05 N of static
        margin, the held contacts' model positions following their sensed ones through a 20 ms filter, and the
        runtime envelopes evaluated every 10th step (100 Hz at 1 kHz; what a stale reading can miss:
        :mod:`regrasp.supervisor.monitor`). ``overrides`` replace any of these (e.g. the hand's
        ``actuation_delay``)."""
        values = dict(geometry=geometry, envelope_every=10, slide_omega=60.0, integral=0.3, prime_time=0.04,
                      prime_overshoot_max=0.25,
                      friction_filter_time=0.01, breakaway_estimate=True, settle_margin=0.05,
                      start_speed=1e-3, hold_filter_time=0.02,
                      internal_force=InternalForceSettings(f_min=0.2, margin=0.1, target_cone_margin=cone_margin,
                                                           fallback_margin=0.05))
        values.update(overrides)
        return cls(**values)

    def executor_settings(self) -> ExecutorSettings:
        """The executor's part of these settings."""
        values = {name: getattr(self, name) for name in _EXECUTOR_FIELDS}
        if isinstance(self.prime_overshoot, (int, float)) and isinstance(self.prime_overshoot_max, (int, float)):
            values["prime_overshoot_max"] = max(self.prime_overshoot, self.prime_overshoot_max)
        return ExecutorSettings(**values)


@dataclass(frozen=True)
class Measurement:
    """What the hand senses at one control step.

    Attributes:
        t: Time [s].
        X, V: Object pose (x, y, β) and twist in the hand frame [m, rad], [m/s, rad/s].
        xi, xi_dot: Each contact's position along its edge and its rate [m], [m/s].
        sliding: Whether each contact is sliding (a slip sensor), (m,) bool.
        friction: Tangential contact force on the object at each contact [N], (m,) (a force
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
    friction: np.ndarray
    normal_force: np.ndarray | None = None


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


class RegraspSupervisor:
    r"""Keeps every contact inside its feasible envelope by sliding it (module docstring).

    Args:
        hand: The fingers (finger i touches contact i).
        polygon: The object.
        edges: The contact edge of each finger.
        trajectory: The desired object trajectory X_d(t) in the hand frame.
        xi: Initial contact positions ξ [m], one per finger (all contacts start fixed).
        friction: The friction the controllers and the predicate assume: a
            :class:`~regrasp.core.contact.Friction` or a coefficient [-] for all contacts, or one per contact.
        object_mass, object_inertia: What the controllers assume [kg], [kg m²]; default: the polygon's.
        tip_clearance: Per-finger tip clearance [m] for the ``urdf`` geometry (None: default).
        plan: The planner's result for ``trajectory`` (:func:`~regrasp.envelope.planner.plan`), or None: the
            paper's policy looks ahead on it.
        settings: :class:`SupervisorSettings`.
        policy: A policy (:mod:`regrasp.supervisor.policies.scheduled`), or a callable ``context -> policy``; default: the
            paper's heuristic (:class:`~regrasp.supervisor.policies.paper.PaperPolicy`; with ``settings.regrasp``
            False it reports danger and never slides).
    """

    def __init__(self, hand: Hand, polygon: ConvexPolygon, edges: Iterable[int], trajectory: Trajectory,
                 xi: ArrayLike, friction: FrictionLike = 0.5, *,
                 object_mass: float | None = None, object_inertia: float | None = None,
                 tip_clearance: Iterable[float | None] | None = None, plan: PlanResult | None = None,
                 settings: SupervisorSettings = SupervisorSettings(),
                 policy: Policy | Callable[[SupervisorContext], Policy] | None = None):
        m = hand.m
        edges = [int(e) for e in edges]
        if len(edges) != m:
            raise InvalidParameterError("edges", edges, f"one edge per finger ({m})")
        if not isinstance(settings, SupervisorSettings):
            raise InvalidParameterError("settings", settings, "a SupervisorSettings")
        if plan is not None and len(plan.fingers) != m:
            raise InvalidParameterError("plan", len(plan.fingers), f"a plan with one finger per finger ({m})")
        self.hand = hand
        self.trajectory = trajectory
        self.settings = settings
        friction = as_frictions(friction, m)
        mass = as_mass("object_mass", polygon.mass if object_mass is None else object_mass)
        inertia = as_inertia("object_inertia", polygon.inertia if object_inertia is None else object_inertia)
        self.names = tuple(f.name for f in hand.fingers)
        grasp = Grasp(polygon, edges, [ContactMode.FIXED] * m)
        self.context = SupervisorContext(hand, polygon, grasp, trajectory, friction, mass, inertia, plan, self.names)
        clearances = [None] * m if tip_clearance is None else list(tip_clearance)
        envelopes = [FingerEnvelope(f, polygon, e, geometry=settings.geometry, tip_clearance=c)
                     for f, e, c in zip(hand.fingers, edges, clearances)]
        # the prior for how fast the bounds move: the plan's, along the planned motion (monitor.py)
        speeds = 0.0 if plan is None else bound_speeds([f.samples for f in plan.fingers])
        self.monitor = EnvelopeMonitor(envelopes, every=settings.envelope_every, track=settings.track_envelopes,
                                       bound_speed=speeds)
        self.executor = SlideExecutor(hand, grasp, as_finite_array("xi", xi, (m,)), friction, object_mass=mass,
                                      object_inertia=inertia, settings=settings.executor_settings())
        if policy is None:  # (with regrasp False it still reports danger, and never slides)
            policy = PaperPolicy(self.context, settings)
        elif callable(policy) and not hasattr(policy, "propose"):
            policy = policy(self.context)
        if not all(hasattr(policy, a) for a in ("propose", "notify", "planned_xi")):
            raise InvalidParameterError("policy", policy, "a policy (propose, notify, planned_xi; regrasp.supervisor.policies.scheduled)")
        self.policy = policy
        self.events: list[Event] = []

    # the executor's state, for readers
    @property
    def phases(self) -> list[ContactPhase]:
        return self.executor.phases

    @property
    def regrasps(self) -> list[int]:
        """Completed slides per contact."""
        return self.executor.regrasps

    @property
    def plan(self) -> PlanResult | None:
        return self.context.plan

    def step(self, meas: Measurement, dt: float) -> SupervisorOutput:
        """Decide and compute the torques for one control period ``dt`` [s]."""
        start = time.perf_counter()
        out: list[Event] = []
        quiet = getattr(self.policy, "quiet_until", None)  # (a policy that decides now reads fresh envelopes)
        deciding = quiet is not None and not float(meas.t) < quiet(self.executor.phases)
        reading = self.monitor.read(meas.t, meas.X, meas.xi, fresh=deciding)
        ex = self.executor
        for i in range(self.hand.m):
            if reading.margins[i] < 0.0 and ex.phases[i] is ContactPhase.FIXED:
                sample = reading.samples[i]
                where = ("(empty: " + str(sample.reason) + ")" if not sample.feasible else
                         "[" + ", ".join(f"[{lo * 1e3:.2f}, {hi * 1e3:.2f}]" for lo, hi in sample.feasible) + "] mm")
                out.append(Event(float(meas.t), self.names[i], EventKind.LEFT_ENVELOPE,
                                 f"xi = {meas.xi[i] * 1e3:.2f} mm is outside its feasible set {where}",
                                 values={"xi": float(meas.xi[i]), "margin": float(reading.margins[i])}))
        ends = ex.advance(meas, out)
        if ends:
            self.policy.notify(ends, meas, out)
        for order in self.policy.propose(meas, reading, tuple(ex.phases), out):
            ex.start(order, meas, out)
        desired = self.trajectory.sample(float(meas.t))
        supervisor_seconds = time.perf_counter() - start
        control, law, reference, aborted = ex.command(meas, desired, dt, out)
        if aborted:
            self.policy.notify(aborted, meas, out)
        targets = np.full(self.hand.m, np.nan)
        for i in ex.active:
            targets[i] = ex.order_of(i).target
        self.events.extend(out)
        return SupervisorOutput(
            tau=control.tau, control=control, law=law, phases=tuple(ex.phases), envelopes=reading.samples,
            margins=reading.margins, bounds=reading.bounds, targets=targets, reference_xi=reference,
            planned_xi=self.policy.planned_xi(float(meas.t)), desired=desired, events=tuple(out),
            supervisor_seconds=supervisor_seconds, control_seconds=control.seconds)

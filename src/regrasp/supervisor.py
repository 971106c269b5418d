r"""The regrasp supervisor (paper §4, Figure 4.1): slide a contact to safety while the motion goes on.

At every control step the supervisor

1. evaluates each contact's feasible envelope at the *measured* object pose (the planner's
   :class:`~regrasp.envelope.FingerEnvelope` for one time sample, ``ideal`` geometry by default;
   ``envelope_every`` > 1 re-evaluates it only every k-th step and reuses the last sample in
   between);
2. for a fixed contact whose margin to the nearer bound of its feasible interval is below
   ``danger_fraction`` × the interval's width (its *danger zone*), or that the plan squeezes within
   ``reaction_time``, plans a slide to the middle of what stays feasible, but only if
   :func:`~regrasp.sliding.sliding_feasibility` accepts that direction at ``path_checks`` points
   from the contact to the target (at the desired pose and object acceleration); otherwise it
   looks for a slide of another contact that makes it possible and does that first
   (``enabling``), or logs why and tries the next contact in danger, or waits;
3. runs a slide in three phases: **priming** (the fixed-contact law with the internal force moved
   so the contact sits just past the edge of its static friction cone, :math:`\mu_s` +
   ``prime_overshoot``, in the sliding direction, until it is sensed slipping or for at most
   ``prime_time``), **sliding** (Proposition 3, which
   predicts the friction from the commanded motion and, for more than two fingers, chooses the
   slider's normal force with the internal force; ξ follows a second-order filter towards the
   target, :math:`\ddot\xi_r = \omega_n^2 (\xi^* - \xi_r) - 2\zeta\omega_n\dot\xi_r`), and
   **settling** (the fixed-contact law with the contact just inside its kinetic cone in the
   sliding direction, :math:`\mu_k` - ``settle_undershoot``, until the plant's contact sticks);
4. starts at most one slide at a time, so p ≤ 1 and 2m ≥ 3 + p holds for every m ≥ 2.

The supervisor reads only what a hand could sense: the object pose and twist, each contact's
position and rate along its edge and whether each contact is stuck or sliding (a slip sensor). It
never sees the plant.
"""

from __future__ import annotations

import math
import re
import time
from dataclasses import dataclass, field
from enum import Enum

import numpy as np

from .contact import ContactMode, as_frictions
from .control import (
    ComputedTorqueController,
    ControlOutput,
    FixedContactController,
    Gains,
    Proposition3Controller,
)
from .envelope import EnvelopeSample, FingerEnvelope, Geometry
from .envelope_tracker import EnvelopeTracker
from .exceptions import InvalidParameterError
from .grasp import Grasp
from .hand import Hand
from .internal_force import ConeEdge, InternalForceInfeasibleError, InternalForceSettings, InternalForceSolver
from .intervals import intersect, widest
from .planner import PlanResult
from .polygon import ConvexPolygon
from .reduced import ReducedModel
from .sliding import sliding_feasibility
from .trajectory import Trajectory
from .validation import as_finite_array, as_positive_float

__all__ = [
    "ContactPhase",
    "Measurement",
    "RegraspSupervisor",
    "SupervisorEvent",
    "SupervisorOutput",
    "SupervisorSettings",
]


class ContactPhase(str, Enum):
    """What the supervisor is doing with a contact."""

    FIXED = "fixed"
    PRIMING = "priming"
    SLIDING = "sliding"
    SETTLING = "settling"


@dataclass(frozen=True)
class SupervisorSettings:
    """Tuning of :class:`RegraspSupervisor`.

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
        settle_undershoot: A slide that ends with the contact still sliding settles with the
            fixed-contact law asking for (μ_k - this) f_n of friction in the sliding direction [-]
            (this at most μ_k / 2), just inside the kinetic cone: the plant's kinetic friction
            exceeds it by this much f_n, so the contact slows down gently and sticks. The plain
            fixed-contact law would predict static friction of either sign there, which a sliding
            contact cannot give; the plant would redistribute the forces for a step, enough to
            slip another contact when the slider carries much friction (the palm under the object).
        arrive_tolerance: A slide ends when |ξ - ξ*| is below this [m] ...
        arrive_speed: ... and |ξ̇| below this [m/s].
        max_slide_time: A slide that has not arrived after this long ends where it is [s].
        recheck_time: After the predicate rejects a slide, ask again after this long [s].
        control_omega: Bandwidth of the computed-torque laws [rad/s] (critically damped).
        envelope_every: Evaluate the runtime envelopes every k-th step (1: every step).
        track_envelopes: Follow each runtime envelope's ``urdf`` collision cuts from the last
            evaluation (:class:`~regrasp.envelope_tracker.EnvelopeTracker`; it falls back to the full
            evaluation whenever the envelope's structure changes) instead of finding them anew
            (about 2x faster per step). Off by default: it matches a fresh evaluation (same pieces,
            ends within the bisection tolerance) at every step tested on the three-finger paper
            scenario, but on some random fingers it misses, for a few steps, a collision island
            born inside a piece (a thick distal link grazing the edge). No effect with ``ideal``.
        geometry: Envelope geometry, ``"ideal"`` or ``"urdf"``.
        internal_force: Margins of the controllers' internal-force QP (default: push ≥ 0.2 N, fixed
            contacts 0.05 inside their cones). A larger minimum push squeezes harder, which
            makes some slides infeasible for the torque balance (e.g. the side fingers of
            paper_trajectory_2_three_fingers.toml sliding up at 0.5 N).
        feasibility: Margins the sliding-direction predicate requires before a slide starts (at
            least those of ``internal_force``, so that the priming QP is feasible).
        regrasp: False: never slide (every contact stays where it is; for comparison runs).
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
    omega_n: float = 20.0
    zeta: float = 1.0
    prime_time: float = 0.02
    prime_overshoot: float = 0.05
    settle_undershoot: float = 0.05
    arrive_tolerance: float = 5e-4
    arrive_speed: float = 5e-3
    max_slide_time: float = 1.5
    recheck_time: float = 0.01
    control_omega: float = 20.0
    envelope_every: int = 1
    track_envelopes: bool = False
    geometry: str = "ideal"
    internal_force: InternalForceSettings = field(default_factory=lambda: InternalForceSettings(f_min=0.2))
    feasibility: InternalForceSettings = field(
        default_factory=lambda: InternalForceSettings(f_min=0.2, margin=0.05, f_max=20.0))
    regrasp: bool = True
    path_checks: int = 3
    enabling: bool = True
    enabling_candidates: int = 9
    enabling_recheck_time: float = 0.05

    def __post_init__(self):
        for name in ("reaction_time", "target_horizon", "omega_n", "zeta", "prime_time", "prime_overshoot", "settle_undershoot",
                     "arrive_tolerance",
                     "arrive_speed", "max_slide_time", "recheck_time", "control_omega", "enabling_recheck_time"):
            as_positive_float(name, getattr(self, name))
        for name, least in (("path_checks", 1), ("enabling_candidates", 1)):
            value = getattr(self, name)
            if isinstance(value, bool) or int(value) != value or value < least:
                raise InvalidParameterError(name, value, f"an integer >= {least}")
        if not 0.0 < self.danger_fraction < 0.5:
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


@dataclass(frozen=True)
class Measurement:
    """What the hand senses at one control step.

    Attributes:
        t: Time [s].
        X, V: Object pose (x, y, β) and twist in the hand frame [m, rad], [m/s, rad/s].
        xi, xi_dot: Each contact's position along its edge and its rate [m], [m/s].
        sliding: Whether each contact is sliding (a slip sensor), (m,) bool.
        friction: Tangential contact force on the object at each contact [N], (m,) (a force
            sensor; the supervisor's laws do not read it, Proposition 2 would).
    """

    t: float
    X: np.ndarray
    V: np.ndarray
    xi: np.ndarray
    xi_dot: np.ndarray
    sliding: np.ndarray
    friction: np.ndarray


@dataclass(frozen=True)
class SupervisorEvent:
    """A decision of the supervisor.

    Attributes:
        time: [s].
        contact: Finger name.
        kind: ``danger``, ``slide_rejected``, ``prime``, ``slide_aborted``, ``slide``, ``arrived``,
            ``stuck`` (stuck before the target), ``timed_out`` (``max_slide_time`` passed),
            ``left_envelope``.
        detail: Human-readable numbers and reasons.
    """

    time: float
    contact: str
    kind: str
    detail: str


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
        targets: Each contact's slide target ξ* [m] (NaN when not sliding).
        reference_xi: The slide filter's ξ_r [m] per contact (NaN when not sliding).
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
    events: tuple[SupervisorEvent, ...]
    supervisor_seconds: float
    control_seconds: float


#: The largest change of a bound between two envelope evaluations counted as motion [m].
_MAX_BOUND_STEP = 1e-3
_NO_INTERVAL = (math.nan, math.nan)
_NUMBER = re.compile(r"[-+]?\d[\d.e+-]*")


def _single_intervals(samples) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(lo, hi, single) per sample: the bounds where the feasible set is one interval."""
    single = np.array([len(s.feasible) == 1 for s in samples])
    lo = np.array([s.feasible[0][0] if len(s.feasible) == 1 else np.nan for s in samples])
    hi = np.array([s.feasible[0][1] if len(s.feasible) == 1 else np.nan for s in samples])
    return lo, hi, single


def _interval_of(sample: EnvelopeSample, xi: float) -> tuple[float, float] | None:
    """The feasible interval holding ``xi``, else the nearest one, else None."""
    best, best_gap = None, math.inf
    for lo, hi in sample.feasible:
        gap = 0.0 if lo <= xi <= hi else min(abs(xi - lo), abs(xi - hi))
        if gap < best_gap:
            best, best_gap = (lo, hi), gap
    return best


class RegraspSupervisor:
    r"""Keeps every contact inside its feasible envelope by sliding it (paper §4).

    Args:
        hand: The fingers (finger i touches contact i).
        polygon: The object.
        edges: The contact edge of each finger.
        trajectory: The desired object trajectory X_d(t) in the hand frame.
        xi: Initial contact positions ξ [m], one per finger (all contacts start fixed).
        friction: The friction the controllers and the predicate assume: a
            :class:`~regrasp.contact.Friction` or a coefficient [-] for all contacts, or one per contact.
        object_mass, object_inertia: [kg], [kg m²]; default: the polygon's.
        tip_clearance: Per-finger tip clearance [m] for the ``urdf`` geometry (None: default).
        plan: The planner's result for ``trajectory`` (:func:`~regrasp.planner.plan`), or None.
            With a plan the supervisor looks ahead: a contact is in danger when the planned
            envelopes of the next ``reaction_time`` would squeeze it, and a slide's target is the
            middle of what the plan keeps feasible over the next ``target_horizon``, within the
            current interval (the planner's prefix-intersection rule applied from now), which on a
            wide still interval is its midpoint. Without a plan: the current interval's midpoint.
        settings: :class:`SupervisorSettings`.
    """

    def __init__(self, hand: Hand, polygon: ConvexPolygon, edges, trajectory: Trajectory, xi, friction=0.5, *,
                 object_mass: float | None = None, object_inertia: float | None = None,
                 tip_clearance=None, plan: PlanResult | None = None,
                 settings: SupervisorSettings = SupervisorSettings()):
        m = hand.m
        edges = [int(e) for e in edges]
        if len(edges) != m:
            raise InvalidParameterError("edges", edges, f"one edge per finger ({m})")
        self.hand = hand
        self.polygon = polygon
        self.edges = edges
        self.trajectory = trajectory
        self.settings = settings
        self.friction = as_frictions(friction, m)
        self.object_mass = as_positive_float("object_mass", polygon.mass if object_mass is None else object_mass)
        self.object_inertia = as_positive_float(
            "object_inertia", polygon.inertia if object_inertia is None else object_inertia)
        self.names = [f.name for f in hand.fingers]
        clearances = [None] * m if tip_clearance is None else list(tip_clearance)
        self.envelopes = [FingerEnvelope(f, polygon, e, geometry=settings.geometry, tip_clearance=c)
                          for f, e, c in zip(hand.fingers, edges, clearances)]
        # the runtime envelopes: tracked from step to step, or evaluated anew (FingerEnvelope.at)
        self.trackers = ([EnvelopeTracker(env) for env in self.envelopes]
                         if settings.track_envelopes and Geometry(settings.geometry) is Geometry.URDF else None)
        self.grasp = Grasp(polygon, edges, [ContactMode.FIXED] * m)
        if plan is not None and len(plan.fingers) != m:
            raise InvalidParameterError("plan", len(plan.fingers), f"a plan with one finger per finger ({m})")
        self.plan = plan
        self._plan_bounds = None if plan is None else [_single_intervals(f.samples) for f in plan.fingers]
        self.xi = as_finite_array("xi", xi, (m,)).copy()
        self.phases = [ContactPhase.FIXED] * m
        self.regrasps = [0] * m
        self.events: list[SupervisorEvent] = []
        self._active: int | None = None        # the contact being primed, slid or settled
        self._direction = 0.0
        self._target = math.nan
        self._filter = np.zeros(2)             # ξ_r, ξ̇_r
        self._phase_start = 0.0
        self._slipped = False
        self._aborted = False
        self._samples: list[EnvelopeSample | None] = [None] * m
        self._step = 0
        self._rejected: dict[int, str] = {}    # last logged rejection per contact (log once per reason)
        self._in_danger = [False] * m
        self._recheck = [-math.inf] * m       # when a rejected slide may be asked about again
        self._enable_recheck = [-math.inf] * m  # when to search for an enabling slide again
        self._feasibility = InternalForceSolver(settings.feasibility)  # the predicate's persistent QP
        self._previous: tuple[float, np.ndarray] | None = None   # (t, bounds) of the last envelope
        self._rates = np.zeros((m, 2))                          # d(lo)/dt, d(hi)/dt [m/s]
        self._controller = self._fixed_controller()

    # ------------------------------------------------------------------ controllers
    def _gains(self, n: int) -> Gains:
        return Gains.critically_damped(self.settings.control_omega, n)

    def _model(self, modes) -> ReducedModel:
        return ReducedModel(self.hand, self.grasp.with_modes(modes), self.xi, object_mass=self.object_mass,
                            object_inertia=self.object_inertia)

    def _fixed_controller(self, cone_edge: ConeEdge | None = None) -> ComputedTorqueController:
        """The fixed-contact law; with ``cone_edge``, that contact's force on that edge (its coefficient:
        μ_s + ``prime_overshoot`` to prime a slide, μ_k - ``settle_undershoot`` to settle one)."""
        model = self._model([ContactMode.FIXED] * self.hand.m)
        return FixedContactController(model, self._gains(3), self.friction, internal_force=self.settings.internal_force,
                                      cone_edge=cone_edge)

    def _sliding_controller(self, i: int) -> ComputedTorqueController:
        modes = [ContactMode.SLIDING if j == i else ContactMode.FIXED for j in range(self.hand.m)]
        # Proposition 3 predicts the friction from the commanded motion; with m > 2 it chooses the
        # slider's normal force together with the internal force (its class docstring)
        return Proposition3Controller(self._model(modes), self._gains(4), self.friction, direction=self._direction,
                                      internal_force=self.settings.internal_force)

    # ------------------------------------------------------------------ logging
    def _log(self, out: list, t: float, i: int, kind: str, detail: str) -> None:
        event = SupervisorEvent(float(t), self.names[i], kind, detail)
        out.append(event)
        self.events.append(event)

    # ------------------------------------------------------------------ decisions
    def _envelope_state(self, meas: Measurement):
        if self._step % self.settings.envelope_every == 0 or any(s is None for s in self._samples):
            if self.trackers is not None:
                for i, tracker in enumerate(self.trackers):
                    self._samples[i] = tracker.update(meas.X, meas.t)
            else:
                for i, env in enumerate(self.envelopes):
                    self._samples[i] = env.at(meas.X, meas.t)
            fresh = True
        else:
            fresh = False
        margins, rows = [], []  # on floats, then one array each
        for sample, xi in zip(self._samples, meas.xi.tolist()):
            margins.append(sample.margin(xi))
            iv = _interval_of(sample, xi)
            rows.append(_NO_INTERVAL if iv is None else iv)
        margins, bounds = np.array(margins), np.array(rows)
        if fresh:
            if self._previous is not None and meas.t > self._previous[0]:
                change = bounds - self._previous[1]
                rates = change / (meas.t - self._previous[0])
                # a jump is a change of the set's shape (pieces joining or splitting), not a motion:
                # the margin sees it at once, so it gets no rate
                smooth = np.isfinite(rates) & (np.abs(change) <= _MAX_BOUND_STEP)
                self._rates = np.where(smooth, rates, 0.0)
            self._previous = (meas.t, bounds)
        return margins, bounds

    def _plan_index(self, t: float) -> int:
        """Index of the planned sample at or just before t."""
        return max(0, int(np.searchsorted(self.plan.times, t, side="right")) - 1)

    def _squeezed_ahead(self, i: int, t: float, xi: float) -> float | None:
        """The first planned time within ``reaction_time`` where ξ is in a danger zone or outside."""
        times = self.plan.times
        k0 = self._plan_index(t)
        k1 = int(np.searchsorted(times, t + self.settings.reaction_time, side="right"))
        lo, hi, single = (a[k0:k1] for a in self._plan_bounds[i])
        # samples with one interval, vectorised; the others (empty or split sets) one by one
        width = hi - lo
        bad = single & (np.minimum(xi - lo, hi - xi) < self.settings.danger_fraction * width)
        samples = self.plan.fingers[i].samples
        for k in np.flatnonzero(~single):
            sample = samples[k0 + k]
            iv = _interval_of(sample, xi)
            bad[k] = iv is None or sample.margin(xi) < self.settings.danger_fraction * (iv[1] - iv[0])
        hits = np.flatnonzero(bad)
        return float(times[k0 + hits[0]]) if hits.size else None

    def _slide_target(self, i: int, t: float, xi: float, interval: tuple[float, float]) -> tuple[float, float | None]:
        """(ξ*, until): the middle of the widest piece of ``interval`` that the plan keeps feasible
        over [t, t + target_horizon] (or its longest prefix with a non-empty intersection), and
        the last planned time of that prefix."""
        (lo, hi), until = self._kept_feasible(i, t, interval)
        return 0.5 * (lo + hi), until

    def _kept_feasible(self, i: int, t: float, interval: tuple[float, float]) -> tuple[tuple[float, float], float | None]:
        """The widest piece of ``interval`` the plan keeps feasible for contact i (see
        :meth:`_slide_target`), and until when; without a plan, ``interval`` itself."""
        if self.plan is None:
            return interval, None
        prefix, until = (interval,), None
        for sample in self.plan.fingers[i].samples[self._plan_index(t):]:
            if sample.time > t + self.settings.target_horizon:
                break
            nxt = intersect(prefix, sample.feasible)
            if not nxt:
                break
            prefix, until = nxt, sample.time
        return widest(prefix), until

    def _time_to_bound(self, i: int, xi: float, bounds) -> float:
        """Time [s] until the nearer moving bound reaches ``xi`` at its current rate (inf if never)."""
        lo, hi = bounds[i]
        times = [math.inf]
        if self._rates[i, 0] > 0.0:
            times.append((xi - lo) / self._rates[i, 0])
        if self._rates[i, 1] < 0.0:
            times.append((hi - xi) / -self._rates[i, 1])
        return min(times)

    def _try_start(self, meas: Measurement, margins, bounds, out: list) -> None:
        """Start priming the most endangered contact whose slide the predicate accepts."""
        fraction = self.settings.danger_fraction
        danger = []
        for i in range(self.hand.m):
            lo, hi = bounds[i]
            width = hi - lo
            if not np.isfinite(width):
                self._in_danger[i] = False
                continue
            why, urgency = "", meas.t
            if margins[i] < fraction * width:
                why = "in the danger zone"
            elif self.plan is not None:
                when = self._squeezed_ahead(i, meas.t, meas.xi[i])
                if when is not None:
                    why, urgency = f"the plan squeezes it at t = {when:.3f} s", when
            else:
                reach = self._time_to_bound(i, meas.xi[i], bounds)
                if reach < self.settings.reaction_time:
                    why = f"a bound arrives in {reach:.3f} s"
            in_danger = bool(why)
            if in_danger and not self._in_danger[i]:
                self._log(out, meas.t, i, "danger", f"xi = {meas.xi[i] * 1e3:.2f} mm, feasible "
                          f"[{lo * 1e3:.2f}, {hi * 1e3:.2f}] mm, margin {margins[i] * 1e3:.2f} mm: {why}")
            if not in_danger:
                self._rejected.pop(i, None)
            self._in_danger[i] = in_danger
            if in_danger:
                danger.append((urgency, margins[i] / width, i))
        if not self.settings.regrasp:
            return
        if not danger:
            return
        for *_, i in sorted(danger):  # the soonest squeezed first
            if meas.t < self._recheck[i]:
                continue
            lo, hi = bounds[i]
            target, until = self._slide_target(i, meas.t, meas.xi[i], (lo, hi))
            if abs(target - meas.xi[i]) < 2.0 * self.settings.arrive_tolerance:
                continue  # already where a slide would take it
            direction = 1.0 if target > meas.xi[i] else -1.0
            verdict, where = self._slide_verdict(i, direction, meas.xi, target, meas.t)
            if verdict.possible:
                self._rejected.pop(i, None)
                self._start_priming(meas, out, i, direction, target, (lo, hi), until, verdict, "")
                return
            reason = f"slide {'+' if direction > 0 else '-'}xi rejected: {verdict.reason}" + (
                f" (at xi = {where * 1e3:.2f} mm on the way)" if where != meas.xi[i] else "")
            key = _NUMBER.sub("#", reason)
            if self._rejected.get(i) != key:  # log each kind of rejection once per danger episode
                self._log(out, meas.t, i, "slide_rejected", reason + "; waiting")
                self._rejected[i] = key
            self._recheck[i] = meas.t + self.settings.recheck_time
            if self.settings.enabling and meas.t >= self._enable_recheck[i]:
                self._enable_recheck[i] = meas.t + self.settings.enabling_recheck_time
                found = self._enabling_slide(meas, i, direction, target, bounds)
                if found is not None:
                    k, target_k, verdict_k, piece, until_k = found
                    self._start_priming(meas, out, k, 1.0 if target_k > meas.xi[k] else -1.0, target_k, piece, until_k,
                                        verdict_k, f" to let {self.names[i]} slide {'+' if direction > 0 else '-'}xi")
                    return

    def _slide_verdict(self, i: int, direction: float, xi, target: float, t: float):
        """The predicate at ``path_checks`` points of contact i's slide from xi[i] to ``target`` (the
        other contacts at ``xi``), each at the desired state of when the slide should pass there:
        (the first rejection, or the last acceptance; the ξ_i [m] where it was asked)."""
        s = self.settings
        n = s.path_checks
        duration = 6.0 / s.omega_n  # a critically damped filter covers ~98 % of a step in 6/ω_n
        xi = np.array(xi, dtype=float)
        start = xi[i]
        for k in range(n):
            fraction = k / (n - 1) if n > 1 else 0.0
            xi[i] = start + fraction * (target - start)
            desired = self.trajectory.sample(min(t + fraction * duration, self.trajectory.t_end))
            # where it starts, the priming asks for μ_s + overshoot (it must break away); on the way
            # the slider carries μ_k
            edge_mu = self.friction[i].static + s.prime_overshoot if k == 0 else None
            verdict = sliding_feasibility(
                self.grasp, desired.pose, xi, desired.acceleration, i, direction, self.friction,
                object_mass=self.object_mass, object_inertia=self.object_inertia,
                gravity_in_hand=self.hand.gravity_in_hand, settings=s.feasibility, solver=self._feasibility,
                edge_mu=edge_mu)
            if not verdict.possible:
                break
        return verdict, float(xi[i])

    def _enabling_slide(self, meas: Measurement, i: int, direction: float, target: float, bounds):
        """A slide of another fixed contact k after which contact i's rejected slide is possible:
        (k, ξ_k*, k's verdict, k's kept-feasible piece, until) with the nearest such ξ_k* over the
        candidates, or None."""
        s = self.settings
        later = meas.t + 6.0 / s.omega_n  # contact i slides once k has arrived
        for k in range(self.hand.m):
            lo, hi = bounds[k]
            if k == i or self.phases[k] is not ContactPhase.FIXED or not math.isfinite(hi - lo):
                continue
            (plo, phi), until = self._kept_feasible(k, meas.t, (lo, hi))
            keep = s.danger_fraction * (phi - plo)
            candidates = np.linspace(plo + keep, phi - keep, s.enabling_candidates) if phi - plo > 0 else []
            for target_k in sorted(candidates, key=lambda c: abs(c - meas.xi[k])):
                if abs(target_k - meas.xi[k]) < 2.0 * s.arrive_tolerance:
                    continue
                moved = meas.xi.copy()
                moved[k] = target_k
                if not self._slide_verdict(i, direction, moved, target, later)[0].possible:
                    continue
                verdict_k, _ = self._slide_verdict(k, 1.0 if target_k > meas.xi[k] else -1.0, meas.xi, target_k, meas.t)
                if verdict_k.possible:
                    return k, float(target_k), verdict_k, (plo, phi), until
        return None

    def _start_priming(self, meas: Measurement, out: list, i: int, direction: float, target: float, interval,
                       until, verdict, why: str) -> None:
        """Prime contact i's slide: the fixed law with i just past its static cone edge in ``direction``."""
        lo, hi = interval
        self._active, self._direction, self._target = i, direction, target
        self._phase_start = meas.t
        self.phases[i] = ContactPhase.PRIMING
        self.xi = meas.xi.copy()
        self._controller = self._fixed_controller(
            ConeEdge(i, direction, self.friction[i].static + self.settings.prime_overshoot))
        self._log(out, meas.t, i, "prime", f"to slide {'+' if direction > 0 else '-'}xi from "
                  f"{meas.xi[i] * 1e3:.2f} mm to {target * 1e3:.2f} mm{why} (feasible [{lo * 1e3:.2f}, "
                  f"{hi * 1e3:.2f}] mm" + (f", planned feasible until t = {until:.3f} s" if until is not None else "")
                  + "); predicted normal forces " + ", ".join(f"{f:.2f}" for f in verdict.normal_forces) + " N")

    def _end_slide(self, meas: Measurement, out: list, kind: str, detail: str) -> None:
        """Stop the slide where it is; a contact still sliding settles until it sticks (see
        ``SupervisorSettings.settle_undershoot``), then the fixed-contact law at the reached ξ."""
        i = self._active
        self.xi = meas.xi.copy()
        self._log(out, meas.t, i, kind, detail)
        if meas.sliding[i]:
            self.phases[i] = ContactPhase.SETTLING
            moving = float(meas.xi_dot[i])
            # (never below half of μ_k: a contact with μ_k under the undershoot still gets a cone)
            kinetic = self.friction[i].kinetic
            undershoot = min(self.settings.settle_undershoot, 0.5 * kinetic)
            self._controller = self._fixed_controller(
                ConeEdge(i, math.copysign(1.0, moving) if moving else self._direction, kinetic - undershoot))
        else:
            self._controller = self._fixed_controller()
            self._finish(meas, out)

    def _finish(self, meas: Measurement, out: list) -> None:
        i = self._active
        self.phases[i] = ContactPhase.FIXED
        if not self._aborted:  # an aborted slide that settles is not a regrasp
            self.regrasps[i] += 1
        self._aborted = False
        if abs(self.xi[i] - meas.xi[i]) > 1e-12 or not isinstance(self._controller, FixedContactController):
            self.xi = meas.xi.copy()
            self._controller = self._fixed_controller()
        self._active = None
        self._target = math.nan

    def _advance(self, meas: Measurement, out: list) -> None:
        """Move the active slide's phase on."""
        s = self.settings
        i = self._active
        phase = self.phases[i]
        if phase is ContactPhase.PRIMING and (meas.sliding[i] or meas.t - self._phase_start >= s.prime_time - 1e-12):
            self.phases[i] = ContactPhase.SLIDING
            self._phase_start = meas.t
            self.xi = meas.xi.copy()
            self._controller = self._sliding_controller(i)
            self._filter[:] = (meas.xi[i], meas.xi_dot[i])
            self._slipped = bool(meas.sliding[i])
            self._log(out, meas.t, i, "slide", f"sliding law {self._controller.law}, target "
                      f"{self._target * 1e3:.2f} mm")
        elif phase is ContactPhase.SLIDING:
            # the plant reports the slip one step after the sliding law starts
            self._slipped = self._slipped or bool(meas.sliding[i])
            if self._slipped and not meas.sliding[i]:
                self._end_slide(meas, out, "stuck", f"the contact stuck at {meas.xi[i] * 1e3:.2f} mm "
                                f"(target {self._target * 1e3:.2f} mm)")
            elif abs(meas.xi[i] - self._target) < s.arrive_tolerance and abs(meas.xi_dot[i]) < s.arrive_speed:
                self._end_slide(meas, out, "arrived", f"xi = {meas.xi[i] * 1e3:.2f} mm after "
                                f"{meas.t - self._phase_start:.3f} s")
            elif meas.t - self._phase_start > s.max_slide_time:
                self._end_slide(meas, out, "timed_out", f"slide stopped after max_slide_time at "
                                f"{meas.xi[i] * 1e3:.2f} mm (target {self._target * 1e3:.2f} mm)")
        elif phase is ContactPhase.SETTLING and not meas.sliding[i]:
            self._finish(meas, out)

    def _filter_step(self, dt: float) -> tuple[float, float, float]:
        """Advance the slide filter by dt (semi-implicit Euler) and return (ξ_r, ξ̇_r, ξ̈_r)."""
        w, z = self.settings.omega_n, self.settings.zeta
        x, v = self._filter
        a = w * w * (self._target - x) - 2.0 * z * w * v
        v = v + a * dt
        x = x + v * dt
        self._filter[:] = (x, v)
        return x, v, w * w * (self._target - x) - 2.0 * z * w * v

    # ------------------------------------------------------------------ the step
    def step(self, meas: Measurement, dt: float) -> SupervisorOutput:
        """Decide and compute the torques for one control period ``dt`` [s]."""
        start = time.perf_counter()
        out: list[SupervisorEvent] = []
        margins, bounds = self._envelope_state(meas)
        for i in range(self.hand.m):
            if margins[i] < 0.0 and self.phases[i] is ContactPhase.FIXED:
                self._log(out, meas.t, i, "left_envelope", f"xi = {meas.xi[i] * 1e3:.2f} mm is outside its feasible "
                          "set " + ("(empty: " + str(self._samples[i].reason) + ")" if not self._samples[i].feasible
                                    else "[" + ", ".join(f"[{lo * 1e3:.2f}, {hi * 1e3:.2f}]"
                                                         for lo, hi in self._samples[i].feasible) + "] mm"))
        if self._active is not None:
            self._advance(meas, out)
        desired = self.trajectory.sample(float(meas.t))
        if self._active is None:
            self._try_start(meas, margins, bounds, out)
        X_d, V_d, A_d = desired.pose, desired.velocity, desired.acceleration
        targets = np.full(self.hand.m, np.nan)
        reference = np.full(self.hand.m, np.nan)
        controller = self._controller
        if self._active is not None and self.phases[self._active] is ContactPhase.SLIDING:
            i = self._active
            xr, vr, ar = self._filter_step(dt)
            targets[i], reference[i] = self._target, xr
            S = np.append(meas.X, meas.xi[i])
            S_dot = np.append(meas.V, meas.xi_dot[i])
            S_d, S_d_dot, S_d_ddot = np.append(X_d, xr), np.append(V_d, vr), np.append(A_d, ar)
        else:
            if self._active is not None:
                targets[self._active] = self._target
            S, S_dot, S_d, S_d_dot, S_d_ddot = meas.X, meas.V, X_d, V_d, A_d
        supervisor_seconds = time.perf_counter() - start
        try:
            control = controller(S, S_dot, S_d, S_d_dot, S_d_ddot)
        except InternalForceInfeasibleError as exc:
            if self._active is None or self.phases[self._active] not in (ContactPhase.PRIMING, ContactPhase.SLIDING):
                raise
            # the slide cannot go on after all (the predicate's forecast used the desired state):
            # abort it, hold with the fixed law (which the contact settles into) and ask again later
            i = self._active
            self._aborted = True
            self._log(out, meas.t, i, "slide_aborted", f"no internal force keeps the slide in its cones ({exc.status})")
            self._recheck[i] = meas.t + self.settings.recheck_time
            self.xi = meas.xi.copy()
            if meas.sliding[i]:
                self.phases[i] = ContactPhase.SETTLING
            else:
                self.phases[i] = ContactPhase.FIXED
                self._active, self._target, self._aborted = None, math.nan, False
            controller = self._controller = self._fixed_controller()
            control = controller(meas.X, meas.V, X_d, V_d, A_d)
        self._step += 1
        return SupervisorOutput(
            tau=control.tau,
            control=control,
            law=controller.law + (" (cone edge)" if controller.cone_edge is not None else ""),
            phases=tuple(self.phases),
            envelopes=tuple(self._samples),
            margins=margins,
            bounds=bounds,
            targets=targets,
            reference_xi=reference,
            events=tuple(out),
            supervisor_seconds=supervisor_seconds,
            control_seconds=control.seconds,
        )

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
   :class:`~regrasp.supervisor.policies.paper.PaperPolicy` (the default), or
   :class:`~regrasp.supervisor.policies.base.NoRegraspPolicy`;
4. computes the torques with the control law of the contacts' phases
   (:meth:`~regrasp.supervisor.executor.SlideExecutor.command`).

The supervisor reads only what a hand could sense (:class:`Measurement`): the object pose and
twist, each contact's position and rate along its edge and whether each contact is stuck or
sliding (a slip sensor). It never sees the plant.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable

import numpy as np
from numpy.typing import ArrayLike

from ..core.contact import DEFAULT_FRICTION, ContactMode, FrictionLike, as_frictions
from ..core.events import Event, EventKind
from ..core.exceptions import InvalidParameterError
from ..core.measurement import Measurement
from ..core.polygon import ConvexPolygon
from ..core.trajectory import Trajectory
from ..core.validation import as_finite_array, as_inertia, as_mass
from ..dynamics.grasp import Grasp
from ..envelope.finger_envelope import FingerEnvelope
from ..envelope.planner import PlanResult
from ..model.hand import Hand
from .executor import SlideExecutor
from .monitor import EnvelopeMonitor, bound_speeds
from .policies.base import Policy
from .policies.paper import PaperPolicy
from .settings import SupervisorSettings
from .types import ContactPhase, SupervisorContext, SupervisorOutput

__all__ = ["RegraspSupervisor"]


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
        object_mass: The mass the controllers assume [kg]; default: the polygon's.
        object_inertia: The inertia the controllers assume [kg m²]; default: the polygon's.
        tip_clearance: Per-finger tip clearance [m] for the ``urdf`` geometry (None: default).
        plan: The planner's result for ``trajectory`` (:func:`~regrasp.envelope.planner.plan`), or None: the
            paper's policy looks ahead on it.
        settings: :class:`SupervisorSettings`.
        policy: A policy (:mod:`regrasp.supervisor.policies.scheduled`), or a callable ``context -> policy``; default:
            the paper's heuristic (:class:`~regrasp.supervisor.policies.paper.PaperPolicy`; with
            ``settings.paper.regrasp`` False it reports danger and never slides).
    """

    def __init__(self, hand: Hand, polygon: ConvexPolygon, edges: Iterable[int], trajectory: Trajectory,
                 xi: ArrayLike, friction: FrictionLike = DEFAULT_FRICTION, *,
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
        envelopes = [FingerEnvelope(f, polygon, e, geometry=settings.monitor.geometry, tip_clearance=c)
                     for f, e, c in zip(hand.fingers, edges, clearances)]
        # the prior for how fast the bounds move: the plan's, along the planned motion (monitor.py)
        speeds = 0.0 if plan is None else bound_speeds([f.samples for f in plan.fingers])
        self.monitor = EnvelopeMonitor(envelopes, every=settings.monitor.every, track=settings.monitor.track,
                                       bound_speed=speeds)
        self.executor = SlideExecutor(hand, grasp, as_finite_array("xi", xi, (m,)), friction, object_mass=mass,
                                      object_inertia=inertia, settings=settings.executor)
        if policy is None:  # (with regrasp False it still reports danger, and never slides)
            policy = PaperPolicy(self.context, settings)
        elif callable(policy) and not hasattr(policy, "propose"):
            policy = policy(self.context)
        if not all(hasattr(policy, a) for a in ("propose", "notify", "planned_xi")):
            raise InvalidParameterError("policy", policy, "a policy (propose, notify, planned_xi; "
                                        "regrasp.supervisor.policies.scheduled)")
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

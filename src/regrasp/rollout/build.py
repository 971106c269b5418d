"""A regrasping rollout: the independent plant driven by the supervisor and its control laws.

:func:`build_rollout` sets up a plant (full coordinates, :mod:`regrasp.plants.project.plant`) and a
:class:`~regrasp.supervisor.supervisor.RegraspSupervisor` with a policy (``"scheduled"``: a schedule planned
ahead with :func:`~regrasp.schedule.planner.plan_regrasps` and re-planned when reality drifts;
``"paper"``: the paper's danger-zone heuristic; ``"none"``: no regrasp). The supervisor never sees
the plant: it gets a :class:`~regrasp.core.measurement.Measurement` per step. The plant may differ from
what the controllers assume (``plant_mass_scale``, ``plant_mu_scale``: model error).
:meth:`Rollout.run` runs the one simulation loop (:func:`~regrasp.plants.simulation.simulate`) until the
end or the first failure (:class:`~regrasp.core.events.FailureKind`):

* the plant stops (a contact leaving its edge, a link–object collision, a singular finger);
* a contact is lost by the health criteria (:mod:`regrasp.core.health`, the run's
  :class:`~regrasp.core.health.HealthCriteria`, the same on every plant): a held contact that carries less than the
  force floor for too long or slips too far (an *unplanned slip*), a slider that carries too little;
* a fixed contact leaves its feasible envelope;
* the control law has no solution (no internal force keeps the contacts in their cones, a singular model);
* Ctrl-C (``INTERRUPTED``: the result so far, and a complete recording).

A failure is a result, not an exception: :class:`RolloutResult` says when and why.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

from ..core.events import PLANT_FAILURES, EventKind, EventSource, Failure, FailureKind
from ..core.exceptions import InvalidParameterError
from ..core.health import HealthCriteria, HealthMonitor
from ..core.measurement import Measurement
from ..core.validation import as_finite_array, expect_type, step_count
from ..envelope.planner import PlanResult, plan_scenario
from ..kernels.warm import STRETCH_WAIT_STEPS, compiling, warm_up
from ..model.hand import Hand
from ..model.scenario import Scenario
from ..plants.disturbance import Disturbance
from ..plants.simulation import Command, PlantLike, StepRecord, simulate
from ..plants.spec import PlantSpec
from ..schedule.planner import RegraspSettings, plan_regrasps
from ..schedule.problem import trajectory_period
from ..schedule.schedule import RegraspSchedule
from ..supervisor.policies.base import NoRegraspPolicy
from ..supervisor.policies.paper import PaperPolicy
from ..supervisor.policies.scheduled import ScheduledPolicy
from ..supervisor.settings import ExecutorSettings, SupervisorSettings
from ..supervisor.supervisor import RegraspSupervisor
from ..supervisor.types import ContactPhase
from .result import RolloutResult, RolloutRows
from .spec import RunSpec
from .stretch import CompiledStretches

if TYPE_CHECKING:
    from .recording.recorder import RolloutRecorder

__all__ = ["POLICIES", "Rollout", "SupervisorDriver", "build_rollout"]

#: The policies :func:`build_rollout` knows by name.
POLICIES = ("scheduled", "paper", "none")

class SupervisorDriver:
    """The simulation loop's driver (:class:`~regrasp.plants.simulation.Driver`) around a supervisor."""

    def __init__(self, supervisor: RegraspSupervisor):
        self.supervisor = supervisor

    def step(self, meas: Measurement, dt: float) -> Command:
        out = self.supervisor.step(meas, dt)
        desired = out.desired
        sliders = [i for i, p in enumerate(out.phases) if p is ContactPhase.SLIDING]
        S = np.concatenate([meas.X, meas.xi[sliders]])
        if len(S) != len(out.control.error):  # (a slide aborted at this step: the fixed law ran)
            S = meas.X
        return Command(out.tau, out.control, out.law, desired, S + out.control.error, out)


@dataclass
class Rollout:
    """A plant and a supervisor, ready to run (see :func:`build_rollout`).

    Attributes:
        plant, supervisor, duration [s], names: as built.
        policy: The policy's name.
        schedule: The schedule the run starts with (``"scheduled"``), else None.
        scenario: The scenario, with its trajectory repeated when the run is longer than it.
        disturbance: The sensing noise and actuation between the plant and the supervisor, or None.
        health: When a contact is lost (:class:`~regrasp.core.health.HealthCriteria`).
    """

    plant: PlantLike
    supervisor: RegraspSupervisor
    duration: float
    names: tuple[str, ...]
    policy: str = "paper"
    schedule: RegraspSchedule | None = None
    scenario: Scenario | None = None
    disturbance: Disturbance | None = None
    health: HealthCriteria = field(default_factory=HealthCriteria)
    #: The last run's compiled stretches (their ``steps`` and ``calls``), or None.
    stretches: CompiledStretches | None = field(default=None, init=False, repr=False)

    def check(self, record: StepRecord) -> Failure | None:
        """The failure a step's events mean, if any (module docstring). A contact's loss is the health monitor's
        to judge (:mod:`regrasp.core.health`), not the plant's events: a slip or a separation the plant reports
        fails the run only through what the contact then carries and how far it slips."""
        for e in record.events:
            if e.source is EventSource.SUPERVISOR and e.kind is EventKind.LEFT_ENVELOPE:
                return Failure(e.time, FailureKind.LEFT_ENVELOPE, f"{e.contact} left its feasible envelope: {e.detail}",
                               e.contact)
            if e.source is not EventSource.PLANT:
                continue
            if e.kind in PLANT_FAILURES and e.kind in self.plant.stop_on:
                return Failure(e.time, PLANT_FAILURES[e.kind], f"{e.kind.value} of {e.contact}: {e.detail}", e.contact)
        return None

    def run(self, *, recorder: RolloutRecorder | None = None, progress: Callable[[int, int], None] | None = None,
            interruptible: bool = True, compiled_stretches: bool | None = None) -> RolloutResult:
        """Run to ``duration`` or the first failure.

        Args:
            recorder: A :class:`~regrasp.rollout.recording.recorder.RolloutRecorder` for this rollout's plant: each
                step's record is logged (:meth:`~regrasp.rollout.recording.recorder.RolloutRecorder.log_record`);
                the caller closes it. Or None.
            progress: Called as ``progress(done, total)`` every 50 steps and at the end.
            interruptible: Ctrl-C ends the run with an ``INTERRUPTED`` failure (else it propagates).
            compiled_stretches: Run the steps between the supervisor's decisions in compiled stretches
                (:mod:`regrasp.rollout.stretch`; the same steps, faster); False: every step on the reference path;
                None (default): compiled stretches, unless a worker process still compiles their kernel (a
                machine's first run) and the run is shorter than
                :data:`~regrasp.kernels.warm.STRETCH_WAIT_STEPS` steps.
        """
        plant = self.plant
        total = step_count("duration", self.duration, plant.dt)  # (a run of no step is refused)
        if compiled_stretches is None:
            compiled_stretches = not (compiling("stretch") and total < STRETCH_WAIT_STEPS)
        rows = RolloutRows(total, plant.hand.m, plant.friction)
        consumers = [rows.add]
        if recorder is not None:
            recorder.log_initial(plant, self.supervisor.trajectory.pose(plant.state.t))
            trajectory = self.supervisor.trajectory
            t_end = trajectory.t_end  # (the last step may end half a step past the run's duration)
            consumers.append(lambda record: recorder.log_record(record, trajectory.pose(min(record.plant.state.t,
                                                                                              t_end))))
        stretches = None
        if compiled_stretches:
            stretches = CompiledStretches(self.supervisor, plant, rows, total, recorder=recorder,
                                          disturbance=self.disturbance, force_floor=self.health.force_floor)
            if stretches.enabled:  # (their kernel: at once when loaded; else it waits for a worker, or compiles)
                warm_up(groups=("stretch",))
        health = HealthMonitor(self.health, self.names, plant.dt)
        judged = 0

        def check(record: StepRecord) -> Failure | None:
            nonlocal judged
            failure = self.check(record)
            judged, lost = rows.judge(health, judged)  # (after the events: a plant's stop comes first)
            return failure if failure is not None else lost

        outcome = simulate(plant, SupervisorDriver(self.supervisor), total, consumers=consumers, check=check,
                           progress=progress, interruptible=interruptible, disturbance=self.disturbance,
                           stretches=stretches)
        if stretches is not None:
            stretches.finish()
        judged, lost = rows.judge(health, judged)  # (a last stretch's rows)
        if lost is not None and outcome.failure is None:
            outcome = replace(outcome, failure=lost)
        self.stretches = stretches
        if recorder is not None and outcome.failure is not None:
            recorder.log_failure(outcome.failure, plant)
        policy = self.supervisor.policy
        return rows.result(
            outcome, duration=self.duration, object_width=plant.polygon.scale, names=self.names,
            regrasps=dict(zip(self.names, self.supervisor.regrasps)), supervisor_events=tuple(self.supervisor.events),
            policy=self.policy, replans=getattr(policy, "replans", 0), schedule=self.schedule,
            rrd=None if recorder is None or recorder.rrd_path is None else str(recorder.rrd_path),
            health=health.reports())


def build_rollout(scenario: Scenario, run: RunSpec = RunSpec(), *, policy: str = "scheduled",
                  settings: SupervisorSettings | None = None, regrasp_settings: RegraspSettings | None = None,
                  schedule: RegraspSchedule | None = None, plan: PlanResult | None = None,
                  plant: PlantSpec | str = "project",
                  plan_progress: Callable[[int, int], None] | None = None) -> Rollout:
    """Plant + supervisor for ``scenario``, every contact fixed at the start.

    Args:
        scenario: The scenario (fingers, edges, object, trajectory, gravity, friction).
        run: How long, the step, where the contacts start, the hand's noise and its seed (:class:`RunSpec`).
        policy: ``"scheduled"`` (plan the slides ahead, follow and re-plan them), ``"paper"`` (the
            danger-zone heuristic) or ``"none"`` (never slide).
        settings: Supervisor settings (default :meth:`SupervisorSettings.robust` with the scenario's geometry,
            the schedule's cone margin, the run's actuation delay and, on MuJoCo or Drake, the tips' radius); the
            scheduled policy's are its ``scheduled`` branch.
        regrasp_settings: The schedule planner's settings (``"scheduled"``; default :class:`RegraspSettings`).
        schedule: A schedule planned already (``"scheduled"``; default: planned here).
        plan: The scenario's envelope plan (:func:`~regrasp.envelope.planner.plan_scenario`) computed already (a
            study plans it once for all its runs; default: planned here).
        plant: The plant (:class:`~regrasp.plants.spec.PlantSpec`: its kind, settings and model errors), or a
            kind's name (``"project"``, ``"mujoco"``, ``"drake"``).
        plan_progress: Passed to :func:`~regrasp.schedule.planner.plan_regrasps` as ``progress``.

    Raises:
        NoScheduleError: ``"scheduled"`` and no schedule exists (the planner's diagnosis).
        MissingDependencyError: a MuJoCo or Drake plant and its package (``mujoco``, ``drake``) is not installed.
    """
    if not isinstance(scenario, Scenario):
        raise InvalidParameterError("scenario", scenario, "a Scenario (regrasp.load_scenario)")
    expect_type("run", run, RunSpec, "a RunSpec (regrasp.rollout.spec)")
    if policy not in POLICIES:
        raise InvalidParameterError("policy", policy, f"one of {', '.join(POLICIES)}")
    plant = PlantSpec.of(plant)
    regrasp_settings = RegraspSettings.of(scenario) if regrasp_settings is None \
        else expect_type("regrasp_settings", regrasp_settings, RegraspSettings, "a RegraspSettings")
    if schedule is not None:
        expect_type("schedule", schedule, RegraspSchedule, "a RegraspSchedule (regrasp.plan_regrasps)")
    if settings is None:  # the supervisor's runtime envelopes use the scenario's planner geometry; the laws know
        # the MuJoCo or Drake plant's sphere tips and the hand's actuation delay (a latency is measured, unlike a
        # friction) and its sensors' noise: a held contact's model position moves when its filtered reading moved
        # by half the noise's standard deviation, not at every step
        xi_noise = run.sensor_noise.xi
        hold = ExecutorSettings.hold_resolution if xi_noise == 0.0 else max(ExecutorSettings.hold_resolution,
                                                                             0.5 * xi_noise)
        settings = SupervisorSettings.robust(scenario.geometry, regrasp_settings.cone_margin,
                                             actuation_delay=run.actuator_noise.delay, tip_radius=plant.tip_radius,
                                             hold_resolution=hold, slider_floor=regrasp_settings.slider_floor,
                                             holder_preload=regrasp_settings.holder_preload)
    scenario.check_geometry(expect_type("settings", settings, SupervisorSettings, "a SupervisorSettings")
                            .monitor.geometry)
    run_scenario, duration = run.resolve(scenario)
    traj = run_scenario.trajectory
    m = len(scenario.contacts)
    if plan is None:
        plan = plan_scenario(scenario)
    elif not isinstance(plan, PlanResult) or len(plan.fingers) != m:
        raise InvalidParameterError("plan", plan, f"a PlanResult of this scenario ({m} fingers)")
    xi0 = run.start(m)
    if policy == "scheduled" and schedule is None:
        schedule = plan_regrasps(scenario, regrasp_settings, xi0=xi0, progress=plan_progress)
    if xi0 is None:
        if policy == "scheduled":
            xi0 = schedule.at(traj.t_start).xi
        else:
            missing = [p.name for p in plan.fingers if p.initial_xi is None]
            if missing:
                raise InvalidParameterError("scenario", scenario.name,
                                            f"a feasible initial grasp; none for {', '.join(missing)} at t = "
                                            f"{traj.t_start:.6g} s")
            xi0 = [p.initial_xi for p in plan.fingers]
    xi0 = as_finite_array("xi0", xi0, (m,))
    hand = Hand([c.finger for c in scenario.contacts], gravity_in_hand=scenario.gravity_in_hand)
    names = tuple(f.name for f in hand.fingers)
    t_run_end = traj.t_start + duration
    if policy == "scheduled":
        def replanner(t: float, xi: np.ndarray) -> RegraspSchedule:
            return plan_regrasps(run_scenario, replace(regrasp_settings, periodic=False), start_time=t, xi0=xi,
                                 t_end=min(t_run_end, t + max(1.0, 2.0 * (trajectory_period(traj) or 0.0))))
        chosen = ScheduledPolicy(schedule, names, replan=replanner if settings.scheduled.replan else None,
                                 settings=settings.scheduled)
    elif policy == "none":
        chosen = NoRegraspPolicy(m)
    else:
        chosen = lambda context: PaperPolicy(context, settings)  # noqa: E731
    supervisor = RegraspSupervisor(hand, scenario.polygon, [c.edge for c in scenario.contacts], traj, xi0,
                                   scenario.friction, tip_clearance=[c.tip_clearance for c in scenario.contacts],
                                   plan=plan, settings=settings, policy=chosen)
    t0 = traj.t_start
    built = plant.build(scenario, hand, xi0, traj.pose(t0), traj.velocity(t0), t0, run.dt)
    return Rollout(built, supervisor, duration, names, policy, schedule, run_scenario, run.disturbance(), run.health)

"""A regrasping rollout: the independent plant driven by the supervisor and its control laws.

:func:`build_rollout` sets up a plant (full coordinates, :mod:`regrasp.plants.project.plant`) and a
:class:`~regrasp.supervisor.supervisor.RegraspSupervisor` with a policy (``"scheduled"``: a schedule planned
ahead with :func:`~regrasp.schedule.planner.plan_regrasps` and re-planned when reality drifts;
``"paper"``: the paper's danger-zone heuristic; ``"none"``: no regrasp). The supervisor never sees
the plant: it gets a :class:`~regrasp.supervisor.supervisor.Measurement` per step. The plant may differ from
what the controllers assume (``plant_mass_scale``, ``plant_mu_scale``: model error).
:meth:`Rollout.run` runs the one simulation loop (:func:`~regrasp.plants.simulation.simulate`) until the
end or the first failure (:class:`~regrasp.core.events.FailureKind`):

* the plant stops (separation, a contact leaving its edge, a link–object collision, a singular finger);
* a contact slips that the supervisor holds fixed (an *unplanned slip*);
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
from numpy.typing import ArrayLike

from ..core.contact import ContactMode, Friction, FrictionLike
from ..plants.disturbance import ActuatorNoise, Disturbance, SensorNoise
from ..core.events import PLANT_FAILURES, EventKind, EventSource, Failure, FailureKind
from ..core.exceptions import InvalidParameterError
from ..supervisor.executor import SLIPPING_PHASES, ContactPhase, ExecutorSettings
from ..dynamics.grasp import Grasp
from ..model.hand import Hand
from ..plants.project.plant import Plant, PlantContact
from ..envelope.planner import PlanResult, plan_scenario
from ..supervisor.policies.scheduled import NoRegraspPolicy, ScheduledPolicy, ScheduledSettings
from ..supervisor.policies.paper import PaperPolicy
from ..dynamics.reduced import ReducedModel
from .result import RolloutResult, RolloutRows
from ..model.scenario import Scenario
from ..schedule.schedule import RegraspSchedule
from ..schedule.planner import RegraspSettings, plan_regrasps
from ..schedule.problem import trajectory_period
from ..plants.simulation import Command, PlantLike, StepRecord, simulate
from .stretch import CompiledStretches
from ..supervisor.supervisor import Measurement, RegraspSupervisor, SupervisorSettings
from ..core.trajectory import RepeatedTrajectory
from ..core.validation import MAX_DURATION, as_duration, as_finite_array, as_integer, as_positive_float, expect_type

if TYPE_CHECKING:
    from ..plants.mujoco.mjcf import MujocoSettings
    from .recording.recorder import RolloutRecorder

__all__ = ["DEFAULT_CONE_MARGIN", "PLANTS", "POLICIES", "Rollout", "RolloutResult", "build_rollout"]

#: The policies :func:`build_rollout` knows by name.
POLICIES = ("scheduled", "paper", "none")

#: The plants :func:`build_rollout` knows by name: the project's (:class:`~regrasp.plants.project.plant.Plant`) and MuJoCo
#: (:class:`~regrasp.plants.mujoco.plant.MujocoPlant`, the ``mujoco`` extra).
PLANTS = ("project", "mujoco")

#: The cone margin [N] rollouts plan with and keep by default: 0.2 N costs no slide over 0.1 N on the
#: three-finger scenario (4 per period) and leaves room for a plant 10 % off the model.
DEFAULT_CONE_MARGIN = 0.2


class _SupervisorDriver:
    """The simulation loop's driver around a supervisor."""

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
    """

    plant: PlantLike
    supervisor: RegraspSupervisor
    duration: float
    names: tuple[str, ...]
    policy: str = "paper"
    schedule: RegraspSchedule | None = None
    scenario: Scenario | None = None
    disturbance: Disturbance | None = None
    #: The last run's compiled stretches (their ``steps`` and ``calls``), or None.
    stretches: CompiledStretches | None = field(default=None, init=False, repr=False)

    def check(self, record: StepRecord) -> Failure | None:
        """The failure a step's events mean, if any (module docstring)."""
        phases = record.supervision.phases
        index = {n: i for i, n in enumerate(self.names)}
        for e in record.events:
            if e.source is EventSource.SUPERVISOR and e.kind is EventKind.LEFT_ENVELOPE:
                return Failure(e.time, FailureKind.LEFT_ENVELOPE, f"{e.contact} left its feasible envelope: {e.detail}",
                               e.contact)
            if e.source is not EventSource.PLANT:
                continue
            if e.kind is EventKind.SLIP and phases[index[e.contact]] not in SLIPPING_PHASES:
                return Failure(e.time, FailureKind.UNPLANNED_SLIP, f"unplanned slip of {e.contact}: {e.detail}",
                               e.contact)
            if e.kind in PLANT_FAILURES and e.kind in self.plant.stop_on:
                return Failure(e.time, PLANT_FAILURES[e.kind], f"{e.kind.value} of {e.contact}: {e.detail}", e.contact)
        return None

    def run(self, *, recorder: RolloutRecorder | None = None, progress: Callable[[int, int], None] | None = None,
            interruptible: bool = True, compiled_stretches: bool = True) -> RolloutResult:
        """Run to ``duration`` or the first failure.

        Args:
            recorder: A :class:`~regrasp.rollout.recording.recorder.RolloutRecorder` for this rollout's plant: each
                step's record is logged (:meth:`~regrasp.rollout.recording.recorder.RolloutRecorder.log_record`);
                the caller closes it. Or None.
            progress: Called as ``progress(done, total)`` every 50 steps and at the end.
            interruptible: Ctrl-C ends the run with an ``INTERRUPTED`` failure (else it propagates).
            compiled_stretches: Run the steps between the supervisor's decisions in compiled stretches
                (:mod:`regrasp.rollout.stretch`; the same steps, faster); False: every step on the reference path.
        """
        plant = self.plant
        total = int(round(self.duration / plant.dt))
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
                                          disturbance=self.disturbance)
        outcome = simulate(plant, _SupervisorDriver(self.supervisor), total, consumers=consumers, check=self.check,
                           progress=progress, interruptible=interruptible, disturbance=self.disturbance,
                           stretches=stretches)
        if stretches is not None:
            stretches.finish()
        self.stretches = stretches
        if recorder is not None and outcome.failure is not None:
            recorder.log_failure(outcome.failure, plant)
        policy = self.supervisor.policy
        return rows.result(
            outcome, duration=self.duration, object_width=plant.polygon.scale, names=self.names,
            regrasps=dict(zip(self.names, self.supervisor.regrasps)), supervisor_events=tuple(self.supervisor.events),
            policy=self.policy, replans=getattr(policy, "replans", 0), schedule=self.schedule,
            rrd=None if recorder is None or recorder.rrd_path is None else str(recorder.rrd_path))


def _mujoco_defaults() -> MujocoSettings:
    from ..plants.mujoco.mjcf import MujocoSettings

    return MujocoSettings()


def _run_scenario(scenario: Scenario, duration: float | None, periods) -> tuple[Scenario, float]:
    """The scenario with its trajectory repeated to cover the run, and the run's duration [s]."""
    traj = scenario.trajectory
    domain = traj.t_end - traj.t_start
    period = trajectory_period(traj)
    if periods is not None:
        if duration is not None:
            raise InvalidParameterError("periods", periods, "either periods or duration, not both")
        if isinstance(periods, bool) or not isinstance(periods, (int, np.integer)) or periods < 1:
            raise InvalidParameterError("periods", periods, "an integer number of periods >= 1")
        if period is None:
            raise InvalidParameterError("periods", periods, f"a periodic trajectory (scenario {scenario.name!r} "
                                        "is not; use duration)")
        duration = float(periods) * period
        if duration > MAX_DURATION:
            raise InvalidParameterError("periods", periods, f"at most {MAX_DURATION:g} s of simulated time "
                                        f"({int(MAX_DURATION // period)} periods of {period:.6g} s)")
    duration = domain if duration is None else as_duration("duration", duration)
    if duration > domain + 1e-9:
        if period is None:
            raise InvalidParameterError("duration", duration, f"at most the trajectory's domain, {domain:.6g} s "
                                        "(it is not periodic, so it cannot be repeated)")
        scenario = replace(scenario, trajectory=RepeatedTrajectory(traj, traj.t_start + duration))
    return scenario, float(duration)


def build_rollout(scenario: Scenario, *, duration: float | None = None, periods: int | None = None,
                  policy: str = "scheduled", settings: SupervisorSettings | None = None,
                  regrasp_settings: RegraspSettings | None = None, schedule: RegraspSchedule | None = None,
                  scheduled_settings: ScheduledSettings = ScheduledSettings(), dt: float = 1e-3,
                  xi0: ArrayLike | None = None, plant_friction: FrictionLike | None = None,
                  plant_mass_scale: float = 1.0, plant_mu_scale: float = 1.0,
                  plant_inertia_scale: float | None = None, plant_link_mass_scale: float = 1.0,
                  plant_mu_kinetic_scale: float = 1.0, plant_xi_offset: ArrayLike | None = None,
                  sensor_noise: SensorNoise = SensorNoise(), actuator_noise: ActuatorNoise = ActuatorNoise(),
                  seed: int | np.random.SeedSequence | None = None, replan: bool = True,
                  plan_progress: Callable[[int, int], None] | None = None, plant: str = "project",
                  mujoco_settings: MujocoSettings | None = None, plan: PlanResult | None = None) -> Rollout:
    """Plant + supervisor for ``scenario``, every contact fixed at the start.

    Args:
        scenario: The scenario (fingers, edges, object, trajectory, gravity, friction).
        duration: Simulated time [s]; default: the trajectory's domain. A periodic trajectory repeats.
        periods: Instead of ``duration``: this many periods of a periodic trajectory.
        policy: ``"scheduled"`` (plan the slides ahead, follow and re-plan them), ``"paper"`` (the
            danger-zone heuristic) or ``"none"`` (never slide).
        settings: Supervisor settings (default :meth:`SupervisorSettings.robust` with the scenario's geometry,
            the schedule's cone margin, ``actuator_noise``'s delay and, on MuJoCo, the tips' radius).
        regrasp_settings: The schedule planner's settings (``"scheduled"``; default :class:`RegraspSettings`
            with a cone margin of ``DEFAULT_CONE_MARGIN`` = 0.2 N).
        schedule: A schedule planned already (``"scheduled"``; default: planned here).
        plan: The scenario's envelope plan (:func:`~regrasp.envelope.planner.plan_scenario`) computed already (a study
            plans it once for all its runs; default: planned here).
        scheduled_settings: :class:`~regrasp.supervisor.policies.scheduled.ScheduledSettings` (re-plan tolerances).
        dt: Control and plant step [s].
        xi0: Initial contact positions [m] (default: the schedule's start, else the planner's ``initial_xi``).
        plant_friction: The plant's friction, anything :class:`~regrasp.plants.project.plant.Plant` takes (default: the
            scenario's, times ``plant_mu_scale``).
        plant_mass_scale: The plant's object mass and inertia are this times the scenario's (the
            controllers keep the scenario's) [-].
        plant_inertia_scale: The plant's object inertia is this times the scenario's instead [-] (None: the
            mass's scale).
        plant_link_mass_scale: The plant's finger links' masses and inertias are this times the URDFs' (the
            controllers keep the URDFs') [-].
        plant_mu_scale: The plant's μ_s and μ_k are this times the scenario's [-].
        plant_mu_kinetic_scale: The plant's μ_k is this times ``plant_mu_scale`` times the scenario's, at most
            the plant's μ_s [-].
        plant_xi_offset: Where the plant's fingertips are placed relative to ``xi0`` [m], (m,): the supervisor
            believes ``xi0`` (a placement or calibration error of the initial grasp); default zeros.
        sensor_noise, actuator_noise: The hand's sensing noise, slip sensor, torque noise and actuation delay
            (:mod:`regrasp.plants.disturbance`); default: none.
        seed: Seeds the noise (required when there is any): an int or a ``numpy.random.SeedSequence``.
        replan: Let the scheduled policy re-plan.
        plan_progress: Passed to :func:`~regrasp.schedule.planner.plan_regrasps` as ``progress``.
        plant: ``"project"`` (:class:`~regrasp.plants.project.plant.Plant`) or ``"mujoco"``
            (:class:`~regrasp.plants.mujoco.plant.MujocoPlant`: sphere tips, soft contacts; the ``mujoco`` extra).
        mujoco_settings: The MuJoCo plant's :class:`~regrasp.plants.mujoco.mjcf.MujocoSettings` (tip radius, contact
            parameters, MuJoCo's step; default ``MujocoSettings()``). Only with ``plant="mujoco"``.

    Raises:
        NoScheduleError: ``"scheduled"`` and no schedule exists (the planner's diagnosis).
        MissingDependencyError: ``plant="mujoco"`` and the ``mujoco`` package is not installed.
    """
    if not isinstance(scenario, Scenario):
        raise InvalidParameterError("scenario", scenario, "a Scenario (regrasp.load_scenario)")
    if policy not in POLICIES:
        raise InvalidParameterError("policy", policy, f"one of {', '.join(POLICIES)}")
    if not isinstance(plant, str) or plant not in PLANTS:
        raise InvalidParameterError("plant", plant, f"one of {', '.join(PLANTS)}")
    if plant == "mujoco":  # (before any planning: a missing extra is a bad input)
        from ..plants.mujoco.mjcf import require_mujoco

        require_mujoco()
    if mujoco_settings is not None:
        from ..plants.mujoco.mjcf import MujocoSettings

        expect_type("mujoco_settings", mujoco_settings, MujocoSettings, "a MujocoSettings (regrasp.plants.mujoco.mjcf)")
        if plant != "mujoco":
            raise InvalidParameterError("mujoco_settings", mujoco_settings, "None unless plant='mujoco'")
    mass_scale = as_positive_float("plant_mass_scale", plant_mass_scale)
    mu_scale = as_positive_float("plant_mu_scale", plant_mu_scale)
    inertia_scale = mass_scale if plant_inertia_scale is None else as_positive_float("plant_inertia_scale",
                                                                                     plant_inertia_scale)
    link_scale = as_positive_float("plant_link_mass_scale", plant_link_mass_scale)
    kinetic_scale = as_positive_float("plant_mu_kinetic_scale", plant_mu_kinetic_scale)
    expect_type("sensor_noise", sensor_noise, SensorNoise, "a SensorNoise (regrasp.plants.disturbance)")
    expect_type("actuator_noise", actuator_noise, ActuatorNoise, "an ActuatorNoise (regrasp.plants.disturbance)")
    if seed is not None and not isinstance(seed, np.random.SeedSequence):
        seed = as_integer("seed", seed)
    regrasp_settings = RegraspSettings(cone_margin=DEFAULT_CONE_MARGIN) if regrasp_settings is None \
        else expect_type("regrasp_settings", regrasp_settings, RegraspSettings, "a RegraspSettings")
    if schedule is not None:
        expect_type("schedule", schedule, RegraspSchedule, "a RegraspSchedule (regrasp.plan_regrasps)")
    expect_type("scheduled_settings", scheduled_settings, ScheduledSettings, "a ScheduledSettings")
    if settings is None:  # the supervisor's runtime envelopes use the scenario's planner geometry; the laws know
        # the MuJoCo plant's sphere tips and the hand's actuation delay (a latency is measured, unlike a friction)
        # and its sensors' noise: a held contact's model position moves when its filtered reading moved by
        # half the noise's standard deviation, not at every step
        tips = {} if plant != "mujoco" else {"tip_radius": (mujoco_settings or _mujoco_defaults()).tip_radius}
        hold = {} if sensor_noise.xi == 0.0 else {"hold_resolution": max(ExecutorSettings.hold_resolution,
                                                                          0.5 * sensor_noise.xi)}
        settings = SupervisorSettings.robust(scenario.geometry.value, regrasp_settings.cone_margin,
                                             actuation_delay=actuator_noise.delay, **tips, **hold)
    scenario.check_geometry(expect_type("settings", settings, SupervisorSettings, "a SupervisorSettings").geometry)
    run_scenario, duration = _run_scenario(scenario, duration, periods)
    traj = run_scenario.trajectory
    m = len(scenario.contacts)
    if plan is None:
        plan = plan_scenario(scenario)
    elif not isinstance(plan, PlanResult) or len(plan.fingers) != m:
        raise InvalidParameterError("plan", plan, f"a PlanResult of this scenario ({m} fingers)")
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
    edges = [c.edge for c in scenario.contacts]
    friction = scenario.friction
    names = tuple(f.name for f in hand.fingers)
    t_run_end = traj.t_start + duration
    if policy == "scheduled":
        def replanner(t: float, xi: np.ndarray) -> RegraspSchedule:
            return plan_regrasps(run_scenario, replace(regrasp_settings, periodic=False), start_time=t, xi0=xi,
                                 t_end=min(t_run_end, t + max(1.0, 2.0 * (trajectory_period(traj) or 0.0))))
        chosen = ScheduledPolicy(schedule, names, replan=replanner if replan else None, settings=scheduled_settings)
    elif policy == "none":
        chosen = NoRegraspPolicy(m)
    else:
        chosen = lambda context: PaperPolicy(context, settings)  # noqa: E731
    supervisor = RegraspSupervisor(hand, scenario.polygon, edges, traj, xi0, friction,
                                   tip_clearance=[c.tip_clearance for c in scenario.contacts], plan=plan,
                                   settings=settings, policy=chosen)
    X0, V0 = traj.pose(traj.t_start), traj.velocity(traj.t_start)
    xi_plant = xi0 if plant_xi_offset is None else xi0 + as_finite_array("plant_xi_offset", plant_xi_offset, (m,))
    st_plant = ReducedModel(hand, Grasp(scenario.polygon, edges, [ContactMode.FIXED] * m), xi_plant).state(X0, V0)
    if plant_friction is None:
        plant_friction = tuple(Friction(f.static * mu_scale, min(f.static, f.kinetic * kinetic_scale) * mu_scale)
                               for f in friction)
    plant_hand = hand if link_scale == 1.0 else Hand(list(hand.fingers), gravity_in_hand=scenario.gravity_in_hand,
                                                      link_mass_scale=link_scale)
    contacts = [PlantContact(e, ContactMode.FIXED, x) for e, x in zip(edges, xi_plant)]
    physics = dict(friction=plant_friction, object_mass=scenario.polygon.mass * mass_scale,
                   object_inertia=scenario.polygon.inertia * inertia_scale, dt=dt)
    if plant == "mujoco":
        from ..plants.mujoco.plant import MujocoPlant

        built: PlantLike = MujocoPlant(plant_hand, scenario.polygon, contacts, **physics,
                                       settings=_mujoco_defaults() if mujoco_settings is None else mujoco_settings,
                                       tip_clearance=[c.tip_clearance for c in scenario.contacts])
    else:
        built = Plant(plant_hand, scenario.polygon, contacts, **physics)
    built.reset(st_plant.q, st_plant.q_dot, X0, V0, t=traj.t_start)
    disturbance = None
    if not (sensor_noise.ideal and actuator_noise.ideal):
        rng = None if seed is None else np.random.default_rng(seed)
        disturbance = Disturbance(sensor_noise, actuator_noise, rng)
    return Rollout(built, supervisor, duration, names, policy, schedule, run_scenario, disturbance)


"""regrasp: planar multifingered hands that plan feasible contacts, control sliding
fingertips and regrasp dynamically (after "Dynamic regrasping by sliding").

The names below load on first use (PEP 562): ``import regrasp`` and the command line's ``--help``
do not import Pinocchio, coal, scipy or rerun until something needs them.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

__version__ = "0.1.0"

#: Where each public name lives.
_SOURCES = {
    "ClosedLoopLog": "plants.closed_loop",
    "measure_reduced_state": "plants.closed_loop",
    "run_closed_loop": "plants.closed_loop",
    "UrdfCollisionChecker": "model.collision",
    "default_tip_clearance": "model.collision",
    "segment_hits_polygon": "model.collision",
    "ContactMode": "core.contact",
    "Friction": "core.contact",
    "cone_margin": "core.contact",
    "ComputedTorqueController": "dynamics.control",
    "ControlOutput": "dynamics.control",
    "FixedContactController": "dynamics.control",
    "Gains": "dynamics.control",
    "Proposition1Controller": "dynamics.control",
    "Proposition2Controller": "dynamics.control",
    "Proposition3Controller": "dynamics.control",
    "ActuatorNoise": "plants.disturbance",
    "Disturbance": "plants.disturbance",
    "SensorNoise": "plants.disturbance",
    "Condition": "envelope.finger_envelope",
    "EdgeLine": "envelope.finger_envelope",
    "EnvelopeSample": "envelope.finger_envelope",
    "FingerEnvelope": "envelope.finger_envelope",
    "Geometry": "envelope.finger_envelope",
    "condition_of": "envelope.finger_envelope",
    "reachable_on_line": "envelope.finger_envelope",
    "Event": "core.events",
    "EventKind": "core.events",
    "Failure": "core.events",
    "FailureKind": "core.events",
    "FingerModelError": "core.exceptions",
    "InvalidParameterError": "core.exceptions",
    "MissingDependencyError": "core.exceptions",
    "PolygonError": "core.exceptions",
    "RegraspError": "core.exceptions",
    "ScenarioError": "core.exceptions",
    "SingularFingerError": "core.exceptions",
    "SlidingContactCountError": "core.exceptions",
    "TrajectoryError": "core.exceptions",
    "UnknownEdgeError": "core.exceptions",
    "UnreachableError": "core.exceptions",
    "SlideOrder": "supervisor.executor",
    "Configuration": "model.finger",
    "Finger": "model.finger",
    "LinkShape": "model.finger",
    "planar_2r_urdf": "model.finger_urdf",
    "Grasp": "dynamics.grasp",
    "Hand": "model.hand",
    "HandDynamics": "model.hand",
    "ConeEdge": "dynamics.internal_force.solver",
    "InternalForceInfeasibleError": "dynamics.internal_force.solver",
    "InternalForceQP": "dynamics.internal_force.solver",
    "InternalForceResult": "dynamics.internal_force.solver",
    "InternalForceSettings": "dynamics.internal_force.solver",
    "InternalForceSolver": "dynamics.internal_force.solver",
    "build_internal_force_qp": "dynamics.internal_force.solver",
    "solve_internal_force_qp": "dynamics.internal_force.solver",
    "MujocoSettings": "plants.mujoco.mjcf",
    "scenario_to_mjcf": "plants.mujoco.mjcf",
    "MujocoPlant": "plants.mujoco.plant",
    "Perturbation": "model.perturbation",
    "FingerPlan": "envelope.planner",
    "InfeasibleInterval": "envelope.planner",
    "PlanResult": "envelope.planner",
    "plan": "envelope.planner",
    "plan_scenario": "envelope.planner",
    "Plant": "plants.project.plant",
    "PlantContact": "plants.project.plant",
    "PlantEvent": "plants.project.plant",
    "PlantState": "plants.project.plant",
    "PlantStep": "plants.project.plant",
    "NoRegraspPolicy": "supervisor.policies.scheduled",
    "OrderedSlidesPolicy": "supervisor.policies.scheduled",
    "ScheduledPolicy": "supervisor.policies.scheduled",
    "ScheduledSettings": "supervisor.policies.scheduled",
    "PaperPolicy": "supervisor.policies.paper",
    "ConvexPolygon": "core.polygon",
    "Edge": "core.polygon",
    "RolloutRecorder": "rollout.recording.recorder",
    "ReducedModel": "dynamics.reduced",
    "ReducedState": "dynamics.reduced",
    "Rollout": "rollout.build",
    "RolloutResult": "rollout.build",
    "build_rollout": "rollout.build",
    "FingerContact": "model.scenario",
    "Scenario": "model.scenario",
    "load_scenario": "model.scenario",
    "NoScheduleError": "schedule.schedule",
    "RegraspSchedule": "schedule.schedule",
    "ScheduleLimit": "schedule.schedule",
    "Slide": "schedule.schedule",
    "RegraspSettings": "schedule.planner",
    "plan_regrasps": "schedule.planner",
    "StepRecord": "plants.simulation",
    "PlantLike": "plants.simulation",
    "simulate": "plants.simulation",
    "SlideFeasibility": "dynamics.sliding",
    "StudyResult": "study.study",
    "run_study": "study.study",
    "sliding_feasibility": "dynamics.sliding",
    "ContactPhase": "supervisor.supervisor",
    "Measurement": "supervisor.supervisor",
    "RegraspSupervisor": "supervisor.supervisor",
    "SupervisorOutput": "supervisor.supervisor",
    "SupervisorSettings": "supervisor.supervisor",
    "EllipseTrajectory": "core.trajectory",
    "Trajectory": "core.trajectory",
    "TrajectorySample": "core.trajectory",
    "WaypointTrajectory": "core.trajectory",
}

__all__ = [
    "ActuatorNoise",
    "ClosedLoopLog",
    "ComputedTorqueController",
    "Condition",
    "ConeEdge",
    "Configuration",
    "ContactMode",
    "ContactPhase",
    "ControlOutput",
    "ConvexPolygon",
    "Disturbance",
    "Edge",
    "EdgeLine",
    "EllipseTrajectory",
    "EnvelopeSample",
    "Event",
    "EventKind",
    "Failure",
    "FailureKind",
    "Finger",
    "FingerContact",
    "FingerEnvelope",
    "FingerModelError",
    "FingerPlan",
    "FixedContactController",
    "Friction",
    "Gains",
    "Geometry",
    "Grasp",
    "Hand",
    "HandDynamics",
    "InfeasibleInterval",
    "InternalForceInfeasibleError",
    "InternalForceQP",
    "InternalForceResult",
    "InternalForceSettings",
    "InternalForceSolver",
    "InvalidParameterError",
    "LinkShape",
    "Measurement",
    "MissingDependencyError",
    "MujocoPlant",
    "MujocoSettings",
    "NoRegraspPolicy",
    "NoScheduleError",
    "OrderedSlidesPolicy",
    "PaperPolicy",
    "Perturbation",
    "PlanResult",
    "Plant",
    "PlantContact",
    "PlantEvent",
    "PlantLike",
    "PlantState",
    "PlantStep",
    "PolygonError",
    "Proposition1Controller",
    "Proposition2Controller",
    "Proposition3Controller",
    "ReducedModel",
    "ReducedState",
    "RegraspError",
    "RegraspSchedule",
    "RegraspSettings",
    "RegraspSupervisor",
    "Rollout",
    "RolloutRecorder",
    "RolloutResult",
    "Scenario",
    "ScenarioError",
    "ScheduleLimit",
    "ScheduledPolicy",
    "ScheduledSettings",
    "SensorNoise",
    "SingularFingerError",
    "Slide",
    "SlideFeasibility",
    "SlideOrder",
    "SlidingContactCountError",
    "StepRecord",
    "StudyResult",
    "SupervisorOutput",
    "SupervisorSettings",
    "Trajectory",
    "TrajectoryError",
    "TrajectorySample",
    "UnknownEdgeError",
    "UnreachableError",
    "UrdfCollisionChecker",
    "WaypointTrajectory",
    "build_internal_force_qp",
    "build_rollout",
    "condition_of",
    "cone_margin",
    "default_tip_clearance",
    "load_scenario",
    "measure_reduced_state",
    "plan",
    "plan_regrasps",
    "plan_scenario",
    "planar_2r_urdf",
    "reachable_on_line",
    "run_closed_loop",
    "run_study",
    "scenario_to_mjcf",
    "segment_hits_polygon",
    "simulate",
    "sliding_feasibility",
    "solve_internal_force_qp",
]


def __getattr__(name: str):
    module = _SOURCES.get(name)
    if module is None:
        raise AttributeError(f"module 'regrasp' has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value  # the next lookup is a plain attribute
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


if TYPE_CHECKING:  # for type checkers and IDEs: the same names, imported eagerly
    from .plants.closed_loop import ClosedLoopLog, measure_reduced_state, run_closed_loop  # noqa: F401
    from .model.collision import UrdfCollisionChecker, default_tip_clearance, segment_hits_polygon  # noqa: F401
    from .core.contact import ContactMode, Friction, cone_margin  # noqa: F401
    from .dynamics.control import (  # noqa: F401
        ComputedTorqueController,
        ControlOutput,
        FixedContactController,
        Gains,
        Proposition1Controller,
        Proposition2Controller,
        Proposition3Controller,
    )
    from .plants.disturbance import ActuatorNoise, Disturbance, SensorNoise  # noqa: F401
    from .envelope.finger_envelope import (  # noqa: F401
        Condition,
        EdgeLine,
        EnvelopeSample,
        FingerEnvelope,
        Geometry,
        condition_of,
        reachable_on_line,
    )
    from .core.events import Event, EventKind, Failure, FailureKind  # noqa: F401
    from .core.exceptions import (  # noqa: F401
        FingerModelError,
        InvalidParameterError,
        MissingDependencyError,
        PolygonError,
        RegraspError,
        ScenarioError,
        SingularFingerError,
        SlidingContactCountError,
        TrajectoryError,
        UnknownEdgeError,
        UnreachableError,
    )
    from .supervisor.executor import SlideOrder  # noqa: F401
    from .model.finger import Configuration, Finger, LinkShape  # noqa: F401
    from .model.finger_urdf import planar_2r_urdf  # noqa: F401
    from .dynamics.grasp import Grasp  # noqa: F401
    from .model.hand import Hand, HandDynamics  # noqa: F401
    from .dynamics.internal_force.solver import (  # noqa: F401
        ConeEdge,
        InternalForceInfeasibleError,
        InternalForceQP,
        InternalForceResult,
        InternalForceSettings,
        InternalForceSolver,
        build_internal_force_qp,
        solve_internal_force_qp,
    )
    from .plants.mujoco.mjcf import MujocoSettings, scenario_to_mjcf  # noqa: F401
    from .plants.mujoco.plant import MujocoPlant  # noqa: F401
    from .model.perturbation import Perturbation  # noqa: F401
    from .envelope.planner import FingerPlan, InfeasibleInterval, PlanResult, plan, plan_scenario  # noqa: F401
    from .plants.project.plant import Plant, PlantContact, PlantEvent, PlantState, PlantStep  # noqa: F401
    from .supervisor.policies.scheduled import NoRegraspPolicy, OrderedSlidesPolicy, ScheduledPolicy, ScheduledSettings  # noqa: F401
    from .supervisor.policies.paper import PaperPolicy  # noqa: F401
    from .core.polygon import ConvexPolygon, Edge  # noqa: F401
    from .rollout.recording.recorder import RolloutRecorder  # noqa: F401
    from .dynamics.reduced import ReducedModel, ReducedState  # noqa: F401
    from .rollout.build import Rollout, RolloutResult, build_rollout  # noqa: F401
    from .model.scenario import FingerContact, Scenario, load_scenario  # noqa: F401
    from .schedule.schedule import NoScheduleError, RegraspSchedule, ScheduleLimit, Slide  # noqa: F401
    from .schedule.planner import RegraspSettings, plan_regrasps  # noqa: F401
    from .plants.simulation import PlantLike, StepRecord, simulate  # noqa: F401
    from .dynamics.sliding import SlideFeasibility, sliding_feasibility  # noqa: F401
    from .study.study import StudyResult, run_study  # noqa: F401
    from .supervisor.supervisor import (  # noqa: F401
        ContactPhase,
        Measurement,
        RegraspSupervisor,
        SupervisorOutput,
        SupervisorSettings,
    )
    from .core.trajectory import EllipseTrajectory, Trajectory, TrajectorySample, WaypointTrajectory  # noqa: F401

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
    "ClosedLoopLog": "closed_loop",
    "measure_reduced_state": "closed_loop",
    "run_closed_loop": "closed_loop",
    "UrdfCollisionChecker": "collision",
    "default_tip_clearance": "collision",
    "segment_hits_polygon": "collision",
    "ContactMode": "contact",
    "Friction": "contact",
    "cone_margin": "contact",
    "ComputedTorqueController": "control",
    "ControlOutput": "control",
    "FixedContactController": "control",
    "Gains": "control",
    "Proposition1Controller": "control",
    "Proposition2Controller": "control",
    "Proposition3Controller": "control",
    "ActuatorNoise": "disturbance",
    "Disturbance": "disturbance",
    "SensorNoise": "disturbance",
    "Condition": "envelope",
    "EdgeLine": "envelope",
    "EnvelopeSample": "envelope",
    "FingerEnvelope": "envelope",
    "Geometry": "envelope",
    "condition_of": "envelope",
    "reachable_on_line": "envelope",
    "Event": "events",
    "EventKind": "events",
    "Failure": "events",
    "FailureKind": "events",
    "FingerModelError": "exceptions",
    "InvalidParameterError": "exceptions",
    "MissingDependencyError": "exceptions",
    "PolygonError": "exceptions",
    "RegraspError": "exceptions",
    "ScenarioError": "exceptions",
    "SingularFingerError": "exceptions",
    "SlidingContactCountError": "exceptions",
    "TrajectoryError": "exceptions",
    "UnknownEdgeError": "exceptions",
    "UnreachableError": "exceptions",
    "SlideOrder": "executor",
    "Configuration": "finger",
    "Finger": "finger",
    "LinkShape": "finger",
    "planar_2r_urdf": "finger_urdf",
    "Grasp": "grasp",
    "Hand": "hand",
    "HandDynamics": "hand",
    "ConeEdge": "internal_force",
    "InternalForceInfeasibleError": "internal_force",
    "InternalForceQP": "internal_force",
    "InternalForceResult": "internal_force",
    "InternalForceSettings": "internal_force",
    "InternalForceSolver": "internal_force",
    "build_internal_force_qp": "internal_force",
    "solve_internal_force_qp": "internal_force",
    "MujocoSettings": "mjcf",
    "scenario_to_mjcf": "mjcf",
    "MujocoPlant": "mujoco_plant",
    "Perturbation": "perturbation",
    "FingerPlan": "planner",
    "InfeasibleInterval": "planner",
    "PlanResult": "planner",
    "plan": "planner",
    "plan_scenario": "planner",
    "Plant": "plant",
    "PlantContact": "plant",
    "PlantEvent": "plant",
    "PlantState": "plant",
    "PlantStep": "plant",
    "NoRegraspPolicy": "policies",
    "OrderedSlidesPolicy": "policies",
    "ScheduledPolicy": "policies",
    "ScheduledSettings": "policies",
    "PaperPolicy": "policy_paper",
    "ConvexPolygon": "polygon",
    "Edge": "polygon",
    "RolloutRecorder": "recording",
    "ReducedModel": "reduced",
    "ReducedState": "reduced",
    "Rollout": "rollout",
    "RolloutResult": "rollout",
    "build_rollout": "rollout",
    "FingerContact": "scenario",
    "Scenario": "scenario",
    "load_scenario": "scenario",
    "NoScheduleError": "schedule",
    "RegraspSchedule": "schedule",
    "ScheduleLimit": "schedule",
    "Slide": "schedule",
    "RegraspSettings": "schedule_planner",
    "plan_regrasps": "schedule_planner",
    "StepRecord": "simulation",
    "PlantLike": "simulation",
    "simulate": "simulation",
    "SlideFeasibility": "sliding",
    "StudyResult": "study",
    "run_study": "study",
    "sliding_feasibility": "sliding",
    "ContactPhase": "supervisor",
    "Measurement": "supervisor",
    "RegraspSupervisor": "supervisor",
    "SupervisorOutput": "supervisor",
    "SupervisorSettings": "supervisor",
    "EllipseTrajectory": "trajectory",
    "Trajectory": "trajectory",
    "TrajectorySample": "trajectory",
    "WaypointTrajectory": "trajectory",
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
    from .closed_loop import ClosedLoopLog, measure_reduced_state, run_closed_loop  # noqa: F401
    from .collision import UrdfCollisionChecker, default_tip_clearance, segment_hits_polygon  # noqa: F401
    from .contact import ContactMode, Friction, cone_margin  # noqa: F401
    from .control import (  # noqa: F401
        ComputedTorqueController,
        ControlOutput,
        FixedContactController,
        Gains,
        Proposition1Controller,
        Proposition2Controller,
        Proposition3Controller,
    )
    from .disturbance import ActuatorNoise, Disturbance, SensorNoise  # noqa: F401
    from .envelope import (  # noqa: F401
        Condition,
        EdgeLine,
        EnvelopeSample,
        FingerEnvelope,
        Geometry,
        condition_of,
        reachable_on_line,
    )
    from .events import Event, EventKind, Failure, FailureKind  # noqa: F401
    from .exceptions import (  # noqa: F401
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
    from .executor import SlideOrder  # noqa: F401
    from .finger import Configuration, Finger, LinkShape  # noqa: F401
    from .finger_urdf import planar_2r_urdf  # noqa: F401
    from .grasp import Grasp  # noqa: F401
    from .hand import Hand, HandDynamics  # noqa: F401
    from .internal_force import (  # noqa: F401
        ConeEdge,
        InternalForceInfeasibleError,
        InternalForceQP,
        InternalForceResult,
        InternalForceSettings,
        InternalForceSolver,
        build_internal_force_qp,
        solve_internal_force_qp,
    )
    from .mjcf import MujocoSettings, scenario_to_mjcf  # noqa: F401
    from .mujoco_plant import MujocoPlant  # noqa: F401
    from .perturbation import Perturbation  # noqa: F401
    from .planner import FingerPlan, InfeasibleInterval, PlanResult, plan, plan_scenario  # noqa: F401
    from .plant import Plant, PlantContact, PlantEvent, PlantState, PlantStep  # noqa: F401
    from .policies import NoRegraspPolicy, OrderedSlidesPolicy, ScheduledPolicy, ScheduledSettings  # noqa: F401
    from .policy_paper import PaperPolicy  # noqa: F401
    from .polygon import ConvexPolygon, Edge  # noqa: F401
    from .recording import RolloutRecorder  # noqa: F401
    from .reduced import ReducedModel, ReducedState  # noqa: F401
    from .rollout import Rollout, RolloutResult, build_rollout  # noqa: F401
    from .scenario import FingerContact, Scenario, load_scenario  # noqa: F401
    from .schedule import NoScheduleError, RegraspSchedule, ScheduleLimit, Slide  # noqa: F401
    from .schedule_planner import RegraspSettings, plan_regrasps  # noqa: F401
    from .simulation import PlantLike, StepRecord, simulate  # noqa: F401
    from .sliding import SlideFeasibility, sliding_feasibility  # noqa: F401
    from .study import StudyResult, run_study  # noqa: F401
    from .supervisor import (  # noqa: F401
        ContactPhase,
        Measurement,
        RegraspSupervisor,
        SupervisorOutput,
        SupervisorSettings,
    )
    from .trajectory import EllipseTrajectory, Trajectory, TrajectorySample, WaypointTrajectory  # noqa: F401

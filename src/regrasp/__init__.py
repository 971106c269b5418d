"""regrasp: planar multifingered hands that plan feasible contacts, control sliding
fingertips and regrasp dynamically (after "Dynamic regrasping by sliding")."""

from .closed_loop import ClosedLoopLog, measure_reduced_state, run_closed_loop
from .collision import UrdfCollisionChecker, default_tip_clearance, segment_hits_polygon
from .contact import ContactMode, Friction, cone_margin
from .control import (
    ComputedTorqueController,
    ControlOutput,
    FixedContactController,
    Gains,
    Proposition1Controller,
    Proposition2Controller,
    Proposition3Controller,
)
from .envelope import (
    Condition,
    EdgeLine,
    EnvelopeSample,
    FingerEnvelope,
    Geometry,
    condition_of,
    reachable_on_line,
)
from .events import Event, EventKind, Failure, FailureKind
from .exceptions import (
    FingerModelError,
    InvalidParameterError,
    PolygonError,
    RegraspError,
    ScenarioError,
    SingularFingerError,
    SlidingContactCountError,
    TrajectoryError,
    UnknownEdgeError,
    UnreachableError,
)
from .executor import SlideOrder
from .finger import Configuration, Finger, LinkShape
from .finger_urdf import planar_2r_urdf
from .grasp import Grasp
from .hand import Hand, HandDynamics
from .planner import FingerPlan, InfeasibleInterval, PlanResult, plan, plan_scenario
from .internal_force import (
    ConeEdge,
    InternalForceInfeasibleError,
    InternalForceQP,
    InternalForceResult,
    InternalForceSettings,
    InternalForceSolver,
    build_internal_force_qp,
    solve_internal_force_qp,
)
from .plant import Plant, PlantContact, PlantEvent, PlantState, PlantStep
from .polygon import ConvexPolygon, Edge
from .recording import RolloutRecorder
from .reduced import ReducedModel, ReducedState
from .policies import NoRegraspPolicy, ScheduledPolicy, ScheduledSettings
from .policy_paper import PaperPolicy
from .rollout import Rollout, RolloutResult, build_rollout
from .scenario import FingerContact, Scenario, load_scenario
from .schedule import NoScheduleError, RegraspSchedule, ScheduleLimit, Slide
from .schedule_planner import RegraspSettings, plan_regrasps
from .sliding import SlideFeasibility, sliding_feasibility
from .simulation import StepRecord, simulate
from .supervisor import (
    ContactPhase,
    Measurement,
    RegraspSupervisor,
    SupervisorOutput,
    SupervisorSettings,
)
from .trajectory import EllipseTrajectory, Trajectory, TrajectorySample, WaypointTrajectory

__version__ = "0.1.0"

__all__ = [
    "ClosedLoopLog",
    "ComputedTorqueController",
    "Condition",
    "ConeEdge",
    "Configuration",
    "ContactMode",
    "ContactPhase",
    "ControlOutput",
    "ConvexPolygon",
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
    "NoRegraspPolicy",
    "NoScheduleError",
    "PaperPolicy",
    "PlanResult",
    "Plant",
    "PlantContact",
    "PlantEvent",
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
    "SingularFingerError",
    "Slide",
    "SlideFeasibility",
    "SlideOrder",
    "SlidingContactCountError",
    "StepRecord",
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
    "segment_hits_polygon",
    "simulate",
    "sliding_feasibility",
    "solve_internal_force_qp",
]

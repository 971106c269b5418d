"""regrasp: planar multifingered hands that plan feasible contacts, control sliding
fingertips and regrasp dynamically (after "Dynamic regrasping by sliding")."""

from .collision import UrdfCollisionChecker, default_tip_clearance, segment_hits_polygon
from .envelope import (
    Condition,
    EdgeLine,
    EnvelopeSample,
    FingerEnvelope,
    Geometry,
    condition_of,
    reachable_on_line,
)
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
from .finger import Configuration, Finger, LinkShape
from .finger_urdf import planar_2r_urdf
from .grasp import ContactMode, Grasp
from .hand import Hand, HandDynamics
from .planner import FingerPlan, InfeasibleInterval, PlanResult, plan, plan_scenario
from .plant import Plant, PlantContact, PlantEvent, PlantState, PlantStep
from .polygon import ConvexPolygon, Edge
from .reduced import ReducedModel, ReducedState
from .scenario import FingerContact, Scenario, load_scenario
from .trajectory import EllipseTrajectory, Trajectory, TrajectorySample, WaypointTrajectory

__version__ = "0.1.0"

__all__ = [
    "Condition",
    "Configuration",
    "ContactMode",
    "ConvexPolygon",
    "Edge",
    "EdgeLine",
    "EllipseTrajectory",
    "EnvelopeSample",
    "Finger",
    "FingerContact",
    "FingerEnvelope",
    "FingerModelError",
    "FingerPlan",
    "Geometry",
    "Grasp",
    "Hand",
    "HandDynamics",
    "InfeasibleInterval",
    "InvalidParameterError",
    "LinkShape",
    "PlanResult",
    "Plant",
    "PlantContact",
    "PlantEvent",
    "PlantState",
    "PlantStep",
    "PolygonError",
    "ReducedModel",
    "ReducedState",
    "RegraspError",
    "Scenario",
    "ScenarioError",
    "SingularFingerError",
    "SlidingContactCountError",
    "Trajectory",
    "TrajectoryError",
    "TrajectorySample",
    "UnknownEdgeError",
    "UnreachableError",
    "UrdfCollisionChecker",
    "WaypointTrajectory",
    "condition_of",
    "default_tip_clearance",
    "load_scenario",
    "plan",
    "plan_scenario",
    "planar_2r_urdf",
    "reachable_on_line",
    "segment_hits_polygon",
]

"""regrasp: planar multifingered hands that plan feasible contacts, control sliding fingertips and regrasp
dynamically (after "Dynamic regrasping by sliding").

The package is laid out by concern, after the paper's sections:

* :mod:`regrasp.core`: the shared value types (contact mode, friction, polygon, trajectory, events, errors);
* :mod:`regrasp.model`: fingers from URDF, the hand, collision geometry, scenarios, a real hand's noise;
* :mod:`regrasp.envelope` (§2): where a fingertip may touch, and the planner over a trajectory;
* :mod:`regrasp.dynamics` (§3): grasp matrices, the reduced model, the control laws, the internal-force QP;
* :mod:`regrasp.plants`: the project's plant, MuJoCo, Drake, the simulation loop;
* :mod:`regrasp.schedule` (§4, planned): the slides of every contact, planned jointly;
* :mod:`regrasp.supervisor` (§4, at run time): monitor, policies, executor, and their settings;
* :mod:`regrasp.rollout`, :mod:`regrasp.study`: one run, recorded; many runs under model errors and noise;
* :mod:`regrasp.kernels`: the compiled fast paths, each checked against its reference.

This module holds the names a user builds and the functions a user calls; each subpackage exports its own. They
load on first use (PEP 562): ``import regrasp`` and the command line's ``--help`` load neither Pinocchio, coal,
scipy, rerun nor numba.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .core.lazy import lazy_exports

__version__ = "0.1.0"

if TYPE_CHECKING:
    from .core.contact import ContactMode, Friction  # noqa: F401
    from .core.curves import Disc, Ellipse, RoundedPolygon, SupportCurve  # noqa: F401
    from .core.events import EventKind, FailureKind  # noqa: F401
    from .core.exceptions import InvalidParameterError, RegraspError, ScenarioError  # noqa: F401
    from .core.polygon import ConvexPolygon  # noqa: F401
    from .core.trajectory import EllipseTrajectory, WaypointTrajectory  # noqa: F401
    from .dynamics.grasp import Grasp  # noqa: F401
    from .dynamics.internal_force.settings import InternalForceSettings  # noqa: F401
    from .dynamics.reduced import ReducedModel  # noqa: F401
    from .envelope.finger_envelope import FingerEnvelope  # noqa: F401
    from .envelope.planner import plan, plan_scenario  # noqa: F401
    from .model.finger import Finger  # noqa: F401
    from .model.finger_urdf import planar_2r_urdf  # noqa: F401
    from .model.geometry import Geometry
    from .model.hand import Hand  # noqa: F401
    from .model.noise import ActuatorNoise, SensorNoise  # noqa: F401
    from .model.perturbation import Perturbation  # noqa: F401
    from .model.scenario import FingerContact, Scenario, load_scenario  # noqa: F401
    from .plants.mujoco.mjcf import MujocoSettings  # noqa: F401
    from .plants.project.plant import Plant
    from .plants.project.state import PlantContact
    from .plants.spec import ModelErrors, PlantSpec  # noqa: F401
    from .rollout.build import build_rollout  # noqa: F401
    from .rollout.recording.recorder import RolloutRecorder  # noqa: F401
    from .rollout.spec import RunSpec  # noqa: F401
    from .schedule.planner import plan_regrasps  # noqa: F401
    from .schedule.problem import RegraspSettings  # noqa: F401
    from .schedule.schedule import NoScheduleError  # noqa: F401
    from .study.study import run_study  # noqa: F401
    from .supervisor.settings import SupervisorSettings  # noqa: F401
    from .supervisor.supervisor import RegraspSupervisor  # noqa: F401

__getattr__, __dir__, __all__ = lazy_exports(__name__)

"""``regrasp.model``: The hand and its task as described: fingers loaded from URDF through Pinocchio, the hand's
dynamics, the links' collision geometry, spherical fingertips, scenario files, and what a real hand adds (sensing and
actuation noise; the perturbations a study draws)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..core.lazy import lazy_exports

if TYPE_CHECKING:
    from .collision import UrdfCollisionChecker, default_tip_clearance, segment_hits_polygon
    from .finger import Configuration, Finger, LinkShape  # noqa: F401
    from .finger_urdf import planar_2r_urdf  # noqa: F401
    from .geometry import Geometry
    from .hand import Hand, HandDynamics, KernelMismatchWarning  # noqa: F401
    from .noise import ActuatorNoise, SensorNoise  # noqa: F401
    from .perturbation import Perturbation  # noqa: F401
    from .scenario import FingerContact, Scenario, load_scenario  # noqa: F401
    from .sphere_tip import sphere_tip_torque  # noqa: F401

__getattr__, __dir__, __all__ = lazy_exports(__name__)

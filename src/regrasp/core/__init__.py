"""``regrasp.core``: Value types and arithmetic every concern shares: the contact's mode, friction and cone margin, the
object (a convex polygon, or a curved object: :mod:`regrasp.core.curves`), its trajectory, what a hand senses
(:class:`Measurement`), events and failures, the typed errors and the one validation layer."""

from __future__ import annotations

from typing import TYPE_CHECKING

from .lazy import lazy_exports

if TYPE_CHECKING:
    from .contact import DEFAULT_CONE_MARGIN, DEFAULT_FRICTION, ContactMode, Friction, FrictionLike, cone_margin  # noqa: F401
    from .curves import CurvedObject, Disc, Ellipse, RoundedPolygon, SupportCurve, rounded  # noqa: F401
    from .events import Event, EventKind, EventSource, Failure, FailureKind  # noqa: F401
    from .exceptions import (  # noqa: F401
        CurveError,
        FingerModelError,
        InvalidParameterError,
        MissingDependencyError,
        PlantStateError,
        PolygonError,
        RegraspError,
        ScenarioError,
        SingularFingerError,
        SingularModelError,
        SlidingContactCountError,
        TrajectoryError,
        UnknownEdgeError,
        UnreachableError,
    )
    from .measurement import Measurement  # noqa: F401
    from .pad import Pad  # noqa: F401
    from .polygon import ConvexPolygon, Edge  # noqa: F401
    from .trajectory import EllipseTrajectory, Trajectory, TrajectorySample, WaypointTrajectory  # noqa: F401

__getattr__, __dir__, __all__ = lazy_exports(__name__)

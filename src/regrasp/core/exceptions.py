"""Typed errors raised by regrasp.

Every error the library raises on purpose derives from :class:`RegraspError`;
subclasses carry the diagnostics a caller needs to fix the input (the file, the
key, the joint, the offending value) as attributes, not only in the message.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path, PurePath
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from numpy.typing import ArrayLike


class RegraspError(Exception):
    """Base class of every error raised by regrasp."""


class InvalidParameterError(RegraspError, ValueError):
    """A numeric argument is out of its domain (negative length, non-finite value...).

    Attributes:
        name: Name of the parameter.
        value: The rejected value (the message shows at most 80 characters of its repr, on one line).
        expected: What was expected.
    """

    def __init__(self, name: str, value: Any, expected: str):
        self.name = name
        self.value = value
        self.expected = expected
        super().__init__(f"invalid {name} = {short_repr(value)}: expected {expected}")


def short_repr(value: Any, limit: int = 80) -> str:
    """``repr(value)`` on one line, cut to ``limit`` characters (a 400-digit integer or a large array stays
    readable in a one-line error); a string or a path is cut only past 4096 characters (PATH_MAX: the user needs
    to see which file)."""
    if isinstance(value, (str, PurePath)):
        limit = max(limit, 4096)
    try:
        text = " ".join(repr(value).split())
    except Exception:  # noqa: BLE001 (a broken __repr__ must not hide the real error)
        text = f"<{type(value).__name__}>"
    return text if len(text) <= limit else text[:limit - 3] + "..."


class FingerModelError(RegraspError):
    """A finger model (URDF) is not a planar two-revolute-joint chain we can use.

    Attributes:
        source: The URDF path (or ``"<model>"`` for an in-memory model).
        joint: Name of the offending joint or frame, or None when the problem is global.
        shape: Name of the offending collision shape (Pinocchio's geometry object), or None.
    """

    def __init__(self, message: str, *, source: str | Path = "<model>", joint: str | None = None,
                 shape: str | None = None):
        self.source = str(source)
        self.joint = joint
        self.shape = shape
        where = (f"{self.source}" + (f", joint '{joint}'" if joint is not None else "")
                 + (f", collision shape '{shape}'" if shape is not None else ""))
        super().__init__(f"{where}: {message}")


class UnreachableError(RegraspError, ValueError):
    """A fingertip target lies outside the finger's workspace annulus.

    Attributes:
        finger: Finger name.
        target: The requested tip position [m] in the hand frame.
        distance: Distance [m] from the first joint to the target.
        reach: (inner, outer) radii [m] of the workspace annulus.
    """

    def __init__(self, finger: str, target: Sequence[float] | np.ndarray, distance: float,
                 reach: tuple[float, float]):
        self.finger = finger
        self.target = target
        self.distance = distance
        self.reach = reach
        super().__init__(
            f"finger '{finger}': target {list(map(float, target))} is at {distance:.6g} m from the "
            f"first joint, outside the reachable annulus [{reach[0]:.6g}, {reach[1]:.6g}] m"
        )


class PolygonError(RegraspError, ValueError):
    """Polygon vertices do not describe a valid convex polygon.

    Attributes:
        vertices: The vertices as given.
        index: Index of the offending vertex, or None.
    """

    def __init__(self, message: str, *, vertices: ArrayLike | None = None, index: int | None = None):
        self.vertices = vertices
        self.index = index
        super().__init__(message)


class CurveError(RegraspError, ValueError):
    """A curved object's parameters do not describe a valid convex closed curve (a radius that is not positive, a
    support function whose radius of curvature is not positive somewhere, a corner radius too large for its polygon).

    Attributes:
        parameter: The offending parameter's name.
        value: Its value as given.
        where: Where the curve fails, when that is a place (a normal angle [rad], an edge index), else None.
    """

    def __init__(self, message: str, *, parameter: str, value: Any, where: float | int | None = None):
        self.parameter = parameter
        self.value = value
        self.where = where
        super().__init__(message)


class UnknownEdgeError(RegraspError, IndexError):
    """An edge index does not exist on the polygon.

    Attributes:
        edge: The requested edge index.
        n_edges: Number of edges of the polygon.
    """

    def __init__(self, edge: int, n_edges: int):
        self.edge = edge
        self.n_edges = n_edges
        super().__init__(f"edge {short_repr(edge)} does not exist: the polygon has edges 0..{n_edges - 1}")


class TrajectoryError(RegraspError, ValueError):
    """A trajectory is ill-defined (bad waypoints, time outside its domain...).

    Attributes:
        name: The argument at fault (``"times"``, ``"poses"``), or None when it is not one argument.
    """

    def __init__(self, message: str, *, name: str | None = None):
        self.name = name
        super().__init__(message)


class ScenarioError(RegraspError):
    """A scenario file is malformed.

    Attributes:
        path: The scenario file.
        key: Dotted key of the offending entry (``"fingers[1].edge"``), or None.
        expected: What was expected there.
    """

    def __init__(self, path: str | Path, key: str | None, expected: str):
        self.path = str(path)
        self.key = key
        self.expected = expected
        where = f"{self.path}" + (f": key '{key}'" if key else "")
        super().__init__(f"{where}: {expected}")


class SlidingContactCountError(RegraspError, ValueError):
    """Too many sliding contacts: the sliding grasp needs 2m >= 3 + p (paper Remark 3.2).

    Attributes:
        m: Number of fingers (contacts).
        p: Number of sliding contacts.
    """

    def __init__(self, m: int, p: int):
        self.m = m
        self.p = p
        super().__init__(
            f"{p} sliding contact(s) with {m} finger(s): the grasp needs 2m >= 3 + p (Remark 3.2), "
            f"so at most {max(2 * m - 3, 0)} contact(s) may slide at once"
        )


class SingularFingerError(RegraspError):
    """A finger's tip Jacobian is (nearly) singular, so H = J^-1 [...] does not exist.

    Attributes:
        finger: Finger name.
        q: The finger's joint positions [rad].
        condition: Condition number of its 2x2 tip Jacobian.
        threshold: The threshold it exceeded.
    """

    def __init__(self, finger: str, q: Sequence[float] | np.ndarray, condition: float, threshold: float):
        self.finger = finger
        self.q = q
        self.condition = condition
        self.threshold = threshold
        super().__init__(
            f"finger '{finger}' is singular at q = {list(map(float, q))}: its tip Jacobian has condition "
            f"number {condition:.3g} > {threshold:.3g} (stretched or folded)"
        )


class SingularModelError(RegraspError, np.linalg.LinAlgError):
    """A control law's equations are singular (a singular grasp or finger posture): no torque."""


class PlantStateError(RegraspError, np.linalg.LinAlgError):
    """A plant cannot step from its state: its equations are singular or overflow there (a reset to a state far
    from any the hand can hold, or a run that diverged); a :class:`numpy.linalg.LinAlgError` as the singular solve
    it replaces was.

    Attributes:
        t: The state's time [s].
        reason: What failed.
    """

    def __init__(self, t: float, reason: str):
        self.t, self.reason = t, reason
        super().__init__(f"the plant cannot step from its state at t = {t:.6g} s: {reason}")


class MissingDependencyError(RegraspError, ImportError):
    """An optional dependency is not installed.

    Attributes:
        package: The missing Python package.
        extra: The regrasp extra that installs it (``pip install 'regrasp[extra]'``).
        feature: What needs it.
    """

    def __init__(self, package: str, extra: str, feature: str):
        self.package, self.extra, self.feature = package, extra, feature
        super().__init__(f"{feature} needs the '{package}' package: pip install 'regrasp[{extra}]'")


class ClusterConnectionError(RegraspError, ConnectionError):
    """A Ray cluster cannot be reached at its address (nothing listens there, or what does is no Ray cluster), said
    within seconds instead of Ray's endless retries.

    Attributes:
        address: The address as given.
        reason: What failed (the connection's error, a timeout...).
    """

    def __init__(self, address: str, reason: str):
        self.address, self.reason = address, reason
        super().__init__(f"no Ray cluster at {short_repr(address)}: {reason}")

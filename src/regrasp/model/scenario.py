r"""Scenario files (TOML): the object, its trajectory, the fingers and planner settings.

All lengths are in metres, angles in radians, masses in kilograms, times in seconds.
Unknown keys are errors (they are usually typos). Every error is a
:class:`~regrasp.core.exceptions.ScenarioError` naming the file, the key and what was expected.

.. code-block:: toml

    name = "paper_trajectory_2"
    [object]                             # a convex polygon; origin = centre of mass
    width = 0.10
    height = 0.04
    mass = 0.1                           # [kg]; with inertia [kg m^2], or density [kg/m^2] alone
    [trajectory]                         # object pose (x, y, beta) in the hand frame
    type = "ellipse"                     # x = cx + a sin(w t), y = cy + b cos(w t), beta = beta0 + beta_a sin(w t)
    cx = 0.0
    cy = 0.12
    a = 0.09
    b = 0.05
    omega = 2.0
    [[fingers]]                          # one table per finger
    name = "finger1"
    urdf = "../../urdf/planar_2r_finger.urdf"   # relative to the scenario file
    base = [-0.05, 0.0, 1.5707963267948966]     # base pose (x, y, theta) in the hand frame
    configuration = "left"
    edge = 1                             # edge k runs from vertex k to vertex k+1 (0-based, CCW order)

Every key, its unit, default and bounds (``[hand]``, ``[pad]``, ``[planner]``, ``[study]`` and the waypoint
trajectory) is in the scenario reference, ``docs/scenario.md``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..core.contact import DEFAULT_FRICTION, Friction
from ..core.curves import CurvedObject
from ..core.exceptions import (
    FingerModelError,
    InvalidParameterError,
    PolygonError,
    ScenarioError,
    short_repr,
)
from ..core.pad import Pad
from ..core.polygon import ConvexPolygon
from ..core.trajectory import EllipseTrajectory, Trajectory, WaypointTrajectory
from ..core.validation import (
    MAX_SAMPLES,
    as_finite_array,
    as_positive_float,
    as_sample_count,
    expect_sequence_of,
    expect_type,
    file_problem,
    read_toml,
)
from .finger import Finger, as_effort_limit
from .geometry import Geometry, as_geometry
from .perturbation import Perturbation
from .scenario_object import SceneObject, read_object
from .toml_table import TableReader, wrap_errors

__all__ = ["FingerContact", "Scenario", "load_scenario", "scenario_from_document"]

#: The friction when neither a finger nor [hand] gives one.


@dataclass(frozen=True)
class FingerContact:
    """A finger and the object edge it touches.

    Attributes:
        finger: The finger (URDF, base pose, configuration).
        edge: Index of the contact edge.
        tip_clearance: Tip clearance [m] for the ``urdf`` geometry, or None for the default.
        friction: Coulomb friction of the fingertip on the object (μ_s, μ_k [-]; used by rollouts).
    """

    finger: Finger
    edge: int
    tip_clearance: float | None = None
    friction: Friction = DEFAULT_FRICTION

    def __post_init__(self):
        if not isinstance(self.finger, Finger):
            raise InvalidParameterError("finger", self.finger, "a Finger (Finger.from_urdf)")
        if isinstance(self.edge, bool) or not isinstance(self.edge, (int, np.integer)) or self.edge < 0:
            raise InvalidParameterError("edge", self.edge, "an edge index (an integer >= 0)")
        object.__setattr__(self, "edge", int(self.edge))
        if self.tip_clearance is not None:
            object.__setattr__(self, "tip_clearance", as_positive_float("tip_clearance", self.tip_clearance,
                                                                        allow_zero=True))
        if not isinstance(self.friction, Friction):
            raise InvalidParameterError("friction", self.friction, "a Friction (regrasp.Friction)")


@dataclass(frozen=True)
class Scenario:
    """Everything a scenario file describes, built and validated (:func:`load_scenario` reads one; in code, give
    at least ``name``, ``polygon``, ``trajectory`` and ``contacts`` by keyword).

    Attributes:
        name: The scenario's name.
        polygon: The object: a convex polygon or a curved object (:mod:`regrasp.core.curves`).
        trajectory: The object's pose (x [m], y [m], β [rad]) in the hand frame over time.
        contacts: The fingers, each with its edge (a sequence of :class:`FingerContact`; kept as a tuple).
        description: Free text.
        path: The file it was read from (None: built in code).
        gravity_in_hand: Gravity (2,) [m/s²] in the hand frame.
        samples: The §2 planner's number of time samples.
        geometry: The planner's link geometry (``ideal`` or ``urdf``).
        xi_resolution: The regrasp planner's cell [m] for this scenario (None: its default,
            :class:`~regrasp.schedule.problem.RegraspSettings`); :meth:`RegraspSettings.of` reads it.
        study: The robustness study's perturbations (the ``[study]`` table).
        pad: The fingertips' compliant pad (the ``[pad]`` table), or None: rigid contacts on the project's plant.
    """

    name: str
    polygon: SceneObject
    trajectory: Trajectory
    contacts: tuple[FingerContact, ...]
    description: str = ""
    path: Path | None = None
    gravity_in_hand: np.ndarray = field(default_factory=lambda: np.array([0.0, -9.81]))
    samples: int = 401
    geometry: Geometry = Geometry.IDEAL
    xi_resolution: float | None = None
    study: Perturbation = Perturbation()
    pad: Pad | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise InvalidParameterError("name", self.name, "a non-empty string")
        if not isinstance(self.description, str):
            raise InvalidParameterError("description", self.description, "a string")
        if self.path is not None and not isinstance(self.path, Path):
            object.__setattr__(self, "path", Path(expect_type("path", self.path, str, "a path or None")))
        expect_type("polygon", self.polygon, (ConvexPolygon, CurvedObject), "a ConvexPolygon or a CurvedObject")
        expect_type("trajectory", self.trajectory, Trajectory, "a Trajectory")
        contacts = expect_sequence_of("contacts", self.contacts, FingerContact, "FingerContact")
        if not contacts:
            raise InvalidParameterError("contacts", self.contacts, "at least one FingerContact")
        object.__setattr__(self, "contacts", contacts)
        object.__setattr__(self, "gravity_in_hand", as_finite_array("gravity_in_hand", self.gravity_in_hand, (2,)))
        object.__setattr__(self, "samples", as_sample_count("samples", self.samples))
        object.__setattr__(self, "geometry", as_geometry("geometry", self.geometry))
        if self.xi_resolution is not None:
            object.__setattr__(self, "xi_resolution", as_positive_float("xi_resolution", self.xi_resolution))
        expect_type("study", self.study, Perturbation, "a Perturbation")
        if self.pad is not None:
            expect_type("pad", self.pad, Pad, "a Pad or None")

    def check_geometry(self, geometry: Geometry | str) -> Geometry:
        """``geometry`` as a :class:`~regrasp.model.geometry.Geometry` every finger of this scenario can be planned
        with: for ``urdf``, each finger's collision shapes (:func:`~regrasp.model.collision.checked_link_shapes`),
        else a :class:`~regrasp.core.exceptions.ScenarioError` naming the finger's ``urdf`` key."""
        try:
            geometry = Geometry(geometry)
        except ValueError:
            raise InvalidParameterError("geometry", geometry, "'ideal' or 'urdf'") from None
        if geometry is Geometry.URDF:
            from .collision import checked_link_shapes, default_tip_clearance

            try:
                self.polygon.to_coal(1.0)
            except PolygonError as exc:
                raise ScenarioError(self.path or "<scenario>", "object.vertices",
                                    f"{exc} (needed by the 'urdf' geometry)") from exc

            for i, c in enumerate(self.contacts):
                clearance = default_tip_clearance(c.finger) if c.tip_clearance is None else c.tip_clearance
                try:
                    checked_link_shapes(c.finger, clearance)
                except FingerModelError as exc:
                    raise ScenarioError(self.path or "<scenario>", f"fingers[{i}].urdf",
                                        f"{exc} (needed by the 'urdf' geometry)") from exc
        return geometry

    @property
    def friction(self) -> tuple[Friction, ...]:
        """Each fingertip's friction (μ_s, μ_k [-]), in finger order."""
        return tuple(c.friction for c in self.contacts)


def _trajectory(path: Path, table: Any) -> Trajectory:
    if not isinstance(table, dict):
        raise ScenarioError(path, "trajectory", "expected a table [trajectory]")
    r = TableReader(path, table, "trajectory.")
    kind = r.string("type", choices=("ellipse", "waypoints"))
    if kind == "ellipse":
        args = {k: r.number(k) for k in ("cx", "cy", "a", "b", "omega")}
        args.update(beta0=r.number("beta0", 0.0), beta_a=r.number("beta_a", 0.0),
                    t_start=r.number("t_start", 0.0), t_end=r.number("t_end", None))
        traj = wrap_errors(r, None, lambda: EllipseTrajectory(**args))
    else:
        times = r.array("times", (-1,))
        poses = r.array("poses", (-1, 3))
        boundary = r.string("boundary", "natural", choices=("natural", "clamped", "periodic"))
        unwrap = r.get("unwrap_angle", False)
        if not isinstance(unwrap, bool):
            raise r.fail("unwrap_angle", f"expected true or false, got {unwrap!r}")
        traj = wrap_errors(r, "poses", lambda: WaypointTrajectory(times, poses, boundary=boundary, unwrap_angle=unwrap))
    r.finish()
    return traj


def _friction(r: TableReader, default: Friction) -> Friction:
    """A table's friction keys: ``mu`` (both coefficients), or ``mu_static`` and ``mu_kinetic``
    together; ``default`` when it has none."""
    has_mu, has_static, has_kinetic = r.has("mu"), r.has("mu_static"), r.has("mu_kinetic")
    if has_mu and (has_static or has_kinetic):
        raise r.fail("mu", "expected either 'mu' (both coefficients) or 'mu_static' and 'mu_kinetic', not both")
    if has_static != has_kinetic:
        given, missing = ("mu_static", "mu_kinetic") if has_static else ("mu_kinetic", "mu_static")
        raise r.fail(given, f"expected '{given}' and '{missing}' together (or 'mu' for both)")
    if not (has_mu or has_static):
        return default
    names = ("mu",) if has_mu else ("mu_static", "mu_kinetic")
    values = [r.number(name) for name in names]
    for name, value in zip(names, values):
        if not value >= 0.0:
            raise r.fail(name, f"expected a friction coefficient >= 0, got {value!r}")
    if len(values) == 2 and values[1] > values[0]:
        raise r.fail("mu_kinetic", f"expected a kinetic coefficient <= mu_static = {values[0]:g}, got {values[1]!r}")
    try:
        return Friction(*values)
    except InvalidParameterError as exc:  # (Friction's own bounds, at the key that set the coefficient)
        raise r.fail(exc.name if exc.name in names else names[0], f"expected {exc.expected}, got "
                                                                   f"{short_repr(exc.value)}") from None


def _effort(r: TableReader, default: np.ndarray | None) -> np.ndarray | None:
    """A table's ``effort`` key: the joints' torque limits [N m], a number > 0 for both or one per joint
    (:func:`~regrasp.model.finger.as_effort_limit`); ``default`` when it has none (None: the URDF's)."""
    if not r.has("effort"):
        return default
    value = r.get("effort")
    try:
        return as_effort_limit(r.key("effort"), value)
    except InvalidParameterError:
        raise r.fail("effort", f"expected a joint torque limit > 0 [N m] or a list of two (joint 1, joint 2), "
                               f"got {short_repr(value)}") from None


def _fingers(path: Path, tables: Any, polygon: SceneObject, friction: Friction,
             effort: np.ndarray | None = None) -> tuple[FingerContact, ...]:
    if not isinstance(tables, list) or not tables or not all(isinstance(t, dict) for t in tables):
        raise ScenarioError(path, "fingers", "expected one or more [[fingers]] tables")
    contacts = []
    names = set()
    for i, table in enumerate(tables):
        r = TableReader(path, table, f"fingers[{i}].")
        name = r.string("name", f"finger{i + 1}")
        if name in names:
            raise r.fail("name", f"finger names must be unique; '{name}' is repeated")
        names.add(name)
        urdf = Path(r.string("urdf"))
        relative = not urdf.is_absolute()
        if relative:
            urdf = path.parent / urdf
        problem = file_problem(urdf, "URDF file")  # (before resolving: a symlink loop is no file, not a crash)
        if problem is not None:
            raise r.fail("urdf", f"{problem}: {urdf}")
        if relative:
            urdf = urdf.resolve()
        base = r.array("base", (3,))
        configuration = r.string("configuration", choices=("left", "right"))
        if isinstance(polygon, CurvedObject):  # one face, the whole boundary
            edge = r.integer("edge", 0)
            if edge != 0:
                raise r.fail("edge", f"edge {edge} does not exist: a curved object has one face, 0 (its boundary)")
        else:
            edge = r.integer("edge")
            if not 0 <= edge < polygon.n_vertices:
                raise r.fail("edge", f"edge {edge} does not exist: the object has edges 0..{polygon.n_vertices - 1}")
        clearance = r.number("tip_clearance", None)
        if clearance is not None and clearance < 0.0:
            raise r.fail("tip_clearance", f"expected a length >= 0 [m], got {clearance!r}")
        own = _friction(r, friction)
        limits = _effort(r, effort)
        finger = wrap_errors(r, "urdf", lambda: Finger.from_urdf(
            urdf, base_in_hand=base, configuration=configuration, name=name, effort_limit=limits))
        r.finish()
        contacts.append(FingerContact(finger, edge, clearance, own))
    return tuple(contacts)


def _study(path: Path, table: Any) -> Perturbation:
    """The ``[study]`` table: a :class:`~regrasp.model.perturbation.Perturbation`'s fields by name."""
    from dataclasses import fields

    if not isinstance(table, dict):
        raise ScenarioError(path, "study", "expected a table [study]")
    r = TableReader(path, table, "study.")
    values = {}
    for f in fields(Perturbation):
        if r.has(f.name):
            values[f.name] = r.integer(f.name) if f.name in ("delay", "slip_delay") else r.number(f.name)
    r.finish()
    return wrap_errors(r, None, lambda: Perturbation(**values))


def _pad(path: Path, table: Any) -> Pad | None:
    """The ``[pad]`` table: a :class:`~regrasp.core.pad.Pad`'s stiffness, damping, preload and substeps, or None."""
    if table is None:
        return None
    if not isinstance(table, dict):
        raise ScenarioError(path, "pad", "expected a table [pad]")
    r = TableReader(path, table, "pad.")
    values: dict[str, Any] = {"stiffness": r.number("stiffness")}
    for name in ("damping", "preload"):
        if r.has(name):
            values[name] = r.number(name)
    if r.has("substeps"):
        values["substeps"] = r.integer("substeps")
    r.finish()
    return wrap_errors(r, None, lambda: Pad(**values))


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario file; raises ScenarioError naming the file and key."""
    path, data = read_toml(path, "scenario file")
    return scenario_from_document(data, path)


def scenario_from_document(data: dict, path: str | Path) -> Scenario:
    """A scenario from a TOML document already read (a dict, as :mod:`tomllib` gives it: a suite's variant,
    :mod:`regrasp.suite.variants`), validated as :func:`load_scenario` validates a file; ``path``: the file it stands
    for (relative URDF paths are relative to it, and errors name it)."""
    path = Path(expect_type("path", path, (str, Path), "a path (str or pathlib.Path)"))
    if not isinstance(data, dict):
        raise ScenarioError(path, None, f"expected a TOML document (a table), got {short_repr(data)}")
    top = TableReader(path, data, "")
    name = top.string("name", path.stem)
    description = top.string("description", "")
    polygon = read_object(path, top.get("object"))
    trajectory = _trajectory(path, top.get("trajectory"))
    hand_table = top.get("hand", {})
    if not isinstance(hand_table, dict):
        raise ScenarioError(path, "hand", "expected a table [hand]")
    hand = TableReader(path, hand_table, "hand.")
    gravity = hand.array("gravity", (2,), [0.0, -9.81])
    friction = _friction(hand, DEFAULT_FRICTION)
    effort = _effort(hand, None)
    hand.finish()
    contacts = _fingers(path, top.get("fingers"), polygon, friction, effort)

    planner_table = top.get("planner", {})
    if not isinstance(planner_table, dict):
        raise ScenarioError(path, "planner", "expected a table [planner]")
    planner = TableReader(path, planner_table, "planner.")
    samples = planner.integer("samples", 401)
    if not 2 <= samples <= MAX_SAMPLES:
        raise planner.fail("samples", f"expected an integer in [2, {MAX_SAMPLES}], got {short_repr(samples)}")
    geometry = Geometry(planner.string("geometry", "ideal", choices=("ideal", "urdf")))
    xi_resolution = planner.number("xi_resolution", None)
    if xi_resolution is not None and not 1e-5 <= xi_resolution <= 0.01:
        raise planner.fail("xi_resolution", f"expected a cell in [1e-5, 0.01] m, got {xi_resolution!r}")
    planner.finish()
    study = _study(path, top.get("study", {}))
    pad = _pad(path, top.get("pad", None))
    top.finish()
    scenario = Scenario(
        path=path,
        name=name,
        description=description,
        polygon=polygon,
        trajectory=trajectory,
        contacts=contacts,
        gravity_in_hand=gravity,
        samples=samples,
        geometry=geometry,
        xi_resolution=xi_resolution,
        study=study,
        pad=pad,
    )
    scenario.check_geometry(geometry)
    return scenario

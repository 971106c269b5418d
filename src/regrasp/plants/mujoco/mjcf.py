r"""A scenario as a MuJoCo model (MJCF), for the second, independent plant (:mod:`regrasp.plants.mujoco.plant`).

The hand and the object are built with ``mujoco.MjSpec``; :func:`scenario_to_mjcf` writes the same model
as MJCF text. Nothing here uses the project's reduced model, grasp matrices or plant: the fingers are read
from their URDF files by MuJoCo's own URDF parser, the object from its polygon or curve.

**Fingers.** Each finger's URDF (``Finger.source``) is parsed by MuJoCo with ``fusestatic`` off, so its
``tip`` frame stays a body, and attached at the finger's base pose in the hand frame (x, y, rotation θ
about z); its link masses, inertias and joint damping are the URDF's (times ``link_mass_scale``), its
two joints hinges about +z, without limits (the project's plant has none). A **sphere of radius r**
(``MujocoSettings.tip_radius``) is centred on the tip frame; a site there is what the plant senses.
The links' collision shapes are the project's ``urdf`` geometry (:func:`~regrasp.model.collision.checked_link_shapes`:
the URDF's cylinders, capsules and boxes, the distal one shortened by the tip clearance), so a link
contact here is what the planner and the project's plant call a collision.

**Object.** A planar body: joints slide x, slide y and hinge z (in that order, so ``qpos`` is the pose
X = (x, y, β) of the centre of mass in the hand frame), the object's mass and rotational inertia, and
two prisms of thickness ``object_thickness`` along z:

* ``object`` (the tips touch it): the polygon **eroded by r**, every edge moved inwards by r. A sphere of radius r
  touching an edge of the eroded polygon has its centre on the original edge's line (the Minkowski sum of the eroded
  polygon and the sphere is the polygon, up to its rounded corners), so the tip frame is where the point-contact model
  puts the contact, in the normal direction exactly (``contact_depth`` less, 1 µm);
* ``hull`` (the links touch it): the polygon itself.

A **curved object** (:mod:`regrasp.core.curves`) gets the same two prisms (:mod:`regrasp.plants.mujoco.curve_mesh`):
``hull`` the curve, ``object`` its inner parallel curve at distance r − ``contact_depth``, which shares the curve's
normals, so that a tip touching it has its centre on the curve: a disc's are cylinders, other curves' convex meshes of
points on those curves, dense enough that every chord stays within ``MESH_SAGITTA`` (0.1 µm) of its curve. The
parallel curve is convex and smooth only while r − ``contact_depth`` is below the curve's smallest radius of
curvature: a larger tip radius is an error.

**Contacts.** Each tip touches ``object`` through an explicit contact pair with the finger's friction
coefficient (MuJoCo has one per contact: μ_k, see :class:`MujocoSettings`), ``condim`` 3 (no torsional
or rolling friction: a point contact transmits no moment), elliptic cones. The links touch ``hull``
(``contype``/``conaffinity`` bits): those contacts are reported as collisions. Tips never touch
``hull``, links never touch ``object``, and fingers never touch each other (no contact bits in common).
Gravity is the scenario's, in the hand's plane.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np

from ...core.contact import Friction
from ...core.curves import CurvedObject
from ...core.exceptions import FingerModelError, InvalidParameterError, MissingDependencyError
from ...core.polygon import ConvexPolygon
from ...core.validation import (
    as_count,
    as_finite_float,
    as_flag,
    as_positive_float,
    as_tip_radius,
    check_fields,
    expect_sequence_of,
    expect_type,
)
from ...model.collision import checked_link_shapes, default_tip_clearance
from ...model.finger import Finger
from .curve_mesh import add_curve_prism, check_erosion, curvature_table

if TYPE_CHECKING:
    from ...model.scenario import Scenario

__all__ = ["MjcfHand", "MujocoSettings", "build_mjcf", "eroded_vertices", "require_mujoco", "scenario_to_mjcf"]

#: Contact bits: links (contype) against the object's hull (conaffinity); tips only through explicit pairs.
_LINK_BIT = 2
_INTEGRATORS = ("euler", "implicit", "implicitfast", "rk4")
#: The friction rows' time constant as a fraction of the normal rows' (``MujocoSettings.friction_time_constant``
#: None): on the default scenario at solref 2 ms, 0.25 of it let a slider chatter off its edge and 0.4 did not, and
#: longer ones let the held contacts drift further (``examples/13_mujoco_contact_artifacts.py --rollouts``;
#: ``docs/derivations.md``, "MuJoCo's contacts: drift and hops").
FRICTION_TIME_RATIO = 0.4
#: The friction rows' least default time constant [s]: the normal rows' default, so that the default plant's friction
#: rows keep the 0.5 ms they had.
FRICTION_TIME_FLOOR = 5e-4


@dataclass(frozen=True)
class MujocoSettings:
    r"""MuJoCo's physics for the second plant (``docs/derivations.md``, "A second plant: MuJoCo").

    Attributes:
        tip_radius: r [m], the fingertips' sphere radius (at most 5 cm,
            :data:`~regrasp.core.validation.MAX_TIP_RADIUS`).
        timestep: MuJoCo's step [s]; the plant takes ``round(dt / timestep)`` of them per control step,
            with the torques held (zero-order hold).
        time_constant: The contacts' ``solref`` time constant [s] (their normal rows): how fast a penetration
            is undone, the pad's softness. MuJoCo needs at least 2 ``timestep``.
        friction_time_constant: The friction rows' time constant [s] (``solreffriction``): how fast a slip
            velocity is undone. Not a material property but MuJoCo's drift correction: its contact constraints
            leave out the velocity-product term J̇q̇, so a contact stuck on a turning object slips at a steady
            speed proportional to this; and far below the normal rows' it makes a sliding contact chatter off its
            edge (``docs/derivations.md``, "MuJoCo's contacts: drift and hops"). None (default): the normal rows'
            ``time_constant`` times ``FRICTION_TIME_RATIO`` (0.4), but not below 0.5 ms nor above
            ``time_constant`` (:attr:`friction_rows_time_constant`).
        damping_ratio: ``solref``'s damping ratio [-] (1: critically damped).
        solimp: ``solimp`` (d_min, d_max, width [m], midpoint, power): the constraint's impedance grows
            from d_min to d_max over ``width`` of penetration.
        impratio: Friction-to-normal impedance ratio [-] of the elliptic cones: large makes stuck
            contacts creep less (a soft contact always creeps a little inside its cone).
        noslip_iterations: MuJoCo's no-slip post-solver iterations (0: off).
        iterations, tolerance: The main solver's (Newton) iterations and tolerance.
        object_thickness: The object prisms' extent along z [m] (the tips and links lie at z = 0).
        contact_depth: The object the tips touch is eroded by r less this [m], so that a tip the point-contact
            model puts on an edge starts in contact, this deep. MuJoCo's soft contacts carry force only when
            penetrating; a tip placed exactly on the surface is a nanometre off it (the mesh's rounding), flies
            in under the squeeze for a step and micro-slips on impact (3 to 8 mm/s on Figure 3.4's hold).
            A loaded contact sinks about as deep anyway (1 to 3 µm at 1 to 5 N).
        erode: Erode the object the tips touch by r (the sphere's centre then lies on the edge's line);
            False only to measure what the erosion buys.
        integrator: ``"euler"``, ``"implicit"``, ``"implicitfast"`` (the default: the joint damping
            implicitly) or ``"rk4"``.

    MuJoCo has one friction coefficient per contact; a scenario with μ_s > μ_k gets μ_k (the
    coefficient the sliding law relies on): its contacts then break away at μ_k f_n, earlier than the
    model's μ_s f_n, and the plant reports its friction as ``Friction(μ_k)``.
    """

    tip_radius: float = 2.5e-4
    timestep: float = 1e-4
    time_constant: float = 5e-4
    friction_time_constant: float | None = None
    damping_ratio: float = 1.0
    solimp: tuple[float, float, float, float, float] = (0.99, 0.999, 1e-4, 0.5, 2.0)
    impratio: float = 100.0
    noslip_iterations: int = 0
    iterations: int = 100
    tolerance: float = 1e-10
    object_thickness: float = 0.02
    contact_depth: float = 1e-6
    erode: bool = True
    integrator: str = "implicitfast"

    def __post_init__(self):
        check_fields(self, as_tip_radius, ("tip_radius",))
        check_fields(self, as_positive_float, ("timestep", "time_constant", "damping_ratio", "impratio", "tolerance",
                                               "object_thickness"))
        check_fields(self, as_positive_float, ("friction_time_constant",), optional=True)
        check_fields(self, as_positive_float, ("contact_depth",), allow_zero=True)
        if not 1e-7 <= self.timestep <= 1e-3:
            raise InvalidParameterError("timestep", self.timestep, "a step from 1e-7 to 1e-3 s")
        for name in ("time_constant", "friction_time_constant"):
            if getattr(self, name) is not None and not getattr(self, name) >= 2.0 * self.timestep:
                raise InvalidParameterError(name, getattr(self, name), f"at least 2 timesteps "
                                            f"({2.0 * self.timestep:.3g} s): MuJoCo's stable minimum")
        solimp = tuple(as_finite_float("solimp", v) for v in self.solimp) if isinstance(self.solimp, (tuple, list)) \
            else None
        if solimp is None or len(solimp) != 5 or not (0.0 < solimp[0] <= solimp[1] < 1.0 and solimp[2] > 0.0
                                                      and 0.0 < solimp[3] < 1.0 and solimp[4] >= 1.0):
            raise InvalidParameterError("solimp", self.solimp, "(d_min, d_max, width, midpoint, power) with "
                                        "0 < d_min <= d_max < 1, width > 0, 0 < midpoint < 1, power >= 1")
        object.__setattr__(self, "solimp", solimp)
        check_fields(self, as_count, ("noslip_iterations",))
        check_fields(self, as_count, ("iterations",), 1)
        check_fields(self, as_flag, ("erode",))
        if not isinstance(self.integrator, str) or self.integrator not in _INTEGRATORS:
            raise InvalidParameterError("integrator", self.integrator, f"one of {', '.join(_INTEGRATORS)}")

    @property
    def friction_rows_time_constant(self) -> float:
        """The friction rows' ``solreffriction`` time constant [s]: ``friction_time_constant``, or when None
        ``time_constant`` · ``FRICTION_TIME_RATIO`` kept within [``FRICTION_TIME_FLOOR``, ``time_constant``]."""
        if self.friction_time_constant is not None:
            return self.friction_time_constant
        return min(self.time_constant, max(FRICTION_TIME_FLOOR, FRICTION_TIME_RATIO * self.time_constant))


def eroded_vertices(polygon: ConvexPolygon, distance: float, name: str = "distance") -> np.ndarray:
    r"""The polygon with every edge moved inwards by ``distance`` [m] (outwards if negative): (n, 2) vertices,
    object frame; an error names ``distance`` as ``name`` (a plant's ``"tip_radius"``).

    Vertex k is where the moved lines of edges k − 1 and k meet: :math:`n_j \cdot p = n_j \cdot v_j + d`
    for j = k − 1, k (n_j the inward normals).

    Raises:
        InvalidParameterError: the distance is so large that an edge vanishes.
    """
    expect_type("polygon", polygon, ConvexPolygon, "a ConvexPolygon")
    r = as_finite_float(name, distance)
    if abs(r) > polygon.scale:
        raise InvalidParameterError(name, r, f"an offset of at most the object's size ({polygon.scale:.3g} m)")
    edges = polygon.edges
    n = len(edges)
    out = np.empty((n, 2))
    for k in range(n):
        a, b = edges[k - 1], edges[k]
        normals = np.array([a.inward_normal, b.inward_normal])
        offsets = np.array([a.inward_normal @ a.start + r, b.inward_normal @ b.start + r])
        out[k] = np.linalg.solve(normals, offsets)
    for k in range(n):  # each moved edge keeps its direction (else the erosion swallowed it)
        d = out[(k + 1) % n] - out[k]
        if not d @ (edges[k].end - edges[k].start) > 0.0:
            raise InvalidParameterError(name, r, f"a radius small enough that edge {k} of the object "
                                        "survives the erosion by it")
    if not np.isfinite(out).all():
        raise InvalidParameterError(name, r, "an offset the polygon's edges survive")
    return out


@dataclass(frozen=True, eq=False)
class MjcfHand:
    """The built model and the names the plant needs.

    Attributes:
        spec: The ``mujoco.MjSpec`` (compile it with ``spec.compile()``).
        finger_joints: Per finger, its two hinge joints' names (proximal, distal).
        tip_sites: Per finger, the site at its tip frame.
        tip_geoms: Per finger, its tip sphere.
        link_geoms: Per finger, its links' collision geoms as (name, link: 0 proximal, 1 distal).
        object_joints: The object's slide x, slide y and hinge z.
        object_geom, hull_geom: The prism the tips touch and the one the links touch.
        friction: Each contact's friction coefficient in the model [-].
        settings: The :class:`MujocoSettings` it was built with.
        sagitta: The chord errors [m] of the ``object`` and ``hull`` meshes of a curved object (0 for a polygon's
            prisms and a disc's cylinders, which are exact).
    """

    spec: object
    finger_joints: tuple[tuple[str, str], ...]
    tip_sites: tuple[str, ...]
    tip_geoms: tuple[str, ...]
    link_geoms: tuple[tuple[tuple[str, int], ...], ...]
    object_joints: tuple[str, str, str]
    object_geom: str
    hull_geom: str
    friction: tuple[float, ...]
    settings: MujocoSettings
    sagitta: tuple[float, float] = (0.0, 0.0)


def require_mujoco() -> ModuleType:
    """The ``mujoco`` module, or a :class:`~regrasp.core.exceptions.MissingDependencyError` naming the extra."""
    try:
        import mujoco
    except ImportError as exc:
        raise MissingDependencyError("mujoco", "mujoco", "the MuJoCo plant") from exc
    return mujoco


_mujoco = require_mujoco


def _urdf_spec(mujoco, finger: Finger):
    """MuJoCo's parse of ``finger``'s URDF file, with its fixed links (the tip frame) kept as bodies."""
    path = Path(finger.source)
    if not path.is_file():
        raise FingerModelError("the MuJoCo plant reads the finger's URDF file, and this finger has none (built "
                               "from text? write it to a file and use Finger.from_urdf)", source=finger.source)
    text = path.read_text(encoding="utf-8")
    start = text.find("<robot")
    head = text.find(">", start) + 1 if start >= 0 else 0
    if head <= 0:
        raise FingerModelError("no <robot> element", source=finger.source)
    text = text[:head] + '<mujoco><compiler fusestatic="false" discardvisual="true"/></mujoco>' + text[head:]
    try:
        return mujoco.MjSpec.from_string(text)
    except Exception as exc:  # mujoco raises its own ValueError subclasses with the parser's message
        raise FingerModelError(f"MuJoCo cannot parse it: {exc}", source=finger.source) from exc


def _quat(rotation: np.ndarray) -> list[float]:
    mujoco = _mujoco()
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.asarray(rotation, dtype=float).reshape(9))
    return q.tolist()


def _add_link_geom(mujoco, body, shape, name: str) -> None:
    """A link's collision shape (a coal cylinder, capsule or box placed in its joint's frame) as a geom."""
    geom = shape.geometry
    kind = type(geom).__name__
    if kind == "Cylinder":
        gtype, size = mujoco.mjtGeom.mjGEOM_CYLINDER, [float(geom.radius), float(geom.halfLength), 0.0]
    elif kind == "Capsule":
        gtype, size = mujoco.mjtGeom.mjGEOM_CAPSULE, [float(geom.radius), float(geom.halfLength), 0.0]
    elif kind == "Box":
        gtype, size = mujoco.mjtGeom.mjGEOM_BOX, np.asarray(geom.halfSide, dtype=float).tolist()
    else:
        raise FingerModelError(f"the MuJoCo plant cannot use a {kind} collision shape (cylinder, capsule or box)",
                               shape=shape.name)
    placement = shape.placement_in_joint
    body.add_geom(name=name, type=gtype, size=size, pos=np.asarray(placement.translation, dtype=float).tolist(),
                  quat=_quat(placement.rotation), contype=_LINK_BIT, conaffinity=0, density=0.0, mass=0.0,
                  group=1)


def _add_finger(mujoco, spec, index: int, finger: Finger, clearance: float, mass_scale: float, radius: float):
    """Attach finger ``index`` at its base pose; returns its joints, tip site and geoms' names."""
    child = _urdf_spec(mujoco, finger)
    hinges = [j for j in child.joints if j.type == mujoco.mjtJoint.mjJNT_HINGE]
    if len(hinges) != 2 or len(child.joints) != 2:
        raise FingerModelError("the MuJoCo parse does not have exactly two hinge joints", source=finger.source)
    tip_body = child.body(finger.tip_frame)
    if tip_body is None:
        raise FingerModelError(f"the MuJoCo parse has no '{finger.tip_frame}' frame", source=finger.source)
    link_bodies = [j.parent for j in hinges]
    for geom in list(child.geoms):  # the links' contact shapes are the project's (below)
        child.delete(geom)
    for body in link_bodies:
        body.mass = body.mass * mass_scale
        body.inertia = np.asarray(body.inertia) * mass_scale
    for joint in hinges:
        joint.limited = mujoco.mjtLimited.mjLIMITED_FALSE
        joint.actfrclimited = mujoco.mjtLimited.mjLIMITED_FALSE
        joint.armature = 0.0
        joint.frictionloss = 0.0
    prefix = f"f{index}/"
    link_names, joint_names = [b.name for b in link_bodies], [j.name for j in hinges]
    x, y, theta = finger.base_in_hand.tolist()
    frame = spec.worldbody.add_frame(pos=[x, y, 0.0], quat=[math.cos(theta / 2), 0.0, 0.0, math.sin(theta / 2)])
    spec.attach(child, prefix=prefix, frame=frame)
    links = [spec.body(prefix + name) for name in link_names]
    names = []
    for k, shape in enumerate(checked_link_shapes(finger, clearance)):
        name = f"{prefix}link{shape.link + 1}_shape{k}"
        _add_link_geom(mujoco, links[shape.link], shape, name)
        names.append((name, shape.link))
    tip = spec.body(prefix + finger.tip_frame)
    tip.add_site(name=prefix + "tip_site", size=[radius, 0.0, 0.0])
    tip.add_geom(name=prefix + "tip_sphere", type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[radius, 0.0, 0.0],
                 contype=0, conaffinity=0, density=0.0, mass=0.0, group=1)
    return (prefix + joint_names[0], prefix + joint_names[1]), prefix + "tip_site", prefix + "tip_sphere", tuple(names)


def _add_prism(mujoco, spec, body, name: str, vertices: np.ndarray, thickness: float, conaffinity: int) -> None:
    half = 0.5 * thickness
    points = [[float(x), float(y), z] for x, y in vertices for z in (-half, half)]
    spec.add_mesh(name=name + "_mesh", uservert=[c for p in points for c in p],
                  inertia=mujoco.mjtMeshInertia.mjMESH_INERTIA_CONVEX)
    body.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=name + "_mesh", contype=0,
                  conaffinity=conaffinity, density=0.0, mass=0.0, group=0)


def build_mjcf(fingers: Sequence[Finger], polygon: ConvexPolygon | CurvedObject, frictions: Sequence[Friction], *,
               gravity_in_hand: Sequence[float] = (0.0, -9.81), object_mass: float | None = None,
               object_inertia: float | None = None, tip_clearance: Sequence[float | None] | None = None,
               link_mass_scale: float = 1.0, settings: MujocoSettings = MujocoSettings()) -> MjcfHand:
    r"""The hand and the object as a ``mujoco.MjSpec`` (module docstring).

    Args:
        fingers: The fingers (from URDF files), finger i touching contact i.
        polygon: The object: a convex polygon or a curved object.
        frictions: Each contact's friction (MuJoCo gets μ_k).
        gravity_in_hand: Gravity [m/s²] in the hand frame.
        object_mass: The object's mass [kg] (default: the object's).
        object_inertia: The object's inertia [kg m²] (default: the object's).
        tip_clearance: Per finger, the distal link's tip clearance [m] (None: the default).
        link_mass_scale: The links' masses and inertias are this times the URDFs' [-].
        settings: :class:`MujocoSettings`.

    Raises:
        FingerModelError: a finger has no URDF file, or a shape MuJoCo cannot take.
        InvalidParameterError: bad arguments, or a tip radius the object cannot be eroded by (a polygon's edge
            would vanish; a curve's smallest radius of curvature is below r − ``contact_depth``).
    """
    mujoco = _mujoco()
    fingers = expect_sequence_of("fingers", fingers, Finger, "Finger (Finger.from_urdf)")
    expect_type("polygon", polygon, (ConvexPolygon, CurvedObject), "a ConvexPolygon or a CurvedObject")
    expect_type("settings", settings, MujocoSettings, "a MujocoSettings")
    frictions = expect_sequence_of("frictions", frictions, Friction, "Friction")
    m = len(fingers)
    if len(frictions) != m:
        raise InvalidParameterError("frictions", frictions, f"one Friction per finger ({m})")
    clearances = [None] * m if tip_clearance is None else list(tip_clearance)
    if len(clearances) != m:
        raise InvalidParameterError("tip_clearance", tip_clearance, f"one clearance per finger ({m})")
    gx, gy = (as_finite_float("gravity_in_hand", g) for g in np.asarray(gravity_in_hand, dtype=float).reshape(2))
    mass = as_positive_float("object_mass", polygon.mass if object_mass is None else object_mass)
    inertia = as_positive_float("object_inertia", polygon.inertia if object_inertia is None else object_inertia)
    scale = as_positive_float("link_mass_scale", link_mass_scale)
    r = settings.tip_radius
    offset = (r if settings.erode else 0.0) - settings.contact_depth
    curved = isinstance(polygon, CurvedObject)
    if curved:
        kappa = curvature_table(polygon)
        check_erosion(polygon, offset, r, kappa)
    else:
        tip_vertices = eroded_vertices(polygon, offset, "tip_radius")

    spec = mujoco.MjSpec()
    spec.modelname = "regrasp_hand"
    spec.compiler.degree = False
    opt = spec.option
    opt.timestep = settings.timestep
    opt.gravity = [gx, gy, 0.0]
    opt.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    opt.impratio = settings.impratio
    opt.noslip_iterations = settings.noslip_iterations
    opt.iterations = settings.iterations
    opt.tolerance = settings.tolerance
    opt.integrator = {"euler": mujoco.mjtIntegrator.mjINT_EULER, "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT,
                      "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
                      "rk4": mujoco.mjtIntegrator.mjINT_RK4}[settings.integrator]
    opt.enableflags |= mujoco.mjtEnableBit.mjENBL_ENERGY

    body = spec.worldbody.add_body(name="object", pos=[0.0, 0.0, 0.0])
    body.explicitinertial = True
    body.ipos, body.iquat = [0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]  # (without them to_xml leaves the inertial out)
    body.mass = mass
    body.inertia = [inertia, inertia, inertia]  # (x and y never rotate: only the z entry matters)
    axes = {"object_x": (mujoco.mjtJoint.mjJNT_SLIDE, [1.0, 0.0, 0.0]),
            "object_y": (mujoco.mjtJoint.mjJNT_SLIDE, [0.0, 1.0, 0.0]),
            "object_beta": (mujoco.mjtJoint.mjJNT_HINGE, [0.0, 0.0, 1.0])}
    for name, (kind, axis) in axes.items():
        body.add_joint(name=name, type=kind, axis=axis, limited=mujoco.mjtLimited.mjLIMITED_FALSE)
    sagitta = (0.0, 0.0)
    if curved:
        sagitta = tuple(add_curve_prism(mujoco, spec, body, name, polygon, d, settings.object_thickness, bits, kappa)
                        for name, d, bits in (("object", offset, 0), ("hull", 0.0, _LINK_BIT)))
    else:
        _add_prism(mujoco, spec, body, "object", tip_vertices, settings.object_thickness, 0)
        _add_prism(mujoco, spec, body, "hull", np.asarray(polygon.vertices, dtype=float), settings.object_thickness,
                   _LINK_BIT)

    joints, sites, tips, links, mus = [], [], [], [], []
    for i, finger in enumerate(fingers):
        clearance = default_tip_clearance(finger) if clearances[i] is None else as_positive_float(
            "tip_clearance", clearances[i], allow_zero=True)
        j, site, tip, link = _add_finger(mujoco, spec, i, finger, clearance, scale, r)
        joints.append(j)
        sites.append(site)
        tips.append(tip)
        links.append(link)
        mu = frictions[i].kinetic
        mus.append(mu)
        spec.add_pair(name=f"f{i}/tip_object", geomname1=tip, geomname2="object", condim=3,
                      friction=[mu, mu, 0.0, 0.0, 0.0], solref=[settings.time_constant, settings.damping_ratio],
                      solreffriction=[settings.friction_rows_time_constant, settings.damping_ratio],
                      solimp=list(settings.solimp), margin=0.0, gap=0.0)
    # the links' contacts with the hull get the same solver parameters (they end the run anyway)
    for geoms in links:
        for name, _ in geoms:
            g = spec.geom(name)
            g.solref = [settings.time_constant, settings.damping_ratio]
            g.solimp = list(settings.solimp)
    return MjcfHand(spec, tuple(joints), tuple(sites), tuple(tips), tuple(links), tuple(axes), "object", "hull",
                    tuple(mus), settings, sagitta)


def scenario_to_mjcf(scenario: Scenario, settings: MujocoSettings = MujocoSettings(),
                     path: str | Path | None = None) -> str:
    """The scenario's hand and object as MJCF text (and written to ``path`` if given); see :func:`build_mjcf`."""
    from ...model.scenario import Scenario  # (a runtime import: the scenario module is heavier than this one)

    expect_type("scenario", scenario, Scenario, "a Scenario (regrasp.load_scenario)")
    built = build_mjcf([c.finger for c in scenario.contacts], scenario.polygon, scenario.friction,
                       gravity_in_hand=scenario.gravity_in_hand,
                       tip_clearance=[c.tip_clearance for c in scenario.contacts], settings=settings)
    built.spec.compile()
    text = built.spec.to_xml()
    if path is not None:
        Path(path).write_text(text, encoding="utf-8")
    return text

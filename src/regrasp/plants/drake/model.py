r"""A scenario as a Drake ``MultibodyPlant``, for the third, independent plant (:mod:`regrasp.plants.drake.plant`).

Nothing here uses the project's reduced model, grasp matrices or plant: the fingers are read from their URDF files
by Drake's own parser, the object is built from its polygon or curve.

**Fingers.** Each finger's URDF (``Finger.source``) is parsed by ``pydrake.multibody.parsing.Parser`` into a model
instance of its own (prefix ``f<i>``), without its ``<visual>`` and ``<collision>`` elements (the contact shapes
are the project's, below), and its root link is welded to the world at the finger's base pose in the hand plane
(the world's xy plane: x, y and a rotation θ about z). Its link masses, centres of mass, inertias and joint damping
are the URDF's (the masses and inertias times ``link_mass_scale``, set in the plant's context); its two revolute
joints have their limits removed (the project's plant has none). A **sphere of radius r**
(:attr:`DrakeSettings.tip_radius`) is centred on the ``tip`` frame's body. The links' collision shapes are the
project's ``urdf`` geometry (:func:`~regrasp.model.collision.checked_link_shapes`: the URDF's cylinders, capsules
and boxes, the distal one shortened by the tip clearance), so a link contact here is what the planner and the
project's plant call a collision.

**Object.** A rigid body on a ``PlanarJoint`` to the world (x, y and a rotation about z: the pose X = (x, y, β) of
the centre of mass), with the object's mass and rotational inertia, and, for a polygon, convex prisms of thickness
``object_thickness`` along z (``pydrake.geometry.Convex`` built from the prism's corners):

* one ``tips<i>`` prism per finger, touched only by tip i: the polygon **eroded by r** (less ``contact_depth``), so
  that a sphere of radius r touching it has its centre on the original edge's line (as the MuJoCo plant's object,
  :func:`~regrasp.plants.mujoco.mjcf.eroded_vertices`). One per finger because Drake combines the two geometries'
  friction coefficients (μ = 2 μ_A μ_B / (μ_A + μ_B)): a prism with tip i's own coefficients gives the pair
  exactly them;
* ``hull`` (the links touch it): the polygon itself.

A **curved object** (:mod:`regrasp.core.curves`; ``docs/derivations.md``, "The plants on curves") is touched on its
inner parallel curve :math:`c + (r - \text{depth})\,n` (which shares the curve's normals, so that a sphere touching it
has its centre on the curve ``contact_depth`` in, as on MuJoCo, :mod:`regrasp.plants.mujoco.curve_mesh`), smooth and
convex only while r − ``contact_depth`` is below the curve's smallest radius of curvature (a larger tip radius is an
error):

* a **disc**: ``hull`` a ``Cylinder`` of radius R and each ``tips<i>`` one of R − r + depth. Drake's point contact
  of a sphere and a cylinder is its own exact signed distance: a tip placed on the circle starts ``contact_depth``
  deep to 1e-16 m, along the circle's normal;
* **other curves**: ``hull`` a ``Convex`` prism of points on the curve whose chords stay within
  :data:`~regrasp.plants.mujoco.curve_mesh.MESH_SAGITTA` (0.1 µm) of it (only the links touch it), and each
  ``tips<i>`` a **tangent face**: a ``Box`` whose face lies on the eroded curve's tangent at the foot ξ of tip i's
  centre on the curve (:func:`tangent_face`), which the plant puts there before each Drake step
  (``SceneGraph.ChangeShape`` on its context; :class:`DrakeHand` ``face_filter``). Of the geometry, Drake's discrete
  solver uses only the pair's penetration, normal and witness points at the step's start (it takes the penetration
  as linear over the step), and a face tangent at the foot gives exactly the eroded curve's: a tip placed on the
  curve starts ``contact_depth`` deep to 1e-16 m along its normal, and a finger sliding round an ellipse with a = b
  on tangent faces takes the disc's path on its cylinders to 1e-12 m. A ``Convex`` mesh of the eroded curve (the
  MuJoCo plant's) would not do: Drake's sphere–``Convex`` penetration is FCL's GJK/EPA, whose tolerance leaves the
  normal of a 0.4 µm contact on a mesh of nearly parallel facets off by up to 0.37 rad (by more than 1 mrad at a
  third of the places on the ellipse of the tests), a friction cone tilted that much.

Drake's step bounds how fast a contact may slide over a curve: the solver's linear penetration misses the surface's
turning away under a tip sliding at v, by v²h²κ/2 over a step h, a force error of k h² v² κ / 2 that the next step's
exact penetration undoes. At the defaults (k = 1e7 N/m, h = 0.1 ms) that is 0.3 N at 0.25 m/s over a 1 cm radius,
where a slide chatters (the normal force swings step to step) and carries about 0.31 f_n of friction for μ = 0.5; at
h = 20 µs it slides at μ f_n (``tests/plants/drake/test_curved_drake.py``). A held or slowly sliding contact is
unaffected.

**Contacts.** Drake's point contact (``contact_model="point"``) on its discrete solver: compliant normal force
:math:`f_n = k x (1 + d \dot x)_+` (penetration x, ``point_contact_stiffness`` k, ``hunt_crossley_dissipation``
d) and regularized Coulomb friction. Each geometry gets stiffness 2k (Drake puts the two in series: k) and
dissipation d (combined weighted by the stiffnesses: d). Collision filters leave tip i against ``tips<i>`` and
the links against ``hull``; nothing else (no finger–finger, tip–hull or link–tips contacts). Gravity is the
scenario's, in the hand's plane.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from xml.etree import ElementTree

import numpy as np

from ...core.contact import Friction
from ...core.curves import CurvedObject, Disc
from ...core.exceptions import FingerModelError, InvalidParameterError, MissingDependencyError
from ...core.polygon import ConvexPolygon
from ...core.validation import (
    as_finite_float,
    as_positive_float,
    as_tip_radius,
    check_fields,
    expect_sequence_of,
    expect_type,
)
from ...model.collision import checked_link_shapes, default_tip_clearance
from ...model.finger import Finger
from ..mujoco.curve_mesh import MESH_SAGITTA, check_erosion, curvature_table, curve_points
from ..mujoco.mjcf import eroded_vertices

__all__ = ["APPROXIMATIONS", "DrakeHand", "DrakeSettings", "build_drake", "require_drake", "tangent_face"]

#: The discrete contact approximations the plant takes: the two convex ones that use Hunt–Crossley dissipation.
APPROXIMATIONS = ("lagged", "similar")


@dataclass(frozen=True)
class DrakeSettings:
    r"""Drake's physics for the third plant (``docs/derivations.md``, "A third plant: Drake").

    Attributes:
        tip_radius: r [m], the fingertips' sphere radius (at most 5 cm,
            :data:`~regrasp.core.validation.MAX_TIP_RADIUS`).
        time_step: Drake's discrete step [s]; the plant takes ``round(dt / time_step)`` of them per control step,
            with the torques held (zero-order hold). On a curve a contact sliding at v over a curvature κ needs
            k time_step² v² κ well below its normal force (the module docstring): 20 µs for 0.25 m/s over 1 cm.
        point_contact_stiffness: k [N/m] of every contact (tip–object and link–object).
        hunt_crossley_dissipation: d [s/m] of every contact: the normal force is k x (1 + d ẋ).
        approximation: Drake's discrete contact approximation, ``"lagged"`` (the default: friction bounded by the
            normal force at the step's start, no "gliding" of sliding contacts, Drake's recommended one) or
            ``"similar"``. Both are convex (the SAP solver always converges) and use Hunt–Crossley dissipation;
            ``"sap"`` is not offered (it replaces the dissipation by a linear Kelvin–Voigt relaxation time) nor
            ``"tamsi"`` (non-convex, deprecated in Drake).
        stiction_tolerance: v_s [m/s], the friction's regularization: Drake's friction is
            μ f_n s / √(1 + s²) with s = |v_t| / ε and ε = max(v_s, μ R_t n₀) (R_t SAP's own regularization, n₀ the
            previous step's normal impulse: about 10 µm/s at a 0.1 ms step, so smaller v_s change little). A stuck
            contact at a fraction ρ of its cone creeps at ε ρ / √(1 − ρ²).
        near_rigid_threshold: SAP's near-rigid threshold β [-] (0: off): contacts stiffer than the step can
            resolve are softened (Drake's default, 1).
        object_thickness: The object prisms' extent along z [m] (the tips and links lie at z = 0).
        contact_depth: The prisms the tips touch are eroded by r less this [m], so that a tip the point-contact
            model puts on an edge starts this deep (a preload of k × depth, 4 N by default: a compliant contact
            carries force only when penetrating, and a tip placed on the surface flies in under the law's squeeze
            while its tangential force is already there, a slip at the first step of Figure 3.4's hold).

    Friction: every contact gets ``CoulombFriction(μ_s, μ_k)``, but Drake's discrete solver uses only μ_k (the
    "dynamic" coefficient: ``GetCombinedDynamicCoulombFriction`` in its discrete update; measured in
    ``tests/plants/drake/test_plant.py``): a contact breaks away at μ_k f_n, and the plant reports
    ``Friction(μ_k)``.
    """

    tip_radius: float = 2.5e-4
    time_step: float = 1e-4
    point_contact_stiffness: float = 1e7
    hunt_crossley_dissipation: float = 10.0
    approximation: str = "lagged"
    stiction_tolerance: float = 1e-5
    near_rigid_threshold: float = 1.0
    object_thickness: float = 0.02
    contact_depth: float = 4e-7

    def __post_init__(self):
        check_fields(self, as_tip_radius, ("tip_radius",))
        check_fields(self, as_positive_float, ("time_step", "point_contact_stiffness",
                                               "stiction_tolerance", "object_thickness"))
        check_fields(self, as_positive_float, ("hunt_crossley_dissipation", "near_rigid_threshold", "contact_depth"),
                     allow_zero=True)
        if not 1e-6 <= self.time_step <= 1e-3:
            raise InvalidParameterError("time_step", self.time_step, "a step from 1e-6 to 1e-3 s")
        if not isinstance(self.approximation, str) or self.approximation not in APPROXIMATIONS:
            raise InvalidParameterError("approximation", self.approximation, f"one of {', '.join(APPROXIMATIONS)} "
                                        "(the convex approximations with Hunt-Crossley dissipation)")


def require_drake() -> ModuleType:
    """The ``pydrake`` module, or a :class:`~regrasp.core.exceptions.MissingDependencyError` naming the extra."""
    try:
        import pydrake
        import pydrake.multibody.plant  # (the compiled library: a broken install fails here)
    except ImportError as exc:
        raise MissingDependencyError("drake", "drake", "the Drake plant") from exc
    return pydrake


@dataclass(frozen=True, eq=False)
class DrakeHand:
    """The built diagram and the indices the plant needs.

    Attributes:
        diagram: The ``Diagram`` (the plant and its scene graph).
        plant: The ``MultibodyPlant`` (discrete, finalized).
        finger_q, finger_v: The fingers' joints' position and velocity indices in the plant's q and v, (2m,)
            (finger by finger, proximal first).
        object_q, object_v: The planar joint's (x, y, rotation), (3,).
        tip_bodies: Per finger, the body its tip sphere is on (whose frame is the tip frame).
        geometries: geometry id -> ("tip", finger, -1), ("link", finger, link) or ("object", -1, -1).
        object_body: The object's body index.
        link_bodies: Per finger, its (proximal, distal) link bodies (their masses scale).
        friction: Each contact's friction coefficient in the model [-] (μ_k: what the discrete solver uses).
        settings: The :class:`DrakeSettings` it was built with.
        sagitta: The chord error [m] of a curved object's ``hull`` mesh (0 for a disc's cylinder and a polygon's
            prism).
        scene_graph: The ``SceneGraph`` (its context holds the tangent faces' poses).
        faces: Per finger, the geometry id of its ``tips<i>``.
        face_filter: None, or (a curved object other than a disc) the ``CollisionFilterDeclaration`` that leaves each
            ``tips<i>``, a tangent face the plant re-places before each Drake step (:func:`tangent_face`), against tip
            i alone: ``SceneGraph.ChangeShape`` drops a geometry's filters, the plant applies it again after.
    """

    diagram: object
    plant: object
    finger_q: np.ndarray
    finger_v: np.ndarray
    object_q: np.ndarray
    object_v: np.ndarray
    tip_bodies: tuple
    geometries: dict
    object_body: object
    link_bodies: tuple
    friction: tuple[float, ...]
    settings: DrakeSettings
    sagitta: float = 0.0
    scene_graph: object = None
    faces: tuple = ()
    face_filter: object = None


def _urdf_text(finger: Finger) -> str:
    """``finger``'s URDF file, without its visual and collision elements."""
    path = Path(finger.source)
    if not path.is_file():
        raise FingerModelError("the Drake plant reads the finger's URDF file, and this finger has none (built "
                               "from text? write it to a file and use Finger.from_urdf)", source=finger.source)
    try:
        root = ElementTree.fromstring(path.read_text(encoding="utf-8"))
    except ElementTree.ParseError as exc:
        raise FingerModelError(f"not XML: {exc}", source=finger.source) from exc
    for link in root.iter("link"):
        for child in [c for c in link if c.tag in ("visual", "collision")]:
            link.remove(child)
    return ElementTree.tostring(root, encoding="unicode")


def _shape(shape):
    """A link's coal collision shape as Drake's."""
    from pydrake.geometry import Box, Capsule, Cylinder

    kind = type(shape.geometry).__name__
    g = shape.geometry
    if kind == "Cylinder":
        return Cylinder(float(g.radius), 2.0 * float(g.halfLength))
    if kind == "Capsule":
        return Capsule(float(g.radius), 2.0 * float(g.halfLength))
    if kind == "Box":
        return Box(*(2.0 * np.asarray(g.halfSide, dtype=float)).tolist())
    raise FingerModelError(f"the Drake plant cannot use a {kind} collision shape (cylinder, capsule or box)",
                           shape=shape.name)


def _properties(stiffness: float, dissipation: float, friction: Friction | None):
    from pydrake.geometry import AddContactMaterial, ProximityProperties
    from pydrake.multibody.plant import CoulombFriction

    props = ProximityProperties()
    mu = Friction(1.0) if friction is None else friction
    AddContactMaterial(dissipation=dissipation, point_stiffness=2.0 * stiffness,
                       friction=CoulombFriction(mu.static, mu.kinetic), properties=props)
    return props


def _prism(vertices: np.ndarray, thickness: float, label: str):
    from pydrake.geometry import Convex

    half = 0.5 * thickness
    points = np.array([[x, y, z] for x, y in np.asarray(vertices, dtype=float).tolist() for z in (-half, half)])
    return Convex(points.T.copy(), label)


def tangent_face(curve: CurvedObject, offset: float, xi: float, thickness: float) -> tuple[object, object]:
    r"""A tip's face on a curve at ξ [m] (module docstring): (a ``Box`` of side twice the curve's diameter and
    ``thickness`` [m] along z, its pose in the object's frame), the box's face on the tangent line of the parallel
    curve ``offset`` [m] inwards at ξ, the box inside it: the face's outward normal is −n(ξ) and it passes through
    :math:`c(\xi) + \mathrm{offset}\,n(\xi)`."""
    from pydrake.geometry import Box
    from pydrake.math import RigidTransform, RotationMatrix

    cx, cy, nx, ny, _ = curve.local_floats(xi)
    size = 2.0 * curve.scale
    reach = offset + 0.5 * size  # (the box's centre, inwards from the curve)
    rotation = RotationMatrix(np.array([[nx, -ny, 0.0], [ny, nx, 0.0], [0.0, 0.0, 1.0]]))  # (box x along n)
    return Box(size, size, thickness), RigidTransform(rotation, [cx + reach * nx, cy + reach * ny, 0.0])


def _curve_prisms(curve: CurvedObject, offset: float, tip_radius: float, thickness: float) -> tuple[object, float,
                                                                                                    object]:
    """(the ``hull`` shape, its chord error [m], a function of a finger's index giving its ``tips<i>`` (shape, pose in
    the object frame)) of a curved object (module docstring), once its erosion by ``offset`` [m] is checked."""
    from pydrake.geometry import Cylinder
    from pydrake.math import RigidTransform

    kappa = curvature_table(curve)
    check_erosion(curve, offset, tip_radius, kappa)
    if isinstance(curve, Disc):
        return Cylinder(curve.radius, thickness), 0.0, lambda i: (Cylinder(curve.radius - offset, thickness),
                                                                  RigidTransform())
    points, sagitta = curve_points(curve, 0.0, curvature=kappa)
    assert sagitta <= MESH_SAGITTA, f"the hull mesh's chord error {sagitta:.3g} m exceeds {MESH_SAGITTA:g} m"
    return _prism(points, thickness, "hull"), sagitta, lambda i: tangent_face(curve, offset, 0.0, thickness)


def _add_finger(plant, index: int, finger: Finger, clearance: float, settings: DrakeSettings, props,
                friction: Friction):
    """Parse and weld finger ``index``; returns its joints, tip body, link bodies and (shape, link, geometry id)s."""
    from pydrake.geometry import Sphere
    from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix
    from pydrake.multibody.parsing import Parser
    from pydrake.multibody.tree import RevoluteJoint

    try:
        (instance,) = Parser(plant, f"f{index}").AddModelsFromString(_urdf_text(finger), "urdf")
    except RuntimeError as exc:  # Drake's parser raises RuntimeError with its message
        raise FingerModelError(f"Drake cannot parse it: {exc}", source=finger.source) from exc
    joints = [plant.get_joint(j) for j in plant.GetJointIndices(instance)]
    revolute = [j for j in joints if isinstance(j, RevoluteJoint)]
    if len(revolute) != 2 or len(joints) != 3:
        raise FingerModelError("Drake's parse does not have exactly two revolute joints and the tip's fixed one",
                               source=finger.source)
    children = {j.child_body().index() for j in joints}
    roots = [plant.get_body(b) for b in plant.GetBodyIndices(instance) if b not in children]
    proximal = [j for j in revolute if j.parent_body().index() == roots[0].index()]
    if len(roots) != 1 or len(proximal) != 1:
        raise FingerModelError("Drake's parse is not a chain root - proximal - distal - tip", source=finger.source)
    distal = revolute[1] if revolute[0] is proximal[0] else revolute[0]
    if not plant.HasBodyNamed(finger.tip_frame, instance):
        raise FingerModelError(f"Drake's parse has no '{finger.tip_frame}' link", source=finger.source)
    tip = plant.GetBodyByName(finger.tip_frame, instance)
    for joint in (proximal[0], distal):
        joint.set_position_limits([-np.inf], [np.inf])
        joint.set_velocity_limits([-np.inf], [np.inf])
    x, y, theta = finger.base_in_hand.tolist()
    plant.WeldFrames(plant.world_frame(), roots[0].body_frame(),
                     RigidTransform(RollPitchYaw(0.0, 0.0, theta), [x, y, 0.0]))
    links = (proximal[0].child_body(), distal.child_body())
    shapes = []
    for k, shape in enumerate(checked_link_shapes(finger, clearance)):
        place = shape.placement_in_joint
        pose = RigidTransform(RotationMatrix(np.asarray(place.rotation, dtype=float)),
                              np.asarray(place.translation, dtype=float))
        gid = plant.RegisterCollisionGeometry(links[shape.link], pose, _shape(shape),
                                              f"f{index}/link{shape.link + 1}_shape{k}", props)
        shapes.append((gid, shape.link))
    tip_id = plant.RegisterCollisionGeometry(tip, RigidTransform(), Sphere(settings.tip_radius), f"f{index}/tip",
                                             _properties(settings.point_contact_stiffness,
                                                         settings.hunt_crossley_dissipation, friction))
    return (proximal[0], distal), tip, links, tip_id, tuple(shapes)


def build_drake(fingers: Sequence[Finger], polygon: ConvexPolygon | CurvedObject, frictions: Sequence[Friction], *,
                gravity_in_hand: Sequence[float] = (0.0, -9.81), object_mass: float | None = None,
                object_inertia: float | None = None, tip_clearance: Sequence[float | None] | None = None,
                settings: DrakeSettings = DrakeSettings()) -> DrakeHand:
    r"""The hand and the object as a Drake diagram (module docstring).

    Args:
        fingers: The fingers (from URDF files), finger i touching contact i.
        polygon: The object: a convex polygon or a curved object.
        frictions: Each contact's friction (``CoulombFriction(μ_s, μ_k)``; Drake's discrete solver uses μ_k).
        gravity_in_hand: Gravity [m/s²] in the hand frame.
        object_mass: The object's mass [kg] (default: the object's).
        object_inertia: The object's inertia [kg m²] (default: the object's).
        tip_clearance: Per finger, the distal link's tip clearance [m] (None: the default).
        settings: :class:`DrakeSettings`.

    Raises:
        FingerModelError: a finger has no URDF file, or one Drake cannot parse, or a shape Drake cannot take.
        InvalidParameterError: bad arguments, or a tip radius the object cannot be eroded by (a polygon's edge
            would vanish; a curve's smallest radius of curvature is below r − ``contact_depth``).
    """
    require_drake()
    from pydrake.geometry import CollisionFilterDeclaration, GeometrySet
    from pydrake.math import RigidTransform
    from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlantConfig
    from pydrake.multibody.tree import PlanarJoint, RotationalInertia, SpatialInertia
    from pydrake.systems.framework import DiagramBuilder

    fingers = expect_sequence_of("fingers", fingers, Finger, "Finger (Finger.from_urdf)")
    expect_type("polygon", polygon, (ConvexPolygon, CurvedObject), "a ConvexPolygon or a CurvedObject")
    expect_type("settings", settings, DrakeSettings, "a DrakeSettings")
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
    s = settings
    offset, sagitta, curved = s.tip_radius - s.contact_depth, 0.0, isinstance(polygon, CurvedObject)
    if curved:
        hull_shape, sagitta, tips_prism = _curve_prisms(polygon, offset, s.tip_radius, s.object_thickness)
    else:
        tip_vertices = eroded_vertices(polygon, offset, "tip_radius")
        hull_shape = _prism(polygon.vertices, s.object_thickness, "hull")

        def tips_prism(i: int):
            return _prism(tip_vertices, s.object_thickness, f"tips{i}"), RigidTransform()

    builder = DiagramBuilder()
    config = MultibodyPlantConfig(time_step=s.time_step, contact_model="point", discrete_contact_approximation=
                                  s.approximation, stiction_tolerance=s.stiction_tolerance,
                                  sap_near_rigid_threshold=s.near_rigid_threshold, use_sampled_output_ports=False)
    plant, scene_graph = AddMultibodyPlant(config, builder)
    plant.mutable_gravity_field().set_gravity_vector([gx, gy, 0.0])
    body = plant.AddRigidBody("object", SpatialInertia.MakeFromCentralInertia(
        mass, np.zeros(3), RotationalInertia(inertia, inertia, inertia)))  # (only the z moment matters)
    planar = plant.AddJoint(PlanarJoint("object_planar", plant.world_frame(), body.body_frame()))
    link_props = _properties(s.point_contact_stiffness, s.hunt_crossley_dissipation, None)
    hull = plant.RegisterCollisionGeometry(body, RigidTransform(), hull_shape, "hull", link_props)
    geometries: dict = {hull: ("object", -1, -1)}
    joints, tips, links, mus, sets = [], [], [], [], []
    for i, finger in enumerate(fingers):
        clearance = default_tip_clearance(finger) if clearances[i] is None else as_positive_float(
            "tip_clearance", clearances[i], allow_zero=True)
        pair, tip, link_bodies, tip_id, shapes = _add_finger(plant, i, finger, clearance, s, link_props, frictions[i])
        shape, pose = tips_prism(i)
        face = plant.RegisterCollisionGeometry(
            body, pose, shape, f"tips{i}",
            _properties(s.point_contact_stiffness, s.hunt_crossley_dissipation, frictions[i]))
        joints.append(pair)
        tips.append(tip)
        links.append(link_bodies)
        mus.append(frictions[i].kinetic)
        geometries[tip_id] = ("tip", i, -1)
        geometries[face] = ("object", -1, -1)
        geometries.update({gid: ("link", i, link) for gid, link in shapes})
        sets.append((tip_id, face, [gid for gid, _ in shapes]))
    manager = scene_graph.collision_filter_manager()
    hand = GeometrySet([g for tip_id, _, shapes in sets for g in (tip_id, *shapes)])
    declaration = CollisionFilterDeclaration().ExcludeWithin(hand)
    for i, (tip_id, face, shapes) in enumerate(sets):
        others = [f for j, (_, f, _) in enumerate(sets) if j != i]
        declaration.ExcludeBetween(GeometrySet([tip_id]), GeometrySet([hull, *others]))
    declaration.ExcludeBetween(GeometrySet([g for _, _, shapes in sets for g in shapes]),
                               GeometrySet([face for _, face, _ in sets]))
    manager.Apply(declaration)
    face_filter = None
    if curved and not isinstance(polygon, Disc):
        face_filter = CollisionFilterDeclaration()
        for i, (tip_id, face, _) in enumerate(sets):
            face_filter.ExcludeBetween(GeometrySet([face]), GeometrySet([g for g in geometries if g != tip_id]))
        manager.Apply(face_filter)
    plant.Finalize()
    diagram = builder.Build()
    return DrakeHand(diagram, plant, np.array([j.position_start() for pair in joints for j in pair]),
                     np.array([j.velocity_start() for pair in joints for j in pair]),
                     np.arange(planar.position_start(), planar.position_start() + 3),
                     np.arange(planar.velocity_start(), planar.velocity_start() + 3), tuple(tips), geometries,
                     body, tuple(links), tuple(mus), s, sagitta, scene_graph, tuple(face for _, face, _ in sets),
                     face_filter)

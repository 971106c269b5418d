r"""Link–object collision for the grasp planner (paper Definition 2.2).

Two models of the finger's links:

* ``ideal`` — each link is the segment between its joints. A link *collides* when the
  segment meets the **open** interior of the convex polygon; touching the boundary
  (passing exactly through a vertex, lying along an edge) is not a collision.
* ``urdf`` — each link is its URDF collision geometry, tested against the polygon
  extruded to a prism with ``coal``; a link collides when coal's signed distance is
  negative. The distal link always touches the object at the fingertip (its end
  cap straddles the contact edge), which is contact, not collision. We exclude it by
  removing a *tip clearance* :math:`\rho` [m] from the tip end of every distal
  shape: a cylinder, capsule or box along the link is shortened by :math:`\rho` and
  shifted back towards joint 2 by :math:`\rho/2`. What remains still collides when the
  link approaches the edge at an angle :math:`\alpha` with
  :math:`\tan\alpha < r_2/\rho` (the shortened rim dips under the edge), which is a
  real limitation of a flat-ended link of radius :math:`r_2`. As :math:`r_2 \to 0` at
  fixed :math:`\rho` the ``urdf`` envelope converges to the ``ideal`` one.

Where every kept shape is symmetric about the hand plane (a box turned about z, a cylinder or
capsule with its axis in the plane, a sphere centred in it), its distance to the prism is the planar
distance of its footprint to the polygon (:mod:`regrasp.kernels.footprint` derives it), and
:attr:`UrdfCollisionChecker.footprints` gives those footprints for the envelope's compiled path;
coal stays the reference and the checker of the closed form (``tests/kernels/test_footprint.py``).
"""

from __future__ import annotations

import math

import coal
import numpy as np
import pinocchio as pin

from ..core.curves import CurvedObject
from ..core.exceptions import FingerModelError
from ..core.polygon import ConvexPolygon
from ..core.validation import as_finite_array, as_positive_float, expect_type
from ..kernels.footprint import FOOTPRINT
from .finger import Finger, LinkShape

__all__ = ["UrdfCollisionChecker", "checked_link_shapes", "default_tip_clearance", "planar_footprint",
           "segment_hits_polygon"]


#: How far [m, or a unit vector's component] a shape may be from the symmetric placement of
#: :func:`planar_footprint` (an axis out of the plane, a centre off it) and still count as in it.
FOOTPRINT_TOLERANCE = 1e-9

#: Safety margin of the certified-free shortcut of :meth:`UrdfCollisionChecker.links_collide`,
#: as a fraction of the finger's reach l1 + l2.
_CERTIFY_MARGIN = 1e-4


def segment_hits_polygon(a: np.ndarray, b: np.ndarray, normals: np.ndarray, offsets: np.ndarray,
                         *, eps: float) -> bool:
    r"""Whether segment [a, b] meets the open interior of a convex polygon.

    The polygon is :math:`\{y : n_k \cdot y > o_k\ \forall k\}` (inward normals ``normals``
    (n, 2), ``offsets`` (n,)). Clip the segment :math:`a + t (b - a)`, :math:`t \in [0, 1]`,
    against every closed half-plane (Cyrus–Beck); it meets the open interior iff the
    clipped range is not empty and its midpoint is inside by more than ``eps`` [m]
    (a segment through a vertex or along an edge only touches the boundary).
    """
    (ax, ay), (bx, by) = np.asarray(a, dtype=float).tolist(), np.asarray(b, dtype=float).tolist()
    halfplanes = [(nx, ny, off) for (nx, ny), off in zip(np.asarray(normals, dtype=float).tolist(),
                                                          np.asarray(offsets, dtype=float).tolist())]
    return segment_hits_halfplanes(ax, ay, bx, by, halfplanes, eps)


def segment_hits_halfplanes(ax: float, ay: float, bx: float, by: float,
                            halfplanes: list[tuple[float, float, float]], eps: float) -> bool:
    r""":func:`segment_hits_polygon` on plain floats: the segment (ax, ay)–(bx, by) [m] and the
    polygon as ``(n_x, n_y, o)`` half-planes :math:`n \cdot y > o` (no validation; hot paths)."""
    t0, t1 = 0.0, 1.0
    dists = []  # signed distances of a and b to each edge line (>0 inside)
    for nx, ny, off in halfplanes:
        fa = nx * ax + ny * ay - off
        fb = nx * bx + ny * by - off
        if fa < 0.0:
            if fb < 0.0:
                return False
            t0 = max(t0, fa / (fa - fb))
        elif fb < 0.0:
            t1 = min(t1, fa / (fa - fb))
        if t1 <= t0:
            return False
        dists.append((fa, fb))
    tm = 0.5 * (t0 + t1)
    return min(fa + tm * (fb - fa) for fa, fb in dists) > eps


def _truncate_distal(shape: LinkShape, tip_in_joint: np.ndarray, clearance: float,
                     source: str) -> LinkShape | None:
    """Shorten a distal shape along the link by ``clearance`` [m] at its tip end."""
    if clearance == 0.0:
        return shape
    geom = shape.geometry
    placement = shape.placement_in_joint
    link_dir = tip_in_joint / np.linalg.norm(tip_in_joint)
    if isinstance(geom, (coal.Cylinder, coal.Capsule)):
        axis_local = np.array([0.0, 0.0, 1.0])
        half = float(geom.halfLength)
    elif isinstance(geom, coal.Box):
        dims = np.asarray(geom.halfSide, dtype=float)
        axis_world = placement.rotation.T @ np.array([link_dir[0], link_dir[1], 0.0])
        k = int(np.argmax(np.abs(axis_world)))
        axis_local = np.eye(3)[k]
        half = float(dims[k])
    else:
        raise FingerModelError(
            f"cannot apply the tip clearance to a {type(geom).__name__} collision shape "
            "(supported on the distal link: cylinder, capsule, box)",
            source=source,
            shape=shape.name,
        )
    axis = placement.rotation @ axis_local
    if abs(abs(axis[0] * link_dir[0] + axis[1] * link_dir[1]) - 1.0) > 1e-9 or abs(axis[2]) > 1e-9:
        raise FingerModelError(
            "the distal collision shape is not aligned with the link (joint 2 to tip), so the tip "
            "clearance cannot be applied",
            source=source,
            shape=shape.name,
        )
    new_half = half - clearance / 2.0
    if new_half <= 0.0:
        return None
    toward_tip = np.sign(axis[0] * link_dir[0] + axis[1] * link_dir[1]) * axis
    if isinstance(geom, coal.Cylinder):
        new_geom = coal.Cylinder(float(geom.radius), 2.0 * new_half)
    elif isinstance(geom, coal.Capsule):
        new_geom = coal.Capsule(float(geom.radius), 2.0 * new_half)
    else:
        sides = 2.0 * np.asarray(geom.halfSide, dtype=float)
        sides[int(np.argmax(np.abs(axis_local)))] = 2.0 * new_half
        new_geom = coal.Box(*sides)
    new_placement = pin.SE3(placement.rotation, placement.translation - toward_tip * clearance / 2.0)
    return LinkShape(link=shape.link, name=shape.name, geometry=new_geom, placement_in_joint=new_placement)


def planar_footprint(geometry: object, placement: pin.SE3, plane_z: float, half_thickness: float,
                     link: int = 0) -> tuple | None:
    r"""The planar footprint of a collision shape placed at ``placement`` (a frame whose z-axis is the hand's),
    as a :data:`~regrasp.kernels.footprint.FOOTPRINT` tuple (link, centre, unit axis, half-sides along and
    across it, dilation radius, largest :math:`|z - z_p|` [m]), or None when the closed form of
    :mod:`regrasp.kernels.footprint` does not apply: a geometry other than a box, cylinder, capsule or sphere,
    a shape not symmetric about the plane :math:`z = z_p` (``plane_z``: the object's mid-plane in this frame;
    the centre off it, a cylinder's or capsule's axis out of it, a box not turned about z only, each beyond
    :data:`FOOTPRINT_TOLERANCE`), or one reaching beyond the prism's half-height ``half_thickness`` [m]."""
    rot, trans = np.asarray(placement.rotation), np.asarray(placement.translation)
    if abs(trans[2] - plane_z) > FOOTPRINT_TOLERANCE:
        return None
    center = (float(trans[0]), float(trans[1]))
    if isinstance(geometry, (coal.Cylinder, coal.Capsule)):
        axis = rot[:, 2]
        if abs(axis[2]) > FOOTPRINT_TOLERANCE:
            return None
        radius = float(geometry.radius)
        if isinstance(geometry, coal.Cylinder):
            sides, rad = (float(geometry.halfLength), radius), 0.0
        else:
            sides, rad = (float(geometry.halfLength), 0.0), radius
        zext = radius
    elif isinstance(geometry, coal.Box):
        half = np.asarray(geometry.halfSide, dtype=float)
        vertical = [j for j in range(3) if abs(abs(rot[2, j]) - 1.0) <= FOOTPRINT_TOLERANCE]
        if len(vertical) != 1:
            return None
        along, across = [j for j in range(3) if j != vertical[0]]
        axis = rot[:, along]
        sides, rad, zext = (float(half[along]), float(half[across])), 0.0, float(half[vertical[0]])
    elif isinstance(geometry, coal.Sphere):
        axis = np.array([1.0, 0.0, 0.0])
        sides, rad = (0.0, 0.0), float(geometry.radius)
        zext = rad
    else:
        return None
    if zext > half_thickness:
        return None
    norm = math.hypot(axis[0], axis[1])
    return (int(link), *center, float(axis[0] / norm), float(axis[1] / norm), *sides, rad, zext)


def _reach_in_plane(geometry, placement: pin.SE3) -> float:
    """Largest distance [m] from the z-axis of a point of ``geometry`` placed at ``placement``
    (from the corners of its local bounding box, so an upper bound)."""
    geometry.computeLocalAABB()
    lo, hi = np.asarray(geometry.aabb_local.min_), np.asarray(geometry.aabb_local.max_)
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    points = corners @ placement.rotation.T + placement.translation
    return float(np.max(np.hypot(points[:, 0], points[:, 1])))


def _half_width(geometry) -> float:
    """Half the thickness [m] of a link shape across the link: a radius, or a box's middle half-side."""
    if hasattr(geometry, "radius"):
        return float(geometry.radius)
    if hasattr(geometry, "halfSide"):
        return float(sorted(np.asarray(geometry.halfSide, dtype=float))[1])
    return 0.0


def default_tip_clearance(finger: Finger) -> float:
    r"""The default tip clearance :math:`\rho` [m]: three times the distal link's half-width
    (a cylinder's or capsule's radius, a box's middle half-side)."""
    expect_type("finger", finger, Finger, "a Finger")
    return 3.0 * max((_half_width(s.geometry) for s in finger.link_shapes() if s.link == 1), default=0.0)


def checked_link_shapes(finger: Finger, tip_clearance: float) -> tuple[LinkShape, ...]:
    r"""The finger's collision shapes as the ``urdf`` geometry uses them: both links must have one, and the
    distal shapes are shortened by the tip clearance :math:`\rho` [m] (a shape shorter than :math:`\rho`
    is dropped). Raises :class:`~regrasp.core.exceptions.FingerModelError` naming the URDF and the shape when the
    finger's collision model cannot be used so (a scenario reader checks this at load)."""
    shapes = finger.link_shapes()
    for link in (0, 1):
        if not any(s.link == link for s in shapes):
            raise FingerModelError(
                f"link {link + 1} has no collision geometry, which the 'urdf' geometry mode needs "
                "(urdfdom silently drops <capsule> elements: use <cylinder> or <box>)",
                source=finger.source,
            )
    tip_in_joint = finger.model.frames[finger.tip_frame_id].placement.translation[:2]
    kept = []
    for shape in shapes:
        if shape.link == 1:
            shape = _truncate_distal(shape, tip_in_joint, tip_clearance, finger.source)
        if shape is not None:
            kept.append(shape)
    return tuple(kept)


class UrdfCollisionChecker:
    r"""Signed distances between a finger's URDF collision shapes and a polygon prism.

    Args:
        finger: The finger (its collision model must have a shape on each link).
        polygon: The object: a polygon, or a curved object (its :meth:`~regrasp.core.curves.CurvedObject.to_coal`
            prism: a disc's exact cylinder, else a circumscribed convex polygon).
        tip_clearance: :math:`\rho` [m] removed from the tip end of the distal shapes.
        half_thickness: Half height [m] of the object's prism; default: the finger's
            reach, far larger than any link radius so the 3-D distance is the planar one.
        coal_tolerance: Tolerance [m] of coal's GJK and EPA iterations; default: coal's (1e-6), which
            makes its distances accurate to about 1e-6 m (``tests/kernels/test_footprint.py``).
    """

    def __init__(self, finger: Finger, polygon: ConvexPolygon | CurvedObject, tip_clearance: float,
                 half_thickness: float | None = None, coal_tolerance: float | None = None):
        expect_type("finger", finger, Finger, "a Finger")
        expect_type("polygon", polygon, (ConvexPolygon, CurvedObject), "a ConvexPolygon or a CurvedObject")
        tip_clearance = as_positive_float("tip_clearance", tip_clearance, allow_zero=True)
        self.finger = finger
        self.tip_clearance = float(tip_clearance)
        self.shapes: tuple[LinkShape, ...] = checked_link_shapes(finger, tip_clearance)
        h = half_thickness if half_thickness is not None else sum(finger.link_lengths)
        #: Half height [m] of the object's prism.
        self.half_thickness = float(h)
        self.object_geometry = polygon.to_coal(h)
        #: coal distance queries asked by the collision tests (:meth:`links_collide`, :meth:`links_collide_kept`) so
        #: far.
        self.queries = 0
        # (a curve's collision shape lies within its circumscribed polygon, whose corners bound its radius)
        corners = polygon.circumscribed_polygon() if isinstance(polygon, CurvedObject) else polygon.vertices
        self._object_radius = float(np.max(np.hypot(corners[:, 0], corners[:, 1])))
        self._request = coal.DistanceRequest()
        self._request.enable_signed_distance = True
        if coal_tolerance is not None:
            coal_tolerance = as_positive_float("coal_tolerance", coal_tolerance)
            self._request.gjk_tolerance = coal_tolerance
            self._request.epa_tolerance = coal_tolerance
        self._result = coal.DistanceResult()
        self._init_planar_kinematics()

    def _init_planar_kinematics(self) -> None:
        r"""Precompute the planar fast path of :meth:`signed_distances`.

        Link k's *link frame* :math:`L_k` has its origin at joint k and its x-axis along the
        link (joint 1 → joint 2, joint 2 → tip). The finger is planar, so a shape's placement
        is :math:`L_k A` with a constant :math:`A` (from Pinocchio at q = 0). Coal distances
        are invariant under a common rigid motion, so each shape is tested at :math:`A`
        against the object at :math:`L_k^{-1} X` (X the object's placement), which is planar:
        per query only a z-rotation and a translation are written into a ``coal.Transform3s``.
        """
        finger = self.finger
        model, data = finger.model, finger.data
        pin.forwardKinematics(model, data, np.zeros(model.nq))
        tip = pin.updateFramePlacement(model, data, finger.tip_frame_id).translation
        points = [data.oMi[1].translation.copy(), data.oMi[2].translation.copy(), tip.copy()]
        self._link_frames0 = []  # link frames at q = 0: (angle psi_k [rad], placement L_k)
        for k in (0, 1):
            start, end = points[k], points[k + 1]
            psi = math.atan2(end[1] - start[1], end[0] - start[0])
            rot = np.eye(3)
            rot[:2, :2] = [[math.cos(psi), -math.sin(psi)], [math.sin(psi), math.cos(psi)]]
            self._link_frames0.append((psi, pin.SE3(rot, start)))
        self._l1 = float(np.linalg.norm(points[1][:2] - points[0][:2]))
        self._joint1 = points[0][:2].tolist()
        self._object = (0.0, 0.0, 1.0, 0.0)  # object pose (x, y, cos beta, sin beta), hand frame
        # per link: the object's transform L_k^-1 X (rotation and translation buffers, written
        # through flat memoryviews), the link's shapes (coal functor, placement A, index) and
        # the largest distance [m] of a shape point from the link's z-axis
        self._links = []
        footprints = [None] * len(self.shapes)
        for k in (0, 1):
            psi0, frame0 = self._link_frames0[k]
            rot, trans = np.eye(3), np.array([0.0, 0.0, -frame0.translation[2]])
            shapes, reach = [], 0.0
            for i, shape in enumerate(self.shapes):
                if shape.link == k:
                    a = frame0.actInv(data.oMi[k + 1] * shape.placement_in_joint)
                    shapes.append((coal.ComputeDistance(shape.geometry, self.object_geometry),
                                   coal.Transform3s(a.rotation, a.translation), i))
                    reach = max(reach, _reach_in_plane(shape.geometry, a))
                    footprints[i] = planar_footprint(shape.geometry, a, trans[2], self.half_thickness, k)
            views = (memoryview(rot).cast("B").cast("d"), memoryview(trans).cast("B").cast("d"))
            self._links.append((rot, trans, *views, coal.Transform3s(), shapes, reach))
        # (the coal functors hold raw pointers to the geometries: self.shapes and
        # self.object_geometry keep them alive)
        self._margin = _CERTIFY_MARGIN * sum(finger.link_lengths)
        self._certificates: list[tuple[float, ...] | None] = [None, None]
        self._footprints = None
        if all(fp is not None for fp in footprints):
            self._footprints = np.array(footprints, dtype=FOOTPRINT)
            self._footprints.flags.writeable = False

    @property
    def footprints(self) -> np.ndarray | None:
        """Every kept shape's planar footprint in its link frame (:data:`~regrasp.kernels.footprint.FOOTPRINT`
        records, in the order of :attr:`shapes`; read-only), or None when a shape has none
        (:func:`planar_footprint`): then only coal gives this finger's distances. The link frame of link k
        has its origin at joint k and its x-axis along the link (joint 1 to joint 2, joint 2 to the tip)."""
        return self._footprints

    @property
    def joint1(self) -> tuple[float, float]:
        """Joint 1's axis (x, y) [m] in the hand frame (link 1's frame origin)."""
        return tuple(self._joint1)

    def set_object_pose(self, x: float, y: float, beta: float) -> None:
        """Object pose (x [m], y [m], beta [rad]) in the hand frame for :meth:`links_collide` (no validation)."""
        self._object = (x, y, math.cos(beta), math.sin(beta))
        self._certificates = [None, None]

    def _object_in_link(self, k: int, ox: float, oy: float, c: float, s: float):
        """The coal transform :math:`L_k^{-1} X` for link frame origin (ox, oy), direction (c, s)."""
        x, y, cb, sb = self._object
        rot, trans, rv, tv, tf, _, _ = self._links[k]
        cj = c * cb + s * sb  # rotation by beta - psi
        sj = c * sb - s * cb
        rv[0] = cj
        rv[1] = -sj
        rv[3] = sj
        rv[4] = cj
        dx, dy = x - ox, y - oy
        tv[0] = c * dx + s * dy
        tv[1] = c * dy - s * dx
        tf.setTransform(rot, trans)
        return tf

    def _link_distance(self, k: int, ox: float, oy: float, c: float, s: float) -> float:
        """Smallest signed distance [m] of link k's shapes to the object, stopping at the first
        negative one (link frame at joint (ox, oy) [m] with direction (c, s); +inf if no shapes)."""
        shapes = self._links[k][5]
        if not shapes:
            return math.inf
        request, result = self._request, self._result
        tf = self._object_in_link(k, ox, oy, c, s)
        nearest = math.inf
        for distance, placement, _ in shapes:
            self.queries += 1
            result.clear()
            nearest = min(nearest, distance(placement, tf, request, result))
            if nearest < 0.0:
                break
        return nearest

    def links_collide(self, c1: float, s1: float, x2: float, y2: float, c2: float, s2: float) -> bool:
        r"""Whether any link shape penetrates the object (pose from :meth:`set_object_pose`).

        The finger's posture is given by link 1's direction (c1, s1) = (cos psi1, sin psi1),
        the elbow (x2, y2) [m] in the hand frame and link 2's direction (c2, s2). No validation
        (hot path of the ``urdf`` envelope), and coal is called only where needed:

        * it stops at the first penetrating shape;
        * a link that coal found free at distance :math:`\delta` [m] (the last such query for
          this object pose) is free wherever none of its points has moved by :math:`\delta` or
          more (distances are 1-Lipschitz in a rigid motion). Joint move :math:`\Delta o` and
          direction :math:`u` move a shape point by at most :math:`|\Delta o| + |\Delta u| R`
          (:math:`R`: the largest distance of a point of the link's shapes from its joint axis),
          so when that is below :math:`\delta (1 - 10^{-3}) - m` (:math:`m = 10^{-4} (l_1 + l_2)`,
          far above coal's tolerance) the link is free without a coal call, and coal's verdict
          there would be the same.
        """
        hypot = math.hypot
        cert = self._certificates[0]  # (cos psi, sin psi, budget [m]): link 1 turns about joint 1
        if cert is None or hypot(c1 - cert[0], s1 - cert[1]) * self._links[0][6] >= cert[2]:
            dist = self._link_distance(0, *self._joint1, c1, s1)
            if dist < 0.0:
                return True
            self._certificates[0] = (c1, s1, dist * (1.0 - 1e-3) - self._margin)
        cert = self._certificates[1]  # (x, y, cos psi, sin psi, budget [m])
        if cert is None or (hypot(x2 - cert[0], y2 - cert[1])
                            + hypot(c2 - cert[2], s2 - cert[3]) * self._links[1][6] >= cert[4]):
            dist = self._link_distance(1, x2, y2, c2, s2)
            if dist < 0.0:
                return True
            self._certificates[1] = (x2, y2, c2, s2, dist * (1.0 - 1e-3) - self._margin)
        return False

    def links_collide_kept(self, kept: list, c1: float, s1: float, x2: float, y2: float, c2: float,
                           s2: float) -> bool:
        r""":meth:`links_collide` with certificates that the caller keeps and that outlive the object pose.

        ``kept`` is a list of two entries (None at first), one per link, which this method reads and
        writes: the link frame (joint x, y [m], direction cos, sin), the object pose (x, y [m], cos,
        sin of beta) and the signed distance :math:`\delta` [m] coal returned there (the smallest over
        the link's shapes, or the first negative one). Signed distances of convex shapes are
        1-Lipschitz in a rigid motion of either, so coal's verdict stands wherever no point of the
        link's shapes or of the object has moved by :math:`|\delta| (1 - 10^{-3}) - m` or more (the
        margin of :meth:`links_collide`): a shape point by at most :math:`|\Delta o| + |\Delta u| R`
        (as there), an object point by at most :math:`|\Delta x_o| + |\Delta(\cos\beta, \sin\beta)|
        R_o` (:math:`R_o`: the object's largest vertex radius). A negative :math:`\delta` certifies a
        collision the same way. Coal is called for a link only when its certificate does not hold.
        The object pose is the one of :meth:`set_object_pose`; no validation (hot path).
        """
        x, y, cb, sb = self._object
        hypot = math.hypot
        r_o = self._object_radius
        cert = kept[0]  # link 1 turns about joint 1
        if cert is None or (hypot(c1 - cert[2], s1 - cert[3]) * self._links[0][6] + hypot(x - cert[4], y - cert[5])
                            + hypot(cb - cert[6], sb - cert[7]) * r_o >= abs(cert[8]) * (1.0 - 1e-3) - self._margin):
            ox, oy = self._joint1
            dist = self._link_distance(0, ox, oy, c1, s1)
            kept[0] = cert = (ox, oy, c1, s1, x, y, cb, sb, dist)
        if cert[8] < 0.0:
            return True
        cert = kept[1]
        if cert is None or (hypot(x2 - cert[0], y2 - cert[1]) + hypot(c2 - cert[2], s2 - cert[3]) * self._links[1][6]
                            + hypot(x - cert[4], y - cert[5]) + hypot(cb - cert[6], sb - cert[7]) * r_o
                            >= abs(cert[8]) * (1.0 - 1e-3) - self._margin):
            dist = self._link_distance(1, x2, y2, c2, s2)
            kept[1] = cert = (x2, y2, c2, s2, x, y, cb, sb, dist)
        return cert[8] < 0.0

    def _posture(self, q) -> tuple[float, float, float, float, float, float]:
        """(cos psi1, sin psi1, elbow x [m], elbow y [m], cos psi2, sin psi2) for joint positions q."""
        q1, q2 = np.asarray(q, dtype=float).tolist()
        psi1 = self._link_frames0[0][0] + q1
        psi2 = self._link_frames0[1][0] + q1 + q2
        c1, s1 = math.cos(psi1), math.sin(psi1)
        ox, oy = self._joint1
        return c1, s1, ox + self._l1 * c1, oy + self._l1 * s1, math.cos(psi2), math.sin(psi2)

    def link_frames(self, q: np.ndarray) -> np.ndarray:
        """The link frames at joint positions ``q`` [rad] (hand frame): (joint 1 x, y [m], cos psi1, sin psi1,
        elbow x, y [m], cos psi2, sin psi2), psi_k the direction of link k (the ``posture`` of
        :func:`~regrasp.kernels.footprint.footprint_distances`)."""
        c1, s1, x2, y2, c2, s2 = self._posture(as_finite_array("q", q, (2,)))
        return np.array([*self._joint1, c1, s1, x2, y2, c2, s2])

    def _set_object(self, pose_object_in_hand: np.ndarray | pin.SE3) -> None:
        if isinstance(pose_object_in_hand, pin.SE3):
            rot, trans = pose_object_in_hand.rotation, pose_object_in_hand.translation
            self.set_object_pose(float(trans[0]), float(trans[1]), math.atan2(rot[1, 0], rot[0, 0]))
        else:
            self.set_object_pose(*np.asarray(pose_object_in_hand, dtype=float).tolist())

    def signed_distances(self, q: np.ndarray, pose_object_in_hand: np.ndarray | pin.SE3) -> np.ndarray:
        """Signed distance [m] of each kept shape to the object (negative: penetration).

        ``pose_object_in_hand`` is the planar pose (x, y, beta) or its ``pin.SE3``.
        """
        self._set_object(pose_object_in_hand)
        c1, s1, x2, y2, c2, s2 = self._posture(q)
        links = ((*self._joint1, c1, s1), (x2, y2, c2, s2))
        request, result = self._request, self._result
        out = np.empty(len(self.shapes))
        for k in (0, 1):
            shapes = self._links[k][5]
            if shapes:
                tf = self._object_in_link(k, *links[k])
                for distance, placement, i in shapes:
                    result.clear()
                    out[i] = distance(placement, tf, request, result)
        return out

    def collides(self, q: np.ndarray, pose_object_in_hand: np.ndarray | pin.SE3) -> bool:
        """Whether any link shape penetrates the object."""
        self._set_object(pose_object_in_hand)
        return self.links_collide(*self._posture(q))

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
"""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin

from .exceptions import FingerModelError, InvalidParameterError
from .finger import Finger, LinkShape
from .planar import se3_from_planar
from .polygon import ConvexPolygon

__all__ = ["UrdfCollisionChecker", "default_tip_clearance", "segment_hits_polygon"]


def segment_hits_polygon(a: np.ndarray, b: np.ndarray, normals: np.ndarray, offsets: np.ndarray,
                         *, eps: float) -> bool:
    r"""Whether segment [a, b] meets the open interior of a convex polygon.

    The polygon is :math:`\{y : n_k \cdot y > o_k\ \forall k\}` (inward normals ``normals``
    (n, 2), ``offsets`` (n,)). Clip the segment :math:`a + t (b - a)`, :math:`t \in [0, 1]`,
    against every closed half-plane (Cyrus–Beck); it meets the open interior iff the
    clipped range is not empty and its midpoint is inside by more than ``eps`` [m]
    (a segment through a vertex or along an edge only touches the boundary).
    """
    t0, t1 = 0.0, 1.0
    da = normals @ a - offsets  # signed distance of a to each edge line (>0 inside)
    db = normals @ b - offsets
    for fa, fb in zip(da, db):
        if fa < 0.0 and fb < 0.0:
            return False
        if fa < 0.0:
            t0 = max(t0, fa / (fa - fb))
        elif fb < 0.0:
            t1 = min(t1, fa / (fa - fb))
        if t1 <= t0:
            return False
    tm = 0.5 * (t0 + t1)
    depth = np.min(da + tm * (db - da))
    return bool(depth > eps)


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
            joint=shape.name,
        )
    axis = placement.rotation @ axis_local
    if abs(abs(axis[0] * link_dir[0] + axis[1] * link_dir[1]) - 1.0) > 1e-9 or abs(axis[2]) > 1e-9:
        raise FingerModelError(
            "the distal collision shape is not aligned with the link (joint 2 to tip), so the tip "
            "clearance cannot be applied",
            source=source,
            joint=shape.name,
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
    return 3.0 * max((_half_width(s.geometry) for s in finger.link_shapes() if s.link == 1), default=0.0)


class UrdfCollisionChecker:
    r"""Signed distances between a finger's URDF collision shapes and a polygon prism.

    Args:
        finger: The finger (its collision model must have a shape on each link).
        polygon: The object.
        tip_clearance: :math:`\rho` [m] removed from the tip end of the distal shapes.
        half_thickness: Half height [m] of the object's prism; default: the finger's
            reach, far larger than any link radius so the 3-D distance is the planar one.
    """

    def __init__(self, finger: Finger, polygon: ConvexPolygon, tip_clearance: float,
                 half_thickness: float | None = None):
        if not np.isfinite(tip_clearance) or tip_clearance < 0.0:
            raise InvalidParameterError("tip_clearance", tip_clearance, "a finite length >= 0 [m]")
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
        self.finger = finger
        self.tip_clearance = float(tip_clearance)
        self.shapes: tuple[LinkShape, ...] = tuple(kept)
        h = half_thickness if half_thickness is not None else sum(finger.link_lengths)
        self.object_geometry = polygon.to_coal(h)
        self._request = coal.DistanceRequest()
        self._request.enable_signed_distance = True
        self._result = coal.DistanceResult()

    def signed_distances(self, q: np.ndarray, pose_object_in_hand: np.ndarray | pin.SE3) -> np.ndarray:
        """Signed distance [m] of each kept shape to the object (negative: penetration).

        ``pose_object_in_hand`` is the planar pose (x, y, beta) or its ``pin.SE3``.
        """
        model, data = self.finger.model, self.finger.data
        pin.forwardKinematics(model, data, q)
        object_placement = (pose_object_in_hand if isinstance(pose_object_in_hand, pin.SE3)
                            else se3_from_planar(pose_object_in_hand))
        out = np.empty(len(self.shapes))
        for i, shape in enumerate(self.shapes):
            placement = data.oMi[shape.link + 1] * shape.placement_in_joint
            self._result.clear()
            out[i] = coal.distance(shape.geometry, placement, self.object_geometry, object_placement,
                                   self._request, self._result)
        return out

    def collides(self, q: np.ndarray, pose_object_in_hand: np.ndarray | pin.SE3) -> bool:
        """Whether any link shape penetrates the object."""
        return bool(np.min(self.signed_distances(q, pose_object_in_hand), initial=np.inf) < 0.0)

"""The fingers as a recording draws them: each link's URDF collision shape as its outline in the plane, the
fingers' entity names and colours, and the forward kinematics that places the outlines at a joint configuration.

An outline is computed once, in its joint's frame: the shape's points (cylinders and boxes give rectangles,
capsules stadiums, spheres circles, other shapes their bounding box) are projected onto the plane of the joint
and closed as their 2-D convex hull; at each logged step Pinocchio's joint frame (``data.oMi[joint]``) places it
in the hand frame.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .style import FINGER_COLOURS, Colour

if TYPE_CHECKING:
    from ...model.finger import Finger

__all__ = ["FingerDrawing", "HandDrawing", "circle", "entity_name", "outline_in_joint_frame"]


def entity_name(name: str, taken: set[str]) -> str:
    """A path-safe entity-path part for a finger name, unique among ``taken`` (which it joins)."""
    base = re.sub(r"[^A-Za-z0-9_\-]", "_", str(name)) or "finger"
    key, k = base, 1
    while key in taken:
        k += 1
        key = f"{base}_{k}"
    taken.add(key)
    return key


def circle(radius: float, n: int = 24) -> np.ndarray:
    """``n`` points (n, 2) on a circle of ``radius`` around the origin, counter-clockwise from +x, not closed."""
    a = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return radius * np.stack([np.cos(a), np.sin(a)], axis=1)


def _sphere_samples(centre: np.ndarray, radius: float) -> np.ndarray:
    """Points on a sphere's three great circles (enough for the hull of its projection)."""
    c = circle(radius)
    z = np.zeros(len(c))
    rings = [np.column_stack([c[:, 0], c[:, 1], z]), np.column_stack([c[:, 0], z, c[:, 1]]),
             np.column_stack([z, c[:, 0], c[:, 1]])]
    return np.concatenate(rings) + centre


def _shape_samples(geometry: object) -> np.ndarray:
    """Points (n, 3) of a coal shape, in the shape's frame, whose hull is the shape's."""
    kind = type(geometry).__name__
    if kind == "Box":
        h = np.asarray(geometry.halfSide, dtype=float)
        signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=float)
        return signs * h
    if kind == "Cylinder":
        c = circle(float(geometry.radius))
        h = float(geometry.halfLength)
        return np.concatenate([np.column_stack([c, np.full(len(c), s * h)]) for s in (-1, 1)])
    if kind == "Capsule":
        r, h = float(geometry.radius), float(geometry.halfLength)
        return np.concatenate([_sphere_samples(np.array([0.0, 0.0, s * h]), r) for s in (-1, 1)])
    if kind == "Sphere":
        return _sphere_samples(np.zeros(3), float(geometry.radius))
    geometry.computeLocalAABB()  # meshes, convexes, ...: their bounding box
    lo, hi = np.asarray(geometry.aabb_local.min_), np.asarray(geometry.aabb_local.max_)
    return np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])


def _hull_2d(points: np.ndarray) -> np.ndarray:
    """Convex hull (k, 2) of 2-D points, counter-clockwise, collinear points dropped (monotone chain)."""
    pts = sorted(set(map(tuple, np.round(points, 12))))
    if len(pts) <= 2:
        return np.array(pts, dtype=float)

    def half(seq):
        out = []
        for p in seq:
            while len(out) >= 2 and ((out[-1][0] - out[-2][0]) * (p[1] - out[-2][1])
                                     - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0])) <= 0.0:
                out.pop()
            out.append(p)
        return out

    lower, upper = half(pts), half(reversed(pts))
    return np.array(lower[:-1] + upper[:-1], dtype=float)


def outline_in_joint_frame(geometry: object, placement: pin.SE3) -> np.ndarray:
    """A coal shape's outline in the plane of its joint, as the points (k, 3) [m] of a closed polyline in the
    joint's frame (``placement``: the shape's placement in that frame), so that ``oMi[joint]`` puts it in the
    hand frame."""
    samples = _shape_samples(geometry)
    in_joint = samples @ placement.rotation.T + placement.translation
    hull = _hull_2d(in_joint[:, :2])
    hull = np.vstack([hull, hull[:1]])
    in_plane = np.column_stack([hull, np.zeros(len(hull))])
    in_shape = (in_plane - placement.translation) @ placement.rotation  # (the shape's own frame, then back)
    return in_shape @ placement.rotation.T + placement.translation


@dataclass(frozen=True)
class FingerDrawing:
    """One finger as drawn.

    Attributes:
        name: The finger's name.
        key: Its entity-path part (``scene/fingers/<key>``, ``plots/xi/<key>``).
        colour: Its colour.
        shapes: Per link collision shape: (joint 0 or 1 whose frame moves it, outline points (k, 3) [m] in that
            joint's frame).
        labels: Each shape's label, then the chain's.
        width: Points per strip (the longest outline, at least the chain's 3): shorter strips repeat their last.
    """

    name: str
    key: str
    colour: Colour
    shapes: tuple[tuple[int, np.ndarray], ...]
    labels: tuple[str, ...]
    width: int

    @property
    def path(self) -> str:
        """The finger's scene entity."""
        return f"scene/fingers/{self.key}"


class HandDrawing:
    """The fingers as drawn (:class:`FingerDrawing`, in finger order) and their forward kinematics.

    Args:
        fingers: The hand's fingers (their URDF models and collision shapes).
    """

    def __init__(self, fingers: Sequence[Finger]):
        taken: set[str] = set()
        self.fingers: list[FingerDrawing] = []
        self._models = []  # per finger: (model, data, tip placement in joint 2's frame)
        for i, f in enumerate(fingers):
            link_shapes = f.link_shapes()
            shapes = tuple((sh.link, outline_in_joint_frame(sh.geometry, sh.placement_in_joint))
                           for sh in link_shapes)
            self.fingers.append(FingerDrawing(
                name=f.name, key=entity_name(f.name, taken), colour=FINGER_COLOURS[i % len(FINGER_COLOURS)],
                shapes=shapes, labels=tuple(f"{f.name} {sh.name}" for sh in link_shapes) + (f.name,),
                width=max([3] + [len(p) for _, p in shapes])))
            self._models.append((f.model, f.model.createData(), f.model.frames[f.tip_frame_id].placement))

    @property
    def keys(self) -> list[str]:
        """Each finger's entity-path part."""
        return [f.key for f in self.fingers]

    def kinematics(self, q: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """The fingers' joint frames at joint angles ``q`` (2m,) [rad]: joints 1 and 2 of each finger as 4x4
        homogeneous matrices in the hand frame ((2m, 4, 4), finger by finger), and their chains (m, 3, 2) [m]:
        joint 1, elbow and tip in the hand frame. (Arrays, not lists: a recording buffers them, and the garbage
        collector does not track arrays.)"""
        m = len(self._models)
        chains = np.empty((m, 3, 2))
        frames = np.empty((2 * m, 4, 4))
        for i, (model, data, tip_placement) in enumerate(self._models):
            pin.forwardKinematics(model, data, q[2 * i:2 * i + 2])
            oMi = data.oMi
            frames[2 * i] = H1 = oMi[1].homogeneous
            frames[2 * i + 1] = H2 = oMi[2].homogeneous
            chains[i, 0] = H1[:2, 3]
            chains[i, 1] = H2[:2, 3]
            chains[i, 2] = (oMi[2] * tip_placement).translation[:2]
        return frames, chains

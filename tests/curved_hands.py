"""The two-finger hand and the curved objects the sphere-tip plants' curve tests share (MuJoCo's and Drake's):
finger 1 on the left, finger 2 on the right, gravity off; a disc, a rounded box and an ellipse, each with a pose
and the contacts' ξ for a hold and for a placement."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from regrasp import Finger, Hand
from regrasp.core.curves import Disc, Ellipse, RoundedPolygon

URDF = Path(__file__).resolve().parents[1] / "urdf" / "planar_2r_finger.urdf"
FINGERS = (Finger.from_urdf(URDF, base_in_hand=(-0.05, 0.0, math.pi / 2), configuration="left", name="finger1"),
           Finger.from_urdf(URDF, base_in_hand=(0.05, 0.0, math.pi / 2), configuration="right", name="finger2"))
HAND = Hand(list(FINGERS), gravity_in_hand=(0.0, 0.0))

DISC = Disc(0.04, mass=0.1)
BOX = RoundedPolygon([[-0.035, -0.025], [0.035, -0.025], [0.035, 0.025], [-0.035, 0.025]], 0.01, mass=0.1)
ELLIPSE = Ellipse(0.045, 0.03, mass=0.1)
#: The middle of the rounded box's arc at corner 0.
ARC0 = next(0.5 * (a + b) for kind, k, a, b in BOX.piece_ranges() if (kind, k) == ("arc", 0))
#: name: (curve, object pose X, the contacts' ξ for the hold (opposite normals through the centre of mass), ξ for
#: the placement (anywhere, one of them a whole perimeter on: ξ is unbounded)). The disc and the ellipse are turned
#: by 90°, so ξ = 0 (the object's top) faces finger 1.
CASES = {
    "disc": (DISC, (0.0, 0.12, math.pi / 2), (0.0, 0.5 * DISC.perimeter),
             (2.0 * DISC.perimeter - 0.002, 0.5 * DISC.perimeter + 0.003)),
    "box": (BOX, (0.0, 0.12, 0.0), (BOX.project_floats(-0.035, 0.0)[0], BOX.project_floats(0.035, 0.0)[0]),
            (ARC0, BOX.project_floats(0.035, 0.01)[0])),
    "ellipse": (ELLIPSE, (0.0, 0.12, math.pi / 2), (0.0, 0.5 * ELLIPSE.perimeter),
                (ELLIPSE.perimeter + 0.004, 0.5 * ELLIPSE.perimeter - 0.006)),
}


def in_hand(X, point) -> np.ndarray:
    """A point of the object frame in the hand frame, the object at X."""
    c, s = math.cos(X[2]), math.sin(X[2])
    return np.array([X[0] + c * point[0] - s * point[1], X[1] + s * point[0] + c * point[1]])


def rotation(beta: float) -> np.ndarray:
    """R(β)."""
    return np.array([[math.cos(beta), -math.sin(beta)], [math.sin(beta), math.cos(beta)]])


def polygon_distance(polygon: np.ndarray, vertex_xi: np.ndarray, points: np.ndarray, xi: np.ndarray) -> np.ndarray:
    """Each point's distance [m] from the closed polygon of ``polygon``'s vertices in increasing ``vertex_xi``, the
    points at ``xi`` on the same curve: from the sides of the vertices around its ξ (and their neighbours)."""
    n = len(polygon)
    k = np.searchsorted(vertex_xi, xi) - 1
    out = np.full(len(points), np.inf)
    for shift in (-1, 0, 1):
        a, b = polygon[(k + shift) % n], polygon[(k + shift + 1) % n]
        ab = b - a
        t = np.clip(np.einsum("ij,ij->i", points - a, ab) / np.einsum("ij,ij->i", ab, ab), 0.0, 1.0)
        out = np.minimum(out, np.linalg.norm(points - (a + t[:, None] * ab), axis=1))
    return out

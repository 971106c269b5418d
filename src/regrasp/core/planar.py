r"""Planar (SE(2)) helpers shared by every module.

Conventions: a planar pose is ``(x [m], y [m], theta [rad])``; ``rotation(theta)`` is
the active rotation :math:`R(\theta) = [[c, -s], [s, c]]`; ``perp(v)`` rotates ``v`` by
+90 degrees, :math:`\perp v = (-v_y, v_x)`; ``cross(a, b) = a_x b_y - a_y b_x``.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin


def rotation(theta: float) -> np.ndarray:
    """2x2 rotation matrix R(theta) [-]."""
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s], [s, c]])


def perp(v: np.ndarray) -> np.ndarray:
    """Rotate a 2-vector (or an (n, 2) array of them) by +90 degrees."""
    v = np.asarray(v, dtype=float)
    if v.ndim == 1:  # the common case, without np.stack's overhead
        return np.array([-v[1], v[0]])
    return np.stack([-v[..., 1], v[..., 0]], axis=-1)


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray | float:
    """Scalar planar cross product a_x b_y - a_y b_x."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def transform_points(pose: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Map points (n, 2) or (2,) given in a frame with planar ``pose`` to its parent frame."""
    pose = np.asarray(pose, dtype=float)
    return np.asarray(points, dtype=float) @ rotation(pose[2]).T + pose[:2]


def inverse_transform_points(pose: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Map points given in the parent frame into the frame with planar ``pose``."""
    pose = np.asarray(pose, dtype=float)
    return (np.asarray(points, dtype=float) - pose[:2]) @ rotation(pose[2])


def se3_from_planar(pose: np.ndarray) -> pin.SE3:
    """The pin.SE3 of a planar pose (rotation about z, translation in the xy-plane)."""
    pose = np.asarray(pose, dtype=float)
    rot = np.eye(3)
    rot[:2, :2] = rotation(pose[2])
    return pin.SE3(rot, np.array([pose[0], pose[1], 0.0]))


def wrap_angle(angle: float | np.ndarray) -> float | np.ndarray:
    """Wrap an angle [rad] to (-pi, pi]."""
    if isinstance(angle, float):  # the scalar case without numpy's overhead (same arithmetic as np.mod)
        wrapped = float(angle + math.pi) % (2.0 * math.pi) - math.pi
        return math.pi if wrapped == -math.pi else wrapped
    wrapped = np.mod(np.asarray(angle, dtype=float) + np.pi, 2.0 * np.pi) - np.pi
    wrapped = np.where(wrapped == -np.pi, np.pi, wrapped)
    return float(wrapped) if np.ndim(wrapped) == 0 else wrapped

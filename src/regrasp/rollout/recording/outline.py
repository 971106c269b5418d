r"""The object's outline as the recordings and the figures draw it: a polygon's vertices, a curved object's boundary
(:mod:`regrasp.core.curves`) sampled evenly in ξ finely enough that the drawn polyline strays at most
:data:`CHORD_ERROR` from the curve, and polylines along a curve (each contact's feasible intervals drawn just
outside it).

A chord spanning arc length Δ of a curve of curvature at most κ strays at most
:math:`(1 - \cos(\kappa\Delta/2))/\kappa \le \kappa\Delta^2/8` from it, and on the parallel curve at a distance o
outside, :math:`(1 + \kappa o)` times that; so an arc of length L takes
:math:`\lceil L\sqrt{\kappa(1 + \kappa o)/(8 e)}\rceil` chords for a chord error e (:func:`chords`), κ the curve's
largest curvature (:func:`max_curvature`, sampled once per curve).
"""

from __future__ import annotations

import math
import weakref

import numpy as np
from numpy.typing import ArrayLike

from ...core.curves import CurvedObject
from ...core.polygon import ConvexPolygon

__all__ = ["CHORD_ERROR", "CURVATURE_SAMPLES", "MAX_POINTS", "MIN_POINTS", "chords", "closed_outline", "curve_path",
           "max_curvature", "outline_in", "outline_points", "outline_size"]

#: The largest distance [m] between a drawn curve and its polyline: 0.05 mm in the scene's millimetres.
CHORD_ERROR = 5e-5
#: Points of a curved object's outline: at least, and at most (past that, the chord error may exceed the bound).
MIN_POINTS, MAX_POINTS = 32, 4096
#: Samples of a curve's curvature (evenly in ξ) for its largest value.
CURVATURE_SAMPLES = 2048

_KAPPA: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def max_curvature(curve: CurvedObject) -> float:
    """The curve's largest curvature [1/m] over :data:`CURVATURE_SAMPLES` samples evenly in ξ (computed once per
    curve)."""
    kappa = _KAPPA.get(curve)
    if kappa is None:
        xi = np.linspace(0.0, curve.perimeter, CURVATURE_SAMPLES, endpoint=False)
        kappa = _KAPPA[curve] = float(np.max(curve.frames(xi)[2]))
    return kappa


def chords(curve: CurvedObject, length: float, offset: float = 0.0, error: float = CHORD_ERROR) -> int:
    """How many chords of equal ξ-span draw an arc of ``length`` [m] of ``curve``, ``offset`` [m] outside it, within
    ``error`` [m] (module docstring); at least 1."""
    kappa = max_curvature(curve)
    return max(1, math.ceil(abs(length) * math.sqrt(kappa * (1.0 + kappa * max(offset, 0.0)) / (8.0 * error))))


def outline_size(curve: CurvedObject) -> int:
    """Points of ``curve``'s drawn outline: one per chord of the whole perimeter (:func:`chords`), within
    [:data:`MIN_POINTS`, :data:`MAX_POINTS`]."""
    return min(max(chords(curve, curve.perimeter), MIN_POINTS), MAX_POINTS)


def outline_points(obj: ConvexPolygon | CurvedObject) -> np.ndarray:
    """The object's outline (n, 2) [m], object frame: a polygon's vertices, a curve's :meth:`CurvedObject.outline`
    of :func:`outline_size` points (from ξ = 0, clockwise)."""
    if isinstance(obj, CurvedObject):
        return obj.outline(outline_size(obj))
    return obj.vertices


def closed_outline(obj: ConvexPolygon | CurvedObject) -> np.ndarray:
    """:func:`outline_points` closed: its first point repeated at the end (n + 1, 2) [m]."""
    points = outline_points(obj)
    return np.vstack([points, points[:1]])


def outline_in(obj: ConvexPolygon | CurvedObject, pose: ArrayLike) -> np.ndarray:
    """:func:`outline_points` in the parent frame for the pose ``(x [m], y [m], β [rad])``: a polygon's
    ``vertices_in``, a curve's ``outline_in``."""
    if isinstance(obj, CurvedObject):
        return obj.outline_in(pose, outline_size(obj))
    return obj.vertices_in(pose)


def curve_path(curve: CurvedObject, lo: float, hi: float, offset: float = 0.0) -> np.ndarray:
    r"""The arc of ``curve`` from ξ = ``lo`` to ``hi`` [m] moved ``offset`` [m] outside it, :math:`c(\xi) - o\,n(\xi)`,
    as a polyline (k, 2) [m], object frame, evenly in ξ with :func:`chords` chords (``lo == hi``: that point
    twice)."""
    xi = np.linspace(lo, hi, min(chords(curve, hi - lo, offset), MAX_POINTS) + 1)
    points, normals, _ = curve.frames(xi)
    return points - offset * normals

r"""The envelope of feasible contacts of one finger on one edge (paper §2.2).

Frames and parameters (eqs. 2.1.1–2.1.2). Let :math:`o_1` be the finger's first joint
in the hand frame, :math:`n` the edge's inward normal and :math:`x_i` the edge's ξ origin,
both mapped to the hand frame by the object pose :math:`X = (x_o, \beta)`:
:math:`x_i = x_o + R(\beta) c_i`. Then

.. math:: d = (x_i - o_1)^T n, \qquad \lambda = \angle n \text{ in the finger base frame}.

The edge's line is :math:`p(s) = o_1 + d\,n + s\,t` with :math:`t = \perp n` (the ξ
direction); :math:`s = \xi + s_0` with :math:`s_0 = (x_i - o_1)^T t`.

**Reachable set (Definition 2.1, exact form).** A point :math:`p(s)` is reachable in
configuration :math:`\sigma` (+1 left, -1 right) iff :math:`|l_1 - l_2| \le r \le l_1 + l_2`
(:math:`r = |p - o_1| = \sqrt{d^2 + s^2}`) and the elbow of the inverse-kinematics
solution is not in the open interior half-plane :math:`\{y : n^T (y - o_1) > d\}`. With
:math:`a = (l_1^2 - l_2^2 + r^2) / 2r` and :math:`h = \sqrt{l_1^2 - a^2}`, the elbow is
:math:`e = o_1 + a u + \sigma h \perp u` (:math:`u` the unit vector to the tip), and
:math:`n^T(e - o_1) \le d` reduces to

.. math:: g(s) = \sigma\, s\, K(r) - d\,(l_1^2 - l_2^2 - r^2) \ge 0,\qquad
          K(r) = \sqrt{((l_1 + l_2)^2 - r^2)(r^2 - (l_1 - l_2)^2)} = 2 r h.

:math:`g` is continuous on the annulus and vanishes only where the elbow lies on the line,
i.e. where the second link lies on the line: :math:`s = \pm c \pm l_2` with
:math:`c = \sqrt{l_1^2 - d^2}` (only when :math:`|d| \le l_1`). So the interval ends are among

* :math:`\pm\sqrt{(l_1 + l_2)^2 - d^2}` (full stretch: the paper's ξ1, ξ2, ξ4),
* :math:`\pm\sqrt{(l_1 - l_2)^2 - d^2}` (full fold, only when :math:`|d| < |l_1 - l_2|`),
* :math:`\pm c \pm l_2` (second link on the line: ξ3, ξ5, ξ6),

and the sign of :math:`g` between them selects the pieces. For the left configuration
this gives condition II: :math:`[-S, S]`; III: :math:`[c - l_2, S] \cup [-S, -c - l_2]`;
IV: :math:`[l_2 - c, l_2 + c]` (each minus the inner disc when :math:`l_1 \ne l_2`, which may
split it in two), and the right configuration is the mirror image :math:`s \to -s`
(:func:`reachable_on_line`). Isolated points (zero-length pieces) are dropped.
``docs/derivations.md`` has the derivation.

**Feasible set (Definition 2.2).** Reachable, on the actual edge (ξ within the edge's
range), and no link collides with the object (:mod:`regrasp.model.collision`). In ``ideal``
mode link 2 never collides (it lies in the closed outer half-plane of a convex object),
and link 1 changes between colliding and free only where it passes through a vertex
:math:`v` (:math:`|v - o_1| \le l_1`): the elbow is then :math:`o_1 + l_1 (v - o_1)/|v - o_1|`
and the tip is one of the two points of the line at distance :math:`l_2` from it. These
points (Example 2.2's "limiting vertex") join the breakpoints, and each piece is
classified at its midpoint. In ``urdf`` mode the pieces of reachable ∩ edge are sampled
on a grid (plus the ``ideal`` feasible ends) and every change of coal's verdict is
bisected to ``1e-4`` of the edge length or finer.

**Compiled path.** When every link shape of the finger has a planar footprint (boxes turned
about z, cylinders and capsules with their axis in the plane, spheres centred in it:
:mod:`regrasp.kernels.footprint`, which states why the 3-D distance to the prism is then the
planar one), a ``urdf`` sample is one call of :func:`~regrasp.kernels.envelope.envelope_sample_into`:
the same grid, bisection and rules, with closed-form signed distances in place of coal's
(``compiled=False`` keeps coal; other shapes always do).
"""

from __future__ import annotations

import math
import time as _time
from dataclasses import dataclass
from enum import Enum
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from ..core.exceptions import InvalidParameterError
from ..core.intervals import Intervals, intersect, merge
from ..core.planar import rotation
from ..core.polygon import ConvexPolygon
from ..core.validation import (
    as_finite_array,
    as_finite_float,
    as_flag,
    as_integer,
    as_positive_float,
    as_sign,
    expect_type,
)
from ..kernels.envelope import ENVELOPE_PARAMETERS, envelope_sample_into, feasible_capacity, tip_is_free, workspace_size
from ..model.collision import Geometry, UrdfCollisionChecker, default_tip_clearance, segment_hits_halfplanes
from ..model.finger import Finger

__all__ = [
    "Condition",
    "EdgeLine",
    "EnvelopeSample",
    "FingerEnvelope",
    "condition_of",
    "elbow_margin",
    "reachable_on_line",
]


class Condition(str, Enum):
    r"""The paper's conditions I–IV on :math:`d` and :math:`l_1` (§2.2).

    I: :math:`d < -l_1`; II: :math:`d > l_1`; III: :math:`0 \le d \le l_1`;
    IV: :math:`-l_1 \le d < 0`. (The paper uses strict inequalities; the boundaries are
    assigned to the side written here.)
    """

    I = "I"  # noqa: E741
    II = "II"
    III = "III"
    IV = "IV"



def condition_of(d: float, l1: float) -> Condition:
    """The condition (I–IV) for signed line distance ``d`` [m] and first link ``l1`` [m] (> 0)."""
    d, l1 = as_finite_float("d", d), as_finite_float("l1", l1)
    if not l1 > 0.0:
        raise InvalidParameterError("l1", l1, "a link length l1 > 0 [m]")
    return _condition(d, l1)


def _condition(d: float, l1: float) -> Condition:
    """:func:`condition_of` of finite floats, ``l1`` > 0 (no validation)."""
    if d < -l1:
        return Condition.I
    if d > l1:
        return Condition.II
    return Condition.III if d >= 0.0 else Condition.IV


def elbow_margin(s: float, d: float, l1: float, l2: float, sign: int) -> float:
    r"""The reachability function :math:`g(s)` of the module docstring (-inf outside the annulus).

    :math:`g(s) \ge 0` iff the elbow of the configured IK solution for the tip at line
    coordinate ``s`` is not in the open interior half-plane. Kept as an independent
    check of :func:`reachable_on_line`.
    """
    r2 = d * d + s * s
    k2 = ((l1 + l2) ** 2 - r2) * (r2 - (l1 - l2) ** 2)
    if k2 < 0.0:
        return -math.inf
    return sign * s * math.sqrt(k2) - d * (l1 * l1 - l2 * l2 - r2)


def reachable_on_line(d: float, l1: float, l2: float, sign: int) -> Intervals:
    r"""Reachable set (Definition 2.1) on the line at signed distance ``d`` [m], in ``s`` [m].

    ``s`` is measured along :math:`t = \perp n` from the foot of the perpendicular from
    the first joint; ``sign`` is +1 for the left and -1 for the right configuration.
    With :math:`S = \sqrt{(l_1 + l_2)^2 - d^2}`, :math:`c = \sqrt{l_1^2 - d^2}` and
    :math:`S_{in} = \sqrt{(l_1 - l_2)^2 - d^2}`, for the left configuration:

    * I (:math:`d < -l_1`): empty;
    * II (:math:`d > l_1`): :math:`[-S, S]` (ξ1, ξ2);
    * III (:math:`0 \le d \le l_1`): :math:`[c - l_2, S]` (ξ3, ξ4) and the sliver
      :math:`[-S, -c - l_2]` near full stretch on the other side;
    * IV (:math:`-l_1 \le d < 0`): :math:`[l_2 - c, l_2 + c]` (ξ5, ξ6);

    each minus the open inner disc :math:`(-S_{in}, S_{in})` when :math:`|d| < |l_1 - l_2|`
    (which can split an interval in two). The right configuration is the mirror image
    :math:`s \to -s`. Zero-length pieces are dropped.
    """
    d = as_finite_float("d", d)
    for name, length in (("l1", l1), ("l2", l2)):
        if not 0.0 < as_finite_float(name, length) <= 1e3:
            raise InvalidParameterError(name, length, "a link length in (0, 1000] m")
    sign = int(as_sign("sign", sign))
    l1, l2 = float(l1), float(l2)
    outer2 = (l1 + l2) ** 2 - d * d
    if outer2 <= 0.0 or d < -l1:
        return ()
    big = math.sqrt(outer2)
    if d > l1:
        pieces = [(-big, big)]
    else:
        c = math.sqrt(l1 * l1 - d * d)
        pieces = [(c - l2, big), (-big, -c - l2)] if d >= 0.0 else [(l2 - c, l2 + c)]
    inner2 = (l1 - l2) ** 2 - d * d
    if inner2 > 0.0:
        hole = math.sqrt(inner2)
        pieces = [p for lo, hi in pieces for p in ((lo, min(hi, -hole)), (max(lo, hole), hi))]
    if sign < 0:
        pieces = [(-hi, -lo) for lo, hi in pieces]
    return merge(pieces)


@dataclass(frozen=True)
class EdgeLine:
    """The contact edge's line seen from a finger at one object pose (eqs. 2.1.1–2.1.2).

    Attributes:
        d: Signed distance [m] of the line from the first joint along the inward normal.
        lam: Angle λ [rad] of the inward normal in the finger's base frame.
        normal_in_hand: Inward normal n (unit) in the hand frame.
        tangent_in_hand: ξ direction t = ⊥n (unit) in the hand frame.
        s0: Line coordinate s [m] of the edge's ξ origin (s = ξ + s0).
    """

    d: float
    lam: float
    normal_in_hand: np.ndarray
    tangent_in_hand: np.ndarray
    s0: float


@dataclass(frozen=True)
class EnvelopeSample:
    """The envelope of one finger on its edge at one object pose.

    All sets are tuples of closed ξ-intervals ``(lo, hi)`` [m] on the edge's ξ axis.

    Attributes:
        time: Sample time [s].
        d: Signed line distance [m] (eq. 2.1.2).
        lam: Inward normal angle λ [rad] in the finger base frame.
        condition: Condition I–IV.
        reachable: Reachable set (Definition 2.1) on the edge's whole line.
        edge_range: ξ range of the actual edge.
        feasible: Feasible set (Definition 2.2).
        reason: None when ``feasible`` is non-empty, else why it is empty:
            ``"condition I"``, ``"out of reach"``, ``"off the edge"`` or ``"collision"``.
        seconds: Wall time [s] spent computing this sample.
    """

    time: float
    d: float
    lam: float
    condition: Condition
    reachable: Intervals
    edge_range: tuple[float, float]
    feasible: Intervals
    reason: str | None
    seconds: float = 0.0

    @property
    def is_feasible(self) -> bool:
        """Whether the feasible set is non-empty."""
        return bool(self.feasible)

    def margin(self, xi: float) -> float:
        """Distance [m] from ``xi`` to the nearest bound of the feasible interval holding it
        (negative: distance to the nearest feasible interval; -inf if none); ``xi`` must be finite."""
        xi = as_finite_float("xi", xi)
        best = -math.inf
        for lo, hi in self.feasible:
            best = max(best, min(xi - lo, hi - xi))
        return best


def _wrap(angle: float) -> float:
    """:func:`~regrasp.core.planar.wrap_angle` of one float (same arithmetic, without numpy)."""
    wrapped = (angle + math.pi) % (2.0 * math.pi) - math.pi
    return math.pi if wrapped == -math.pi else wrapped


def _pose_floats(value) -> tuple[float, float, float]:
    """A planar pose ``(x, y, beta)`` as floats, validated like ``as_finite_array(…, (3,))``."""
    if type(value) is np.ndarray and value.shape == (3,) and value.dtype.kind == "f":
        x, y, beta = value.tolist()
        if math.isfinite(x) and math.isfinite(y) and math.isfinite(beta):
            return x, y, beta
    x, y, beta = as_finite_array("pose_object_in_hand", value, (3,)).tolist()
    return x, y, beta


def _linspace(lo: float, hi: float, num: int) -> list[float]:
    """``np.linspace(lo, hi, num).tolist()`` (num >= 2) with numpy's arithmetic, without numpy."""
    delta = hi - lo
    div = num - 1
    step = delta / div
    if step == 0.0:  # numpy's handling of denormal spans
        out = [(k / div) * delta + lo for k in range(div)]
    else:
        out = [k * step + lo for k in range(div)]
    out.append(hi)
    return out


class _Frame(NamedTuple):
    """The closed-form part of a sample (line coordinates s [m]; see :class:`EdgeLine`)."""

    d: float
    lam: float
    s0: float
    nx: float
    ny: float
    c: float  # cos beta
    s: float  # sin beta
    condition: Condition
    reach: Intervals  # reachable set on the line
    base: Intervals  # reachable ∩ edge
    ideal: Intervals  # feasible with segment links (the ``urdf`` mode's hints)


def _urdf_pieces(base: Intervals, ends) -> Intervals:
    """The free pieces of ``base`` from :meth:`FingerEnvelope._urdf_ends`'s (start verdict, flips) per piece."""
    pieces = []
    for (lo, hi), (start_free, flips) in zip(base, ends):
        start = lo if start_free else None
        for e in flips:
            if start is None:  # colliding -> free: open a piece at the free side
                start = e
            else:  # free -> colliding: close the piece at the free side
                pieces.append((start, e))
                start = None
        if start is not None:
            pieces.append((start, hi))
    return merge(pieces)


class FingerEnvelope:
    r"""Computes the feasible-contact envelope of one finger on one polygon edge.

    Build once for a (finger, object, edge) and call :meth:`at` for each object pose.
    :meth:`at` works on plain floats with constants precomputed here (it is called at
    every control step by a regrasp supervisor).

    Args:
        finger: The finger (its configuration selects the reachable set).
        polygon: The object.
        edge: Index of the contact edge (edge k runs from vertex k to vertex k+1).
        geometry: ``"ideal"`` (links are segments, closed form) or ``"urdf"`` (the URDF
            collision shapes against the object with coal).
        tip_clearance: :math:`\rho` [m] of :mod:`regrasp.model.collision` (``urdf`` only);
            default: three times the distal link's half-width (a cylinder's or capsule's
            radius, a box's middle half-side).
        urdf_grid: Grid points per piece of reachable ∩ edge in ``urdf`` mode.
        urdf_tolerance: Bisection tolerance in ``urdf`` mode, as a fraction of the edge length.
        compiled: ``urdf`` mode only: compute a sample with the compiled kernel
            (:mod:`regrasp.kernels.envelope`, closed-form distances) instead of coal. None: when every
            link shape has a planar footprint (:attr:`UrdfCollisionChecker.footprints
            <regrasp.model.collision.UrdfCollisionChecker.footprints>`); True: it must (else an
            :class:`~regrasp.core.exceptions.InvalidParameterError`); False: never.
        coal_tolerance: ``urdf`` mode: the tolerance [m] of coal's GJK and EPA iterations
            (:class:`~regrasp.model.collision.UrdfCollisionChecker`; default: coal's, 1e-6).

    Attributes:
        compiled: Whether :meth:`at` runs the compiled kernel.
    """

    def __init__(
        self,
        finger: Finger,
        polygon: ConvexPolygon,
        edge: int,
        *,
        geometry: Geometry | str = Geometry.IDEAL,
        tip_clearance: float | None = None,
        urdf_grid: int = 33,
        urdf_tolerance: float = 5e-5,
        compiled: bool | None = None,
        coal_tolerance: float | None = None,
    ):
        self.finger = expect_type("finger", finger, Finger, "a Finger")
        self.polygon = expect_type("polygon", polygon, ConvexPolygon, "a ConvexPolygon")
        self.edge = polygon.edge(edge)
        try:
            self.geometry = Geometry(geometry)
        except ValueError:
            raise InvalidParameterError("geometry", geometry, "'ideal' or 'urdf'") from None
        urdf_grid = as_integer("urdf_grid", urdf_grid, 2)
        if not 0.0 < as_finite_float("urdf_tolerance", urdf_tolerance) <= 1e-4:
            raise InvalidParameterError("urdf_tolerance", urdf_tolerance, "a fraction in (0, 1e-4]")
        self.urdf_grid = int(urdf_grid)
        self.urdf_tolerance = float(urdf_tolerance)
        self.l1, self.l2 = finger.link_lengths
        self.sign = finger.configuration.sign
        self._eps = 1e-12 * (polygon.scale + self.l1 + self.l2)
        self.checker: UrdfCollisionChecker | None = None
        if tip_clearance is not None:  # (checked in either geometry, though only 'urdf' uses it)
            tip_clearance = as_positive_float("tip_clearance", tip_clearance, allow_zero=True)
        if self.geometry is Geometry.URDF:
            if tip_clearance is None:
                tip_clearance = default_tip_clearance(finger)
            self.checker = UrdfCollisionChecker(finger, polygon, float(tip_clearance), coal_tolerance=coal_tolerance)
        self.tip_clearance = None if self.checker is None else self.checker.tip_clearance
        # constants of the hot path, as floats
        self._joint1 = tuple(finger.joint1_in_hand.tolist())
        self._base_angle = float(finger.base_in_hand[2])
        self._edge_normal = tuple(self.edge.inward_normal.tolist())
        self._edge_origin = tuple(self.edge.xi_origin.tolist())
        self._vertices = [tuple(v) for v in polygon.vertices.tolist()]
        self._normals = [tuple(e.inward_normal.tolist()) for e in polygon.edges]
        self._l1_sq = self.l1**2
        self._l2_sq = self.l2**2
        self._l1_sq_minus_l2_sq = self.l1**2 - self.l2**2
        self.compiled = self._use_kernel(compiled)
        if self.compiled:
            self._init_kernel()

    def _use_kernel(self, compiled: bool | None) -> bool:
        """Whether :meth:`at` runs the compiled kernel, given the ``compiled`` argument."""
        supported = (self.checker is not None and self.checker.footprints is not None
                     and self.checker.joint1 == self._joint1)
        if compiled is None:
            return supported
        if as_flag("compiled", compiled) and not supported:
            why = ("the 'ideal' geometry has no compiled path" if self.checker is None else
                   "a link shape has no planar footprint (see UrdfCollisionChecker.footprints)")
            raise InvalidParameterError("compiled", compiled, f"False or None for this envelope: {why}")
        return bool(compiled)

    def _init_kernel(self) -> None:
        """The compiled path's constants (an :data:`~regrasp.kernels.envelope.ENVELOPE_PARAMETERS` record, the
        polygon, the footprints) and its preallocated outputs."""
        par = np.zeros(1, dtype=ENVELOPE_PARAMETERS)
        l1, l2 = self.l1, self.l2
        lo_xi, hi_xi = self.edge.xi_range
        par[0] = (*self._joint1, self._base_angle, l1, l2, self._l1_sq, self._l2_sq, self._l1_sq_minus_l2_sq,
                   (l1 + l2) ** 2, (l1 - l2) ** 2, float(self.sign), self._eps, *self._edge_normal,
                   *self._edge_origin, lo_xi, hi_xi, self.urdf_grid, self.urdf_tolerance * self.edge.length,
                   self.checker.half_thickness)
        vertices = np.array(self._vertices, dtype=float)
        normals = np.array(self._normals, dtype=float)
        self._kernel_inputs = (par, self.checker.footprints, vertices, normals)
        rows = feasible_capacity(self.urdf_grid, len(self._vertices))
        self._kernel_outputs = (np.empty(3), np.empty((4, 2)), np.empty((4, 2)), np.empty(4, np.bool_),
                                np.empty(4, np.int64), np.empty(rows), np.empty((rows, 2)),
                                np.empty(workspace_size(self.urdf_grid, len(self._vertices))))

    # ------------------------------------------------------------------ geometry
    def _line(self, x: float, y: float, beta: float) -> tuple[float, ...]:
        """(d, lam, s0, n_x, n_y, cos beta, sin beta) of the edge's line at a pose (floats)."""
        c, s = math.cos(beta), math.sin(beta)
        n0x, n0y = self._edge_normal
        nx, ny = c * n0x - s * n0y, s * n0x + c * n0y
        cx, cy = self._edge_origin
        o1x, o1y = self._joint1
        rx = x + (c * cx - s * cy) - o1x
        ry = y + (s * cx + c * cy) - o1y
        lam = _wrap(math.atan2(ny, nx) - self._base_angle)
        return rx * nx + ry * ny, lam, ry * nx - rx * ny, nx, ny, c, s

    def line(self, pose_object_in_hand: ArrayLike) -> EdgeLine:
        """The edge's line parameters at an object pose ``(x, y, beta)`` in the hand frame."""
        d, lam, s0, nx, ny, _, _ = self._line(*_pose_floats(pose_object_in_hand))
        return EdgeLine(d, lam, np.array([nx, ny]), np.array([-ny, nx]), s0)

    def tip_in_hand(self, line: EdgeLine, s: float) -> np.ndarray:
        """Point [m] of the edge's line with coordinate ``s``, in the hand frame."""
        return self.finger.joint1_in_hand + line.d * line.normal_in_hand + s * line.tangent_in_hand

    def _tip_and_elbow(self, d: float, nx: float, ny: float, s: float) -> tuple[float, float, float, float]:
        """Tip and elbow (x, y, x, y) [m] relative to joint 1 for the tip at line coordinate ``s``
        (line at distance ``d`` with inward normal (nx, ny); inside the annulus)."""
        px = d * nx - s * ny
        py = d * ny + s * nx
        r = math.hypot(px, py)
        ux, uy = px / r, py / r
        a = (self._l1_sq_minus_l2_sq + r * r) / (2.0 * r)
        h = self.sign * math.sqrt(max(self._l1_sq - a * a, 0.0))
        return px, py, a * ux - h * uy, a * uy + h * ux

    def elbow_in_hand(self, line: EdgeLine, s: float) -> np.ndarray:
        """Elbow [m] of the configured IK solution for the tip at ``s`` (inside the annulus)."""
        nx, ny = line.normal_in_hand.tolist()
        _, _, ex, ey = self._tip_and_elbow(line.d, nx, ny, s)
        return self.finger.joint1_in_hand + np.array([ex, ey])

    def _vertex_cuts(self, x: float, y: float, c: float, s: float, d: float, nx: float,
                     ny: float) -> tuple[list[tuple[float, float]], list[float]]:
        """(the object's vertices in the hand frame [m], the line coordinates s [m] of the tip where
        link 1 passes through one of them (Example 2.2's limiting vertices)) at the object pose
        (x, y, cos beta, sin beta) with the edge's line at distance ``d`` and inward normal (nx, ny)."""
        o1x, o1y = self._joint1
        l1 = self.l1
        verts = [(x + (c * vx - s * vy), y + (s * vx + c * vy)) for vx, vy in self._vertices]
        extra = []
        for vx, vy in verts:
            wx, wy = vx - o1x, vy - o1y
            dist = math.hypot(wx, wy)
            if dist == 0.0 or dist > l1:
                continue
            ex, ey = l1 * wx / dist, l1 * wy / dist
            disc = self._l2_sq - (d - (ex * nx + ey * ny)) ** 2
            if disc >= 0.0:
                et, root = ey * nx - ex * ny, math.sqrt(disc)
                extra += (et - root, et + root)
        return verts, extra

    def _ideal_feasible(self, base: Intervals, x: float, y: float, c: float, s: float,
                        d: float, nx: float, ny: float) -> Intervals:
        """Feasible pieces of ``base`` with segment links (line coordinates s)."""
        o1x, o1y = self._joint1
        eps = self._eps
        verts, extra = self._vertex_cuts(x, y, c, s, d, nx, ny)
        halfplanes = []
        for (mx, my), (vx, vy) in zip(self._normals, verts):
            kx, ky = c * mx - s * my, s * mx + c * my
            halfplanes.append((kx, ky, kx * vx + ky * vy))
        pieces = []
        for lo, hi in base:
            cuts = sorted({lo, hi, *(t for t in extra if lo < t < hi)})
            for a, b in zip(cuts[:-1], cuts[1:]):
                if b <= a:
                    continue
                px, py, ex, ey = self._tip_and_elbow(d, nx, ny, 0.5 * (a + b))
                if not (segment_hits_halfplanes(o1x, o1y, o1x + ex, o1y + ey, halfplanes, eps)
                        or segment_hits_halfplanes(o1x + ex, o1y + ey, o1x + px, o1y + py, halfplanes, eps)):
                    pieces.append((a, b))
        return merge(pieces)

    def _free_test(self, x: float, y: float, beta: float, d: float, nx: float, ny: float):
        """The ``urdf`` verdict ``free(s) -> bool`` (no link shape penetrates the object) for the tip at
        line coordinate ``s`` [m], the object at (x [m], y [m], beta [rad]) and its edge's line at
        distance ``d`` [m] with inward normal (nx, ny). Sets the checker's object pose. With a list
        ``kept`` as second argument, the checker's certificates kept across object poses are used
        (:meth:`~regrasp.model.collision.UrdfCollisionChecker.links_collide_kept`); on the compiled path the verdict
        is :func:`~regrasp.kernels.envelope.tip_is_free` and ``kept`` receives each link's smallest signed
        distance [m] (the last entry of its tuple, as for coal's certificates)."""
        if self.compiled:
            return self._compiled_free_test(x, y, beta)
        self.checker.set_object_pose(x, y, beta)
        links_collide = self.checker.links_collide
        links_collide_kept = self.checker.links_collide_kept
        tip_and_elbow = self._tip_and_elbow
        o1x, o1y = self._joint1
        hypot = math.hypot

        def free(s: float, kept: list | None = None) -> bool:
            px, py, ex, ey = tip_and_elbow(d, nx, ny, s)
            n1 = hypot(ex, ey)
            vx, vy = px - ex, py - ey
            n2 = hypot(vx, vy)
            if kept is None:
                return not links_collide(ex / n1, ey / n1, o1x + ex, o1y + ey, vx / n2, vy / n2)
            return not links_collide_kept(kept, ex / n1, ey / n1, o1x + ex, o1y + ey, vx / n2, vy / n2)

        return free

    def _compiled_free_test(self, x: float, y: float, beta: float):
        """:meth:`_free_test` on the compiled path, at the object pose (x [m], y [m], beta [rad])."""
        par, shapes, vertices, normals = self._kernel_inputs
        nearest = np.empty(2)

        def free(s: float, kept: list | None = None) -> bool:
            verdict = tip_is_free(par, shapes, vertices, normals, x, y, beta, s, nearest)
            if kept is not None:
                near = nearest.tolist()
                kept[0], kept[1] = (near[0],), (near[1],)
            return verdict

        return free

    def _urdf_ends(self, base: Intervals, hints: Intervals, free) -> tuple[tuple[bool, tuple[float, ...]], ...]:
        """The ``urdf`` cuts of ``base`` (line coordinates s [m]): grid, then bisection of every flip.

        Per piece of ``base``: (whether ``free`` holds at its start, the free side of every flip of
        the verdict, in order, each within the bisection tolerance of the flip). The flips alternate
        between free → colliding and colliding → free; :func:`_urdf_pieces` turns this into intervals.
        """
        tol = self.urdf_tolerance * self.edge.length
        hint_points = [t for iv in hints for t in iv]
        out = []
        for lo, hi in base:
            grid = set(_linspace(lo, hi, self.urdf_grid))
            grid.update(t for t in hint_points if lo < t < hi)
            pts = sorted(grid)
            verdicts = [free(s) for s in pts]
            ends = []
            for k in range(1, len(pts)):
                if verdicts[k] == verdicts[k - 1]:
                    continue
                a, b = pts[k - 1], pts[k]  # verdict flips in (a, b): bisect
                fa = verdicts[k - 1]
                while b - a > tol:
                    m = 0.5 * (a + b)
                    if free(m) == fa:
                        a = m
                    else:
                        b = m
                ends.append(a if fa else b)  # the free side
            out.append((verdicts[0], tuple(ends)))
        return tuple(out)

    # ------------------------------------------------------------------ envelope
    def at(self, pose_object_in_hand: ArrayLike, time: float = 0.0) -> EnvelopeSample:
        """The envelope at one object pose ``(x [m], y [m], beta [rad])`` in the hand frame."""
        t_start = _time.perf_counter()
        if type(time) is not float or time - time != 0.0:  # (a finite float passes without a call)
            time = as_finite_float("time", time)
        x, y, beta = _pose_floats(pose_object_in_hand)
        if self.compiled:
            return self._at_compiled(x, y, beta, time, t_start)
        frame = self._frame(x, y, beta)
        feasible_s = frame.ideal
        if self.checker is not None and frame.base:
            feasible_s = _urdf_pieces(frame.base, self._frame_ends(frame, x, y, beta))
        return self._sample(frame, feasible_s, time, t_start)

    def kernel_arguments(self, pose_object_in_hand: ArrayLike) -> tuple:
        """The arguments of the compiled path's one :func:`~regrasp.kernels.envelope.envelope_sample_into` call at an
        object pose ``(x [m], y [m], beta [rad])`` (its inputs, the pose as floats, its preallocated outputs)."""
        if not self.compiled:
            raise InvalidParameterError("compiled", self.compiled, "True: this envelope runs the reference path")
        return (*self._kernel_inputs, *_pose_floats(pose_object_in_hand), *self._kernel_outputs)

    @property
    def compiled_arguments(self) -> tuple | None:
        """The compiled path's :func:`~regrasp.kernels.envelope.envelope_sample_into` arguments but the pose: its
        inputs, then its preallocated outputs (:meth:`sample_from_outputs` reads them); None on the reference path."""
        return (*self._kernel_inputs, *self._kernel_outputs) if self.compiled else None

    def sample_from(self, scalars: np.ndarray, reachable: np.ndarray, on_edge: bool, feasible: np.ndarray,
                    time: float) -> EnvelopeSample:
        """The :class:`EnvelopeSample` of a compiled evaluation's outputs (:func:`~regrasp.kernels.envelope.
        envelope_sample_into`'s, as :meth:`at` reads them): (d, λ, s0), the reachable set (k, 2) [m], whether
        reachable ∩ edge is not empty and the feasible set (k, 2) [m], at time ``time`` [s]."""
        d, lam, _ = np.asarray(scalars, dtype=float).tolist()
        return self._make_sample(d, lam, tuple(map(tuple, np.asarray(reachable).tolist())), bool(on_edge),
                                 tuple(map(tuple, np.asarray(feasible).tolist())), float(time), _time.perf_counter())

    def _run_kernel(self, x: float, y: float, beta: float) -> tuple[int, int, int]:
        """One call of :func:`~regrasp.kernels.envelope.envelope_sample_into` at the object pose (x [m], y [m],
        beta [rad]) into the preallocated outputs; (reachable pieces, pieces of reachable ∩ edge, feasible pieces)."""
        return envelope_sample_into(*self._kernel_inputs, x, y, beta, *self._kernel_outputs)

    def _at_compiled(self, x: float, y: float, beta: float, time: float, t_start: float) -> EnvelopeSample:
        """:meth:`at` on the compiled path."""
        n_reach, n_base, n_feasible = self._run_kernel(x, y, beta)
        scalars, reach, _, _, _, _, feasible, _ = self._kernel_outputs
        d, lam, _ = scalars.tolist()
        return self._make_sample(d, lam, tuple(map(tuple, reach[:n_reach].tolist())), n_base > 0,
                                 tuple(map(tuple, feasible[:n_feasible].tolist())), time, t_start)

    def urdf_cuts(self, pose_object_in_hand: ArrayLike) -> tuple[tuple[bool, tuple[float, ...]], ...]:
        """The ``urdf`` cuts of :meth:`at` at an object pose ``(x [m], y [m], beta [rad])``: per piece of reachable ∩
        edge, whether the tip is free at its start and the free side of every flip of the verdict, in order, in
        line coordinates s [m] (ξ = s - s0, :class:`EdgeLine`)."""
        if self.checker is None:
            raise InvalidParameterError("geometry", self.geometry.value, "'urdf' (the 'ideal' geometry has no cuts)")
        x, y, beta = _pose_floats(pose_object_in_hand)
        if self.compiled:
            _, n_base, _ = self._run_kernel(x, y, beta)
            _, _, _, starts, counts, flips, _, _ = self._kernel_outputs
            out, k = [], 0
            for start, count in zip(starts[:n_base].tolist(), counts[:n_base].tolist()):
                out.append((start, tuple(flips[k:k + count].tolist())))
                k += count
            return tuple(out)
        frame = self._frame(x, y, beta)
        return self._frame_ends(frame, x, y, beta) if frame.base else ()

    def _frame_ends(self, frame: _Frame, x: float, y: float, beta: float) -> tuple:
        """:meth:`_urdf_ends` of ``frame`` (with its ``ideal`` set) at the object pose (x [m], y [m], beta [rad])."""
        return self._urdf_ends(frame.base, frame.ideal, self._free_test(x, y, beta, frame.d, frame.nx, frame.ny))

    def _frame(self, x: float, y: float, beta: float, ideal: bool = True) -> _Frame:
        """The closed-form part of a sample at the object pose (x [m], y [m], beta [rad]) (without the
        ``ideal`` feasible set when ``ideal`` is False)."""
        d, lam, s0, nx, ny, c, s = self._line(x, y, beta)
        reach_s = reachable_on_line(d, self.l1, self.l2, self.sign)
        lo_xi, hi_xi = self.edge.xi_range
        base = intersect(reach_s, ((lo_xi + s0, hi_xi + s0),))
        feasible = self._ideal_feasible(base, x, y, c, s, d, nx, ny) if base and ideal else ()
        return _Frame(d, lam, s0, nx, ny, c, s, condition_of(d, self.l1), reach_s, base, feasible)

    def _sample(self, frame: _Frame, feasible_s: Intervals, time: float, t_start: float) -> EnvelopeSample:
        """The :class:`EnvelopeSample` of ``frame`` with the feasible pieces ``feasible_s`` (line coordinates)."""
        s0 = frame.s0
        return self._make_sample(frame.d, frame.lam, tuple((a - s0, b - s0) for a, b in frame.reach), bool(frame.base),
                                 tuple((a - s0, b - s0) for a, b in feasible_s), time, t_start, frame.condition)

    def _make_sample(self, d: float, lam: float, reachable: Intervals, on_edge: bool, feasible: Intervals,
                     time: float, t_start: float, condition: Condition | None = None) -> EnvelopeSample:
        """The :class:`EnvelopeSample` with line distance ``d`` [m], angle ``lam`` [rad], the reachable set
        ``reachable``, whether reachable ∩ edge is not empty, and the feasible set ``feasible`` (both in ξ [m])."""
        if condition is None:
            condition = _condition(d, self.l1)
        if feasible:
            reason = None
        elif condition is Condition.I:
            reason = "condition I"
        elif not reachable:
            reason = "out of reach"
        elif not on_edge:
            reason = "off the edge"
        else:
            reason = "collision"
        return EnvelopeSample(time=float(time), d=d, lam=lam, condition=condition, reachable=reachable,
                              edge_range=self.edge.xi_range, feasible=feasible, reason=reason,
                              seconds=_time.perf_counter() - t_start)

    def tip_at(self, pose_object_in_hand: ArrayLike, xi: float) -> np.ndarray:
        """Tip position [m] in the hand frame for contact ``xi`` [m] at an object pose."""
        pose = as_finite_array("pose_object_in_hand", pose_object_in_hand, (3,))
        return pose[:2] + rotation(pose[2]) @ self.edge.point(as_finite_float("xi", xi))

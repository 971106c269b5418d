r"""The steps of one envelope sample at one object pose, on plain floats (paper §2.2, Definition 2.2).

:class:`EnvelopeEvaluator` holds one finger's and one edge's constants as floats and runs the steps that
:meth:`FingerEnvelope.at <regrasp.envelope.finger_envelope.FingerEnvelope.at>` chains and that
:class:`~regrasp.envelope.tracker.EnvelopeTracker` reuses between control steps. Everything is in the hand frame
and in line coordinates s [m] (ξ = s - s0, :class:`~regrasp.envelope.line.EdgeLine`):

1. the closed-form part (:meth:`EnvelopeEvaluator.closed_form`, a :class:`ClosedForm`): the edge's line
   (eqs. 2.1.1–2.1.2), the condition I–IV, the reachable set (:func:`~regrasp.envelope.line.reachable_on_line`),
   reachable ∩ edge and the ``ideal`` feasible set;
2. the limiting vertices (:meth:`EnvelopeEvaluator.vertex_cuts`, Example 2.2): where link 1 passes through a
   vertex :math:`v` (:math:`|v - o_1| \le l_1`) the elbow is :math:`e = o_1 + l_1 (v - o_1)/|v - o_1|` and the
   tip is one of the two points of the line at distance :math:`l_2` from it,
   :math:`s = (e - o_1)^T t \pm \sqrt{l_2^2 - (d - (e - o_1)^T n)^2}`; with segment links these are the only
   places where the verdict changes (:meth:`EnvelopeEvaluator.ideal_feasible` classifies each piece between
   them at its midpoint);
3. the ``urdf`` verdict (:meth:`EnvelopeEvaluator.free_test`: coal's, or the compiled kernel's
   :func:`~regrasp.kernels.envelope.tip_is_free`) and its cuts (:meth:`EnvelopeEvaluator.urdf_ends`: a grid
   per piece of reachable ∩ edge plus the ``ideal`` ends, every flip bisected), turned into intervals by
   :func:`urdf_pieces`.
"""

from __future__ import annotations

import math
from typing import NamedTuple, Protocol

import numpy as np

from ..core.exceptions import InvalidParameterError
from ..core.intervals import Intervals, intersect, merge
from ..core.planar import wrap_angle
from ..core.polygon import ConvexPolygon, Edge
from ..core.validation import as_flag
from ..kernels.envelope import ENVELOPE_PARAMETERS, envelope_sample_into, feasible_capacity, tip_is_free, workspace_size
from ..model.collision import UrdfCollisionChecker, segment_hits_halfplanes
from ..model.finger import Finger
from .floats import linspace_floats
from .line import Condition, condition_of, reachable_on_line

__all__ = ["ClosedForm", "EnvelopeEvaluator", "FreeTest", "UrdfCuts", "urdf_cuts", "urdf_pieces"]

#: The ``urdf`` cuts of reachable ∩ edge: per piece, (whether the tip is free at its start, the free side [m] of
#: every flip of the verdict, in order).
UrdfCuts = tuple[tuple[bool, tuple[float, ...]], ...]


class FreeTest(Protocol):
    """The ``urdf`` verdict at one object pose (:meth:`EnvelopeEvaluator.free_test`)."""

    def __call__(self, s: float, kept: list | None = None) -> bool:
        """Whether no link shape penetrates the object with the tip at line coordinate ``s`` [m]; ``kept``: the
        collision certificates kept across object poses (see :meth:`EnvelopeEvaluator.free_test`)."""


class ClosedForm(NamedTuple):
    """The closed-form part of a sample at one object pose (line coordinates s [m]; see
    :class:`~regrasp.envelope.line.EdgeLine`)."""

    d: float  #: signed line distance [m]
    lam: float  #: inward normal angle λ [rad] in the finger base frame
    s0: float  #: line coordinate [m] of the edge's ξ origin
    nx: float  #: inward normal, x (hand frame)
    ny: float  #: inward normal, y (hand frame)
    c: float  #: cos beta
    s: float  #: sin beta
    condition: Condition
    reach: Intervals  #: reachable set on the line
    base: Intervals  #: reachable ∩ edge
    ideal: Intervals  #: feasible with segment links (the ``urdf`` mode's hints); empty when not asked for


def urdf_pieces(base: Intervals, ends: UrdfCuts) -> Intervals:
    """The free pieces of ``base`` (line coordinates s [m]) from its ``urdf`` cuts ``ends`` (per piece: the verdict
    at its start, the free side of every flip: :meth:`EnvelopeEvaluator.urdf_ends`)."""
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


def urdf_cuts(base: Intervals, hints: Intervals, free: FreeTest, grid: int, tol: float) -> UrdfCuts:
    """The ``urdf`` cuts of ``base`` (a coordinate along the contact face [m]): grid, then bisection of every flip.

    Per piece of ``base``: (whether ``free`` holds at its start, the free side of every flip of the verdict, in
    order, each within ``tol`` [m] of the flip). The grid has ``grid`` points per piece plus the ends of ``hints``
    inside it (the ``ideal`` feasible set). The flips alternate between free → colliding and colliding → free;
    :func:`urdf_pieces` turns this into intervals.
    """
    hint_points = [t for iv in hints for t in iv]
    out = []
    for lo, hi in base:
        points = set(linspace_floats(lo, hi, grid))
        points.update(t for t in hint_points if lo < t < hi)
        pts = sorted(points)
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


class EnvelopeEvaluator:
    r"""The steps of one finger's envelope on one edge at one object pose (module docstring), on plain floats with
    the constants precomputed. A :class:`~regrasp.envelope.finger_envelope.FingerEnvelope` builds its own (its
    ``evaluator``) from its validated arguments; these are not validated again.

    Args:
        finger: The finger (joint 1, base angle, link lengths and configuration).
        polygon: The object.
        edge: The contact edge of ``polygon``.
        checker: The ``urdf`` collision checker (None in the ``ideal`` geometry).
        urdf_grid: Grid points per piece of reachable ∩ edge in ``urdf`` mode (>= 2).
        urdf_tolerance: Bisection tolerance in ``urdf`` mode, as a fraction of the edge length.
        compiled: Whether to run the compiled kernel (:mod:`regrasp.kernels.envelope`); None: when ``checker``'s
            link shapes all have a planar footprint.

    Attributes:
        compiled: Whether the compiled kernel runs (the ``urdf`` verdict and :meth:`run_kernel`).
        kernel_inputs: The compiled path's constant arguments of :func:`~regrasp.kernels.envelope.
            envelope_sample_into` (parameters, footprints, vertices, normals); None on the reference path.
        kernel_outputs: Its preallocated outputs; None on the reference path.
    """

    def __init__(self, finger: Finger, polygon: ConvexPolygon, edge: Edge, checker: UrdfCollisionChecker | None, *,
                 urdf_grid: int, urdf_tolerance: float, compiled: bool | None):
        self.edge = edge
        self.checker = checker
        self.urdf_grid = urdf_grid
        self.urdf_tolerance = urdf_tolerance
        self.l1, self.l2 = finger.link_lengths
        self.sign = finger.configuration.sign
        self._eps = 1e-12 * (polygon.scale + self.l1 + self.l2)
        self._joint1 = tuple(finger.joint1_in_hand.tolist())
        self._base_angle = float(finger.base_in_hand[2])
        self._edge_normal = tuple(edge.inward_normal.tolist())
        self._edge_origin = tuple(edge.xi_origin.tolist())
        self._vertices = [tuple(v) for v in polygon.vertices.tolist()]
        self._normals = [tuple(e.inward_normal.tolist()) for e in polygon.edges]
        self._l1_sq = self.l1**2
        self._l2_sq = self.l2**2
        self._l1_sq_minus_l2_sq = self.l1**2 - self.l2**2
        self.compiled = self._use_kernel(compiled)
        self.kernel_inputs: tuple | None = None
        self.kernel_outputs: tuple | None = None
        if self.compiled:
            self._init_kernel()

    def _use_kernel(self, compiled: bool | None) -> bool:
        """Whether the compiled kernel runs, given the ``compiled`` argument."""
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
        self.kernel_inputs = (par, self.checker.footprints, vertices, normals)
        rows = feasible_capacity(self.urdf_grid, len(self._vertices))
        self.kernel_outputs = (np.empty(3), np.empty((4, 2)), np.empty((4, 2)), np.empty(4, np.bool_),
                               np.empty(4, np.int64), np.empty(rows), np.empty((rows, 2)),
                               np.empty(workspace_size(self.urdf_grid, len(self._vertices))))

    def run_kernel(self, x: float, y: float, beta: float) -> tuple[int, int, int]:
        """One call of :func:`~regrasp.kernels.envelope.envelope_sample_into` at the object pose (x [m], y [m],
        beta [rad]) into :attr:`kernel_outputs`; (reachable pieces, pieces of reachable ∩ edge, feasible pieces).
        Compiled path only."""
        return envelope_sample_into(*self.kernel_inputs, x, y, beta, *self.kernel_outputs)

    # ------------------------------------------------------------------ geometry
    def edge_line(self, x: float, y: float, beta: float) -> tuple[float, float, float, float, float, float, float]:
        """(d [m], λ [rad], s0 [m], n_x, n_y, cos beta, sin beta) of the edge's line (eqs. 2.1.1–2.1.2) at the
        object pose (x [m], y [m], beta [rad]) in the hand frame."""
        c, s = math.cos(beta), math.sin(beta)
        n0x, n0y = self._edge_normal
        nx, ny = c * n0x - s * n0y, s * n0x + c * n0y
        cx, cy = self._edge_origin
        o1x, o1y = self._joint1
        rx = x + (c * cx - s * cy) - o1x
        ry = y + (s * cx + c * cy) - o1y
        lam = wrap_angle(math.atan2(ny, nx) - self._base_angle)
        return rx * nx + ry * ny, lam, ry * nx - rx * ny, nx, ny, c, s

    def tip_and_elbow(self, d: float, nx: float, ny: float, s: float) -> tuple[float, float, float, float]:
        r"""Tip and elbow (x, y, x, y) [m] relative to joint 1 (hand frame) for the tip at line coordinate ``s`` [m]
        (line at distance ``d`` [m] with inward normal (nx, ny); inside the annulus): the configured IK solution
        :math:`e = a u + \sigma h \perp u` of :mod:`regrasp.envelope.line`."""
        px = d * nx - s * ny
        py = d * ny + s * nx
        r = math.hypot(px, py)
        ux, uy = px / r, py / r
        a = (self._l1_sq_minus_l2_sq + r * r) / (2.0 * r)
        h = self.sign * math.sqrt(max(self._l1_sq - a * a, 0.0))
        return px, py, a * ux - h * uy, a * uy + h * ux

    def closed_form(self, x: float, y: float, beta: float, ideal: bool = True) -> ClosedForm:
        """The closed-form part of a sample at the object pose (x [m], y [m], beta [rad]) (without the
        ``ideal`` feasible set when ``ideal`` is False)."""
        d, lam, s0, nx, ny, c, s = self.edge_line(x, y, beta)
        reach_s = reachable_on_line(d, self.l1, self.l2, self.sign)
        lo_xi, hi_xi = self.edge.xi_range
        base = intersect(reach_s, ((lo_xi + s0, hi_xi + s0),))
        feasible = self.ideal_feasible(base, x, y, c, s, d, nx, ny) if base and ideal else ()
        return ClosedForm(d, lam, s0, nx, ny, c, s, condition_of(d, self.l1), reach_s, base, feasible)

    # ------------------------------------------------------------------ ideal geometry
    def vertex_cuts(self, x: float, y: float, c: float, s: float, d: float, nx: float,
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

    def ideal_feasible(self, base: Intervals, x: float, y: float, c: float, s: float,
                       d: float, nx: float, ny: float) -> Intervals:
        """Feasible pieces of ``base`` with segment links (line coordinates s [m]) at the object pose
        (x [m], y [m], cos beta, sin beta), the edge's line at distance ``d`` [m] with inward normal (nx, ny)."""
        o1x, o1y = self._joint1
        eps = self._eps
        verts, extra = self.vertex_cuts(x, y, c, s, d, nx, ny)
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
                px, py, ex, ey = self.tip_and_elbow(d, nx, ny, 0.5 * (a + b))
                if not (segment_hits_halfplanes(o1x, o1y, o1x + ex, o1y + ey, halfplanes, eps)
                        or segment_hits_halfplanes(o1x + ex, o1y + ey, o1x + px, o1y + py, halfplanes, eps)):
                    pieces.append((a, b))
        return merge(pieces)

    # ------------------------------------------------------------------ urdf geometry
    def free_test(self, x: float, y: float, beta: float, d: float, nx: float, ny: float) -> FreeTest:
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
        tip_and_elbow = self.tip_and_elbow
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

    def _compiled_free_test(self, x: float, y: float, beta: float) -> FreeTest:
        """:meth:`free_test` on the compiled path, at the object pose (x [m], y [m], beta [rad])."""
        par, shapes, vertices, normals = self.kernel_inputs
        nearest = np.empty(2)

        def free(s: float, kept: list | None = None) -> bool:
            verdict = tip_is_free(par, shapes, vertices, normals, x, y, beta, s, nearest)
            if kept is not None:
                near = nearest.tolist()
                kept[0], kept[1] = (near[0],), (near[1],)
            return verdict

        return free

    def urdf_ends(self, base: Intervals, hints: Intervals, free: FreeTest) -> UrdfCuts:
        """The ``urdf`` cuts of ``base`` (line coordinates s [m]): :func:`urdf_cuts` with ``urdf_grid`` points per piece
        and the bisection tolerance ``urdf_tolerance`` × the edge length."""
        return urdf_cuts(base, hints, free, self.urdf_grid, self.urdf_tolerance * self.edge.length)

    def urdf_cuts_of(self, part: ClosedForm, x: float, y: float, beta: float) -> UrdfCuts:
        """:meth:`urdf_ends` of the closed-form part ``part`` (with its ``ideal`` set as hints) at the object pose
        (x [m], y [m], beta [rad])."""
        return self.urdf_ends(part.base, part.ideal, self.free_test(x, y, beta, part.d, part.nx, part.ny))

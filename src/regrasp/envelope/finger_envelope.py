r"""The envelope of feasible contacts of one finger on one edge (paper §2.2).

The edge's line seen from the finger (eqs. 2.1.1–2.1.2), the conditions I–IV and the reachable set
(Definition 2.1) are :mod:`regrasp.envelope.line`'s; the steps of one sample on plain floats are
:class:`~regrasp.envelope.evaluator.EnvelopeEvaluator`'s. :class:`FingerEnvelope` chains them into an
:class:`EnvelopeSample` per object pose.

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

**Curved objects.** On a :class:`~regrasp.core.curves.CurvedObject` (one face, ξ the arc length) a sample is
:class:`~regrasp.envelope.curve_evaluator.CurveEvaluator`'s: the same definitions on the tangent line at each ξ
(:mod:`regrasp.envelope.curve` derives the breakpoints and certifies their bracketing; a disc has them in closed
form), sets on the window of one perimeter about the foot of the first joint (``near``: unwrapped along a
trajectory), ``urdf`` cuts bisected to ``urdf_tolerance`` × the perimeter. No compiled path.

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

import numpy as np
from numpy.typing import ArrayLike

from ..core.curves import CurvedObject
from ..core.exceptions import InvalidParameterError
from ..core.intervals import Intervals
from ..core.planar import rotation
from ..core.polygon import ConvexPolygon
from ..core.validation import as_finite_array, as_finite_float, as_flag, as_integer, as_positive_float, expect_type
from ..model.collision import UrdfCollisionChecker, default_tip_clearance
from ..model.finger import Finger
from ..model.geometry import Geometry
from .curve_evaluator import CurveEvaluator
from .evaluator import ClosedForm, EnvelopeEvaluator, UrdfCuts, urdf_pieces
from .floats import pose_floats
from .line import Condition, EdgeLine, condition_of_floats

__all__ = ["EnvelopeSample", "FingerEnvelope"]


@dataclass(frozen=True)
class EnvelopeSample:
    """The envelope of one finger on its edge at one object pose.

    All sets are tuples of closed ξ-intervals ``(lo, hi)`` [m] on the edge's ξ axis.

    On a curved object ξ is the arc length and the sets lie in the sample's window ``edge_range`` of one perimeter
    about ``xi_foot``; ``d`` and ``lam`` are those of the tangent line at ``xi_foot`` (``d`` is the first joint's
    signed distance from the curve, positive outside; the condition follows from it as on an edge); a closed curve
    has no edge ends, so the reason is never ``"off the edge"``.

    Attributes:
        time: Sample time [s].
        d: Signed line distance [m] (eq. 2.1.2).
        lam: Inward normal angle λ [rad] in the finger base frame.
        condition: Condition I–IV.
        reachable: Reachable set (Definition 2.1) on the edge's whole line (a curve: in the window).
        edge_range: ξ range of the actual edge (a curve: the window (ξ_c - P/2, ξ_c + P/2)).
        feasible: Feasible set (Definition 2.2).
        reason: None when ``feasible`` is non-empty, else why it is empty:
            ``"condition I"``, ``"out of reach"``, ``"off the edge"`` or ``"collision"``.
        seconds: Wall time [s] spent computing this sample.
        xi_foot: On a curved object, ξ_c [m]: the foot of the first joint on the curve (the window's centre; pass it
            as the next sample's ``near``); None on an edge.
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
    xi_foot: float | None = None

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


class FingerEnvelope:
    r"""Computes the feasible-contact envelope of one finger on one polygon edge, or on a curved object's boundary.

    Build once for a (finger, object, edge) and call :meth:`at` for each object pose.
    :meth:`at` works on plain floats with constants precomputed here (it is called at
    every control step by a regrasp supervisor).

    Args:
        finger: The finger (its configuration selects the reachable set).
        polygon: The object: a :class:`~regrasp.core.polygon.ConvexPolygon` or a
            :class:`~regrasp.core.curves.CurvedObject` (module docstring).
        edge: Index of the contact edge (edge k runs from vertex k to vertex k+1; a curve's one face is 0).
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
            :class:`~regrasp.core.exceptions.InvalidParameterError`); False: never. A curved object has no
            compiled path (True raises).
        coal_tolerance: ``urdf`` mode: the tolerance [m] of coal's GJK and EPA iterations
            (:class:`~regrasp.model.collision.UrdfCollisionChecker`; default: coal's, 1e-6).

    Attributes:
        compiled: Whether :meth:`at` runs the compiled kernel.
        curved: Whether the object is a curved one.
        evaluator: The steps of one sample on plain floats (:class:`~regrasp.envelope.evaluator.EnvelopeEvaluator`,
            shared with :class:`~regrasp.envelope.tracker.EnvelopeTracker`; on a curve a
            :class:`~regrasp.envelope.curve_evaluator.CurveEvaluator`).
    """

    def __init__(
        self,
        finger: Finger,
        polygon: ConvexPolygon | CurvedObject,
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
        self.polygon = expect_type("polygon", polygon, (ConvexPolygon, CurvedObject),
                                   "a ConvexPolygon or a CurvedObject")
        self.curved = isinstance(polygon, CurvedObject)
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
        self.checker: UrdfCollisionChecker | None = None
        if tip_clearance is not None:  # (checked in either geometry, though only 'urdf' uses it)
            tip_clearance = as_positive_float("tip_clearance", tip_clearance, allow_zero=True)
        if self.geometry is Geometry.URDF:
            if tip_clearance is None:
                tip_clearance = default_tip_clearance(finger)
            self.checker = UrdfCollisionChecker(finger, polygon, float(tip_clearance), coal_tolerance=coal_tolerance)
        self.tip_clearance = None if self.checker is None else self.checker.tip_clearance
        if self.curved:
            if compiled is not None and as_flag("compiled", compiled):
                raise InvalidParameterError("compiled", compiled, "False or None for a curved object: the compiled "
                                            "kernels take polygon edges")
            self.evaluator = CurveEvaluator(finger, polygon, self.checker, urdf_grid=self.urdf_grid,
                                            urdf_tolerance=self.urdf_tolerance)
        else:
            self.evaluator = EnvelopeEvaluator(finger, polygon, self.edge, self.checker, urdf_grid=self.urdf_grid,
                                               urdf_tolerance=self.urdf_tolerance, compiled=compiled)
        self.compiled = self.evaluator.compiled

    # ------------------------------------------------------------------ geometry
    def line(self, pose_object_in_hand: ArrayLike) -> EdgeLine:
        """The edge's line parameters at an object pose ``(x, y, beta)`` in the hand frame (a curve: its tangent line
        at the first joint's foot ξ_c, with ``s0 = -ξ_c``: the foot is at s = 0)."""
        if self.curved:
            x, y, beta = pose_floats(pose_object_in_hand)
            solution = self.evaluator.solve(x, y, beta)
            nx, ny = (rotation(beta) @ np.array(solution.normal)).tolist()
            return EdgeLine(solution.distance, self.evaluator.normal_angle(solution, beta), np.array([nx, ny]),
                            np.array([-ny, nx]), -solution.xi_foot)
        d, lam, s0, nx, ny, _, _ = self.evaluator.edge_line(*pose_floats(pose_object_in_hand))
        return EdgeLine(d, lam, np.array([nx, ny]), np.array([-ny, nx]), s0)

    def tip_in_hand(self, line: EdgeLine, s: float) -> np.ndarray:
        """Point [m] of the edge's line with coordinate ``s``, in the hand frame."""
        return self.finger.joint1_in_hand + line.d * line.normal_in_hand + s * line.tangent_in_hand

    def elbow_in_hand(self, line: EdgeLine, s: float) -> np.ndarray:
        """Elbow [m] of the configured IK solution for the tip at ``s`` (inside the annulus)."""
        nx, ny = line.normal_in_hand.tolist()
        _, _, ex, ey = self.evaluator.tip_and_elbow(line.d, nx, ny, s)
        return self.finger.joint1_in_hand + np.array([ex, ey])

    def tip_at(self, pose_object_in_hand: ArrayLike, xi: float) -> np.ndarray:
        """Tip position [m] in the hand frame for contact ``xi`` [m] at an object pose."""
        pose = as_finite_array("pose_object_in_hand", pose_object_in_hand, (3,))
        return pose[:2] + rotation(pose[2]) @ self.edge.point(as_finite_float("xi", xi))

    # ------------------------------------------------------------------ envelope
    def at(self, pose_object_in_hand: ArrayLike, time: float = 0.0, *, near: float | None = None) -> EnvelopeSample:
        """The envelope at one object pose ``(x [m], y [m], beta [rad])`` in the hand frame. On a curved object,
        ``near`` [m] (the previous sample's ``xi_foot``) picks the window's representative of ξ (unwrapped along a
        trajectory); on an edge it is ignored."""
        t_start = _time.perf_counter()
        if type(time) is not float or time - time != 0.0:  # (a finite float passes without a call)
            time = as_finite_float("time", time)
        x, y, beta = pose_floats(pose_object_in_hand)
        if self.curved:
            return self._at_curve(x, y, beta, time, None if near is None else as_finite_float("near", near), t_start)
        if self.compiled:
            return self._at_compiled(x, y, beta, time, t_start)
        evaluator = self.evaluator
        part = evaluator.closed_form(x, y, beta)
        feasible_s = part.ideal
        if self.checker is not None and part.base:
            feasible_s = urdf_pieces(part.base, evaluator.urdf_cuts_of(part, x, y, beta))
        return self.sample(part, feasible_s, time, t_start)

    def kernel_arguments(self, pose_object_in_hand: ArrayLike) -> tuple:
        """The arguments of the compiled path's one :func:`~regrasp.kernels.envelope.envelope_sample_into` call at an
        object pose ``(x [m], y [m], beta [rad])`` (its inputs, the pose as floats, its preallocated outputs)."""
        if not self.compiled:
            raise InvalidParameterError("compiled", self.compiled, "True: this envelope runs the reference path")
        evaluator = self.evaluator
        return (*evaluator.kernel_inputs, *pose_floats(pose_object_in_hand), *evaluator.kernel_outputs)

    @property
    def compiled_arguments(self) -> tuple | None:
        """The compiled path's :func:`~regrasp.kernels.envelope.envelope_sample_into` arguments but the pose: its
        inputs, then its preallocated outputs (:meth:`sample_from` reads them); None on the reference path."""
        evaluator = self.evaluator
        return (*evaluator.kernel_inputs, *evaluator.kernel_outputs) if self.compiled else None

    def sample_from(self, scalars: np.ndarray, reachable: np.ndarray, on_edge: bool, feasible: np.ndarray,
                    time: float) -> EnvelopeSample:
        """The :class:`EnvelopeSample` of a compiled evaluation's outputs (:func:`~regrasp.kernels.envelope.
        envelope_sample_into`'s, as :meth:`at` reads them): (d, λ, s0), the reachable set (k, 2) [m], whether
        reachable ∩ edge is not empty and the feasible set (k, 2) [m], at time ``time`` [s]."""
        d, lam, _ = np.asarray(scalars, dtype=float).tolist()
        return self._make_sample(d, lam, tuple(map(tuple, np.asarray(reachable).tolist())), bool(on_edge),
                                 tuple(map(tuple, np.asarray(feasible).tolist())), float(time), _time.perf_counter())

    def _at_compiled(self, x: float, y: float, beta: float, time: float, t_start: float) -> EnvelopeSample:
        """:meth:`at` on the compiled path."""
        n_reach, n_base, n_feasible = self.evaluator.run_kernel(x, y, beta)
        scalars, reach, _, _, _, _, feasible, _ = self.evaluator.kernel_outputs
        d, lam, _ = scalars.tolist()
        return self._make_sample(d, lam, tuple(map(tuple, reach[:n_reach].tolist())), n_base > 0,
                                 tuple(map(tuple, feasible[:n_feasible].tolist())), time, t_start)

    def _at_curve(self, x: float, y: float, beta: float, time: float, near: float | None,
                  t_start: float) -> EnvelopeSample:
        """:meth:`at` on a curved object."""
        evaluator = self.evaluator
        solution = evaluator.solve(x, y, beta, near)
        feasible = evaluator.feasible(solution, x, y, beta)
        d = solution.distance
        condition = condition_of_floats(d, self.l1)
        return EnvelopeSample(time=float(time), d=d, lam=evaluator.normal_angle(solution, beta), condition=condition,
                              reachable=solution.reachable, edge_range=solution.window, feasible=feasible,
                              reason=_reason(feasible, condition, solution.reachable, bool(solution.reachable)),
                              seconds=_time.perf_counter() - t_start, xi_foot=solution.xi_foot)

    def urdf_cuts(self, pose_object_in_hand: ArrayLike) -> UrdfCuts:
        """The ``urdf`` cuts of :meth:`at` at an object pose ``(x [m], y [m], beta [rad])``: per piece of reachable ∩
        edge, whether the tip is free at its start and the free side of every flip of the verdict, in order, in
        line coordinates s [m] (ξ = s - s0, :class:`~regrasp.envelope.line.EdgeLine`; on a curve in ξ [m], on the
        window about the foot)."""
        if self.checker is None:
            raise InvalidParameterError("geometry", self.geometry.value, "'urdf' (the 'ideal' geometry has no cuts)")
        x, y, beta = pose_floats(pose_object_in_hand)
        evaluator = self.evaluator
        if self.curved:
            solution = evaluator.solve(x, y, beta)
            return evaluator.urdf_ends(solution, x, y, beta) if solution.reachable else ()
        if self.compiled:
            _, n_base, _ = evaluator.run_kernel(x, y, beta)
            _, _, _, starts, counts, flips, _, _ = evaluator.kernel_outputs
            out, k = [], 0
            for start, count in zip(starts[:n_base].tolist(), counts[:n_base].tolist()):
                out.append((start, tuple(flips[k:k + count].tolist())))
                k += count
            return tuple(out)
        part = evaluator.closed_form(x, y, beta)
        return evaluator.urdf_cuts_of(part, x, y, beta) if part.base else ()

    def sample(self, part: ClosedForm, feasible_s: Intervals, time: float, t_start: float) -> EnvelopeSample:
        """The :class:`EnvelopeSample` at time ``time`` [s] of the closed-form part ``part``
        (:meth:`EnvelopeEvaluator.closed_form <regrasp.envelope.evaluator.EnvelopeEvaluator.closed_form>`) with the
        feasible pieces ``feasible_s`` (line coordinates s [m]); its ``seconds`` are counted from ``t_start``
        (:func:`time.perf_counter` [s] when its computation began)."""
        s0 = part.s0
        return self._make_sample(part.d, part.lam, tuple((a - s0, b - s0) for a, b in part.reach), bool(part.base),
                                 tuple((a - s0, b - s0) for a, b in feasible_s), time, t_start, part.condition)

    def _make_sample(self, d: float, lam: float, reachable: Intervals, on_edge: bool, feasible: Intervals,
                     time: float, t_start: float, condition: Condition | None = None) -> EnvelopeSample:
        """The :class:`EnvelopeSample` with line distance ``d`` [m], angle ``lam`` [rad], the reachable set
        ``reachable``, whether reachable ∩ edge is not empty, and the feasible set ``feasible`` (both in ξ [m])."""
        if condition is None:
            condition = condition_of_floats(d, self.l1)
        return EnvelopeSample(time=float(time), d=d, lam=lam, condition=condition, reachable=reachable,
                              edge_range=self.edge.xi_range, feasible=feasible,
                              reason=_reason(feasible, condition, reachable, on_edge),
                              seconds=_time.perf_counter() - t_start)


def _reason(feasible: Intervals, condition: Condition, reachable: Intervals, on_edge: bool) -> str | None:
    """Why a feasible set is empty (None when it is not): see :class:`EnvelopeSample`."""
    if feasible:
        return None
    if condition is Condition.I:
        return "condition I"
    if not reachable:
        return "out of reach"
    if not on_edge:
        return "off the edge"
    return "collision"

r"""The steps of one envelope sample on a curved object at one object pose (paper §2.2, Definition 2.2).

:class:`CurveEvaluator` is the curved counterpart of :class:`~regrasp.envelope.evaluator.EnvelopeEvaluator`: it maps
the finger's first joint into the object frame, where :class:`~regrasp.envelope.curve.CurveGeometry` gives the
reachable and ``ideal`` feasible ξ-sets on the window about the joint's foot, and it runs the ``urdf`` verdict
(coal's signed distances between the finger's URDF shapes, the distal one shortened by the tip clearance, and the
object's :meth:`~regrasp.core.curves.CurvedObject.to_coal` prism) on the reachable pieces: a grid of ``urdf_grid``
points per piece plus the ``ideal`` ends, every change of verdict bisected to ``urdf_tolerance`` × the perimeter
(:func:`~regrasp.envelope.evaluator.urdf_cuts`, as on an edge). There is no compiled path: the compiled kernels
take polygon edges.
"""

from __future__ import annotations

import math

from ..core.curves import CurvedObject
from ..core.intervals import Intervals
from ..core.planar import wrap_angle
from ..model.collision import UrdfCollisionChecker
from ..model.finger import Finger
from .curve import CurveGeometry, CurveSolution
from .evaluator import FreeTest, UrdfCuts, urdf_cuts, urdf_pieces

__all__ = ["CurveEvaluator"]


class CurveEvaluator:
    """One finger's envelope on a curved object, per object pose, on plain floats (module docstring). A
    :class:`~regrasp.envelope.finger_envelope.FingerEnvelope` on a curve builds its own (its ``evaluator``).

    Args:
        finger: The finger.
        curve: The object.
        checker: The ``urdf`` collision checker (None in the ``ideal`` geometry).
        urdf_grid: Grid points per reachable piece in ``urdf`` mode (>= 2).
        urdf_tolerance: Bisection tolerance in ``urdf`` mode, as a fraction of the perimeter.
        closed_form: :class:`~regrasp.envelope.curve.CurveGeometry`'s (None: closed form on a disc).

    Attributes:
        geometry: The object-frame computation.
        tolerance: The ``urdf`` bisection tolerance [m].
    """

    #: A curve has no compiled path.
    compiled = False

    def __init__(self, finger: Finger, curve: CurvedObject, checker: UrdfCollisionChecker | None, *,
                 urdf_grid: int, urdf_tolerance: float, closed_form: bool | None = None):
        self.curve = curve
        self.checker = checker
        self.urdf_grid = urdf_grid
        self.tolerance = urdf_tolerance * curve.perimeter
        self.l1, self.l2 = finger.link_lengths
        self.sign = finger.configuration.sign
        self.geometry = CurveGeometry(curve, self.l1, self.l2, self.sign, closed_form=closed_form)
        self._joint1 = tuple(finger.joint1_in_hand.tolist())
        self._base_angle = float(finger.base_in_hand[2])

    def joint_in_object(self, x: float, y: float, beta: float) -> tuple[float, float, float, float]:
        """(joint 1's x, y [m] in the object frame, cos beta, sin beta) at the object pose (x [m], y [m], beta)."""
        c, s = math.cos(beta), math.sin(beta)
        dx, dy = self._joint1[0] - x, self._joint1[1] - y
        return c * dx + s * dy, c * dy - s * dx, c, s

    def solve(self, x: float, y: float, beta: float, near: float | None = None) -> CurveSolution:
        """The reachable and ``ideal`` feasible sets (ξ [m]) at the object pose (x [m], y [m], beta [rad]) on the
        window about joint 1's foot (``near``: the previous foot, for unwrapped ξ)."""
        ox, oy, _, _ = self.joint_in_object(x, y, beta)
        return self.geometry.solve(ox, oy, near)

    def normal_angle(self, solution: CurveSolution, beta: float) -> float:
        """λ [rad]: the angle of the inward normal at the foot in the finger's base frame (object at angle beta)."""
        nx, ny = solution.normal
        return wrap_angle(math.atan2(ny, nx) + beta - self._base_angle)

    def tip_and_elbow(self, d: float, nx: float, ny: float, s: float) -> tuple[float, float, float, float]:
        """Tip and elbow (x, y, x, y) [m] relative to joint 1 for the tip at line coordinate ``s`` [m] on a line at
        distance ``d`` [m] with inward normal (nx, ny) (any frame; inside the annulus)."""
        px, py = d * nx - s * ny, d * ny + s * nx
        return (px, py, *self.geometry.elbow(px, py))

    def free_test(self, x: float, y: float, beta: float) -> FreeTest:
        """The ``urdf`` verdict ``free(xi) -> bool`` (no link shape penetrates the object) for the tip at ξ [m]
        (inside the annulus), the object at (x [m], y [m], beta [rad]); sets the checker's object pose. With a list
        ``kept`` as second argument the certificates kept across poses are used, as on an edge."""
        checker = self.checker
        checker.set_object_pose(x, y, beta)
        ox, oy, c, s = self.joint_in_object(x, y, beta)
        o1x, o1y = self._joint1
        point, elbow, hypot = self.geometry.point, self.geometry.elbow, math.hypot

        def free(xi: float, kept: list | None = None) -> bool:
            p = point(xi, ox, oy)
            ex, ey = elbow(p.vx, p.vy)
            ex, ey = c * ex - s * ey, s * ex + c * ey  # hand frame, relative to joint 1
            vx, vy = c * p.vx - s * p.vy - ex, s * p.vx + c * p.vy - ey  # link 2
            n1, n2 = hypot(ex, ey), hypot(vx, vy)
            if kept is None:
                return not checker.links_collide(ex / n1, ey / n1, o1x + ex, o1y + ey, vx / n2, vy / n2)
            return not checker.links_collide_kept(kept, ex / n1, ey / n1, o1x + ex, o1y + ey, vx / n2, vy / n2)

        return free

    def urdf_ends(self, solution: CurveSolution, x: float, y: float, beta: float) -> UrdfCuts:
        """The ``urdf`` cuts of the reachable pieces of ``solution`` (ξ [m], its ``ideal`` ends as extra grid points)
        at the object pose (x [m], y [m], beta [rad])."""
        free = self.free_test(x, y, beta)
        return urdf_cuts(solution.reachable, solution.ideal, free, self.urdf_grid, self.tolerance)

    def feasible(self, solution: CurveSolution, x: float, y: float, beta: float) -> Intervals:
        """The feasible set (ξ [m]) of ``solution`` at the object pose (x [m], y [m], beta [rad]): its ``ideal`` set,
        or in ``urdf`` mode the free pieces of its reachable set."""
        if self.checker is None or not solution.reachable:
            return solution.ideal if self.checker is None else ()
        return urdf_pieces(solution.reachable, self.urdf_ends(solution, x, y, beta))

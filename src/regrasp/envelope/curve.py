r"""Paper §2.2 and Definition 2.2 on a curved object: one finger's reachable and ``ideal`` feasible ξ-sets on a
smooth convex closed curve (:mod:`regrasp.core.curves`; ξ the clockwise arc length, :math:`c' = t`,
:math:`t' = \kappa n`, :math:`n' = -\kappa t`, n the unit inward normal, :math:`t = \perp n`).

Everything here is in the **object frame**: o is the finger's first joint there, :math:`l_1, l_2` its links,
σ = +1 (left) or -1 (right) its configuration. For the tip at :math:`c(\xi)` let :math:`v = c - o`,
:math:`r = |v|`, and take :mod:`regrasp.envelope.line`'s line parameters of the **tangent line at ξ**:
:math:`d = n \cdot v` (the line's signed distance from o) and :math:`s = t \cdot v` (the tip's line coordinate).

**Reachable (Definition 2.1).** :math:`|l_1 - l_2| \le r \le l_1 + l_2` and the configured IK elbow e not in the
open interior half-plane of the tangent line at the tip: :func:`~regrasp.envelope.line.elbow_margin`
:math:`g(s, d) \ge 0`. *Lemma.* The region lies in the closed inner half-plane of every tangent line (convexity),
so for a reachable tip link 2 (from e, in the closed outer half-plane, to the tip, on the line) misses the open
interior: **link 2 never collides** in the ``ideal`` geometry. Conversely an elbow in the open inner half-plane
points link 2 into the object at the tip (the curve is smooth there). So the condition is exactly "link 2 does
not enter the object", as on an edge.

**Breakpoints of the reachable set.** g changes sign inside the annulus only where the elbow lies on the tangent
line, i.e. where link 2 lies along it: :math:`e = c \pm l_2 t` with :math:`|e - o| = l_1`. So the reachable set
changes only at the sign changes of

* :math:`f_{out} = (l_1 + l_2) - r` and :math:`f_{in} = r - |l_1 - l_2|` (the annulus),
* :math:`\varphi_\pm = |c \pm l_2 t - o| - l_1` (link 2 along the tangent line).

**Link 1 (``ideal`` feasible).** If o is inside the object (or on it), link 1 always meets the open interior. Else
o sees the object between its two tangent points :math:`q_1, q_2` (the zeros of d; d > 0 on the arc between
them that holds the foot of o). The segment o→e (e outside the open interior, by the lemma) meets the open
interior iff its direction is strictly inside the cone :math:`(q_1 - o, q_2 - o)` **and** e is strictly beyond
the chord :math:`q_1 q_2` (a ray in the cone enters through the near arc, crosses the chord inside the object,
and leaves through the far arc; an e outside the object on o's side of the chord is short of the entry). The
verdict changes only when the direction crosses a tangent direction with :math:`|q_j - o| \le l_1` (the elbow is
then :math:`e_j = o + l_1 (q_j - o)/|q_j - o|`, as at an edge's limiting vertex) or when e crosses the boundary,
which the lemma allows only on the tangent line at the tip (a root of :math:`\varphi_\pm`). So link 1 adds the
sign changes of :math:`\chi_j = |c - e_j| - l_2`.

**Certified bracketing (any curve).** Frenet gives :math:`r' = s / r`, :math:`|r'| \le 1`; for
:math:`w_\pm = c \pm l_2 t - o`, :math:`w_\pm' = t \pm l_2 \kappa n`, :math:`|w_\pm'| \le 1 + l_2 \kappa`; and
:math:`|(c - e_j)'| = 1`. So :math:`f_{out}, f_{in}, \chi_j` are 1-Lipschitz and
:math:`|\varphi_\pm'| \le 1 + l_2 \kappa \le 1 + l_2 \kappa_{max}`. Integrated over a cell ``[a, b]`` the bound on
:math:`\varphi_\pm` is :math:`(b - a) + l_2 \Theta(a, b)`, with :math:`\Theta = \int_a^b \kappa \le
\kappa_{max}(b - a)` the turning of the normal, which a convex curve's monotone normal gives exactly from the
two end normals (:func:`turning`; an arc shorter than P/2 turns by less than 2π, since a straight part of a
closed convex curve is shorter than P/2, and the starting grid's cells are P/64 long). These bounds certify
:func:`~regrasp.envelope.bracketing.sign_changes` on a 64-cell grid over the window, refined to
``ROOT_TOLERANCE`` × P; only a pair of roots closer than ``RESOLUTION`` × P (a feature narrower than that) could
be missed. For :math:`f_{out}, f_{in}` a second bound certifies monotonicity, so that the neighbourhood of a
simple root needs no splitting: their derivative :math:`\pm s/r = \pm \hat v \cdot t` has
:math:`(\hat v \cdot t)' = (1 - (\hat v \cdot t)^2)/r + \kappa d / r`, at most :math:`1/r + \kappa`, so its
variation on ``[a, b]`` is at most :math:`(b - a)/r_{min} + \Theta(a, b)` with
:math:`r_{min} \ge (r(a) + r(b) - (b - a))/2`; when :math:`s/r` has one sign at both ends and
:math:`|s/r|(a) + |s/r|(b)` exceeds that, f is strictly monotone on the cell. The same holds for
:math:`\chi_j` with :math:`c - e_j` in place of v. (:math:`\varphi_\pm'` holds κ itself, whose variation a
curve does not bound: those keep the zeroth-order certificate.) Each piece between consecutive breakpoints is
then classified at its midpoint.

**The disc in closed form.** For a disc of radius R about the origin, :math:`c = R(\cos\phi, \sin\phi)` with
:math:`\phi = \pi/2 - \xi/R`. Every breakpoint is where the disc's circle, or the circle
:math:`|c \pm l_2 t| = R' = \sqrt{R^2 + l_2^2}` (on which :math:`c \pm l_2 t` sits at polar angle
:math:`\phi \mp \alpha`, :math:`\alpha = \operatorname{atan2}(l_2, R)`), meets a circle about a point m at
polar angle :math:`\phi_m`, distance D: at :math:`\phi_m \pm \gamma` with
:math:`\cos\gamma = (\rho_0^2 + D^2 - \rho^2)/(2 \rho_0 D)` (circle–circle intersection; none if
:math:`|\cos\gamma| > 1`). The annulus ends: :math:`(\rho_0, m, \rho) = (R, o, l_1 \pm l_2)`, so
:math:`\xi = \xi_c \mp R\gamma`; link 2 along the tangent: :math:`(R', o, l_1)`, then :math:`\phi = \psi \pm
\alpha`; link 1 at a tangent: :math:`(R, e_j, l_2)`; the tangent points: :math:`\phi_o \pm \arccos(R/D)`.

**The window.** Sets are returned on :math:`(\xi_c - P/2, \xi_c + P/2]`, :math:`\xi_c` the foot of o
(``near``: the previous :math:`\xi_c`, for unwrapped ξ along a trajectory). A finger whose link 1 wraps round
the object (condition IV on the far side) can reach past the window's ends; such a set is returned cut in two
at them (both pieces touch the ends).
"""

from __future__ import annotations

import math
from typing import NamedTuple

from ..core.curves import CurvedObject, Disc
from ..core.exceptions import InvalidParameterError
from ..core.intervals import Intervals, merge
from .bracketing import refine_bracket, sign_changes
from .line import elbow_margin

__all__ = ["CurveGeometry", "CurvePoint", "CurveSolution", "turning"]

#: Cells of the starting grid over the window (one period).
GRID_CELLS = 64
#: Breakpoints are refined to this fraction of the perimeter.
ROOT_TOLERANCE = 1e-12
#: Cells narrower than this fraction of the perimeter are not split further: the bracketing's resolution.
RESOLUTION = 1e-9


def turning(nax: float, nay: float, nbx: float, nby: float) -> float:
    r"""The clockwise angle [rad] in [0, 2π) from the unit normal (nax, nay) to (nbx, nby): the turning
    :math:`\int_a^b \kappa\,d\xi` of a convex curve's normal from ξ = a to b (< P) when it is below 2π."""
    angle = math.atan2(nbx * nay - nby * nax, nax * nbx + nay * nby)
    return angle if angle >= 0.0 else angle + 2.0 * math.pi


class CurvePoint(NamedTuple):
    """The curve at one ξ seen from the joint o (object frame)."""

    cx: float  #: point c [m]
    cy: float
    nx: float  #: unit inward normal n
    ny: float
    vx: float  #: v = c - o [m]
    vy: float
    r: float  #: |v| [m]
    d: float  #: n . v [m]: the tangent line's signed distance from o
    s: float  #: t . v [m]: the tip's coordinate on the tangent line


class CurveSolution(NamedTuple):
    """The reachable and ``ideal`` feasible sets of one finger on a curve at one joint position (object frame)."""

    xi_foot: float  #: ξ_c [m]: the foot of the joint on the curve (the window's centre)
    distance: float  #: signed distance [m] of the joint from the curve (> 0 outside): d of the tangent line at ξ_c
    normal: tuple[float, float]  #: inward normal at ξ_c (object frame)
    window: tuple[float, float]  #: (ξ_c - P/2, ξ_c + P/2) [m]
    reachable: Intervals  #: Definition 2.1, in the window [m]
    ideal: Intervals  #: Definition 2.2 with segment links [m]
    breakpoints: tuple[float, ...]  #: every breakpoint found in the window [m], sorted
    tangents: tuple[tuple[float, float], tuple[float, float]] | None  #: q_1 - o, q_2 - o (cross > 0); None inside


class CurveGeometry:
    r"""One finger's reachable and ``ideal`` feasible sets on one curve (module docstring), on plain floats in the
    object frame.

    Args:
        curve: The object.
        l1: First link [m].
        l2: Second link [m].
        sign: +1 left, -1 right configuration.
        closed_form: Breakpoints in closed form (a :class:`~regrasp.core.curves.Disc` only) or by certified
            bracketing; None: closed form for a disc.
    """

    def __init__(self, curve: CurvedObject, l1: float, l2: float, sign: int, *, closed_form: bool | None = None):
        self.curve = curve
        self.l1, self.l2, self.sign = float(l1), float(l2), int(sign)
        self.period = curve.perimeter
        if closed_form is None:
            closed_form = isinstance(curve, Disc)
        elif closed_form and not isinstance(curve, Disc):
            raise InvalidParameterError("closed_form", closed_form, "False or None: only a Disc has the closed form")
        self.closed_form = bool(closed_form)
        self.tol = ROOT_TOLERANCE * self.period
        self.resolution = RESOLUTION * self.period
        self.eps = 1e-12 * (curve.scale + self.l1 + self.l2)

    # ------------------------------------------------------------------ pointwise
    def point(self, xi: float, ox: float, oy: float) -> CurvePoint:
        """The curve at ``xi`` [m] seen from the joint (``ox``, ``oy``) [m]."""
        cx, cy, nx, ny, _ = self.curve.local_floats(xi)
        vx, vy = cx - ox, cy - oy
        return CurvePoint(cx, cy, nx, ny, vx, vy, math.hypot(vx, vy), vx * nx + vy * ny, vy * nx - vx * ny)

    def reachable_at(self, p: CurvePoint) -> bool:
        """Definition 2.1 at the tip ``p``: in the annulus and the elbow outside the tangent line's interior."""
        return elbow_margin(p.s, p.d, self.l1, self.l2, self.sign) >= 0.0

    def elbow(self, vx: float, vy: float) -> tuple[float, float]:
        """The configured IK elbow [m] relative to the joint for the tip at ``(vx, vy)`` [m] relative to it (inside
        the annulus): :math:`a u + \\sigma h \\perp u` of :mod:`regrasp.envelope.line`."""
        r = math.hypot(vx, vy)
        ux, uy = vx / r, vy / r
        a = (self.l1 * self.l1 - self.l2 * self.l2 + r * r) / (2.0 * r)
        h = self.sign * math.sqrt(max(self.l1 * self.l1 - a * a, 0.0))
        return a * ux - h * uy, a * uy + h * ux

    def link1_collides(self, ex: float, ey: float, tangents: tuple | None) -> bool:
        """Whether link 1 (joint to the elbow (``ex``, ``ey``) [m], relative to the joint, outside the open interior)
        meets the open interior: inside the tangent cone and beyond the chord (module docstring)."""
        if tangents is None:
            return True
        (ax, ay), (bx, by) = tangents
        eps = self.eps
        if ax * ey - ay * ex <= eps * math.hypot(ax, ay) or ex * by - ey * bx <= eps * math.hypot(bx, by):
            return False
        mx, my = bx - ax, by - ay
        side_e = mx * (ey - ay) - my * (ex - ax)
        side_o = my * ax - mx * ay
        return (side_e if side_o < 0.0 else -side_e) > eps * math.hypot(mx, my)

    # ------------------------------------------------------------------ the joint's view
    def tangent_points(self, ox: float, oy: float,
                       xi_foot: float) -> tuple[tuple[float, float], tuple[float, float]] | None:
        """q_1 - o and q_2 - o [m] (cross product > 0) for the tangent points q_j from a joint (``ox``, ``oy``)
        outside the object whose foot is ``xi_foot`` [m]: the two zeros of d (closed form on a disc); None when d
        is not positive at the foot (the joint on the curve, to rounding)."""
        if not self.point(xi_foot, ox, oy).d > 0.0:
            return None
        if self.closed_form:
            radius = self.curve.radius
            dist, phi = math.hypot(ox, oy), math.atan2(oy, ox)
            gamma = math.acos(min(radius / dist, 1.0))
            points = [(radius * math.cos(phi + g) - ox, radius * math.sin(phi + g) - oy) for g in (-gamma, gamma)]
        else:
            points = [self.point(x, ox, oy)[4:6] for x in self._tangent_xi(ox, oy, xi_foot)]
        (ax, ay), (bx, by) = points
        return ((ax, ay), (bx, by)) if ax * by - ay * bx > 0.0 else ((bx, by), (ax, ay))

    def _tangent_xi(self, ox: float, oy: float, xi_foot: float) -> tuple[float, float]:
        """ξ [m] of the two zeros of d, d > 0 between them about ``xi_foot``: bracketed against a point of the far
        side, where d < 0 (the foot of a far point beyond the origin, or a scan)."""
        period = self.period

        def d(x: float) -> float:
            return self.point(x, ox, oy).d

        norm = math.hypot(ox, oy)
        far = 1e3 * (self.curve.scale + norm)
        back = self.curve.project_floats(-far * ox / norm, -far * oy / norm)[0]
        back = xi_foot + (back - xi_foot) % period
        if not d(back) < 0.0:
            back = next((x for x in (xi_foot + k * period / 1024 for k in range(1, 1024)) if d(x) < 0.0), None)
            if back is None:
                raise InvalidParameterError("joint", (ox, oy), "a joint off the curve (its far side not found)")
        d_foot, d_back = d(xi_foot), d(back)
        right = refine_bracket(d, xi_foot, back, d_foot, d_back, self.tol)
        left = refine_bracket(d, back - period, xi_foot, d_back, d_foot, self.tol)
        return 0.5 * sum(left), 0.5 * sum(right)

    def tangent_elbows(self, ox: float, oy: float, tangents: tuple | None) -> list[tuple[float, float]]:
        """The elbows e_j [m] (object frame) of link 1 along each tangent q_j - o no longer than l1."""
        out = []
        for ax, ay in tangents or ():
            norm = math.hypot(ax, ay)
            if norm <= self.l1 * (1.0 + 1e-12):
                out.append((ox + self.l1 * ax / norm, oy + self.l1 * ay / norm))
        return out

    # ------------------------------------------------------------------ breakpoints
    def breakpoints(self, ox: float, oy: float, xi_foot: float, elbows: list[tuple[float, float]],
                    cache: dict[float, CurvePoint] | None = None) -> list[float]:
        """Every breakpoint [m] in the window about ``xi_foot`` for the joint (``ox``, ``oy``) and the tangent
        elbows ``elbows``: closed form on a disc, else certified bracketing (``cache``: points by ξ)."""
        if self.closed_form:
            return self.disc_breakpoints(ox, oy, xi_foot, elbows)
        return self.bracketed_breakpoints(ox, oy, xi_foot, elbows, {} if cache is None else cache)

    def bracketed_breakpoints(self, ox: float, oy: float, xi_foot: float, elbows: list[tuple[float, float]],
                              cache: dict[float, CurvePoint]) -> list[float]:
        """The sign changes of the boundary functions of the module docstring on the window, certified."""
        l1, l2 = self.l1, self.l2
        point = self.point

        def at(x: float) -> CurvePoint:
            p = cache.get(x)
            if p is None:
                p = cache[x] = point(x, ox, oy)
            return p

        def lipschitz(a: float, b: float) -> float:
            return b - a

        def radial_monotone(a: float, b: float) -> bool:  # (r - rho)' = s / r, whose variation is <= h/r + turning
            pa, pb = at(a), at(b)
            ga, gb, r_min = pa.s / pa.r, pb.s / pb.r, 0.5 * (pa.r + pb.r - (b - a))
            return (ga > 0.0) == (gb > 0.0) and r_min > 0.0 and (
                abs(ga) + abs(gb) > (b - a) / r_min + turning(pa.nx, pa.ny, pb.nx, pb.ny))

        def link2_variation(a: float, b: float) -> float:
            pa, pb = at(a), at(b)
            return (b - a) + l2 * turning(pa.nx, pa.ny, pb.nx, pb.ny)

        def link2(sign: float):
            def f(x: float) -> float:
                p = at(x)
                return math.hypot(p.vx - sign * l2 * p.ny, p.vy + sign * l2 * p.nx) - l1
            return f

        def tangency(ex: float, ey: float):
            return lambda x: math.hypot(at(x).cx - ex, at(x).cy - ey) - l2

        def tangency_monotone(ex: float, ey: float):
            def monotone(a: float, b: float) -> bool:  # |c - e|' = (c - e).t / |c - e|, as radial_monotone
                pa, pb = at(a), at(b)
                wa, wb = math.hypot(pa.cx - ex, pa.cy - ey), math.hypot(pb.cx - ex, pb.cy - ey)
                ga = ((pa.cy - ey) * pa.nx - (pa.cx - ex) * pa.ny) / wa
                gb = ((pb.cy - ey) * pb.nx - (pb.cx - ex) * pb.ny) / wb
                w_min = 0.5 * (wa + wb - (b - a))
                return (ga > 0.0) == (gb > 0.0) and w_min > 0.0 and (
                    abs(ga) + abs(gb) > (b - a) / w_min + turning(pa.nx, pa.ny, pb.nx, pb.ny))
            return monotone

        functions = [(lambda x: l1 + l2 - at(x).r, lipschitz, radial_monotone), (link2(1.0), link2_variation, None),
                     (link2(-1.0), link2_variation, None)]
        if l1 != l2:
            functions.append((lambda x: at(x).r - abs(l1 - l2), lipschitz, radial_monotone))
        functions += [(tangency(ex, ey), lipschitz, tangency_monotone(ex, ey)) for ex, ey in elbows]
        lo = xi_foot - 0.5 * self.period
        grid = [lo + self.period * k / GRID_CELLS for k in range(GRID_CELLS)] + [xi_foot + 0.5 * self.period]
        roots = []
        for f, variation, monotone in functions:
            roots += sign_changes(f, variation, grid, self.tol, self.resolution, monotone)
        return sorted(roots)

    def disc_breakpoints(self, ox: float, oy: float, xi_foot: float,
                         elbows: list[tuple[float, float]]) -> list[float]:
        """The breakpoints [m] on a disc in closed form (circle–circle intersections, module docstring)."""
        radius, l1, l2 = self.curve.radius, self.l1, self.l2
        phi_o = math.atan2(oy, ox)
        roots: list[float] = []

        def meet(rho0: float, mx: float, my: float, rho: float, shift: float = 0.0) -> None:
            dist = math.hypot(mx, my)
            if dist == 0.0:
                return
            cos_gamma = (rho0 * rho0 + dist * dist - rho * rho) / (2.0 * rho0 * dist)
            if abs(cos_gamma) <= 1.0:
                gamma, phi_m = math.acos(cos_gamma), math.atan2(my, mx)
                for psi in (phi_m - gamma, phi_m + gamma):
                    roots.append(xi_foot - radius * math.remainder(psi + shift - phi_o, 2.0 * math.pi))

        meet(radius, ox, oy, l1 + l2)
        if l1 != l2:
            meet(radius, ox, oy, abs(l1 - l2))
        outer, alpha = math.hypot(radius, l2), math.atan2(l2, radius)
        meet(outer, ox, oy, l1, alpha)
        meet(outer, ox, oy, l1, -alpha)
        for ex, ey in elbows:
            meet(radius, ex, ey, l2)
        return sorted(roots)

    # ------------------------------------------------------------------ the sets
    def solve(self, ox: float, oy: float, near: float | None = None) -> CurveSolution:
        """The reachable and ``ideal`` feasible sets for the joint at (``ox``, ``oy``) [m] (object frame), on the
        window about its foot (``near``: the representative of ξ_c within P/2 of it)."""
        period, tol = self.period, self.tol
        xi_foot, distance = self.curve.project_floats(ox, oy, near)
        lo, hi = xi_foot - 0.5 * period, xi_foot + 0.5 * period
        tangents = self.tangent_points(ox, oy, xi_foot) if distance > self.eps else None
        cache: dict[float, CurvePoint] = {}
        roots = self.breakpoints(ox, oy, xi_foot, self.tangent_elbows(ox, oy, tangents), cache)
        cuts = [lo, *(x for x in roots if lo < x < hi), hi]
        reach, free = [], []
        for a, b in zip(cuts[:-1], cuts[1:]):
            if not b - a > tol:
                continue
            p = self.point(0.5 * (a + b), ox, oy)
            if self.reachable_at(p):
                reach.append((a, b))
                if not self.link1_collides(*self.elbow(p.vx, p.vy), tangents):
                    free.append((a, b))
        foot = self.point(xi_foot, ox, oy)
        return CurveSolution(xi_foot, distance, (foot.nx, foot.ny), (lo, hi), _clean(reach, tol), _clean(free, tol),
                             tuple(roots), tangents)


def _clean(pieces: list[tuple[float, float]], tol: float) -> Intervals:
    """The union of ``pieces`` with gaps of at most ``tol`` [m] closed and pieces of at most ``tol`` dropped."""
    return tuple((a, b) for a, b in merge(pieces, gap=tol) if b - a > tol)

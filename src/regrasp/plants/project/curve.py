r"""The project plant on a curved object (:mod:`regrasp.core.curves`): a tip's foot on the curve, the sliding
constraint's row, and what the plant's events, reports and collision checks take of a curve.

A curved object has one face (index 0), its whole boundary, with ξ the arc length (clockwise, unbounded) and, at
ξ, the point :math:`c(\xi)`, the unit inward normal :math:`n(\xi)`, the tangent :math:`t = \perp n` and the
curvature κ: :math:`c' = t`, :math:`t' = \kappa n`, :math:`n' = -\kappa t` (object frame,
:mod:`regrasp.core.curves.base`).

**Fixed.** The tip stays at the object point :math:`c(\xi_i)`: the polygon's fixed constraint
(:mod:`regrasp.plants.project.equations`) with that point.

**Sliding.** With :math:`p_o = R^T(p - x_o)` the tip in the object frame, its foot :math:`\xi^*` on the curve
(:meth:`~regrasp.core.curves.base.CurvedObject.project_floats`), :math:`n^* = n(\xi^*)`, :math:`t^*`,
:math:`\kappa^*` and the signed distance δ (positive outside), the constraint is
:math:`\psi = -\delta(p_o) = 0` (the sign of the polygon's :math:`n\cdot r - e`). δ's gradient in :math:`p_o` is
:math:`-n^*`, its Hessian :math:`\kappa^*/(1 + \kappa^*\delta)\, t^* t^{*T}` (the foot moves by
:math:`\dot\xi^* = t^*\cdot\dot p_o / (1 + \kappa^*\delta)`, from differentiating
:math:`(c(\xi^*) - p_o)\cdot t(\xi^*) = 0`). With :math:`\dot R^T = -\omega E R^T` (E the rotation by +90°),

.. math::

    \dot p_o = R^T u, \qquad u = \dot p - v_o - \omega E r, \quad r = p - x_o

(u: the tip's velocity relative to the object's material point under it, hand frame). With
:math:`N = R n^*`, :math:`T = R t^* = E N`, :math:`\dot r = \dot p - v_o` and :math:`\ddot p = J\ddot q + \dot J\dot q`:

.. math::

    \dot\psi &= n^*\cdot\dot p_o = N\cdot u = N\cdot\dot r + \omega\,(N_x r_y - N_y r_x), \\
    \ddot\psi &= n^*\cdot\ddot p_o + \dot n^*\cdot\dot p_o
        = N\cdot(\ddot p - \dot v_o) + \dot\omega\,(N_x r_y - N_y r_x) - \omega^2 N\cdot r
          + 2\omega\,(N_x\dot r_y - N_y\dot r_x) - \frac{\kappa^*}{1 + \kappa^*\delta}\,(T\cdot u)^2,

since :math:`\ddot p_o = R^T(\dot u - \omega E u)` and :math:`\dot n^* = -\kappa^* t^*\dot\xi^*`. Every term but
the last is the polygon's sliding row with the edge's normal replaced by :math:`n^*` (an edge is :math:`\kappa = 0`
with δ linear, and the two coincide); the row on :math:`(\ddot q, \ddot X)` is :math:`(N^T J, -N, N_x r_y - N_y
r_x)` and the Baumgarte right-hand side :math:`-(\text{the rest}) - 2\alpha\dot\psi - \alpha^2\psi`. The force on
the object is :math:`f = \lambda_n(N + \mu_k s T)` at the tip (moment :math:`r \times f`, as on a polygon: its
normal column is then minus the row, so the normal force does no work but the constraint's drift).

**Reports.** A contact's ξ is its tip's foot, continued from the contact's last ξ (``near``: within half a
perimeter of it, so ξ is continuous and unbounded), and :math:`\dot\xi = t^*\cdot R^T u / (1 + \kappa^*\delta)`;
its surface frame is the foot's (:math:`n^*, t^*`), its gap δ. The tangent line at the foot, as an
:class:`~regrasp.plants.project.state.EdgeGeometry` with an unbounded ξ range (:func:`foot`), carries the
surface-frame forces and the ``left_edge`` check (which never fires: a closed curve has no end).

**Collision checks** run against the curve's own coal shape
(:meth:`~regrasp.core.curves.base.CurvedObject.to_coal`; :class:`CurveCollisionShape`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import coal

from ...core.contact import ContactMode
from ...core.curves import CurvedObject
from ...core.exceptions import InvalidParameterError
from ...core.polygon import ConvexPolygon
from .state import EdgeGeometry, PlantContact, contact_xi

__all__ = ["CURVE_SLIDING", "CurveCollisionShape", "Foot", "collision_object", "curve_contact_xi", "curve_depth",
           "curve_specs", "curve_violation", "foot", "sliding_row", "tangent_line"]

#: The kind of a sliding contact's spec on a curve (in place of :class:`~regrasp.core.contact.ContactMode`'s
#: ``SLIDING``, compared with ``is``): ``(i, CURVE_SLIDING, curve, near ξ [m], shift [m], μ_k s)``, the constraint
#: :math:`-\delta - \mathrm{shift} = 0` (shift 0 for a rigid contact, :math:`-\delta_0` for a pad's depth); a
#: seventh entry, a curvature [1/m], overrides the foot's (:mod:`regrasp.plants.project.kinks`).
CURVE_SLIDING = "sliding on a curve"


_MODE_FIXED, _MODE_SLIDING, _MODE_SEPARATED = ContactMode.FIXED, ContactMode.SLIDING, ContactMode.SEPARATED


class Foot(NamedTuple):
    """A tip's foot on a curve: its ξ [m], the tip's signed distance δ [m] (positive outside), the curvature κ
    [1/m] there, and the tangent line there (:func:`tangent_line`)."""

    xi: float
    delta: float
    kappa: float
    line: EdgeGeometry


def tangent_line(curve: CurvedObject, xi: float) -> tuple[EdgeGeometry, float, float, float]:
    r"""The curve's tangent line at ξ [m] as an edge of unbounded ξ range whose ξ is the curve's at that point
    (normal n, direction t, ξ-origin :math:`c - \xi t`, offset :math:`n\cdot c`), and the point :math:`c(\xi)`
    (x, y) [m] and the curvature [1/m] there (object frame, floats)."""
    cx, cy, nx, ny, kappa = curve.local_floats(xi)
    tx, ty = -ny, nx
    line = EdgeGeometry(nx, ny, tx, ty, cx - xi * tx, cy - xi * ty, nx * cx + ny * cy, -math.inf, math.inf)
    return line, cx, cy, kappa


def foot(curve: CurvedObject, X: Sequence[float], tip: Sequence[float], near: float | None) -> Foot:
    """The foot of a tip at ``tip`` (hand frame) [m] on the curve of an object at pose X (floats), its ξ within
    half a perimeter of ``near`` [m] (None: in [0, P))."""
    c, s = math.cos(X[2]), math.sin(X[2])
    rx, ry = tip[0] - X[0], tip[1] - X[1]
    xi, delta = curve.project_floats(c * rx + s * ry, c * ry - s * rx, near)
    line, _, _, kappa = tangent_line(curve, xi)
    return Foot(xi, delta, kappa, line)


def curve_contact_xi(ft: Foot, X: list, V: list, c: float, s: float, tip: Sequence[float],
                     tip_vel: Sequence[float]) -> tuple[float, float]:
    r"""ξ [m] of a tip whose foot is ``ft`` and its velocity relative to the object,
    :math:`\dot\xi = t^*\cdot R^T u / (1 + \kappa\delta)` [m/s] (module docstring), at pose X and twist V (floats),
    (c, s) = (cos β, sin β), the tip's position ``tip`` and velocity ``tip_vel`` (hand frame)."""
    rate = contact_xi(ft.line, X, V, c, s, tip, tip_vel)[1]
    return ft.xi, rate / (1.0 + ft.kappa * ft.delta)


def curve_specs(curve: CurvedObject, contacts: Sequence[PlantContact], kinetic: Sequence[float],
                depth0: float | None = None) -> tuple[tuple, ...]:
    r"""The active contacts on ``curve`` as the plant's specs (:meth:`PlantEquations.specs`): a fixed one
    ``(i, FIXED, c_x, c_y)`` (its point, object frame), a sliding one ``(i, CURVE_SLIDING, curve, ξ, 0, μ_k s)``.

    With a pad's preload depth ``depth0`` [m] (:meth:`~regrasp.plants.project.soft.PadEquations.specs`): a fixed
    contact is its tangent line at :math:`c(\xi_i)` as a pad's edge spec, ``(i, FIXED, n_x, n_y, n·c - δ_0, 0,
    t_x, t_y, t·c)`` (its tangential row keeps the tip on the normal line through :math:`c(\xi_i)`, where the pad's
    depth along n is :math:`-\delta`), a sliding one ``(i, CURVE_SLIDING, curve, ξ, -δ_0, μ_k s)``."""
    out = []
    for i, c in enumerate(contacts):
        mode = c.mode
        if mode is _MODE_SEPARATED:
            continue
        if mode is not _MODE_FIXED and mode is not _MODE_SLIDING:
            raise InvalidParameterError("mode", mode, "a ContactMode member (PlantContact converts strings)")
        if c.edge != 0:
            curve.edge(c.edge)  # UnknownEdgeError: a curve has one face
        if mode is _MODE_SLIDING:
            out.append((i, CURVE_SLIDING, curve, c.xi, 0.0 if depth0 is None else -depth0, kinetic[i] * c.sign))
        elif depth0 is None:
            out.append((i, _MODE_FIXED, *curve.local_floats(c.xi)[:2]))
        else:
            g, cx, cy, _ = tangent_line(curve, c.xi)
            out.append((i, _MODE_FIXED, g.nx, g.ny, g.offset - depth0, 0.0, g.tx, g.ty, g.tx * cx + g.ty * cy))
    return tuple(out)


def _normal(spec: tuple, c: float, s: float, rx: float, ry: float) -> tuple[float, float, float, float]:
    """(δ [m], κ [1/m], N_x, N_y) of a curve spec's tip at r = p - x_o (hand frame), (c, s) = (cos β, sin β)."""
    curve = spec[2]
    xi, delta = curve.project_floats(c * rx + s * ry, c * ry - s * rx, spec[3])
    _, _, ux, uy, kappa = curve.local_floats(xi)
    if len(spec) > 6:  # a substep that ends or starts at a jump of the curvature takes its side's
        kappa = spec[6]
    return delta, kappa, c * ux - s * uy, s * ux + c * uy


def curve_violation(spec: tuple, c: float, s: float, rx: float, ry: float) -> float:
    """A curve spec's constraint violation |δ + shift| [m] at r = p - x_o (hand frame)."""
    curve = spec[2]
    return abs(curve.project_floats(c * rx + s * ry, c * ry - s * rx, spec[3])[1] + spec[4])


def sliding_row(spec: tuple, finger: tuple, rx: float, ry: float, c: float, s: float, V: Sequence[float],
                free: tuple[float, float], alpha: float) -> tuple[tuple, float, tuple]:
    r"""A curve's sliding contact's row ``(i, N_x, N_y, -N_x, -N_y, N_x r_y - N_y r_x)``, its right-hand side and
    its force column (:meth:`PlantEquations.rows`' forms; module docstring): ``finger`` is its finger's
    :meth:`~PlantEquations.pin_pass` entry, r = p - x_o, (c, s) = (cos β, sin β), V the twist, ``free`` the tip's
    free acceleration less the object's (hand frame), α the Baumgarte rate [1/s]."""
    i, mus = spec[0], spec[5]
    jax, jay, _, _, pvx, pvy = finger[9:15]
    vx, vy, w = V
    delta, kappa, nx, ny = _normal(spec, c, s, rx, ry)
    tr = nx * ry - ny * rx
    rvx, rvy = pvx - vx, pvy - vy
    psi_dot = w * tr + (nx * rvx + ny * rvy)
    slide = nx * (rvy - w * rx) - ny * (rvx + w * ry)  # T·u, T = (-N_y, N_x), u = ṙ - ω E r
    drift = (-w * w * (nx * rx + ny * ry) + 2 * w * (nx * rvy - ny * rvx) + (nx * jax + ny * jay)
             - kappa / (1.0 + kappa * delta) * slide * slide)
    rhs = (-drift - 2 * alpha * psi_dot - alpha * alpha * (-delta - spec[4])
           - (nx * free[0] + ny * free[1]))
    fx, fy = nx - mus * ny, ny + mus * nx
    return (i, nx, ny, -nx, -ny, tr), rhs, (i, fx, fy, fx, fy, rx * fy - ry * fx)


def curve_depth(spec: tuple, finger: tuple, x: float, y: float, c: float, s: float,
                V: Sequence[float]) -> tuple:
    r"""A pad's sliding contact on a curve as :meth:`~regrasp.plants.project.soft.PadEquations.depths` gives it,
    ``(i, depth, rate, N_x, N_y, r_x, r_y)``: depth :math:`-\delta - \mathrm{shift} = -\delta + \delta_0`, rate
    :math:`\dot\psi = N\cdot u` (module docstring)."""
    px, py, pvx, pvy = finger[11:15]
    vx, vy, w = V
    rx, ry = px - x, py - y
    delta, _, nx, ny = _normal(spec, c, s, rx, ry)
    return (spec[0], -delta - spec[4], w * (nx * ry - ny * rx) + nx * (pvx - vx) + ny * (pvy - vy), nx, ny, rx, ry)


@dataclass(frozen=True, eq=False)
class CurveCollisionShape(ConvexPolygon):
    """A curved object for :class:`~regrasp.model.collision.UrdfCollisionChecker`, which takes a polygon: the
    vertices are the curve's circumscribed polygon
    (:meth:`~regrasp.core.curves.base.CurvedObject.circumscribed_polygon`, which contains it), the coal shape is the
    curve's own (:meth:`~regrasp.core.curves.base.CurvedObject.to_coal`: a disc's exact cylinder)."""

    curve: CurvedObject | None = None

    def to_coal(self, half_thickness: float) -> coal.CollisionGeometry:
        """The curve's coal shape, z in ``[-h, h]`` [m] (object frame)."""
        return self.curve.to_coal(half_thickness)


def collision_object(obj: ConvexPolygon | CurvedObject) -> ConvexPolygon:
    """What the plant's collision checkers take of its object: a polygon itself, a curve as a
    :class:`CurveCollisionShape`."""
    if isinstance(obj, CurvedObject):
        return CurveCollisionShape(obj.circumscribed_polygon(), obj.mass, obj.inertia, obj)
    return obj

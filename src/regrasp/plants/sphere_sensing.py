r"""What a hand with sphere fingertips senses on a simulated plant, and the events it reports: one definition for the
compliant plants (:class:`~regrasp.plants.mujoco.plant.MujocoPlant`, :class:`~regrasp.plants.drake.plant.DrakePlant`).

:class:`SphereTipSensing` turns each contact's measurement before and after a control step (its tip centre's ξ and
ξ̇ along its edge, the centre's distance from the edge's line, the distal link's angle φ relative to the object)
into the step's slip sensor reading, the contact's gap, and the plant events of the plant modules' docstrings:
``separation`` (no force over the step and the tip more than ``separation_gap`` off its edge: the plant's contact
mode; a rollout's verdict is :mod:`regrasp.core.health`'s), ``slip`` / ``stick`` (the slip sensor past
``slip_speed`` / below ``stick_speed``), ``left_edge`` and ``collision``. The plant adds its own ``singular`` check.

**On a curved object** (:mod:`regrasp.core.curves`: one face, ``curved``, ξ the clockwise arc length, unbounded) the
same quantities are measured at the foot of the tip's centre p on the curve. With :math:`p_o = R^T(p - x)` the
centre in the object frame, :math:`(\xi, \delta)` = ``project_floats``:math:`(p_o)` (``near`` the contact's last ξ,
so ξ is continuous and unbounded: no jump at 0 or the perimeter P), δ the distance (positive outside: the gap), and
at ξ the point c, the inward normal n, the tangent :math:`t = \perp n` and the curvature κ
(:math:`c' = t`, :math:`t' = \kappa n`, :math:`n' = -\kappa t`):

* **ξ̇.** The foot satisfies :math:`(c(\xi) - p_o)\cdot t(\xi) = 0`; its time derivative is
  :math:`(t\dot\xi - \dot p_o)\cdot t + (c - p_o)\cdot\kappa n\,\dot\xi = 0` with
  :math:`(c - p_o)\cdot n = \delta`, so :math:`\dot\xi = t\cdot\dot p_o / (1 + \kappa\delta)`. And
  :math:`\dot p_o = R^T(\dot p - v - \omega E \ell) = R^T u` (:math:`\dot R^T = -\omega E R^T`, E the rotation
  by +90°, :math:`\ell = p - x`): u is the centre's velocity relative to the object's material point at p, and
  :math:`R^T u` the same in the object frame. An edge is κ = 0: its :math:`t\cdot R^T u`.
* **Slip.** The tip touches the object at the point p + rN of its sphere (N = Rn: the eroded curve shares the
  curve's normals). That material point of the tip moves at :math:`\dot p + \omega_t E(rN)`, the object's point
  there at :math:`v + \omega E(\ell + rN)`; their difference is :math:`u + r(\omega_t - \omega)EN`, along
  T = EN = Rt: :math:`s = T\cdot u + r\dot\varphi = (1 + \kappa\delta)\,\dot\xi + r\dot\varphi`
  (φ = the distal link's angle relative to the object). Over a control step the sensor reads its mean,
  :math:`(\Delta\xi\,(1 + \overline{\kappa\delta}) + r\Delta\varphi)/dt` with
  :math:`\overline{\kappa\delta}` the mean of the step's ends (the polygon's reading at κ = 0). A sphere that rolls
  without slipping on the curve has :math:`\dot\xi = -r\dot\varphi` (δ = 0).
* **Surface frames** are the curve's (n, t) at the contact's ξ, not an edge's; ``left_edge`` never fires (a closed
  curve has no end: ``xi_range`` is unbounded).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import numpy as np

from ..core.contact import ContactMode
from ..core.events import Event, EventKind, EventSource
from ..core.exceptions import InvalidParameterError
from ..core.validation import as_positive_float
from .project.state import MAX_DT, PlantContact, PlantState

if TYPE_CHECKING:
    from ..core.curves import CurvedObject

__all__ = ["SphereTipSensing"]

_FIXED, _SLIDING, _SEPARATED = ContactMode.FIXED, ContactMode.SLIDING, ContactMode.SEPARATED

#: A contact's measurement: (ξ [m], ξ̇ [m/s], the tip centre's distance from the edge's line or the curve [m] (positive
#: outside), the distal link's angle relative to the object φ [rad]).
Measure = tuple[float, float, float, float]


class SphereTipSensing:
    """The shared sensing of the sphere-tip plants (module docstring). A plant using it has ``hand``, ``polygon`` (a
    convex polygon or a curved object), ``state``, ``contacts``, ``events``, ``stop_on``, ``stopped``, its tips'
    radius ``tip_radius`` [m] and ``contact_xi(state, i)`` (a curve's surface frames), and calls
    :meth:`configure_sensing` (``dt``, ``substeps``, the thresholds, ``max_gap``) and :meth:`copy_contacts` (the
    contacts and their edges, ``contact_edges``) as it is built."""

    def configure_sensing(self, dt: float, engine_step: float, engine: str, slip_speed: float, stick_speed: float,
                          separation_gap: float) -> None:
        """The control step ``dt`` [s] as a whole number of the engine's steps ``engine_step`` [s] (``engine``: how
        an error names that step), and the slip sensor's and the separation's thresholds (the plants' docstrings)."""
        self.dt = as_positive_float("dt", dt)
        substeps = self.dt / engine_step
        if self.dt > MAX_DT or abs(substeps - round(substeps)) > 1e-6 * substeps:
            raise InvalidParameterError("dt", dt, f"a step of at most {MAX_DT} s and a multiple of {engine} "
                                        f"({engine_step:g} s)")
        self.substeps = int(round(substeps))
        self.slip_speed = as_positive_float("slip_speed", slip_speed)
        self.stick_speed = as_positive_float("stick_speed", stick_speed)
        self.separation_gap = as_positive_float("separation_gap", separation_gap)
        if not self.stick_speed <= self.slip_speed:
            raise InvalidParameterError("stick_speed", stick_speed, f"at most slip_speed ({self.slip_speed:g} m/s)")
        #: The largest distance [m] a touching tip's centre ended a step off its edge since the last reset.
        self.max_gap = -np.inf

    def copy_contacts(self, contacts: Sequence[PlantContact]) -> list[PlantContact]:
        """Copies of ``contacts`` (the plant switches their modes), and each one's edge in ``contact_edges`` (a curved
        object's one face, :class:`~regrasp.core.curves.CurveFace`)."""
        out = [PlantContact(c.edge, c.mode, c.xi, c.sign) for c in contacts]
        self.contact_edges = [self.polygon.edge(c.edge) for c in out]
        return out

    def edge_measure(self, i: int, X: Sequence[float], V: Sequence[float], tip: Sequence[float],
                     tip_velocity: Sequence[float], tip_angle: float) -> Measure:
        """Contact i's measurement (:data:`Measure`) from the object's pose X and twist V (hand frame), its tip
        centre's position [m] and velocity [m/s] (hand frame) and the distal link's angle [rad] (hand frame). On a
        curve (module docstring) ξ is the foot's, continued from the contact's last ξ."""
        edge = self.contact_edges[i]
        if getattr(edge, "curved", False):
            return self.curve_measure(edge.curve, self.contacts[i].xi, X, V, tip, tip_velocity, tip_angle)
        x, y, beta = X
        vx, vy, w = V
        c, s = math.cos(beta), math.sin(beta)
        rx, ry = tip[0] - x, tip[1] - y
        ux, uy = tip_velocity[0] - (vx - w * ry), tip_velocity[1] - (vy + w * rx)  # relative to the object's point
        ox, oy = c * rx + s * ry, c * ry - s * rx  # in the object frame
        (nx, ny), (tx, ty), origin = edge.inward_normal.tolist(), edge.xi_direction.tolist(), edge.xi_origin
        return (tx * (ox - origin[0]) + ty * (oy - origin[1]), tx * (c * ux + s * uy) + ty * (c * uy - s * ux),
                -(nx * (ox - origin[0]) + ny * (oy - origin[1])), tip_angle - beta)

    @staticmethod
    def curve_measure(curve: CurvedObject, near: float, X: Sequence[float], V: Sequence[float], tip: Sequence[float],
                      tip_velocity: Sequence[float], tip_angle: float) -> Measure:
        """:meth:`edge_measure` on a curve (module docstring): ξ the foot of the tip's centre within half a perimeter
        of ``near`` [m], ξ̇ = tᵀRᵀu / (1 + κδ), the gap δ (positive outside) and φ."""
        x, y, beta = X
        vx, vy, w = V
        c, s = math.cos(beta), math.sin(beta)
        rx, ry = tip[0] - x, tip[1] - y
        ux, uy = tip_velocity[0] - (vx - w * ry), tip_velocity[1] - (vy + w * rx)  # relative to the object's point
        xi, delta = curve.project_floats(c * rx + s * ry, c * ry - s * rx, near)
        _, _, nx, ny, kappa = curve.local_floats(xi)
        rate = (-ny * (c * ux + s * uy) + nx * (c * uy - s * ux)) / (1.0 + kappa * delta)
        return xi, rate, delta, tip_angle - beta

    def surface_frame(self, i: int, xi: float) -> np.ndarray:
        """Contact i's surface frame at ξ [m], object frame: rows the inward normal and the ξ direction (an edge's,
        whatever ξ; a curve's at ξ)."""
        edge = self.contact_edges[i]
        if getattr(edge, "curved", False):
            _, _, nx, ny, _ = edge.curve.local_floats(xi)
            return np.array([[nx, ny], [-ny, nx]])
        return np.array([edge.inward_normal, edge.xi_direction])

    def surface_forces(self, st: PlantState, forces: np.ndarray) -> np.ndarray:
        """Contact forces (m, 2) on the object, hand frame, in each contact's surface frame (normal, tangential;
        on a curve at the contact's ξ at ``st``)."""
        c, s = math.cos(st.X[2]), math.sin(st.X[2])
        rot = np.array([[c, -s], [s, c]])
        frames = [np.array([rot @ e.inward_normal, rot @ e.xi_direction]) if not getattr(e, "curved", False)
                  else self.surface_frame(i, self.contact_xi(st, i)[0]) @ rot.T
                  for i, e in enumerate(self.contact_edges)]
        return np.array([f @ force for f, force in zip(frames, np.asarray(forces, dtype=float))])

    def log_event(self, i: int, kind: EventKind, detail: str, out: list, **values: float) -> None:
        """Log contact ``i``'s event at the state's time, here and in ``out``; a kind in ``stop_on`` stops the
        plant."""
        ev = Event(self.state.t, self.hand.fingers[i].name, kind, detail, EventSource.PLANT, values)
        out.append(ev)
        self.events.append(ev)
        if kind in self.stop_on:
            self.stopped = True

    def slip_velocity(self, before: Measure, after: Measure, i: int | None = None) -> float:
        r"""The slip velocity over a control step [m/s] from a contact's measurement before and after it: the
        displacement along the edge of the tip's material point at the contact relative to the object's, over
        ``dt``. That point is r n from the centre (n the inward normal), so its coordinate along the edge is
        :math:`\xi + r\varphi`: a sphere that rolls without slipping moves its centre by −r Δφ and does not slip.
        (An average over the step, as a sampled sensor reads it: a soft sliding contact may hop within a step.)
        On a curve (contact ``i``'s face is curved) :math:`(\Delta\xi\,(1 + \overline{\kappa\delta}) +
        r\Delta\varphi)/dt` (module docstring)."""
        turn = (after[3] - before[3] + math.pi) % (2.0 * math.pi) - math.pi
        edge = None if i is None else self.contact_edges[i]
        if getattr(edge, "curved", False):
            curve = edge.curve
            stretch = 1.0 + 0.5 * (curve.local_floats(before[0])[4] * before[2]
                                   + curve.local_floats(after[0])[4] * after[2])
            return ((after[0] - before[0]) * stretch + self.tip_radius * turn) / self.dt
        return (after[0] - before[0] + self.tip_radius * turn) / self.dt

    def contact_events(self, surface: np.ndarray, links: dict, before: list[Measure],
                       measure: Callable[[int], Measure]) -> tuple[list, list, list, float, np.ndarray, np.ndarray]:
        """The events at a step's end (module docstring) for the step's mean surface forces ``surface`` (m, 2) [N],
        the deepest link contact per finger ``links`` (finger: (link, depth [m])) and each contact's measurement at
        the step's start ``before``; ``measure(i)``: contact i's now. Returns (events, ξ, ξ̇, the constraint error
        [m], each tip's gap [m], each contact's slip over the step [m]); switches the contacts' modes."""
        out: list[Event] = []
        xis, rates, err = [], [], 0.0
        m = len(self.contacts)
        gaps, slips = np.empty(m), np.empty(m)
        for i, c in enumerate(self.contacts):
            after = measure(i)
            xi, xi_dot, gap, _ = after
            xis.append(xi)
            rates.append(xi_dot)
            gaps[i], slips[i] = gap, self.slip_velocity(before[i], after, i) * self.dt
            if c.mode is _SEPARATED:
                continue
            fn, ft = surface[i].tolist()
            if fn <= 0.0 and gap > self.separation_gap:
                self.log_event(i, EventKind.SEPARATION, f"no contact force over the step and the tip {gap * 1e6:.1f} "
                               f"um off the edge (more than {self.separation_gap * 1e6:g} um)", out, normal_force=fn,
                               gap=gap)
                c.mode = _SEPARATED
                continue
            self.max_gap = max(self.max_gap, gap)
            err = max(err, abs(gap))
            slip = slips[i] / self.dt
            if c.mode is _FIXED and abs(slip) > self.slip_speed:
                self.log_event(i, EventKind.SLIP, f"slip velocity {slip * 1e3:.3g} mm/s, faster than "
                               f"{self.slip_speed * 1e3:g} mm/s (f_t = {ft:.4g} N, f_n = {fn:.4g} N)", out,
                               normal_force=fn, tangential_force=ft)
                c.mode, c.sign = _SLIDING, math.copysign(1.0, slip)
            elif c.mode is _SLIDING and slip * c.sign < self.stick_speed:
                self.log_event(i, EventKind.STICK, f"slip velocity {slip * 1e3:.3g} mm/s, below "
                               f"{self.stick_speed * 1e3:g} mm/s in the sliding direction", out, xi=xi)
                c.mode = _FIXED
            c.xi = xi  # (a fixed contact is held where its tip is: the sensor reads it there)
            lo, hi = self.contact_edges[i].xi_range  # (a curve's is unbounded: never left)
            if not lo <= xi <= hi:
                self.log_event(i, EventKind.LEFT_EDGE, f"xi = {xi:.5g} m outside [{lo:.5g}, {hi:.5g}]", out, xi=xi)
        for i, (link, depth) in sorted(links.items()):
            self.log_event(i, EventKind.COLLISION, f"link {link + 1} penetrates the object by {depth:.3g} m", out,
                           link=link, depth=depth)
        return out, xis, rates, err, gaps, slips

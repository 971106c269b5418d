r"""What a hand with sphere fingertips senses on a simulated plant, and the events it reports: one definition for the
compliant plants (:class:`~regrasp.plants.mujoco.plant.MujocoPlant`, :class:`~regrasp.plants.drake.plant.DrakePlant`).

:class:`SphereTipSensing` turns each contact's measurement before and after a control step (its tip centre's ξ and
ξ̇ along its edge, the centre's distance from the edge's line, the distal link's angle φ relative to the object)
into the step's slip sensor reading, the contact's gap, and the plant events of the plant modules' docstrings:
``separation`` (no force over the step and the tip more than ``separation_gap`` off its edge: the plant's contact
mode; a rollout's verdict is :mod:`regrasp.core.health`'s), ``slip`` / ``stick`` (the slip sensor past
``slip_speed`` / below ``stick_speed``), ``left_edge`` and ``collision``. The plant adds its own ``singular`` check.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from ..core.contact import ContactMode
from ..core.events import Event, EventKind, EventSource
from ..core.exceptions import InvalidParameterError
from ..core.validation import as_positive_float
from .project.state import MAX_DT, PlantContact, PlantState

__all__ = ["SphereTipSensing"]

_FIXED, _SLIDING, _SEPARATED = ContactMode.FIXED, ContactMode.SLIDING, ContactMode.SEPARATED

#: A contact's measurement: (ξ [m], ξ̇ [m/s], the tip centre's distance from the edge's line [m] (positive outside),
#: the distal link's angle relative to the object φ [rad]).
Measure = tuple[float, float, float, float]


class SphereTipSensing:
    """The shared sensing of the sphere-tip plants (module docstring). A plant using it has ``hand``, ``polygon``,
    ``state``, ``contacts``, ``events``, ``stop_on``, ``stopped`` and its tips' radius ``tip_radius`` [m], and calls
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
        """Copies of ``contacts`` (the plant switches their modes), and each one's edge in ``contact_edges``."""
        out = [PlantContact(c.edge, c.mode, c.xi, c.sign) for c in contacts]
        self.contact_edges = [self.polygon.edge(c.edge) for c in out]
        return out

    def edge_measure(self, i: int, X: Sequence[float], V: Sequence[float], tip: Sequence[float],
                     tip_velocity: Sequence[float], tip_angle: float) -> Measure:
        """Contact i's measurement (:data:`Measure`) from the object's pose X and twist V (hand frame), its tip
        centre's position [m] and velocity [m/s] (hand frame) and the distal link's angle [rad] (hand frame)."""
        edge = self.contact_edges[i]
        x, y, beta = X
        vx, vy, w = V
        c, s = math.cos(beta), math.sin(beta)
        rx, ry = tip[0] - x, tip[1] - y
        ux, uy = tip_velocity[0] - (vx - w * ry), tip_velocity[1] - (vy + w * rx)  # relative to the object's point
        ox, oy = c * rx + s * ry, c * ry - s * rx  # in the object frame
        (nx, ny), (tx, ty), origin = edge.inward_normal.tolist(), edge.xi_direction.tolist(), edge.xi_origin
        return (tx * (ox - origin[0]) + ty * (oy - origin[1]), tx * (c * ux + s * uy) + ty * (c * uy - s * ux),
                -(nx * (ox - origin[0]) + ny * (oy - origin[1])), tip_angle - beta)

    def surface_forces(self, st: PlantState, forces: np.ndarray) -> np.ndarray:
        """Contact forces (m, 2) on the object, hand frame, in each contact's surface frame (normal, tangential)."""
        c, s = math.cos(st.X[2]), math.sin(st.X[2])
        rot = np.array([[c, -s], [s, c]])
        frames = [np.array([rot @ e.inward_normal, rot @ e.xi_direction]) for e in self.contact_edges]
        return np.array([f @ force for f, force in zip(frames, np.asarray(forces, dtype=float))])

    def log_event(self, i: int, kind: EventKind, detail: str, out: list, **values: float) -> None:
        """Log contact ``i``'s event at the state's time, here and in ``out``; a kind in ``stop_on`` stops the
        plant."""
        ev = Event(self.state.t, self.hand.fingers[i].name, kind, detail, EventSource.PLANT, values)
        out.append(ev)
        self.events.append(ev)
        if kind in self.stop_on:
            self.stopped = True

    def slip_velocity(self, before: Measure, after: Measure) -> float:
        r"""The slip velocity over a control step [m/s] from a contact's measurement before and after it: the
        displacement along the edge of the tip's material point at the contact relative to the object's, over
        ``dt``. That point is r n from the centre (n the inward normal), so its coordinate along the edge is
        :math:`\xi + r\varphi`: a sphere that rolls without slipping moves its centre by −r Δφ and does not slip.
        (An average over the step, as a sampled sensor reads it: a soft sliding contact may hop within a step.)"""
        turn = (after[3] - before[3] + math.pi) % (2.0 * math.pi) - math.pi
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
            gaps[i], slips[i] = gap, self.slip_velocity(before[i], after) * self.dt
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
            lo, hi = self.contact_edges[i].xi_range
            if not lo <= xi <= hi:
                self.log_event(i, EventKind.LEFT_EDGE, f"xi = {xi:.5g} m outside [{lo:.5g}, {hi:.5g}]", out, xi=xi)
        for i, (link, depth) in sorted(links.items()):
            self.log_event(i, EventKind.COLLISION, f"link {link + 1} penetrates the object by {depth:.3g} m", out,
                           link=link, depth=depth)
        return out, xis, rates, err, gaps, slips

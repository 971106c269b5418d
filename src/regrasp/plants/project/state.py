"""The project plant's value types: a contact's mode and parameters (:class:`PlantContact`), the continuous state
(:class:`PlantState`), what one step produced (:class:`PlantStep`), the event log (:class:`PlantLog`), and an edge's
constants in plain floats (:class:`EdgeGeometry`) with the contact kinematics on it (:func:`contact_xi`,
:func:`surface_force`)."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from ...core.contact import ContactMode, as_modes
from ...core.events import Event, EventKind, EventSource
from ...core.exceptions import InvalidParameterError, PlantStateError
from ...core.polygon import ConvexPolygon
from ...core.validation import MAX_ANGLE, MAX_POSITION, MAX_SPEED, as_bounded_array, as_finite_float, as_integer

__all__ = ["MAX_DT", "PLANT_EVENT_KINDS", "EdgeGeometry", "PlantContact", "PlantLog", "PlantState", "PlantStep",
           "check_finite_step", "checked_state", "contact_xi", "edge_geometry", "rigid_contact_report",
           "state_magnitudes", "surface_force"]

#: The plant's largest step [s].
MAX_DT = 0.01

#: The kinds of event a plant reports (and may stop on).
PLANT_EVENT_KINDS = frozenset(k.value for k in (EventKind.SEPARATION, EventKind.SLIP, EventKind.STICK,
                                                EventKind.LEFT_EDGE, EventKind.COLLISION, EventKind.SINGULAR,
                                                EventKind.SATURATION))


@dataclass
class PlantContact:
    """One contact's mode and parameters (mutable: the plant switches modes on events).

    Attributes:
        edge: Edge index on the object (on a curved object, 0: its one face).
        mode: A :class:`~regrasp.core.contact.ContactMode` (its string, ``"fixed"``, ``"sliding"`` or
            ``"separated"``, is converted).
        xi: For a fixed contact, its position ξ [m] on the edge (object-fixed). On a curved object any finite ξ
            (the arc length, unbounded), and a sliding or separated contact's ξ is its tip's foot, which the plant
            updates after every step (where it seeks the foot next: :mod:`regrasp.plants.project.curve`).
        sign: For a sliding contact, the sliding direction s = ±1 along the edge's ξ.
    """

    edge: int
    mode: ContactMode
    xi: float = 0.0
    sign: float = 1.0

    def __post_init__(self) -> None:
        self.edge = as_integer("edge", self.edge)
        self.xi = as_finite_float("xi", self.xi)
        self.sign = as_finite_float("sign", self.sign)
        if type(self.mode) is not ContactMode:
            try:
                self.mode = as_modes((self.mode,))[0]
            except InvalidParameterError:
                raise InvalidParameterError("mode", self.mode, "'fixed', 'sliding' or 'separated'") from None


@dataclass
class PlantState:
    """The plant's continuous state and its integrated work terms: joint positions q [rad] and velocities v [rad/s]
    (2m,), the object's pose X = (x, y, β) [m, rad] and twist V [m/s, rad/s] in the hand frame, at time t [s]; the
    work [J] done by the joint torques, the joint damping and the contact forces since the last reset."""

    t: float
    q: np.ndarray
    v: np.ndarray
    X: np.ndarray
    V: np.ndarray
    torque_work: float = 0.0
    damping_work: float = 0.0
    contact_work: float = 0.0

    def copy(self) -> PlantState:
        return PlantState(self.t, self.q.copy(), self.v.copy(), self.X.copy(), self.V.copy(),
                          self.torque_work, self.damping_work, self.contact_work)

    def flat(self) -> np.ndarray:
        """The state as one flat array (q, v, X, V, the three works): the compiled kernels' layout."""
        return np.concatenate((self.q, self.v, self.X, self.V, (self.torque_work, self.damping_work,
                                                                 self.contact_work)))

    @classmethod
    def from_flat(cls, t: float, y: np.ndarray, n: int) -> PlantState:
        """The state at time ``t`` [s] from a flat array ``y`` (:meth:`flat`'s layout) of ``n`` joints; q, v, X and V
        are views of ``y``."""
        return cls(t, y[:n], y[n:2 * n], y[2 * n:2 * n + 3], y[2 * n + 3:2 * n + 6], *y[2 * n + 6:2 * n + 9].tolist())


def checked_state(n: int, q: object, v: object, X: object, V: object) -> tuple[np.ndarray, ...]:
    """A plant reset's (q, v, X, V) as float arrays (``n`` joints), each entry finite and within the physical bounds
    of :mod:`~regrasp.core.validation`: joint angles and β at most ``MAX_ANGLE`` [rad], the object's position at most
    ``MAX_POSITION`` [m], joint and object speeds at most ``MAX_SPEED`` [rad/s, m/s] (beyond them a step's sines and
    squares lose their meaning or overflow); an error names the argument."""
    return (as_bounded_array("q", q, (n,), MAX_ANGLE, "rad"), as_bounded_array("v", v, (n,), MAX_SPEED, "rad/s"),
            as_bounded_array("X", X, (3,), (MAX_POSITION, MAX_POSITION, MAX_ANGLE), "m, m, rad"),
            as_bounded_array("V", V, (3,), MAX_SPEED, "m/s, m/s, rad/s"))


def state_magnitudes(st: PlantState) -> str:
    """The largest |q|, |v|, |X| and |V| of a state, for an error."""
    return ", ".join(f"max |{name}| = {float(np.max(np.abs(value))):.3g}" for name, value in
                     (("q", st.q), ("v", st.v), ("X", st.X), ("V", st.V)))


def check_finite_step(start: PlantState, y: Sequence[float]) -> None:
    """A :class:`~regrasp.core.exceptions.PlantStateError` unless the flat state ``y`` (:meth:`PlantState.flat`'s
    layout) one step after ``start`` is finite (its sum is finite when every entry is, and far from overflow)."""
    if not math.isfinite(sum(y)):
        raise PlantStateError(start.t, f"the step from {state_magnitudes(start)} overflowed (a run that diverged)")


@dataclass(frozen=True)
class PlantStep:
    """What one plant step produced.

    Attributes:
        state: The state after the step.
        forces_surface: Each contact's force on the object in its surface frame
            (normal, tangential) [N], at the step's start (a plant with a compliant pad: averaged over the step);
            zeros when separated.
        xi: Each contact's ξ [m] after the step.
        xi_dot: Each contact's relative tangential velocity ξ̇ [m/s] after the step.
        modes: Contact modes (:class:`~regrasp.core.contact.ContactMode`) during the step.
        constraint_error: Largest constraint violation [m] after the step.
        gap: Each contact's distance from touching after the step [m], (m,): positive apart, negative
            interpenetrating (a soft contact's depth); a rigid contact that touches has 0 (its constraint's drift
            is ``constraint_error``).
        slip: How far each contact's material point moved along its edge relative to the object's point during
            the step [m], (m,): 0 for a contact that stuck (a rigid plant's fixed contact), ξ̇ dt at the step's
            end for a rigid contact that slid, and what a slip sensor reads on a soft one.
        events: Events detected after the step (:class:`~regrasp.core.events.Event`, source ``PLANT``).
    """

    state: PlantState
    forces_surface: np.ndarray
    xi: np.ndarray
    xi_dot: np.ndarray
    modes: tuple[ContactMode, ...]
    constraint_error: float
    gap: np.ndarray
    slip: np.ndarray
    events: tuple[Event, ...] = field(default_factory=tuple)


class EdgeGeometry(NamedTuple):
    """An edge's inward normal n, ξ direction t, ξ origin o, n·o [m] and ξ range [m] (object frame), as floats."""

    nx: float
    ny: float
    tx: float
    ty: float
    ox: float
    oy: float
    offset: float
    lo: float
    hi: float


def rigid_contact_report(modes: Sequence[ContactMode], xi_dot: np.ndarray, dt: float,
                         separated_gap: Callable[[int], float]) -> tuple[np.ndarray, np.ndarray]:
    """A rigid plant's :attr:`PlantStep.gap` and :attr:`PlantStep.slip` [m] for a step of ``dt`` [s] with the contact
    ``modes`` during it and ξ̇ [m/s] at its end: a touching contact has no gap and a fixed one no slip; a sliding one
    slips ξ̇ dt; ``separated_gap(i)``: a separated contact's distance from its edge [m]."""
    m = len(modes)
    gap, slip = np.zeros(m), np.zeros(m)
    for i, mode in enumerate(modes):
        if mode is ContactMode.SLIDING:
            slip[i] = xi_dot[i] * dt
        elif mode is ContactMode.SEPARATED:
            gap[i] = separated_gap(i)
    return gap, slip


def edge_geometry(polygon: ConvexPolygon, k: int) -> EdgeGeometry:
    """Edge ``k``'s constants as floats (object frame); a curved object has no fixed edge line (an
    :class:`~regrasp.core.exceptions.InvalidParameterError`: its contacts' lines are their feet's,
    :mod:`regrasp.plants.project.curve`)."""
    if not isinstance(polygon, ConvexPolygon):
        raise InvalidParameterError("polygon", polygon, "a ConvexPolygon: a curved object's face has no fixed edge "
                                    "line (the plant follows each tip's foot on the curve; the compiled kernel has "
                                    "straight edges only)")
    e = polygon.edge(k)
    (nx, ny), (tx, ty), (ox, oy) = e.inward_normal.tolist(), e.xi_direction.tolist(), e.xi_origin.tolist()
    return EdgeGeometry(nx, ny, tx, ty, ox, oy, float(e.inward_normal @ e.xi_origin), *e.xi_range)


def contact_xi(g: EdgeGeometry, X: list, V: list, c: float, s: float, tip: list,
               tip_vel: list) -> tuple[float, float]:
    """ξ [m] of a tip (position ``tip``, velocity ``tip_vel``: pairs of floats, hand frame) projected on edge ``g``'s
    line, and its velocity relative to the object ξ̇ [m/s], at object pose X and twist V (floats), (c, s) =
    (cos β, sin β)."""
    rx, ry = tip[0] - X[0], tip[1] - X[1]
    xi = g.tx * ((c * rx + s * ry) - g.ox) + g.ty * ((c * ry - s * rx) - g.oy)
    # velocity of the tip relative to the object, in object coordinates
    ux, uy = tip_vel[0] - (V[0] - V[2] * ry), tip_vel[1] - (V[1] + V[2] * rx)
    return xi, g.tx * (c * ux + s * uy) + g.ty * (c * uy - s * ux)


def surface_force(g: EdgeGeometry, c: float, s: float, force: list) -> tuple[float, float]:
    """A force (fx, fy) [N] (hand frame) at a contact on edge ``g`` in its surface frame (normal, tangential), at
    object rotation (c, s) = (cos β, sin β)."""
    fx, fy = force
    return ((c * g.nx - s * g.ny) * fx + (s * g.nx + c * g.ny) * fy,
            (c * g.tx - s * g.ty) * fx + (s * g.tx + c * g.ty) * fy)


class PlantLog:
    """A plant's event log: the events since the last reset (:class:`~regrasp.core.events.Event`, source ``PLANT``)
    and whether one of a kind in ``stop_on`` stopped the plant; ``names``: the fingers'."""

    def __init__(self, names: Sequence[str], stop_on: frozenset[EventKind]):
        self.names, self.stop_on = tuple(names), stop_on
        self.events: list[Event] = []
        self.stopped = False

    def add(self, t: float, i: int, kind: str | EventKind, detail: str, out: list[Event], **values: float) -> None:
        """Log contact ``i``'s event of ``kind`` at ``t`` [s] (``detail``: in words; ``values``: the numbers by name),
        here and in ``out``; a kind in ``stop_on`` stops the plant."""
        ev = Event(t, self.names[i], EventKind(kind), detail, EventSource.PLANT, values)
        out.append(ev)
        self.events.append(ev)
        if kind in self.stop_on:
            self.stopped = True

    def clear(self) -> None:
        """Forget the events; the plant runs again."""
        self.events = []
        self.stopped = False

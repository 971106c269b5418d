r"""A regrasp schedule: where each contact is, and which slides take it there, over a trajectory.

The planner (:func:`~regrasp.schedule.planner.plan_regrasps`) returns a :class:`RegraspSchedule`:
each contact's desired position :math:`\xi_d(t)`, :math:`\dot\xi_d`, :math:`\ddot\xi_d` on its edge,
the slides that move it (:class:`Slide`), and along it, per sample, each contact's envelope margin,
cone margin and normal force. Between slides a contact is fixed (at rest on the object).

**A slide's profile** moves a contact from ``start_xi`` to ``end_xi`` in one direction with a
trapezoidal speed: from rest, a constant acceleration :math:`v/r` for the ramp time r, a cruise at
:math:`v = |\Delta\xi| / (T - r)`, and the mirror-image stop, at rest again at ``end``
(T = ``end - start``). Position and velocity are continuous; the speed never exceeds v and the
acceleration never exceeds :math:`v / r`. With :math:`u = t - t_{start}` and s the direction:

.. math:: \xi(t) = \xi_0 + s \begin{cases} v u^2 / (2r) & u < r \\ v (u - r/2) & r \le u \le T - r \\
          |\Delta\xi| - v (T - u)^2 / (2r) & u > T - r \end{cases}

A **periodic** schedule covers one period of a periodic trajectory and ends where it starts, so
:meth:`RegraspSchedule.at` repeats it for any number of periods.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from enum import Enum

import numpy as np
from numpy.typing import ArrayLike

from ..core.exceptions import InvalidParameterError, RegraspError
from ..core.validation import (
    as_count,
    as_finite_array,
    as_finite_float,
    as_flag,
    as_name,
    as_number_array,
    as_positive_float,
    as_sign,
    check_fields,
    expect_sequence_of,
)

__all__ = ["NoScheduleError", "RegraspSchedule", "ScheduleLimit", "ScheduleSample", "Slide", "slides_at",
           "verification_limit"]


@dataclass(frozen=True)
class Slide:
    """One slide of one contact (its fields checked on construction: a ramp shorter than the slide, a direction
    that is the sign of ``end_xi - start_xi``).

    Attributes:
        contact: Index of the contact (finger order).
        name: Its finger's name.
        direction: +1 (along the edge's ξ) or -1.
        start: When the contact starts moving [s].
        end: When it is at rest again [s].
        start_xi: ξ at ``start`` [m].
        end_xi: ξ at ``end`` [m].
        ramp: Acceleration and deceleration time r [s] (the profile of the module docstring).
    """

    contact: int
    name: str
    direction: int
    start: float
    end: float
    start_xi: float
    end_xi: float
    ramp: float

    def __post_init__(self):
        check_fields(self, as_count, ("contact",))
        check_fields(self, as_name, ("name",))
        object.__setattr__(self, "direction", int(as_sign("direction", self.direction)))
        check_fields(self, as_finite_float, ("start", "end", "start_xi", "end_xi"))
        check_fields(self, as_positive_float, ("ramp",))
        if not self.end > self.start:
            raise InvalidParameterError("end", self.end, f"a time after start = {self.start:g} s")
        if not (self.ramp < self.duration and math.isfinite(self.speed)):
            raise InvalidParameterError("ramp", self.ramp, f"a ramp shorter than the slide ({self.duration:g} s)")
        if (self.end_xi - self.start_xi) * self.direction < 0.0:
            raise InvalidParameterError("direction", self.direction, "the sign of end_xi - start_xi")

    @property
    def duration(self) -> float:
        """end - start [s]."""
        return self.end - self.start

    @property
    def speed(self) -> float:
        """Cruise speed v [m/s]."""
        return abs(self.end_xi - self.start_xi) / (self.duration - self.ramp)

    @property
    def acceleration(self) -> float:
        """Largest |ξ̈| [m/s²] (during the ramps)."""
        return self.speed / self.ramp

    def profile(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(ξ, ξ̇, ξ̈) at times ``t`` [s] (arrays); constant outside [start, end]."""
        t = np.asarray(t, dtype=float)
        T, r, v, s = self.duration, self.ramp, self.speed, float(self.direction)
        u = np.clip(t - self.start, 0.0, T)
        distance = abs(self.end_xi - self.start_xi)
        ramp_up, ramp_down = u < r, u > T - r
        travelled = np.where(ramp_up, v * u * u / (2 * r),
                             np.where(ramp_down, distance - v * (T - u) ** 2 / (2 * r), v * (u - r / 2)))
        speed = np.where(ramp_up, v * u / r, np.where(ramp_down, v * (T - u) / r, v))
        accel = np.where(ramp_up, v / r, np.where(ramp_down, -v / r, 0.0))
        moving = (t > self.start) & (t < self.end)
        return self.start_xi + s * travelled, np.where(moving, s * speed, 0.0), np.where(moving, s * accel, 0.0)

    def profile_at(self, t: float) -> tuple[float, float, float]:
        """:meth:`profile` at one time ``t`` [s], in floats (hot paths: numpy's per-call cost dominates)."""
        T, r, v, s = self.duration, self.ramp, self.speed, float(self.direction)
        u = min(max(t - self.start, 0.0), T)
        if u < r:
            travelled, speed, accel = v * u * u / (2 * r), v * u / r, v / r
        elif u > T - r:
            distance = abs(self.end_xi - self.start_xi)
            travelled, speed, accel = distance - v * (T - u) ** 2 / (2 * r), v * (T - u) / r, -v / r
        else:
            travelled, speed, accel = v * (u - r / 2), v, 0.0
        if self.start < t < self.end:
            return self.start_xi + s * travelled, s * speed, s * accel
        return self.start_xi + s * travelled, 0.0, 0.0

    def to_json_dict(self) -> dict:
        return {"contact": self.name, "direction": self.direction, "start": self.start, "end": self.end,
                "from": self.start_xi, "to": self.end_xi}


@dataclass(frozen=True)
class ScheduleSample:
    """The schedule at one time or at an array of times (``at``).

    Attributes:
        xi: ξ_d per contact [m], (m,) or (n, m).
        xi_dot: ξ̇_d [m/s].
        xi_ddot: ξ̈_d [m/s²].
        direction: Sliding direction per contact: 0 fixed, ±1 sliding (int).
    """

    xi: np.ndarray
    xi_dot: np.ndarray
    xi_ddot: np.ndarray
    direction: np.ndarray


@dataclass(frozen=True, eq=False)
class RegraspSchedule:
    """A planned regrasp schedule (module docstring).

    Its fields are checked on construction, and normalised (the arrays to float arrays of their shapes, ``sliding``
    to ints, the sequences to tuples): a bad one is an :class:`~regrasp.core.exceptions.InvalidParameterError`
    naming it.

    Attributes:
        names: Finger names (contact order).
        edges: Contact edge of each finger.
        t_start, t_end: The planned horizon [s] (one period when ``periodic``).
        periodic: Whether the schedule ends where it starts and repeats with period ``t_end - t_start``.
        xi_start: Each contact's position at ``t_start`` [m], (m,).
        slides: The slides, by start time.
        times: Sample times [s], (k,), over the horizon (the planner's time step).
        xi, xi_dot, xi_ddot: ξ_d and its rates at the samples, (k, m) [m, m/s, m/s²].
        sliding: Sliding direction at the samples (0 fixed, ±1), (k, m) int.
        envelope_margin: Each contact's distance to the nearest bound of its feasible set [m], (k, m).
        cone_margin: Each fixed contact's μ_s f_n - |f_t| [N] in the force system of ``normal_force``
            (NaN at sliding contacts, which are on their kinetic cone edge), (k, m).
        normal_force: Normal forces [N] of the force system that keeps the fixed contacts deepest in
            their cones (the largest smallest cone margin), with the least squeeze among those, (k, m).
        required_envelope_margin, required_cone_margin: The margins the planner guaranteed [m], [N].
        min_envelope_margin: Smallest envelope margin [m] on the planner's verification grid (finer
            than ``times``), with when [s] and which contact (``min_envelope_margin_at``).
        min_cone_margin: Smallest cone margin [N] of a fixed contact over ``times``, when and which (inf at
            (NaN, "") when there is none).
        planning_seconds: Wall time of planning [s].
        slides_lower_bound: The fewest slides any schedule over the horizon needs with a free start
            and end (a periodic schedule can need more), or None.
    """

    names: tuple[str, ...]
    edges: tuple[int, ...]
    t_start: float
    t_end: float
    periodic: bool
    xi_start: np.ndarray
    slides: tuple[Slide, ...]
    times: np.ndarray
    xi: np.ndarray
    xi_dot: np.ndarray
    xi_ddot: np.ndarray
    sliding: np.ndarray
    envelope_margin: np.ndarray
    cone_margin: np.ndarray
    normal_force: np.ndarray
    required_envelope_margin: float
    required_cone_margin: float
    min_envelope_margin: float
    min_envelope_margin_at: tuple[float, str]
    min_cone_margin: float
    min_cone_margin_at: tuple[float, str]
    planning_seconds: float
    slides_lower_bound: int | None = None

    def __post_init__(self):
        _check_schedule(self)

    @property
    def m(self) -> int:
        return len(self.names)

    @property
    def period(self) -> float | None:
        """The period [s] of a periodic schedule, else None."""
        return self.t_end - self.t_start if self.periodic else None

    def slides_per_contact(self) -> dict[str, int]:
        """Number of slides of each contact over the horizon."""
        return {name: sum(1 for s in self.slides if s.contact == i) for i, name in enumerate(self.names)}

    def local_time(self, t: ArrayLike) -> np.ndarray:
        """Times ``t`` [s] (finite numbers: one, or an array of them) mapped into the horizon: modulo the period
        when periodic, else clipped to it."""
        t = as_finite_array("t", t)
        if self.periodic:
            return self.t_start + np.mod(t - self.t_start, self.t_end - self.t_start)
        return np.clip(t, self.t_start, self.t_end)

    def local_time_at(self, t: float) -> float:
        """:meth:`local_time` of one time [s] (a finite number), in floats."""
        if not (type(t) is float and t - t == 0.0):  # (the common case: a finite float)
            t = as_finite_float("t", t)
        if self.periodic:
            return self.t_start + (t - self.t_start) % (self.t_end - self.t_start)
        return min(max(t, self.t_start), self.t_end)

    def at(self, t: ArrayLike) -> ScheduleSample:
        """ξ_d, ξ̇_d, ξ̈_d and the sliding directions at time(s) ``t`` [s]; a periodic schedule repeats
        past ``t_end``, another holds its last positions (and its first before ``t_start``)."""
        if type(t) is float and t - t == 0.0:  # one finite time: in floats (the supervisor's every step)
            return self._at_scalar(t)
        if not isinstance(t, (np.ndarray, list, tuple)):
            return self._at_scalar(as_finite_float("t", t))
        arr = as_finite_array("t", t)
        if arr.ndim > 1:
            raise InvalidParameterError("t", t, "a finite time [s] or a 1-D array of them")
        if arr.ndim == 0:
            return self._at_scalar(float(arr))
        return slides_at(self.xi_start, self.slides, self.local_time(arr))

    def _at_scalar(self, t: float) -> ScheduleSample:
        """:meth:`at` one finite time, in floats (:func:`slides_at` for one time)."""
        local = self.local_time_at(t)
        m = len(self.names)
        xi, xi_dot, xi_ddot, direction = self.xi_start.tolist(), [0.0] * m, [0.0] * m, [0] * m
        for s in self.slides:  # the latest slide that has started sets the position
            if local >= s.start:
                xi[s.contact], v, a = s.profile_at(local)
                if s.start < local < s.end:
                    xi_dot[s.contact], xi_ddot[s.contact], direction[s.contact] = v, a, s.direction
        return ScheduleSample(np.array(xi), np.array(xi_dot), np.array(xi_ddot), np.array(direction))

    def to_json_dict(self) -> dict:
        """The ``"schedule"`` object of ``regrasp plan --regrasp --json``."""
        def num(x):
            return None if not np.isfinite(x) else float(x)

        return {
            "found": True,
            "reason": None,
            "periodic": self.periodic,
            "t_start": self.t_start,
            "t_end": self.t_end,
            "names": list(self.names),
            "times": self.times.tolist(),
            "xi": self.xi.tolist(),
            "xi_dot": self.xi_dot.tolist(),
            "xi_ddot": self.xi_ddot.tolist(),
            "sliding": (self.sliding != 0).tolist(),
            "direction": self.sliding.tolist(),
            "slides": [s.to_json_dict() for s in self.slides],
            "slides_per_contact": self.slides_per_contact(),
            "envelope_margin": self.envelope_margin.tolist(),
            "cone_margin": [[num(x) for x in row] for row in self.cone_margin],
            "normal_force": self.normal_force.tolist(),
            "required_envelope_margin": self.required_envelope_margin,
            "required_cone_margin": self.required_cone_margin,
            "min_envelope_margin": num(self.min_envelope_margin),
            "min_envelope_margin_at": {"time": self.min_envelope_margin_at[0],
                                       "contact": self.min_envelope_margin_at[1]},
            "min_cone_margin": num(self.min_cone_margin),
            "min_cone_margin_at": {"time": self.min_cone_margin_at[0], "contact": self.min_cone_margin_at[1]},
            "planning_seconds": self.planning_seconds,
            "slides_lower_bound": self.slides_lower_bound,
        }


def _check_schedule(s: RegraspSchedule) -> None:
    """Check, and normalise, the fields of the schedule ``s`` (:class:`RegraspSchedule`'s construction): m names and
    edges, a horizon, the slides of those contacts by start time, and k increasing sample times with (k, m)
    arrays of finite numbers (NaN where the fields' documentation allows it)."""
    names = tuple(str(as_name("names", name)) for name in expect_sequence_of("names", s.names, str, "finger names"))
    m = len(names)
    if m == 0:
        raise InvalidParameterError("names", s.names, "at least one finger name")
    edges = tuple(as_count("edges", edge) for edge in expect_sequence_of("edges", s.edges, object, "edge indices"))
    if len(edges) != m:
        raise InvalidParameterError("edges", s.edges, f"one edge index per finger ({m})")
    for name, value in (("names", names), ("edges", edges), ("xi_start", as_finite_array("xi_start", s.xi_start, (m,))),
                        ("slides", expect_sequence_of("slides", s.slides, Slide, "Slide"))):
        object.__setattr__(s, name, value)
    check_fields(s, as_finite_float, ("t_start", "t_end"))
    check_fields(s, as_flag, ("periodic",))
    if not (s.t_end > s.t_start or (s.t_end == s.t_start and not s.periodic)):
        raise InvalidParameterError("t_end", s.t_end, f"a time after t_start = {s.t_start:g} s")
    if any(slide.contact >= m for slide in s.slides) or any(b.start < a.start for a, b in zip(s.slides, s.slides[1:])):
        raise InvalidParameterError("slides", s.slides, f"slides of contacts 0..{m - 1} by start time")
    times = as_finite_array("times", s.times, (-1,))
    if not (len(times) and times[0] >= s.t_start and times[-1] <= s.t_end and np.all(np.diff(times) > 0.0)):
        raise InvalidParameterError("times", s.times, f"increasing sample times in [t_start, t_end] = "
                                    f"[{s.t_start:g}, {s.t_end:g}] s")
    object.__setattr__(s, "times", times)
    shape = (len(times), m)
    for name in ("xi", "xi_dot", "xi_ddot"):
        object.__setattr__(s, name, as_finite_array(name, getattr(s, name), shape))
    sliding = as_number_array("sliding", s.sliding, shape)
    if not np.isin(sliding, (-1.0, 0.0, 1.0)).all():
        raise InvalidParameterError("sliding", s.sliding, "sliding directions -1, 0 or +1")
    object.__setattr__(s, "sliding", sliding.astype(int))
    for name, infinite, what in (("envelope_margin", -math.inf, "margins [m] or -inf (no feasible interval)"),
                                 ("cone_margin", math.nan, "finite margins [N] or NaN"),
                                 ("normal_force", math.nan, "finite forces [N] or NaN")):
        arr = as_number_array(name, getattr(s, name), shape)
        if not (np.isfinite(arr) | (arr == infinite) | (np.isnan(arr) & math.isnan(infinite))).all():
            raise InvalidParameterError(name, getattr(s, name), what)
        object.__setattr__(s, name, arr)
    check_fields(s, as_positive_float, ("required_envelope_margin", "required_cone_margin", "planning_seconds"),
                 allow_zero=True)
    for name in ("min_envelope_margin", "min_cone_margin"):
        value, where = float(as_number_array(name, getattr(s, name), ())), getattr(s, name + "_at")
        if math.isnan(value):
            raise InvalidParameterError(name, value, "a number or inf (none)")
        pair = isinstance(where, (tuple, list)) and len(where) == 2 and isinstance(where[1], str) \
            and where[1] in (*names, "")
        time = float(as_number_array(name + "_at", where[0], ())) if pair else math.inf
        if math.isinf(time):
            raise InvalidParameterError(name + "_at", where, "(a finite time [s] or NaN, a finger's name or '')")
        object.__setattr__(s, name, value)
        object.__setattr__(s, name + "_at", (time, str(where[1])))
    check_fields(s, as_count, ("slides_lower_bound",), optional=True)


def slides_at(xi_start: np.ndarray, slides: Iterable[Slide], t: np.ndarray) -> ScheduleSample:
    """The contacts' (ξ, ξ̇, ξ̈, direction) at times ``t`` (n,) [s] from their positions before any
    slide, ``xi_start`` (m,) [m], and the ``slides`` in start order."""
    n, m = len(t), len(xi_start)
    xi = np.tile(np.asarray(xi_start, dtype=float), (n, 1))
    xi_dot, xi_ddot = np.zeros((n, m)), np.zeros((n, m))
    direction = np.zeros((n, m), dtype=int)
    for s in slides:  # the latest slide that has started sets the position
        started = t >= s.start
        if not started.any():
            continue
        x, v, a = s.profile(t)
        xi[started, s.contact] = x[started]
        moving = (t > s.start) & (t < s.end)
        xi_dot[moving, s.contact] = v[moving]
        xi_ddot[moving, s.contact] = a[moving]
        direction[moving, s.contact] = s.direction
    return ScheduleSample(xi, xi_dot, xi_ddot, direction)


class ScheduleLimit(str, Enum):
    """What ran out when no schedule exists."""

    ENVELOPE = "envelope"    #: a contact's feasible set (less the margin) is empty
    SPEED = "speed"          #: the feasible sets move faster than slides can follow
    FORCES = "forces"        #: no force system allows the slides the envelopes require
    PERIODIC = "periodic"    #: schedules exist, but none ends a period where it starts
    VERIFICATION = "verification"  #: the planner's schedules keep failing its fine-grid check
    TORQUE = "torque"        #: no force system within the joints' torque limits (the finger, joint and time named)
    #: no slide the envelopes need is well-posed there: friction makes the slider's contact problem ill-posed
    #: (Painlevé's paradox; :mod:`regrasp.schedule.well_posed`)
    PAINLEVE = "painleve"
    #: a search found none (the decomposition planner's, or a periodic schedule's from the starts tried): not a proof
    #: that none exists
    SEARCH = "search"


def verification_limit(what: str) -> ScheduleLimit:
    """The limit named when the verification keeps failing, its first violation being ``what``."""
    if what.startswith("torque"):
        return ScheduleLimit.TORQUE
    return ScheduleLimit.PAINLEVE if what.startswith("painleve") else ScheduleLimit.VERIFICATION


class NoScheduleError(RegraspError):
    """No regrasp schedule satisfies the constraints.

    Attributes:
        latest_time: The latest time [s] any admissible state survives.
        limit: The constraint that ran out (:class:`ScheduleLimit`).
        contacts: Names of the contacts concerned.
        reason: The diagnosis, in words (the message).
        rule: For two fingers on parallel edges, the slide rule that forbids the needed slide, or None.
        partial: The best schedule up to ``latest_time`` (not periodic), or None.
    """

    def __init__(self, latest_time: float, limit: ScheduleLimit, contacts: tuple[str, ...], reason: str,
                 rule: str | None = None, partial: RegraspSchedule | None = None):
        self.latest_time = float(latest_time)
        self.limit = ScheduleLimit(limit)
        self.contacts = tuple(contacts)
        self.reason = reason
        self.rule = rule
        self.partial = partial
        super().__init__(f"no regrasp schedule: {reason}" + (f"; {rule}" if rule else ""))

    def to_json_dict(self) -> dict:
        return {"found": False, "reason": str(self), "limit": self.limit.value, "latest_time": self.latest_time,
                "contacts": list(self.contacts), "rule": self.rule,
                "partial": None if self.partial is None else self.partial.to_json_dict()}


def first_minimum(values: np.ndarray, times: np.ndarray, names: Sequence[str], mask: np.ndarray | None = None
                  ) -> tuple[float, tuple[float, str]]:
    """The smallest entry of ``values`` (k, m) (where ``mask``), and (its time, its contact's name)."""
    v = np.where(np.isfinite(values) if mask is None else mask & np.isfinite(values), values, np.inf)
    if not np.isfinite(v).any():
        return math.inf, (math.nan, "")
    k, i = np.unravel_index(int(np.argmin(v)), v.shape)
    return float(v[k, i]), (float(times[k]), names[i])

r"""Contact health: one physical definition of a lost contact, for every plant and every study.

A contact is judged by what it carries and how it moves, never by a plant's own rules (a gap, a slip speed):

* a **held** contact (one the supervisor holds fixed) is lost when its normal force stays below the floor
  :math:`f_{min}` for ``held_window`` or longer, or when it has slipped more than ``held_slip`` along its edge
  since it was last taken hold of (the net displacement of its material point relative to the object's);
* a **slider** (a contact the supervisor primes, slides or settles) is lost when its normal force averaged over the
  last ``slider_window`` falls below :math:`f_{min}`, or when it carries no force at all (:math:`f_n \le 0`) for
  ``zero_window`` or longer.

A step counts for its whole length: a plant reports each contact's normal force over the step (the project plant's at
its start, MuJoCo's averaged over it), and a window of k steps lasts k dt. :class:`HealthMonitor` applies the criteria
step by step and keeps, per contact, the least force it carried while held, the least window-averaged force while
it slid, the longest stretch without force and the largest slip while held (:class:`ContactHealth`):
``regrasp simulate`` prints them and writes them to its JSON.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass

from .events import Failure, FailureKind
from .exceptions import InvalidParameterError
from .validation import as_positive_float

__all__ = ["ContactHealth", "HealthCriteria", "HealthMonitor"]


@dataclass(frozen=True)
class HealthCriteria:
    """When a contact is lost (module docstring).

    Attributes:
        force_floor: f_min, the least normal force a contact must carry [N].
        held_window: A held contact below ``force_floor`` this long is lost [s].
        held_slip: A held contact that slipped more than this since it was taken hold of is lost [m].
        slider_window: A slider whose normal force averaged over this long is below ``force_floor`` is lost [s].
        zero_window: A slider with no normal force this long is lost [s].
    """

    force_floor: float = 0.05
    held_window: float = 2e-3
    held_slip: float = 1e-4
    slider_window: float = 5e-3
    zero_window: float = 2e-3

    def __post_init__(self) -> None:
        for name in ("force_floor", "held_window", "held_slip", "slider_window", "zero_window"):
            object.__setattr__(self, name, as_positive_float(name, getattr(self, name)))

    def steps(self, window: float, dt: float) -> int:
        """How many steps of ``dt`` [s] make ``window`` [s] (at least one)."""
        return max(1, math.ceil(window / dt - 1e-9))


@dataclass(frozen=True)
class ContactHealth:
    """What one contact carried and how it moved over a run, against the :class:`HealthCriteria`.

    Attributes:
        contact: Finger name.
        least_held_force: The least normal force while held [N] (inf: never held) ...
        least_held_force_at: ... when [s] (NaN: never).
        least_slider_force: The least normal force averaged over ``slider_window`` while sliding [N] (inf: never) ...
        least_slider_force_at: ... when [s].
        longest_zero_force: The longest time without normal force (f_n ≤ 0) [s] ...
        longest_zero_force_at: ... when it began [s] (NaN: never).
        largest_held_slip: The largest net slip while held [m] ...
        largest_held_slip_at: ... when [s].
    """

    contact: str
    least_held_force: float
    least_held_force_at: float
    least_slider_force: float
    least_slider_force_at: float
    longest_zero_force: float
    longest_zero_force_at: float
    largest_held_slip: float
    largest_held_slip_at: float

    def to_json_dict(self) -> dict:
        def num(x: float) -> float | None:
            return float(x) if math.isfinite(x) else None

        return {"contact": self.contact, "least_held_force": num(self.least_held_force),
                "least_held_force_at": num(self.least_held_force_at),
                "least_slider_force": num(self.least_slider_force),
                "least_slider_force_at": num(self.least_slider_force_at),
                "longest_zero_force": self.longest_zero_force, "longest_zero_force_at": num(self.longest_zero_force_at),
                "largest_held_slip": self.largest_held_slip, "largest_held_slip_at": num(self.largest_held_slip_at)}


class _Contact:
    """One contact's running counts (:class:`HealthMonitor`)."""

    def __init__(self, name: str, window: int):
        self.name = name
        self.recent: deque[float] = deque(maxlen=window)  # the last normal forces, for the slider's average
        self.total = 0.0  # their sum
        self.below = 0  # steps in a row below the floor (held)
        self.zero = 0  # steps in a row without force
        self.zero_since = math.nan
        self.held = False
        self.slip = 0.0  # net slip since taken hold of [m]
        self.least_held, self.least_held_at = math.inf, math.nan
        self.least_slider, self.least_slider_at = math.inf, math.nan
        self.longest_zero, self.longest_zero_at = 0.0, math.nan
        self.largest_slip, self.largest_slip_at = 0.0, math.nan

    def report(self) -> ContactHealth:
        return ContactHealth(self.name, self.least_held, self.least_held_at, self.least_slider, self.least_slider_at,
                             self.longest_zero, self.longest_zero_at, self.largest_slip, self.largest_slip_at)


class HealthMonitor:
    """Applies :class:`HealthCriteria` to a run's steps (module docstring).

    Args:
        criteria: When a contact is lost.
        names: The fingers' names.
        dt: The plant's step [s].
    """

    def __init__(self, criteria: HealthCriteria, names: Sequence[str], dt: float):
        if not isinstance(criteria, HealthCriteria):
            raise InvalidParameterError("criteria", criteria, "a HealthCriteria")
        self.criteria = criteria
        self.dt = as_positive_float("dt", dt)
        self._held_steps = criteria.steps(criteria.held_window, self.dt)
        self._zero_steps = criteria.steps(criteria.zero_window, self.dt)
        self._contacts = [_Contact(str(n), criteria.steps(criteria.slider_window, self.dt)) for n in names]
        self.failure: Failure | None = None

    def observe(self, t: float, normal_force: Sequence[float], slip: Sequence[float],
                held: Sequence[bool]) -> Failure | None:
        """One step from ``t`` [s]: each contact's normal force over it [N], its slip during it [m] and whether
        the supervisor held it. Returns the first contact lost (and keeps it in :attr:`failure`), else None."""
        c = self.criteria
        floor, dt, end = c.force_floor, self.dt, t + self.dt
        lost: Failure | None = None
        for k, fn, s, h in zip(self._contacts, normal_force, slip, held):
            fn, s = float(fn), float(s)
            if len(k.recent) == k.recent.maxlen:
                k.total -= k.recent[0]
            k.recent.append(fn)
            k.total += fn
            if fn <= 0.0:
                if k.zero == 0:
                    k.zero_since = t
                k.zero += 1
                if k.zero * dt > k.longest_zero + 1e-12:
                    k.longest_zero, k.longest_zero_at = k.zero * dt, k.zero_since
            else:
                k.zero = 0
            if h:
                if not k.held:
                    k.slip = 0.0
                k.slip += s
                if abs(k.slip) > k.largest_slip:
                    k.largest_slip, k.largest_slip_at = abs(k.slip), end
                if fn < k.least_held:
                    k.least_held, k.least_held_at = fn, t
                k.below = k.below + 1 if fn < floor else 0
                if lost is None and k.below >= self._held_steps:
                    lost = Failure(end, FailureKind.SEPARATION, f"lost contact: held {k.name} carried less than "
                                   f"{floor:g} N for {k.below * dt * 1e3:.3g} ms (f_n = {fn:.3g} N)", k.name)
                elif lost is None and abs(k.slip) > c.held_slip:
                    lost = Failure(end, FailureKind.UNPLANNED_SLIP, f"unplanned slip: held {k.name} slipped "
                                   f"{k.slip * 1e3:+.3g} mm (more than {c.held_slip * 1e3:g} mm)", k.name)
            else:
                k.below = 0
                average = k.total / len(k.recent)
                if average < k.least_slider:
                    k.least_slider, k.least_slider_at = average, t
                if lost is None and average < floor:
                    lost = Failure(end, FailureKind.SEPARATION, f"lost contact: sliding {k.name}'s normal force "
                                   f"averaged {average:.3g} N over {len(k.recent) * dt * 1e3:.3g} ms (below "
                                   f"{floor:g} N)", k.name)
                elif lost is None and k.zero >= self._zero_steps:
                    lost = Failure(end, FailureKind.SEPARATION, f"lost contact: sliding {k.name} carried no force "
                                   f"for {k.zero * dt * 1e3:.3g} ms", k.name)
            k.held = bool(h)
        if lost is not None and self.failure is None:
            self.failure = lost
        return lost

    def reports(self) -> tuple[ContactHealth, ...]:
        """Each contact's :class:`ContactHealth` so far."""
        return tuple(k.report() for k in self._contacts)

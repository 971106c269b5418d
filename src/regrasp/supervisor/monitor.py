r"""The runtime envelope monitor (paper Figure 4.1): each contact's feasible set at the measured pose.

At a control step the monitor evaluates every contact's feasible envelope
(:meth:`FingerEnvelope.at <regrasp.envelope.finger_envelope.FingerEnvelope.at>`, the planner's Definition 2.2 for
one pose) at the *measured* object pose, and reports per contact its margin (the distance of ξ to
the nearer bound of the feasible interval holding it, negative outside), that interval's bounds,
and the bounds' rates (finite differences between evaluations; a jump above ``max_bound_step``
is a change of the set's shape, not a motion, and gets rate 0). ``every`` > 1 evaluates at most k calls
apart and reuses the last samples in between (the margins are still taken at the current ξ); a caller may
ask for a fresh evaluation at any call (``read(..., fresh=True)``: the supervisor does at each of its policy's
decisions, so that decisions read fresh margins), and the count of k starts again there; with
``track`` the ``urdf`` cuts are followed from the last evaluation
(:class:`~regrasp.envelope.tracker.EnvelopeTracker`).

**What a reading between evaluations can miss.** A margin is the distance of ξ to the nearer bound of its
interval, so it is 1-Lipschitz in each bound: a reading whose samples are ``age`` old differs from the reading a
fresh evaluation would give by at most how far a bound moved in that time. The reading reports
``miss_bound`` = ``speed_factor`` · v · age per contact, v the fastest its bounds are known to move: the largest
of a prior (``bound_speed``: :func:`bound_speeds` of the plan, along the planned motion) and every smooth rate
the monitor has measured. It holds while the bounds move no faster than ``speed_factor`` · v. What is faster is
seen at the next evaluation, at most (k − 1) steps late: a change of shape (an interval appearing, splitting or
vanishing) and a ``urdf`` collision cut near a tangency (where a link's distance to the object hardly changes
along the edge, the cut moves arbitrarily fast; no finite v bounds it). ``tests/supervisor/test_monitor.py`` checks both
against a monitor evaluating every step, on 1.5 s of the three-finger trajectory at 1 kHz with k = 10: the
plan's fastest bound moves 127 mm/s, so the bound reaches 2.3 mm nine steps after an evaluation, while half of
the stale margins equal the fresh ones (a margin to an edge's end does not move).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..core.exceptions import InvalidParameterError
from ..core.validation import as_finite_array, as_positive_float
from ..envelope.finger_envelope import EnvelopeSample, FingerEnvelope
from ..envelope.tracker import EnvelopeTracker
from ..model.geometry import Geometry

__all__ = ["EnvelopeMonitor", "EnvelopeReading", "bound_speeds", "interval_of"]

_NO_INTERVAL = (math.nan, math.nan)


def interval_of(sample: EnvelopeSample, xi: float) -> tuple[float, float] | None:
    """The feasible interval of ``sample`` holding ``xi`` [m], else the nearest one, else None."""
    best, best_gap = None, math.inf
    for lo, hi in sample.feasible:
        gap = 0.0 if lo <= xi <= hi else min(abs(xi - lo), abs(xi - hi))
        if gap < best_gap:
            best, best_gap = (lo, hi), gap
    return best


@dataclass(frozen=True)
class EnvelopeReading:
    """The monitor's reading at one step.

    Attributes:
        t: Time [s].
        samples: Each contact's envelope sample (the latest evaluated one).
        margins: Each contact's margin [m], (m,): negative outside its feasible set, -inf when it is empty.
        bounds: The feasible interval (lo, hi) holding (or nearest to) each ξ [m], (m, 2); NaN when empty.
        rates: d(lo)/dt, d(hi)/dt [m/s], (m, 2).
        fresh: Whether the samples were evaluated at this step.
        age: How old the samples are [s] (0 when fresh).
        miss_bound: How far each margin may be from a fresh evaluation's [m], (m,), while the sets keep their
            shape (module docstring); zeros when fresh.
    """

    t: float
    samples: tuple[EnvelopeSample, ...]
    margins: np.ndarray
    bounds: np.ndarray
    rates: np.ndarray
    fresh: bool
    age: float = 0.0
    miss_bound: np.ndarray | None = None

    def time_to_bound(self, i: int, xi: float) -> float:
        """Time [s] until contact i's nearer moving bound reaches ``xi`` at its current rate (inf if never)."""
        lo, hi = self.bounds[i]
        times = [math.inf]
        if self.rates[i, 0] > 0.0:
            times.append((xi - lo) / self.rates[i, 0])
        if self.rates[i, 1] < 0.0:
            times.append((hi - xi) / -self.rates[i, 1])
        return min(times)


class EnvelopeMonitor:
    """Evaluates the contacts' runtime envelopes (module docstring).

    Args:
        envelopes: One :class:`~regrasp.envelope.finger_envelope.FingerEnvelope` per contact.
        every: Evaluate every k-th call (k >= 1).
        track: Follow ``urdf`` envelopes' cuts with an :class:`~regrasp.envelope.tracker.EnvelopeTracker`.
        max_bound_step: The largest change of a bound per call counted as motion [m] (k calls apart: k times it).
        bound_speed: A prior for the fastest a bound moves [m/s]: one for all contacts or one per contact
            (:func:`bound_speeds` of a plan); the monitor raises it to every smooth rate it measures.
        speed_factor: The safety factor on that speed in ``miss_bound`` [-] (>= 1).
    """

    def __init__(self, envelopes: Iterable[FingerEnvelope], *, every: int = 1, track: bool = False,
                 max_bound_step: float = 1e-3, bound_speed: ArrayLike = 0.0, speed_factor: float = 2.0):
        self.envelopes = tuple(envelopes)
        if not self.envelopes or not all(isinstance(e, FingerEnvelope) for e in self.envelopes):
            raise InvalidParameterError("envelopes", envelopes, "a non-empty sequence of FingerEnvelope")
        if isinstance(every, bool) or not isinstance(every, (int, np.integer)) or every < 1:
            raise InvalidParameterError("every", every, "an integer >= 1")
        self.every = int(every)
        self.max_bound_step = as_positive_float("max_bound_step", max_bound_step)
        speed = as_finite_array("bound_speed", bound_speed)
        if speed.ndim == 0:
            speed = np.full(len(self.envelopes), float(speed))
        elif speed.shape != (len(self.envelopes),):
            raise InvalidParameterError("bound_speed", bound_speed,
                                        f"one speed, or one per contact ({len(self.envelopes)})")
        if np.any(speed < 0.0):
            raise InvalidParameterError("bound_speed", bound_speed, "speeds >= 0 [m/s]")
        self.speed_factor = as_positive_float("speed_factor", speed_factor)
        if self.speed_factor < 1.0:
            raise InvalidParameterError("speed_factor", speed_factor, "a factor >= 1")
        #: The fastest each contact's bounds have moved [m/s]: the prior, raised by the measured rates.
        self.bound_speed = np.array(speed, dtype=float)
        self._sample_time = math.nan
        self.trackers = ([EnvelopeTracker(e) for e in self.envelopes]
                         if track and all(e.geometry is Geometry.URDF for e in self.envelopes) else None)
        self._calls = 0  # reads since the last evaluation
        self._held: tuple | None = None  # (samples, intervals, counts): see held_intervals()
        self._samples: list[EnvelopeSample] | None = None
        self._previous: tuple[float, np.ndarray] | None = None
        self._rates = np.zeros((len(self.envelopes), 2))

    @property
    def m(self) -> int:
        return len(self.envelopes)

    # stretches (regrasp.rollout.stretch): reads served from the held samples, in compiled code
    def held_reads(self) -> int:
        """How many of the next reads the held samples serve (0: the next read evaluates the envelopes)."""
        if self._samples is None:
            return 0
        return max(0, self.every - self._calls)

    def held_intervals(self) -> tuple[np.ndarray, np.ndarray]:
        """The held samples' feasible intervals (m, k, 2) [m] and how many each has (m,)."""
        if self._samples is None:
            raise InvalidParameterError("monitor", "no samples", "a monitor that has read once")
        if self._held is None or self._held[0] is not self._samples:
            k = max(1, max(len(s.feasible) for s in self._samples))
            intervals = np.zeros((self.m, k, 2))
            counts = np.zeros(self.m, np.int64)
            for i, sample in enumerate(self._samples):
                counts[i] = len(sample.feasible)
                if sample.feasible:
                    intervals[i, :counts[i]] = sample.feasible
            self._held = (self._samples, intervals, counts)
        return self._held[1], self._held[2]

    def stretch_view(self) -> tuple:
        """What a compiled stretch (:mod:`regrasp.rollout.stretch`) reads and updates of the monitor, as new arrays: the
        held samples' feasible intervals (m, k, 2) [m] with room for any evaluation's, their counts (m,), the bounds at
        the last evaluation (m, 2) [m], their rates (m, 2) [m/s], :attr:`bound_speed` (m,) [m/s], the last
        evaluation's time [s] (NaN: none) and the reads since it."""
        intervals, counts = self.held_intervals()
        capacity = max([intervals.shape[1]] + [e.compiled_arguments[10].shape[0] for e in self.envelopes
                                               if e.compiled])
        room = np.zeros((self.m, capacity, 2))
        room[:, :intervals.shape[1]] = intervals
        previous_time, bounds = (math.nan, np.zeros((self.m, 2))) if self._previous is None else self._previous
        return (room, counts.copy(), np.array(bounds, dtype=float), self._rates.copy(), self.bound_speed.copy(),
                float(previous_time), self._calls)

    def take_stretch(self, intervals: np.ndarray, counts: np.ndarray, previous_bounds: np.ndarray, rates: np.ndarray,
                     bound_speed: np.ndarray, previous_time: float, calls: int, evaluated: bool,
                     samples: list[EnvelopeSample] | None) -> None:
        """After a compiled stretch: its reads since the last evaluation and, if it ``evaluated`` the envelopes,
        that evaluation's bounds, rates and time, and its ``samples`` (None: lost to a later evaluation of a step
        the stretch handed over; the next read, that step's, then evaluates anew: ``calls`` >= ``every`` or the
        policy decides there)."""
        self._calls = int(calls)
        if not evaluated:
            return
        self._sample_time = float(previous_time)
        self._previous = (float(previous_time), previous_bounds)
        self._rates = rates
        self.bound_speed = bound_speed
        if samples is not None:
            self._samples = samples
            self._held = (samples, intervals, counts)

    def read(self, t: float, X: np.ndarray, xi: np.ndarray, fresh: bool = False) -> EnvelopeReading:
        """The reading at time ``t`` [s], measured object pose ``X`` (x, y, β) and contact positions ``xi`` [m];
        ``fresh``: evaluate the envelopes now (else only when ``every`` calls have passed since they were)."""
        fresh = fresh or self._samples is None or self._calls >= self.every
        if fresh:
            self._calls = 0
        self._calls += 1
        if fresh:
            if self.trackers is not None:
                self._samples = [tracker.update(X, t) for tracker in self.trackers]
            else:
                self._samples = [env.at(X, t) for env in self.envelopes]
        margins, rows = [], []
        for sample, x in zip(self._samples, np.asarray(xi, dtype=float).tolist()):
            margins.append(sample.margin(x))
            iv = interval_of(sample, x)
            rows.append(_NO_INTERVAL if iv is None else iv)
        margins, bounds = np.array(margins), np.array(rows)
        if fresh:
            self._sample_time = float(t)
            if self._previous is not None and t > self._previous[0]:
                change = bounds - self._previous[1]
                rates = change / (t - self._previous[0])
                # (max_bound_step is per call: k calls apart, a bound may move k times as far)
                smooth = np.isfinite(rates) & (np.abs(change) <= self.max_bound_step * self.every)
                self._rates = np.where(smooth, rates, 0.0)
                self.bound_speed = np.maximum(self.bound_speed, np.abs(self._rates).max(axis=1))
            self._previous = (t, bounds)
        age = max(0.0, float(t) - self._sample_time)
        return EnvelopeReading(float(t), tuple(self._samples), margins, bounds, self._rates.copy(), fresh, age,
                               self.speed_factor * self.bound_speed * age)


def bound_speeds(samples_per_contact: Iterable[Iterable[EnvelopeSample]], max_bound_step: float = 2e-3) -> np.ndarray:
    """The fastest each contact's feasible bounds move [m/s] along a sequence of envelope samples (a plan's:
    ``[f.samples for f in plan.fingers]``): the largest |change| / Δt of a bound between consecutive samples with
    as many intervals, changes above ``max_bound_step`` [m] (a change of shape) left out."""
    out = []
    for samples in samples_per_contact:
        fastest = 0.0
        samples = list(samples)
        for a, b in zip(samples, samples[1:]):
            dt = b.time - a.time
            if not dt > 0.0 or len(a.feasible) != len(b.feasible):
                continue
            for (lo0, hi0), (lo1, hi1) in zip(a.feasible, b.feasible):
                for change in (abs(lo1 - lo0), abs(hi1 - hi0)):
                    if change <= max_bound_step:
                        fastest = max(fastest, change / dt)
        out.append(fastest)
    return np.array(out)

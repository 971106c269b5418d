r"""The runtime envelope monitor (paper Figure 4.1): each contact's feasible set at the measured pose.

At a control step the monitor evaluates every contact's feasible envelope
(:meth:`FingerEnvelope.at <regrasp.envelope.FingerEnvelope.at>`, the planner's Definition 2.2 for
one pose) at the *measured* object pose, and reports per contact its margin (the distance of ξ to
the nearer bound of the feasible interval holding it, negative outside), that interval's bounds,
and the bounds' rates (finite differences between evaluations; a jump above ``max_bound_step``
is a change of the set's shape, not a motion, and gets rate 0). ``every`` > 1 evaluates only every
k-th call and reuses the last samples (the margins are still taken at the current ξ); with
``track`` the ``urdf`` cuts are followed from the last evaluation
(:class:`~regrasp.envelope_tracker.EnvelopeTracker`).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from .envelope import EnvelopeSample, FingerEnvelope, Geometry
from .envelope_tracker import EnvelopeTracker
from .exceptions import InvalidParameterError

__all__ = ["EnvelopeMonitor", "EnvelopeReading", "interval_of"]

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
    """

    t: float
    samples: tuple[EnvelopeSample, ...]
    margins: np.ndarray
    bounds: np.ndarray
    rates: np.ndarray
    fresh: bool

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
        envelopes: One :class:`~regrasp.envelope.FingerEnvelope` per contact.
        every: Evaluate every k-th call (k >= 1).
        track: Follow ``urdf`` envelopes' cuts with an :class:`~regrasp.envelope_tracker.EnvelopeTracker`.
        max_bound_step: The largest change of a bound between evaluations counted as motion [m].
    """

    def __init__(self, envelopes: Iterable[FingerEnvelope], *, every: int = 1, track: bool = False,
                 max_bound_step: float = 1e-3):
        self.envelopes = tuple(envelopes)
        if not self.envelopes or not all(isinstance(e, FingerEnvelope) for e in self.envelopes):
            raise InvalidParameterError("envelopes", envelopes, "a non-empty sequence of FingerEnvelope")
        if isinstance(every, bool) or not isinstance(every, (int, np.integer)) or every < 1:
            raise InvalidParameterError("every", every, "an integer >= 1")
        self.every = int(every)
        self.max_bound_step = float(max_bound_step)
        self.trackers = ([EnvelopeTracker(e) for e in self.envelopes]
                         if track and all(e.geometry is Geometry.URDF for e in self.envelopes) else None)
        self._calls = 0
        self._samples: list[EnvelopeSample] | None = None
        self._previous: tuple[float, np.ndarray] | None = None
        self._rates = np.zeros((len(self.envelopes), 2))

    @property
    def m(self) -> int:
        return len(self.envelopes)

    def read(self, t: float, X: np.ndarray, xi: np.ndarray) -> EnvelopeReading:
        """The reading at time ``t`` [s], measured object pose ``X`` (x, y, β) and contact positions ``xi`` [m]."""
        fresh = self._samples is None or self._calls % self.every == 0
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
            if self._previous is not None and t > self._previous[0]:
                change = bounds - self._previous[1]
                rates = change / (t - self._previous[0])
                smooth = np.isfinite(rates) & (np.abs(change) <= self.max_bound_step)
                self._rates = np.where(smooth, rates, 0.0)
            self._previous = (t, bounds)
        return EnvelopeReading(float(t), tuple(self._samples), margins, bounds, self._rates.copy(), fresh)

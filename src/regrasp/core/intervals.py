"""Finite unions of closed intervals on the real line, as sorted tuples of (lo, hi).

An interval set is a ``tuple[tuple[float, float], ...]`` with ``lo < hi`` in every
pair, sorted and pairwise disjoint; ``()`` is the empty set. These small functions
keep that invariant; they are used for contact envelopes in ξ [m].
"""

from __future__ import annotations

from collections.abc import Iterable

Intervals = tuple[tuple[float, float], ...]

__all__ = [
    "DANGER_FRACTION",
    "Intervals",
    "contains",
    "danger_zones",
    "intersect",
    "merge",
    "total_length",
    "widest",
    "without_danger_zones",
]

#: A contact is in its *danger zone* when it is within this fraction of its feasible interval's width of either
#: bound (paper §4's regrasp trigger). The one definition: the paper policy, the plan's suggested start, the
#: rollout figures and the rerun recording all take it from here (or from a setting that defaults to it).
DANGER_FRACTION = 0.1


def merge(pieces: Iterable[tuple[float, float]], *, gap: float = 0.0) -> Intervals:
    """Union of ``pieces``; pieces closer than ``gap`` are joined, empty ones dropped."""
    items = sorted([(float(lo), float(hi)) for lo, hi in pieces if hi > lo])
    if len(items) < 2:
        return tuple(items)
    out = []
    start, end = items[0]
    for lo, hi in items[1:]:
        if lo <= end + gap:
            if hi > end:
                end = hi
        else:
            out.append((start, end))
            start, end = lo, hi
    out.append((start, end))
    return tuple(out)


def intersect(a: Intervals, b: Intervals) -> Intervals:
    """Intersection of two interval sets."""
    out = []
    i = j = 0
    while i < len(a) and j < len(b):
        lo = max(a[i][0], b[j][0])
        hi = min(a[i][1], b[j][1])
        if hi > lo:
            out.append((lo, hi))
        if a[i][1] < b[j][1]:
            i += 1
        else:
            j += 1
    return tuple(out)


def contains(a: Intervals, x: float, *, tol: float = 0.0) -> bool:
    """Whether ``x`` lies in ``a`` (closed intervals, widened by ``tol``)."""
    return any(lo - tol <= x <= hi + tol for lo, hi in a)


def total_length(a: Intervals) -> float:
    """Sum of the interval lengths."""
    return float(sum(hi - lo for lo, hi in a))


def widest(a: Intervals) -> tuple[float, float] | None:
    """The widest interval of ``a`` (the first one on ties), or None if ``a`` is empty."""
    if not a:
        return None
    return max(a, key=lambda iv: iv[1] - iv[0])


def danger_zones(lo: float, hi: float, fraction: float = DANGER_FRACTION) -> tuple[tuple[float, float], ...]:
    """The two danger zones of the feasible interval ``[lo, hi]`` [m]: ``fraction`` of its width at each end."""
    keep = fraction * (hi - lo)
    return ((lo, lo + keep), (hi - keep, hi))


def without_danger_zones(a: Intervals, fraction: float = DANGER_FRACTION) -> Intervals:
    """``a`` less each interval's danger zones (:func:`danger_zones`)."""
    return tuple((lo + fraction * (hi - lo), hi - fraction * (hi - lo)) for lo, hi in a
                 if hi - lo > 0.0 and fraction < 0.5)

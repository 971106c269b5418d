r"""The runtime envelope monitor's arithmetic in compiled code, for :func:`.stretch.stretch_into`: a contact's
margin and the feasible interval holding (or nearest to) its ξ
(:meth:`regrasp.envelope.finger_envelope.EnvelopeSample.margin`, :func:`regrasp.supervisor.monitor.interval_of`), and
the envelopes' arguments for their evaluation in a stretch (:func:`.envelope.envelope_sample_into` for every finger).
"""

from __future__ import annotations

import numba
import numpy as np

from .envelope import ENVELOPE_PARAMETERS
from .footprint import FOOTPRINT

__all__ = ["envelope_arguments", "reading_at"]


def envelope_arguments(arguments: list[tuple] | None, m: int) -> tuple[tuple, tuple, tuple]:
    """The ``geometry``, ``samples`` and ``scratch`` arguments of :func:`stretch_into` for m fingers whose envelopes
    have the compiled arguments ``arguments``
    (:attr:`regrasp.envelope.finger_envelope.FingerEnvelope.compiled_arguments`: one tuple per finger, all on one
    polygon), or placeholders of the same types for None (the kernel then does not evaluate). ``geometry``: the fingers'
    :data:`.envelope.ENVELOPE_PARAMETERS` (m,), their link footprints one after another (read-only) and where each
    finger's start (m + 1,), the polygon's vertices and inward normals; ``samples``: per finger the last evaluation's
    (d, λ, s0) (m, 3), reachable set (m, 4, 2) and feasible set (m, rows, 2) [m]; ``scratch``: the rest of
    :func:`.envelope.envelope_sample_into`'s outputs, sized for all."""
    if not arguments:
        shapes = np.zeros(1, dtype=FOOTPRINT)
        shapes.flags.writeable = False
        geometry = (np.zeros(m, dtype=ENVELOPE_PARAMETERS), shapes, np.zeros(m + 1, np.int64), np.zeros((1, 2)),
                    np.zeros((1, 2)))
        return geometry, (np.zeros((m, 3)), np.zeros((m, 4, 2)), np.zeros((m, 1, 2))), (
            np.empty((4, 2)), np.empty(4, np.bool_), np.empty(4, np.int64), np.empty(1), np.empty(1))
    params = np.concatenate([a[0] for a in arguments])
    shapes = np.concatenate([a[1] for a in arguments])
    shapes.flags.writeable = False  # (as the library's footprints: the same compiled envelope kernel)
    starts = np.cumsum([0] + [len(a[1]) for a in arguments]).astype(np.int64)
    rows = max(a[10].shape[0] for a in arguments)
    geometry = (params, shapes, starts, arguments[0][2], arguments[0][3])
    samples = (np.zeros((m, 3)), np.zeros((m, 4, 2)), np.zeros((m, rows, 2)))
    scratch = (np.empty((4, 2)), np.empty(4, np.bool_), np.empty(4, np.int64),
               np.empty(max(a[9].shape[0] for a in arguments)), np.empty(max(a[11].shape[0] for a in arguments)))
    return geometry, samples, scratch


@numba.njit(cache=True)
def reading_at(intervals, counts, i, x):
    """Contact i's margin [m] and the interval (lo, hi) holding (or nearest to) ξ = x
    (:meth:`regrasp.envelope.finger_envelope.EnvelopeSample.margin`, :func:`regrasp.supervisor.monitor.interval_of`)."""
    best, lo_best, hi_best, gap_best = -np.inf, np.nan, np.nan, np.inf
    for j in range(counts[i]):
        lo, hi = intervals[i, j, 0], intervals[i, j, 1]
        best = max(best, min(x - lo, hi - x))
        gap = 0.0 if lo <= x <= hi else min(abs(x - lo), abs(x - hi))
        if gap < gap_best:
            lo_best, hi_best, gap_best = lo, hi, gap
    return best, lo_best, hi_best

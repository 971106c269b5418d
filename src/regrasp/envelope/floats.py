"""Float fast paths of the envelope's hot path: numpy's arithmetic on plain Python floats, bit for bit.

An envelope sample is computed at every control step of a supervisor (1 kHz per finger), on floats: these
helpers give the same floats as their numpy counterparts without numpy's per-call overhead.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from ..core.validation import as_finite_array

__all__ = ["linspace_floats", "pose_floats"]


def pose_floats(value: ArrayLike) -> tuple[float, float, float]:
    """A planar pose ``(x [m], y [m], beta [rad])`` as floats, validated like ``as_finite_array(…, (3,))``
    (an :class:`~regrasp.core.exceptions.InvalidParameterError` naming ``pose_object_in_hand``)."""
    if type(value) is np.ndarray and value.shape == (3,) and value.dtype.kind == "f":
        x, y, beta = value.tolist()
        if math.isfinite(x) and math.isfinite(y) and math.isfinite(beta):
            return x, y, beta
    x, y, beta = as_finite_array("pose_object_in_hand", value, (3,)).tolist()
    return x, y, beta


def linspace_floats(lo: float, hi: float, num: int) -> list[float]:
    """``np.linspace(lo, hi, num).tolist()`` (``num`` >= 2 points from ``lo`` to ``hi``, both included) with
    numpy's arithmetic, without numpy."""
    delta = hi - lo
    div = num - 1
    step = delta / div
    if step == 0.0:  # numpy's handling of denormal spans
        out = [(k / div) * delta + lo for k in range(div)]
    else:
        out = [k * step + lo for k in range(div)]
    out.append(hi)
    return out

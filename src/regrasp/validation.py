"""Argument checks that raise typed errors (never ``assert``)."""

from __future__ import annotations

import math

import numpy as np

from .exceptions import InvalidParameterError


def as_finite_array(name: str, value, shape: tuple[int, ...] | None = None) -> np.ndarray:
    """``value`` as a float array of the given shape with only finite entries."""
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError(name, value, "an array of numbers") from exc
    if shape is not None:
        if len(shape) != arr.ndim or any(s != -1 and s != a for s, a in zip(shape, arr.shape)):
            want = "x".join("n" if s == -1 else str(s) for s in shape)
            raise InvalidParameterError(name, value, f"an array of shape ({want})")
    if not np.all(np.isfinite(arr)):
        raise InvalidParameterError(name, value, "finite numbers (no NaN or inf)")
    return arr


def as_finite_float(name: str, value) -> float:
    """``value`` as a finite float."""
    try:
        out = float(value)
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError(name, value, "a number") from exc
    if not np.isfinite(out):
        raise InvalidParameterError(name, value, "a finite number")
    return out


def as_positive_float(name: str, value, *, allow_zero: bool = False) -> float:
    """``value`` as a finite float > 0 (or >= 0 with ``allow_zero``)."""
    out = as_finite_float(name, value)
    if out < 0.0 or (out == 0.0 and not allow_zero):
        raise InvalidParameterError(name, value, ">= 0" if allow_zero else "> 0")
    return out


def as_finite_vectors(names: tuple[str, ...], values: tuple, n: int) -> np.ndarray:
    """The ``values`` as the rows of one (len(values), n) float array, all checked at once (hot paths).

    Raises the error :func:`as_finite_array` raises for the first bad value, in order.
    """
    try:
        arr = np.array(values, dtype=float)
    except (TypeError, ValueError):
        arr = None
    # a sum is finite when every entry is (a finite sum that overflows only takes the slow path)
    if arr is None or arr.shape != (len(values), n) or not math.isfinite(sum(arr.reshape(-1).tolist())):
        arr = np.array([as_finite_array(name, value, (n,)) for name, value in zip(names, values)])
    return arr

"""Linear algebra on tiny systems in plain floats (hot paths: numpy's per-call cost dwarfs the work)."""

from __future__ import annotations

import numpy as np

__all__ = ["solve_small"]


def solve_small(a: list[list[float]], b: list[float]) -> list[float]:
    """x with a x = b for a small dense system (lists; overwritten) in plain floats (numpy's per-call
    overhead dwarfs a 1..2m system): Cramer's rule up to 3 unknowns, else Gaussian elimination with
    partial pivoting."""
    k = len(b)
    if k <= 3:
        if k == 3:
            (a00, a01, a02), (a10, a11, a12), (a20, a21, a22) = a
            c00, c01, c02 = a11 * a22 - a12 * a21, a12 * a20 - a10 * a22, a10 * a21 - a11 * a20
            det = a00 * c00 + a01 * c01 + a02 * c02
            if not abs(det) > 0.0:
                raise np.linalg.LinAlgError("Singular matrix")
            b0, b1, b2 = b
            return [(c00 * b0 + (a02 * a21 - a01 * a22) * b1 + (a01 * a12 - a02 * a11) * b2) / det,
                    (c01 * b0 + (a00 * a22 - a02 * a20) * b1 + (a02 * a10 - a00 * a12) * b2) / det,
                    (c02 * b0 + (a01 * a20 - a00 * a21) * b1 + (a00 * a11 - a01 * a10) * b2) / det]
        if k == 2:
            (a00, a01), (a10, a11) = a
            det = a00 * a11 - a01 * a10
            if not abs(det) > 0.0:
                raise np.linalg.LinAlgError("Singular matrix")
            return [(a11 * b[0] - a01 * b[1]) / det, (a00 * b[1] - a10 * b[0]) / det]
        if not abs(a[0][0]) > 0.0:
            raise np.linalg.LinAlgError("Singular matrix")
        return [b[0] / a[0][0]]
    for col in range(k):
        top = a[col]
        piv, best = col, abs(top[col])
        for r in range(col + 1, k):
            if abs(a[r][col]) > best:
                piv, best = r, abs(a[r][col])
        if not best > 0.0:
            raise np.linalg.LinAlgError("Singular matrix")
        if piv != col:
            a[col], a[piv] = a[piv], top
            top = a[col]
            b[col], b[piv] = b[piv], b[col]
        p, bc = top[col], b[col]
        for r in range(col + 1, k):
            row = a[r]
            factor = row[col] / p
            if factor:
                for j in range(col + 1, k):
                    row[j] -= factor * top[j]
                b[r] -= factor * bc
    x = [0.0] * k
    for col in range(k - 1, -1, -1):
        row, acc = a[col], b[col]
        for j in range(col + 1, k):
            acc -= row[j] * x[j]
        x[col] = acc / row[col]
    return x

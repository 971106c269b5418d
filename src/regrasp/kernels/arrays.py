"""Array helpers the kernels share, written as loops: numba compiles an array-to-array slice assignment
(``a[:] = b``, ``a[i] = row``) with a run-time shape check whose error message it formats in compiled code, most of
a second of compiling per site; a loop compiles in a few milliseconds and does the same copy."""

from __future__ import annotations

import numba

__all__ = ["copy_into"]


@numba.njit(cache=True)
def copy_into(dst, src):
    """``dst[...] = src`` for two C-contiguous arrays of one size (any shapes of that size)."""
    d, s = dst.reshape(dst.size), src.reshape(src.size)
    for i in range(d.size):
        d[i] = s[i]

r"""LAPACK's ``dgesv`` and ``dgelsd`` for the kernels, through public interfaces only.

The kernels need a square solve (the plant's contact forces) and a minimum-norm least-squares solve (the QP's
fallback). numba's ``np.linalg.solve`` and ``np.linalg.lstsq`` call the same LAPACK routines, but compiling their
general implementations (checks, complex and 2-D branches, shape errors) costs about 5.5 s of a machine's first run.
Here the routines are scipy's (``scipy.linalg.cython_lapack``, the LAPACK numba itself calls), their addresses found
with :func:`numba.extending.get_cython_function_address` and given a name with :func:`llvmlite.binding.add_symbol`,
so that a kernel calls them as a :class:`numba.types.ExternalFunction` and stays cacheable (the name, not an
address, is in the cached code; this module registers it in every process before a kernel can load).

Fortran's convention: every argument by pointer, matrices column-major, ``info`` = 0 on success.
"""

from __future__ import annotations

import math

import llvmlite.binding
import numba
import numpy as np
from numba import types
from numba.extending import get_cython_function_address

__all__ = ["checked_fortran_copy", "gelsd", "gesv"]

_I4P = types.CPointer(types.intc)
_F8P = types.CPointer(types.float64)


def _external(routine: str, *arguments: types.Type) -> types.ExternalFunction:
    """``routine`` of ``scipy.linalg.cython_lapack`` as a function a kernel can call (module docstring)."""
    name = f"regrasp_lapack_{routine}"
    llvmlite.binding.add_symbol(name, get_cython_function_address("scipy.linalg.cython_lapack", routine))
    return types.ExternalFunction(name, types.void(*arguments))


#: dgesv(n, nrhs, a, lda, ipiv, b, ldb, info)
_DGESV = _external("dgesv", _I4P, _I4P, _F8P, _I4P, _I4P, _F8P, _I4P, _I4P)
#: dgelsd(m, n, nrhs, a, lda, b, ldb, s, rcond, rank, work, lwork, iwork, info)
_DGELSD = _external("dgelsd", _I4P, _I4P, _I4P, _F8P, _I4P, _F8P, _I4P, _F8P, _F8P, _I4P, _F8P, _I4P, _I4P,
                    _I4P)


@numba.njit(cache=True)
def checked_fortran_copy(a: np.ndarray, b: np.ndarray, fortran: np.ndarray, rhs: np.ndarray) -> None:
    """a (rows, cols) into ``fortran`` (cols, rows: a column-major) and b (rows,) into the head of ``rhs``, raising
    numpy's ``LinAlgError`` for a non-finite entry as ``np.linalg.solve`` and ``lstsq`` do."""
    rows, cols = a.shape
    for i in range(rows):
        if not math.isfinite(b[i]):
            raise np.linalg.LinAlgError("Array must not contain infs or NaNs.")
        rhs[i] = b[i]
        for j in range(cols):
            if not math.isfinite(a[i, j]):
                raise np.linalg.LinAlgError("Array must not contain infs or NaNs.")
            fortran[j, i] = a[i, j]


@numba.njit(cache=True)
def gesv(fortran: np.ndarray, x: np.ndarray) -> int:
    """Solve a x = b in place: ``fortran`` (n, n) holds aᵀ in C order (a column-major; destroyed), ``x`` (n,) holds
    b and receives x. Returns LAPACK's ``info`` (> 0: a is singular)."""
    n = x.size
    ints = np.empty(5, dtype=np.intc)  # n, nrhs, lda, ldb, info
    ints[0], ints[1], ints[2], ints[3], ints[4] = n, 1, n, n, 0
    pivots = np.empty(max(n, 1), dtype=np.intc)
    _DGESV(ints[0:].ctypes, ints[1:].ctypes, fortran.ctypes, ints[2:].ctypes, pivots.ctypes, x.ctypes,
           ints[3:].ctypes, ints[4:].ctypes)
    return int(ints[4])


@numba.njit(cache=True)
def gelsd(fortran: np.ndarray, rows: int, cols: int, rhs: np.ndarray, singular: np.ndarray) -> tuple[int, int]:
    """The minimum-norm least-squares solution of a x = b, singular values below machine precision dropped
    (rcond = -1): ``fortran`` (cols, rows) holds aᵀ in C order (destroyed), ``rhs`` (max(rows, cols),) holds b and
    receives x in its first ``cols``, ``singular`` (min(rows, cols),) the singular values. The workspace is
    LAPACK's optimal one (queried first, as numba's ``np.linalg.lstsq`` does). Returns (info, rank)."""
    ints = np.empty(8, dtype=np.intc)  # m, n, nrhs, lda, ldb, rank, lwork, info
    ints[0], ints[1], ints[2], ints[3], ints[4] = rows, cols, 1, rows, max(rows, cols)
    ints[5], ints[6], ints[7] = 0, -1, 0
    rcond = np.full(1, -1.0)
    query = np.empty(1)
    iquery = np.empty(1, dtype=np.intc)
    _DGELSD(ints[0:].ctypes, ints[1:].ctypes, ints[2:].ctypes, fortran.ctypes, ints[3:].ctypes, rhs.ctypes,
            ints[4:].ctypes, singular.ctypes, rcond.ctypes, ints[5:].ctypes, query.ctypes, ints[6:].ctypes,
            iquery.ctypes, ints[7:].ctypes)
    if ints[7] != 0:
        return int(ints[7]), 0
    work = np.empty(max(int(query[0]), 1))
    iwork = np.empty(max(int(iquery[0]), 1), dtype=np.intc)
    ints[6] = work.size
    _DGELSD(ints[0:].ctypes, ints[1:].ctypes, ints[2:].ctypes, fortran.ctypes, ints[3:].ctypes, rhs.ctypes,
            ints[4:].ctypes, singular.ctypes, rcond.ctypes, ints[5:].ctypes, work.ctypes, ints[6:].ctypes,
            iwork.ctypes, ints[7:].ctypes)
    return int(ints[7]), int(ints[5])

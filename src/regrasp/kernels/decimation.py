"""Which steps a recording logs at a decimation: written once, for the recorder, the compiled stretches and their
kernel (:func:`logged` compiles into :func:`~regrasp.kernels.stretch.stretch_into` and is called from Python too).

Steps are counted as the plant counts them: step 0 is the state before the first plant step, step k the state after
the k-th (a rollout's record of its k-th plant step, index k - 1, is step k). At decimation ``every`` a recording
logs the steps that are multiples of ``every``; ``every`` = 0 logs none.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["logged", "logged_steps"]


@njit(cache=True)
def logged(step: int, every: int) -> bool:
    """Whether step ``step`` is logged at decimation ``every`` (0: none)."""
    return every > 0 and step % every == 0


def logged_steps(first: int, stop: int, every: int) -> np.ndarray:
    """The steps in [``first``, ``stop``) that are logged at decimation ``every`` (0: none), in order."""
    if every <= 0 or stop <= first:
        return np.zeros(0, dtype=np.int64)
    return np.arange(-(-first // every) * every, stop, every, dtype=np.int64)

"""Jobs on a pool of processes: the processes' twin of :func:`~regrasp.study.ray_cluster.ray_runs` (a study's runs,
a suite's variants).

The pool's processes are spawned, not forked: the parent has run OpenMP code (planning), and forking such a process
aborts the child ("fork() called from a process already using GNU OpenMP"). Each worker gets the jobs' shared inputs
once, ignores Ctrl-C (the terminal sends it to the whole process group: the parent decides) and loads the kernels a
rollout calls before its first job, so that no job's wall time pays for them.
"""

from __future__ import annotations

import multiprocessing
import signal
from collections.abc import Callable, Iterator, Sequence

__all__ = ["process_runs"]

_JOB: dict = {}


def _init_worker(threads: int | None, function: Callable, *shared: object) -> None:
    """A pool worker's numba threads, job function and shared inputs, handed over once per worker, not once per
    job."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _JOB["function"], _JOB["shared"] = function, shared
    if threads is not None:
        import numba

        numba.set_num_threads(max(1, min(threads, numba.config.NUMBA_NUM_THREADS)))
    from ..kernels import ROLLOUT, warm_up

    warm_up(groups=ROLLOUT)  # (every kernel loaded before the first job: no job's wall time pays for it)


def _pool_run(item: object) -> object:
    first, *rest = _JOB["shared"]
    return _JOB["function"](first, item, *rest)


def process_runs(workers: int, function: Callable, shared: tuple, items: Sequence, *,
                 threads: int | None = None) -> Iterator:
    """``function(shared[0], item, *shared[1:])`` for each item, on a pool of ``workers`` spawned processes, as they
    finish (in no particular order). ``function`` must be importable by name (a module's top-level function) and the
    shared inputs and items picklable. ``threads``: the numba threads of each worker (None: numba's default, one per
    core; jobs whose kernels are parallel, as the schedule's lattice, want the cores shared out, else the workers'
    threads oversubscribe them). Closing the generator early terminates the workers."""
    with multiprocessing.get_context("spawn").Pool(workers, initializer=_init_worker,
                                                   initargs=(threads, function, *shared)) as pool:
        yield from pool.imap_unordered(_pool_run, items)  # (the pool's exit terminates the workers)

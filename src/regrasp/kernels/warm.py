"""Loading the kernels before the work, and compiling them on a machine's first run.

:func:`warm_up` loads kernel groups (:data:`GROUPS`) in this process, each with the argument types the library
passes, on a one-finger dummy: from numba's disk cache in about a second for all, else compiling them (numba
compiles a kernel on its first call in a process and caches it, ``cache=True``). A cold compile of a rollout's groups
takes about 35 s of CPU, most of it numba's own typing and lowering (Python, one core). So on a cold cache
:func:`compile_in_background` compiles the groups in worker processes, two at a time (:data:`STAGES`: the callees
first, the stretch kernel that calls them last), which fill the disk cache while this process goes on (a command
plans meanwhile); :func:`warm_up` then waits for them and loads what they wrote.

Only what a run calls is compiled: :data:`ROLLOUT` is what a rollout on the project plant calls; ``footprint`` (the
``urdf`` envelope's free-tip test and the links' signed distances) only the paths that check a tip or a link, which
compile it at their first call.
"""

from __future__ import annotations

import os
import subprocess
import sys
import threading
from collections.abc import Callable, Iterable
from functools import cache
from pathlib import Path

import numpy as np

from .control import control_layout, control_step_into, sliding_step_into
from .envelope import ENVELOPE_PARAMETERS, envelope_sample_into, feasible_capacity, tip_is_free, workspace_size
from .finger import FINGER_PARAMETERS, FINGER_TERMS, finger_terms
from .footprint import FOOTPRINT, footprint_distances
from .force import internal_force_into
from .monitor import envelope_arguments
from .plant import PLANT_CONTACT, PLANT_PARAMETERS, SEPARATED, output_size, plant_evaluate, plant_step_into
from .reduced import CONTACT_EDGE, FINGER_IK, reduced_terms
from .stretch import stretch_into
from .stretch_layout import (
    SLIDER,
    STRETCH_SETTINGS,
    STRETCH_STATE,
    StretchDisturbance,
    StretchExecutor,
    StretchLaw,
    StretchMonitor,
    StretchPlant,
    StretchRows,
    StretchSchedule,
    stretch_log,
)

__all__ = ["ALL", "GROUPS", "ROLLOUT", "STAGES", "STEP", "STRETCH_WAIT_STEPS", "BackgroundCompile",
           "compile_in_background", "compiling", "is_cached", "set_wait_progress", "warm_up"]


@cache
def _dummy() -> tuple:
    """A one-finger hand's kernel inputs: (fingers, plant, iks, edges, rows)."""
    fingers = np.zeros(1, dtype=FINGER_PARAMETERS)
    for name in ("m1", "m2", "i1", "i2", "d2x", "tx"):
        fingers[name] = 1.0
    fingers["effort1"] = fingers["effort2"] = np.inf
    plant = np.zeros((), dtype=PLANT_PARAMETERS)
    plant["mass"], plant["inertia"], plant["dt"] = 1.0, 1.0, 1e-3
    plant = plant[()]  # (a record, as the plant passes it)
    iks = np.zeros(1, dtype=FINGER_IK)
    iks["l1"], iks["l2"], iks["outer"], iks["sigma"] = 1.0, 1.0, 2.0, 1.0
    edges = np.zeros(1, dtype=CONTACT_EDGE)
    edges["tx"], edges["ny"] = 1.0, 1.0
    rows = np.zeros((1, 2))
    rows[0, 0] = 1.0
    return fingers, plant, iks, edges, rows


def _finger() -> None:
    zeros = np.zeros(2)
    finger_terms(_dummy()[0], zeros, zeros, zeros, True)


def _plant() -> None:
    fingers, plant, *_ = _dummy()
    contacts = np.zeros(1, dtype=PLANT_CONTACT)
    contacts["mode"] = SEPARATED
    zeros = np.zeros(2)
    plant_evaluate(fingers, plant, contacts, np.zeros(13), zeros)
    plant_step_into(fingers, plant, contacts, np.zeros(13), zeros, np.full((1, 9), np.nan), np.zeros((1, 2)),
                    np.empty(output_size(1)), np.empty(1, dtype=FINGER_TERMS), np.empty(1, np.bool_), np.empty((1, 7)))


def _reduced() -> None:
    fingers, _, iks, edges, _ = _dummy()
    reduced_terms(fingers, iks, edges, np.zeros(2), True, np.zeros(1), np.full(1, -1, dtype=np.int64),
                  np.array([1.0, 0.0, 0.0]), np.zeros(3))


def _force() -> None:
    """The internal force on a one-contact problem with a one-dimensional null space (a 2 x 1 A)."""
    zeros, rows = np.zeros(2), _dummy()[4]
    internal_force_into(np.array([[1.0], [0.0]]), zeros, np.array([[1.0, 0.0, 0.0, 1.0]]), rows, np.zeros(1), 1,
                        np.zeros(1, np.bool_), 0.0, np.zeros(1), 1.0, 0.0, np.zeros((1, 4)), zeros, np.full(2, np.inf),
                        np.empty(2), np.empty(2))


def _control() -> None:
    """A control step with the argument types a controller passes (its answer here: take the reference path)."""
    fingers, _, iks, edges, rows = _dummy()
    s = np.zeros((5, 3))
    s[0, 1] = 1.0
    control_step_into(fingers, iks, edges, np.zeros(2), True, np.zeros(1), np.full(1, -1, dtype=np.int64), s[0], s[1],
                      s[2], s[3], s[4], np.ones(3), np.ones(3), np.ones(3), 1.0, np.zeros(0), 1e8, np.ones(1), True,
                      rows, np.zeros(1), 1, np.zeros(1, np.bool_), 0.0, np.zeros(1), 1.0, 0.0,
                      np.empty(control_layout(1, 3)["f_hat"].stop))


def _sliding() -> None:
    fingers, _, iks, edges, rows = _dummy()
    s = np.zeros((5, 3))
    s[0, 1] = 1.0
    sliding_step_into(fingers, iks, edges, np.zeros(2), True, np.zeros(1), np.full(1, -1, dtype=np.int64), s[0], s[1],
                      s[2], s[3], s[4], np.ones(3), np.ones(3), np.ones(3), 1.0, np.zeros(0, np.int64), np.zeros(0),
                      np.zeros(0), True, 1e-3, 1e8, np.ones(1), True, rows, np.zeros(1), 1, np.zeros(1, np.bool_), 0.0,
                      np.zeros(1), 1.0, 0.0, np.empty(control_layout(1, 3)["f_hat"].stop))


def _square() -> tuple:
    """The envelope kernels' inputs on a unit square and a finger below it (read-only footprints, as the
    library's): (params, shapes, vertices, normals)."""
    shapes = np.zeros(1, dtype=FOOTPRINT)
    shapes["ux"], shapes["hu"], shapes["hv"] = 1.0, 0.5, 0.1
    shapes.flags.writeable = False
    params = np.zeros(1, dtype=ENVELOPE_PARAMETERS)
    for name, value in (("o1y", -2.0), ("l1", 1.0), ("l2", 1.0), ("l1sq", 1.0), ("l2sq", 1.0), ("outer_sq", 4.0),
                        ("sign", 1.0), ("n0y", 1.0), ("c0y", -0.5), ("xi_lo", -0.5), ("xi_hi", 0.5), ("grid", 2),
                        ("tol", 0.1), ("half_thickness", 2.0)):
        params[name] = value
    vertices = np.array([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]])
    normals = np.array([[0.0, 1.0], [-1.0, 0.0], [0.0, -1.0], [1.0, 0.0]])
    return params, shapes, vertices, normals


def _envelope() -> None:
    """An envelope sample (the planner's and the supervisor's)."""
    params, shapes, vertices, normals = _square()
    rows = feasible_capacity(2, 4)
    envelope_sample_into(params, shapes, vertices, normals, 0.0, 0.0, 0.0, np.empty(3), np.empty((4, 2)),
                         np.empty((4, 2)), np.empty(4, np.bool_), np.empty(4, np.int64), np.empty(rows),
                         np.empty((rows, 2)), np.empty(workspace_size(2, 4)))


def _footprint() -> None:
    """The ``urdf`` envelope's free-tip test and the links' signed distances."""
    params, shapes, vertices, normals = _square()
    tip_is_free(params, shapes, vertices, normals, 0.0, 0.0, 0.0, 0.0, np.empty(2))
    footprint_distances(shapes, vertices, normals, 2.0, np.zeros(3),
                        np.array([0.0, -2.0, 0.0, 1.0, 0.0, -1.0, 1.0, 0.0]), np.empty(1))


def _stretch() -> None:
    """The stretch kernel with the argument types :class:`regrasp.rollout.stretch.CompiledStretches` passes (no
    step)."""
    fingers, plant, iks, edges, rows = _dummy()
    m = 1
    head = (fingers, iks, edges, np.zeros(2), True, np.zeros(1), np.full(1, -1, dtype=np.int64))
    contacts = np.zeros(m, dtype=PLANT_CONTACT)
    size = 4 * m + 9
    executor = StretchExecutor(np.zeros(m, np.bool_), np.zeros(m), np.zeros(m), np.zeros(3), np.zeros(0, dtype=SLIDER))
    monitor = StretchMonitor(np.zeros((m, 1, 2)), np.zeros(m, np.int64), np.zeros((m, 2)), np.zeros((m, 2)),
                             np.zeros(m), *envelope_arguments(None, m), np.zeros((m, 3), np.int64))
    law = StretchLaw(head, np.ones(3), np.ones(3), np.ones(3), 1.0, np.zeros(0), np.zeros(0), False, 0.0, 1e8,
                     np.ones(m), True, rows, np.zeros(1), 1, np.zeros(1, np.bool_), 0.0, np.zeros(1), 1.0, 0.0,
                     np.empty(control_layout(m, 3)["f_hat"].stop))
    plant_arguments = StretchPlant(fingers, plant, contacts, np.zeros(size), np.zeros(output_size(m)),
                                   np.full((m, 9), np.nan), np.zeros((m, 2)), np.empty(output_size(m)),
                                   np.empty(m, dtype=FINGER_TERMS), np.empty(m, np.bool_), np.empty((m, 7)))
    rows_out = StretchRows(np.empty((0, m)), np.empty((0, m, 2)), np.empty((0, m)), np.empty((0, 3)),
                           np.empty((0, 3)), np.empty((0, 2 * m)), np.empty((0, m, 2)), np.empty((0, m)),
                           np.empty((0, m)), np.ones(m))
    stretch_into(np.zeros((), dtype=STRETCH_SETTINGS)[()], np.zeros(1, dtype=STRETCH_STATE), np.zeros(0),
                 np.zeros((0, 9)), executor, monitor, StretchSchedule(np.zeros(1), np.zeros((1, m))), law,
                 plant_arguments, rows_out, stretch_log(0, m, 1), 0, 0,
                 StretchDisturbance(np.zeros((0, 0)), np.zeros((1, m), np.bool_), np.zeros((1, 2 * m))), False)


#: The kernel groups, each loaded (compiled on a cold cache) by one call, and the kernel whose disk cache says whether
#: the group is cached (the group's last compiled).
GROUPS: dict[str, tuple[Callable[[], None], Callable]] = {
    "finger": (_finger, finger_terms), "plant": (_plant, plant_step_into), "reduced": (_reduced, reduced_terms),
    "force": (_force, internal_force_into), "control": (_control, control_step_into),
    "sliding": (_sliding, sliding_step_into), "envelope": (_envelope, envelope_sample_into),
    "footprint": (_footprint, footprint_distances), "stretch": (_stretch, stretch_into)}

#: Every group, in the order :func:`warm_up` loads them.
ALL = tuple(GROUPS)

#: What a rollout on the project plant calls (a plan, the laws, the plant, the stretches).
ROLLOUT = tuple(g for g in ALL if g != "footprint")

#: What a rollout calls without its compiled stretches (every step on the reference path).
STEP = tuple(g for g in ROLLOUT if g != "stretch")

#: A run shorter than this many steps does not wait for the stretch kernel while a worker still compiles it
#: (:func:`compile_in_background`): it takes its steps on the reference path, the same steps (``tests/rollout/
#: test_stretch.py``), about 0.1 ms a step slower, while the stretch kernel takes about 10 s of compiling.
STRETCH_WAIT_STEPS = 100_000

#: How :func:`compile_in_background` compiles the groups on a cold cache: stages one after the other, each of worker
#: processes side by side, each compiling its groups in order. A kernel compiles its callees (the control step the
#: QP's, the stretch kernel almost all), from the disk cache when a worker wrote them already: so the callees in the
#: first stage (about 14 and 5 s of CPU), the stretch kernel (about 10 s) in the second. The envelope sample is not
#: there: a command's planning calls it first, in its own process, which caches it for the stretch kernel.
STAGES = ((("force", "control", "sliding"), ("finger", "reduced", "plant")), (("footprint", "stretch"),))

_LOADED: set[str] = set()


def is_cached(group: str) -> bool:
    """Whether numba's disk cache has an index for the group's kernel (True when it cannot tell, so nothing is
    compiled twice). An index of an edited kernel source is dropped at import (:mod:`regrasp.kernels`)."""
    from numba.core.caching import FunctionCache

    function = GROUPS[group][1].py_func
    try:
        path = Path(FunctionCache(function).cache_path)
        name = f"{function.__module__.rsplit('.', 1)[-1]}.{function.__qualname__}-*.nbi"
        return any(path.glob(name))
    except Exception:  # (numba's cache layout is not an API: when it changes, compile in this process)
        return True


class BackgroundCompile:
    """Worker processes compiling kernel groups into the disk cache, stage after stage (:data:`STAGES`), driven by a
    thread of this process; :attr:`finished` holds the groups they compiled. The workers run in a session of their
    own and are not ended when this process exits: a group still compiling then (the stretch kernel, when a short
    run did not wait for it) is cached for the next run."""

    def __init__(self, stages: list[list[list[str]]]):
        self.groups = [g for stage in stages for worker in stage for g in worker]
        self.finished: set[str] = set()
        self._changed = threading.Condition()
        self._ended = False
        self._thread = threading.Thread(target=self._run, args=(stages,), daemon=True, name="regrasp-compile")
        self._thread.start()

    def _run(self, stages: list[list[list[str]]]) -> None:
        src = str(Path(__file__).resolve().parents[2])  # (the workers import this regrasp)
        env = {**os.environ, "PYTHONPATH": os.pathsep.join([src, *filter(None, [os.environ.get("PYTHONPATH")])])}
        try:
            for stage in stages:
                readers = []
                for worker in stage:
                    proc = subprocess.Popen(
                        [sys.executable, "-c", f"from regrasp.kernels.warm import _worker; _worker({worker!r})"],
                        stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, env=env,
                        text=True, start_new_session=True)
                    reader = threading.Thread(target=self._read, args=(proc,), daemon=True)
                    reader.start()
                    readers.append(reader)
                for reader in readers:
                    reader.join()
        finally:
            with self._changed:
                self._ended = True
                self._changed.notify_all()

    def _read(self, proc: subprocess.Popen) -> None:
        for line in proc.stdout:  # (a line per group compiled)
            with self._changed:
                self.finished.add(line.strip())
                self._changed.notify_all()
        proc.wait()

    def pending(self, group: str) -> bool:
        """Whether the workers are still to compile ``group``."""
        with self._changed:
            return group in self.groups and group not in self.finished and not self._ended

    def wait(self, groups: Iterable[str], progress: Callable[[int, int], None] | None = None) -> None:
        """Until the workers have compiled ``groups`` (or ended), calling ``progress(done, total)`` of those as they
        finish."""
        wanted = set(groups) & set(self.groups)
        with self._changed:
            while True:
                if progress is not None:
                    progress(len(wanted & self.finished), len(wanted))
                if wanted <= self.finished or self._ended:
                    return
                self._changed.wait(1.0)


_BACKGROUND: list[BackgroundCompile] = []
_WAIT_PROGRESS: list[Callable[[int, int], None] | None] = [None]


def _worker(groups: list[str]) -> None:
    """A worker process: compile ``groups`` in order, a line on stdout after each (read while this process lives)."""
    for group in groups:
        GROUPS[group][0]()
        try:
            print(group, flush=True)
        except OSError:  # (the command has exited: the cache is what counts)
            pass


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # (not on every platform)
        return os.cpu_count() or 1


def compile_in_background(groups: Iterable[str] = ROLLOUT) -> list[str]:
    """Start compiling those of ``groups`` that numba's disk cache lacks in worker processes (:data:`STAGES`), on a
    machine of at least two cores; :func:`warm_up` waits for them. The groups they compile (none: all cached, or a
    single core, where :func:`warm_up` compiles them in this process)."""
    wanted = set(groups) - _LOADED
    if _BACKGROUND or not wanted or _cores() < 2:
        return []
    cold = {g for g in wanted if not is_cached(g)}
    stages = [[[g for g in worker if g in cold] for worker in stage] for stage in STAGES]
    stages = [[w for w in stage if w] for stage in stages]
    stages = [stage for stage in stages if stage]
    if not stages:
        return []
    job = BackgroundCompile(stages)
    _BACKGROUND.append(job)
    return job.groups


def compiling(group: str | None = None) -> bool:
    """Whether worker processes (:func:`compile_in_background`) are still compiling ``group`` (None: any group)."""
    if not _BACKGROUND:
        return False
    job = _BACKGROUND[0]
    return any(job.pending(g) for g in (job.groups if group is None else [group]))


def set_wait_progress(progress: Callable[[int, int], None] | None) -> None:
    """The ``progress`` a :func:`warm_up` called without one reports its wait for the workers to (a command's
    progress line, while a library call such as a plant's constructor waits)."""
    _WAIT_PROGRESS[0] = progress


def warm_up(progress: Callable[[int, int], None] | None = None, groups: Iterable[str] = ALL) -> None:
    """Load the kernel ``groups`` (default all) once in this process, on a one-finger dummy with the argument types
    the library passes (later calls return at once). Where the disk cache has none (a machine's first run) numba
    compiles them: in the workers of :func:`compile_in_background` when it started them (this waits for those),
    else here. ``progress(done, total)`` is called as groups finish."""
    wanted = set(groups)
    todo = [g for g in ALL if g in wanted and g not in _LOADED]
    if not todo:
        return
    progress = progress if progress is not None else _WAIT_PROGRESS[0]
    total = len(todo)
    compiled: set[str] = set()
    if _BACKGROUND:
        job = _BACKGROUND[0]
        compiled = set(todo) & set(job.groups)
        job.wait(compiled, None if progress is None else lambda k, _: progress(k, total))
    done = len(compiled)
    for group in todo:
        GROUPS[group][0]()
        _LOADED.add(group)
        if group not in compiled:
            done += 1
            if progress is not None:
                progress(done, total)
    if compiled and progress is not None:
        progress(total, total)

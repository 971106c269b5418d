r"""Compiled kernels (numba): the fast paths, each generated from and checked against its reference.

Pinocchio stays the source of every model: a kernel's constants are read from the Pinocchio models when a
hand is built, and the hand checks the kernels against Pinocchio there (M, N, J, J̇q̇ and the tip at random
states, to 1e-12 relative to max(1, |value|)); where they disagree it warns and keeps the Pinocchio path.

==========================  =========================================================  =================================
kernel                      reference path                                             equality test
==========================  =========================================================  =================================
:mod:`.finger`: M, N, J,    Pinocchio (``crba``, ``nonLinearEffects``,                 ``tests/kernels/
J̇q̇, tip                     frame Jacobian, classical acceleration)                    test_finger_and_plant.py``
:mod:`.plant`: a plant      :class:`~regrasp.plants.project.plant.Plant` with          ``tests/kernels/
step (RK4, fixed and        ``compiled=False``                                         test_finger_and_plant.py``
sliding contacts,
Baumgarte, works, event
inputs)
:mod:`.reduced`: the        :class:`~regrasp.dynamics.reduced.ReducedModel` with       ``tests/kernels/
reduced model's terms (IK,  ``compiled=False``                                         test_finger_and_plant.py``
J, H, Ḣ Ṡ, M, N)
:mod:`.force`, :mod:`.qp`:  ``InternalForceSolver(compiled=False)``                    ``tests/kernels/test_qp.py``
the internal-force QP       (:mod:`regrasp.dynamics.internal_force.solver`, OSQP)
(null basis, rows, an
exact dense QP, the check)
:mod:`.control`: a          the controller with ``compiled=False``                     ``tests/kernels/test_control.py``
computed-torque control
step (fixed law, Prop. 1,
Prop. 3 with m > 2)
:mod:`.footprint`: link     coal (``UrdfCollisionChecker.                              ``tests/test_kernels_
shape–prism signed          signed_distances``)                                        footprint.py``
distances in closed form
:mod:`.envelope`: a         :class:`~regrasp.envelope.finger_envelope.FingerEnvelope`  ``tests/test_kernels_
``urdf`` envelope sample    with ``compiled=False``                                    footprint.py``
(grid, bisection)
:mod:`.stretch`: a          the simulation loop with the supervisor                    ``tests/rollout/test_stretch.py``
rollout's steps between     (``Rollout.run(compiled_stretches=False)``)
discrete decisions (the
above, and the
supervisor's continuous
work)
:mod:`.monitor`,            :class:`~regrasp.supervisor.monitor.EnvelopeMonitor`,      ``tests/rollout/test_stretch.py``
:mod:`.disturbance`: a      :class:`~regrasp.plants.disturbance.Disturbance`
reading's margins, the
noise, the slip sensor
and the actuation delay
==========================  =========================================================  =================================

:func:`warm_up` loads every kernel (compiling it where the cache has none): a compiled
:class:`~regrasp.plants.project.plant.Plant` and a study's worker call it when built, so a rollout's timed loop never
pays for it.

Every kernel reads named fields (numpy record dtypes: :data:`FINGER_PARAMETERS`, :data:`FINGER_TERMS`,
:data:`PLANT_CONTACT`, :data:`PLANT_PARAMETERS`, :data:`ENVELOPE_PARAMETERS`, :data:`FOOTPRINT`),
never positional tuples. Compiled code is cached on disk
(``cache=True``), so only the first run on a machine pays for the compile.
"""

import hashlib
from collections.abc import Callable
from pathlib import Path

import numpy as np

from .control import control_layout, control_step_into, sliding_step_into
from .envelope import ENVELOPE_PARAMETERS, envelope_sample_into, feasible_capacity, tip_is_free, workspace_size
from .finger import FINGER_PARAMETERS, FINGER_TERMS, finger_parameters, finger_terms, finger_terms_at
from .footprint import FOOTPRINT, footprint_distances
from .force import internal_force_into
from .monitor import envelope_arguments
from .plant import (
    FIXED,
    PLANT_CONTACT,
    PLANT_PARAMETERS,
    SEPARATED,
    SLIDING,
    output_size,
    plant_evaluate,
    plant_step_into,
)
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

__all__ = ["CONTACT_EDGE", "ENVELOPE_PARAMETERS", "FINGER_IK", "FINGER_PARAMETERS", "FINGER_TERMS", "FIXED",
           "FOOTPRINT", "PLANT_CONTACT", "PLANT_PARAMETERS", "SEPARATED", "SLIDER", "SLIDING", "STRETCH_SETTINGS",
           "STRETCH_STATE", "WARM_UP_STEPS", "control_layout",
           "control_step_into", "envelope_sample_into", "feasible_capacity", "finger_parameters", "finger_terms",
           "finger_terms_at", "footprint_distances", "internal_force_into", "output_size", "plant_evaluate",
           "plant_step_into", "reduced_terms", "sliding_step_into", "stretch_into", "tip_is_free", "warm_up",
           "workspace_size"]


def _drop_stale_caches() -> None:
    """numba keys a kernel's disk cache on its own file's time stamp only: a kernel that calls one in another
    file (the control step calls the reduced terms, the QP) would keep a stale compiled copy after that file
    changes (an editable install being edited). So the caches here are dropped whenever any kernel source
    changes (a hash of them all, kept next to the caches; well under a millisecond at import)."""
    here = Path(__file__).parent
    digest = hashlib.sha256(b"".join(p.read_bytes() for p in sorted(here.glob("*.py")))).hexdigest()
    cache = here / "__pycache__"
    stamp = cache / "kernels.sources.sha256"
    try:
        if stamp.is_file() and stamp.read_text() == digest:
            return
        for stale in [*cache.glob("*.nbi"), *cache.glob("*.nbc")]:
            stale.unlink(missing_ok=True)
        cache.mkdir(exist_ok=True)
        stamp.write_text(digest)
    except OSError:  # (a read-only install: its files never change in place)
        pass


_drop_stale_caches()  # (before any kernel runs: numba reads a cache at a kernel's first call)

_WARM = []


#: The kernel groups :func:`warm_up` loads, in order (what its ``progress`` counts).
WARM_UP_STEPS = 8


def warm_up(progress: Callable[[int, int], None] | None = None) -> None:
    """Load every kernel once in this process, on a one-finger dummy with the argument types the library
    passes (later calls return at once). On a machine's first run (no disk cache yet) this is where numba
    compiles them: ``progress(done, WARM_UP_STEPS)`` is called after each group."""
    if _WARM:
        return
    step = iter(range(1, WARM_UP_STEPS + 1))

    def done() -> None:
        if progress is not None:
            progress(next(step), WARM_UP_STEPS)
    fingers = np.zeros(1, dtype=FINGER_PARAMETERS)
    for name in ("m1", "m2", "i1", "i2", "d2x", "tx"):
        fingers[name] = 1.0
    fingers["effort1"] = fingers["effort2"] = np.inf
    plant = np.zeros((), dtype=PLANT_PARAMETERS)
    plant["mass"], plant["inertia"], plant["dt"] = 1.0, 1.0, 1e-3
    contacts = np.zeros(1, dtype=PLANT_CONTACT)
    contacts["mode"] = SEPARATED
    zeros = np.zeros(2)
    finger_terms(fingers, zeros, zeros, zeros, True)
    done()
    plant_evaluate(fingers, plant, contacts, np.zeros(13), zeros)
    plant_step_into(fingers, plant, contacts, np.zeros(13), zeros, np.full((1, 9), np.nan), np.zeros((1, 2)),
                    np.empty(output_size(1)), np.empty(1, dtype=FINGER_TERMS), np.empty(1, np.bool_), np.empty((1, 7)))
    done()
    iks = np.zeros(1, dtype=FINGER_IK)
    iks["l1"], iks["l2"], iks["outer"], iks["sigma"] = 1.0, 1.0, 2.0, 1.0
    edges = np.zeros(1, dtype=CONTACT_EDGE)
    edges["tx"], edges["ny"] = 1.0, 1.0
    reduced_terms(fingers, iks, edges, zeros, True, np.zeros(1), np.full(1, -1, dtype=np.int64),
                  np.array([1.0, 0.0, 0.0]), np.zeros(3))
    done()
    # the internal force on a one-contact problem with a one-dimensional null space (a 2 x 1 A)
    rows = np.zeros((1, 2))
    rows[0, 0] = 1.0
    internal_force_into(np.array([[1.0], [0.0]]), zeros, np.array([[1.0, 0.0, 0.0, 1.0]]), rows, np.zeros(1), 1,
                        np.zeros(1, np.bool_), 0.0, np.zeros(1), 1.0, 0.0, np.zeros((1, 4)), zeros, np.full(2, np.inf),
                        np.empty(2), np.empty(2))
    done()
    # a control step with the argument types a controller passes (its answer here: take the reference path)
    s = np.zeros((5, 3))
    s[0, 1] = 1.0
    control_step_into(fingers, iks, edges, zeros, True, np.zeros(1), np.full(1, -1, dtype=np.int64), s[0], s[1], s[2],
                      s[3], s[4], np.ones(3), np.ones(3), np.ones(3), 1.0, np.zeros(0), 1e8, np.ones(1), True,
                      rows, np.zeros(1), 1, np.zeros(1, np.bool_), 0.0, np.zeros(1), 1.0, 0.0,
                      np.empty(control_layout(1, 3)["f_hat"].stop))
    done()
    sliding_step_into(fingers, iks, edges, zeros, True, np.zeros(1), np.full(1, -1, dtype=np.int64), s[0], s[1], s[2],
                      s[3], s[4], np.ones(3), np.ones(3), np.ones(3), 1.0, np.zeros(0, np.int64), np.zeros(0),
                      np.zeros(0), True, 1e-3, 1e8, np.ones(1), True, rows, np.zeros(1), 1, np.zeros(1, np.bool_), 0.0,
                      np.zeros(1), 1.0, 0.0, np.empty(control_layout(1, 3)["f_hat"].stop))
    done()
    _warm_envelope()
    done()
    _warm_stretch(fingers, plant, iks, edges, rows)
    done()
    _WARM.append(True)


def _warm_stretch(fingers, plant, iks, edges, rows) -> None:
    """The stretch kernel with the argument types :class:`regrasp.rollout.stretch.CompiledStretches` passes
    (no step)."""
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


def _warm_envelope() -> None:
    """The envelope kernels on a unit square and a finger below it (read-only footprints, as the library's)."""
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
    rows = feasible_capacity(2, 4)
    envelope_sample_into(params, shapes, vertices, normals, 0.0, 0.0, 0.0, np.empty(3), np.empty((4, 2)),
                         np.empty((4, 2)), np.empty(4, np.bool_), np.empty(4, np.int64), np.empty(rows),
                         np.empty((rows, 2)), np.empty(workspace_size(2, 4)))
    tip_is_free(params, shapes, vertices, normals, 0.0, 0.0, 0.0, 0.0, np.empty(2))
    footprint_distances(shapes, vertices, normals, 2.0, np.zeros(3),
                        np.array([0.0, -2.0, 0.0, 1.0, 0.0, -1.0, 1.0, 0.0]), np.empty(1))

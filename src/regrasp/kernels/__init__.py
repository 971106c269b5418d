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

:func:`warm_up` (:mod:`.warm`) loads kernel groups (compiling them where the cache has none): a compiled
:class:`~regrasp.plants.project.plant.Plant` and a study's worker call it when built, so a rollout's timed loop never
pays for it; on a machine's first run :func:`compile_in_background` compiles them in worker processes, side by side,
while the command plans.

Every kernel reads named fields (numpy record dtypes: :data:`FINGER_PARAMETERS`, :data:`FINGER_TERMS`,
:data:`PLANT_CONTACT`, :data:`PLANT_PARAMETERS`, :data:`ENVELOPE_PARAMETERS`, :data:`FOOTPRINT`),
never positional tuples. Compiled code is cached on disk
(``cache=True``), so only the first run on a machine pays for the compile.
"""

import hashlib
from pathlib import Path

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
from .stretch_layout import SLIDER, STRETCH_SETTINGS, STRETCH_STATE
from .warm import ALL, ROLLOUT, compile_in_background, warm_up

__all__ = ["CONTACT_EDGE", "ENVELOPE_PARAMETERS", "FINGER_IK", "FINGER_PARAMETERS", "FINGER_TERMS", "FIXED",
           "FOOTPRINT", "PLANT_CONTACT", "PLANT_PARAMETERS", "SEPARATED", "SLIDER", "SLIDING", "STRETCH_SETTINGS",
           "STRETCH_STATE", "WARM_UP_STEPS", "ALL", "ROLLOUT", "compile_in_background", "control_layout",
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

#: The kernel groups :func:`warm_up` loads by default (what its ``progress`` counts).
WARM_UP_STEPS = len(ALL)

r"""Compiled kernels (numba): the fast paths, each generated from and checked against its reference.

Pinocchio stays the source of every model: a kernel's constants are read from the Pinocchio models when a
hand is built, and the hand checks the kernels against Pinocchio there (M, N, J, J̇q̇ and the tip at random
states, to 1e-12 relative to max(1, |value|)); where they disagree it warns and keeps the Pinocchio path.

=====================================  ==========================================  ===========================
kernel                                 reference path                              equality test
=====================================  ==========================================  ===========================
:mod:`.finger`: M, N, J, J̇q̇, tip      Pinocchio (``crba``, ``nonLinearEffects``,   ``tests/test_kernels.py``
                                       frame Jacobian, classical acceleration)
:mod:`.plant`: a plant step (RK4,      :class:`~regrasp.plant.Plant` with           ``tests/test_kernels.py``
fixed and sliding contacts,            ``compiled=False``
Baumgarte, works, event inputs)
=====================================  ==========================================  ===========================

Every kernel reads named fields (numpy record dtypes: :data:`FINGER_PARAMETERS`, :data:`FINGER_TERMS`,
:data:`PLANT_CONTACT`, :data:`PLANT_PARAMETERS`), never positional tuples. Compiled code is cached on disk
(``cache=True``), so only the first run on a machine pays for the compile.
"""

from .finger import FINGER_PARAMETERS, FINGER_TERMS, finger_parameters, finger_terms, finger_terms_at
from .plant import FIXED, PLANT_CONTACT, PLANT_PARAMETERS, SEPARATED, SLIDING, plant_evaluate, plant_step

__all__ = ["FINGER_PARAMETERS", "FINGER_TERMS", "FIXED", "PLANT_CONTACT", "PLANT_PARAMETERS", "SEPARATED", "SLIDING",
           "finger_parameters", "finger_terms", "finger_terms_at", "plant_evaluate", "plant_step"]

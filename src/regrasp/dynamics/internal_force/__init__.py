"""``regrasp.dynamics.internal_force``: The internal (squeezing) force, chosen by a QP (paper §3.3, eq. 3.3.7): its
settings (:mod:`.settings`), the problem (:func:`build_internal_force_qp`, :mod:`.problem`) and its solution
(:func:`solve_internal_force_qp`; :class:`InternalForceSolver`, :mod:`.solver`); its rows and null space
(:mod:`.rows`); the joint torque limits' rows (:mod:`.torque`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ...core.lazy import lazy_exports

if TYPE_CHECKING:
    from .problem import (  # noqa: F401
        InternalForceInfeasibleError,
        InternalForceQP,
        InternalForceResult,
        build_internal_force_qp,
        solve_internal_force_qp,
    )
    from .settings import ConeEdge, InternalForceSettings  # noqa: F401
    from .solver import InternalForceSolver  # noqa: F401
    from .torque import JointTorques, TorqueShortfall  # noqa: F401

__getattr__, __dir__, __all__ = lazy_exports(__name__)

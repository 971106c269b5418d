"""``regrasp.dynamics.internal_force``: The internal (squeezing) force, chosen by a QP (paper §3.3, eq. 3.3.7): its settings, the problem
(:func:`build_internal_force_qp`) and its solution (:func:`solve_internal_force_qp`, :class:`InternalForceSolver`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ...core.lazy import lazy_exports

if TYPE_CHECKING:
    from .solver import (  # noqa: F401
        ConeEdge,
        InternalForceInfeasibleError,
        InternalForceQP,
        InternalForceResult,
        InternalForceSettings,
        InternalForceSolver,
        build_internal_force_qp,
        solve_internal_force_qp,
    )

__getattr__, __dir__, __all__ = lazy_exports(__name__)

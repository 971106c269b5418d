"""``regrasp.dynamics``: Paper §3: the hand-object dynamics and its control. Grasp matrices (:class:`Grasp`), the
reduced model in S = (x_o, β, ξ) (:class:`ReducedModel`), computed torque (:mod:`.control`) and its laws (:mod:`.laws`:
the fixed-contact law, Propositions 1-3), when a slide is possible (:func:`sliding_feasibility`); the internal-force QP
is :mod:`regrasp.dynamics.internal_force`."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..core.lazy import lazy_exports

if TYPE_CHECKING:
    from .control import ComputedTorqueController, ControlOutput, Gains  # noqa: F401
    from .grasp import Grasp  # noqa: F401
    from .laws import (  # noqa: F401
        FixedContactController,
        Proposition1Controller,
        Proposition2Controller,
        Proposition3Controller,
    )
    from .reduced import ReducedModel, ReducedState, ReducedTerms  # noqa: F401
    from .sliding import SlideFeasibility, sliding_feasibility  # noqa: F401

__getattr__, __dir__, __all__ = lazy_exports(__name__)

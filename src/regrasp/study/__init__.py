"""``regrasp.study``: Robustness studies: many seeded rollouts of one scenario under model errors and noise, across
processes or Ray (:func:`run_study`, :func:`sweep_study`), the runs' draws and the figures."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..core.lazy import lazy_exports

if TYPE_CHECKING:
    from .draws import RunDraw, draw_runs  # noqa: F401
    from .study import RunOutcome, StudyResult, build_run, run_study, sweep_study, wilson_interval  # noqa: F401

__getattr__, __dir__, __all__ = lazy_exports(__name__)

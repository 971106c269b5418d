"""``regrasp.suite``: Task suites: variants of a scenario drawn from the ranges of a spec (:func:`load_suite_spec`),
each planned and, with a schedule, run on the plant (:func:`run_suite`); the fraction with a schedule, why the others
have none, success given a schedule, the planning time and memory; across processes or Ray."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..core.lazy import lazy_exports

if TYPE_CHECKING:
    from .plots import plot_suite  # noqa: F401
    from .result import SuiteResult, VariantOutcome  # noqa: F401
    from .run import run_suite, run_variant  # noqa: F401
    from .spec import SuiteSpec, Varied, load_suite_spec  # noqa: F401
    from .variants import Variant, draw_variant, variant_scenario  # noqa: F401

__getattr__, __dir__, __all__ = lazy_exports(__name__)

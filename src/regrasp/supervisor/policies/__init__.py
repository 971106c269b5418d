"""``regrasp.supervisor.policies``: Regrasp policies: who decides which contact slides, where and when
(:class:`Policy`): the schedule-following :class:`ScheduledPolicy`, the paper's danger-zone :class:`PaperPolicy`,
:class:`NoRegraspPolicy` and :class:`OrderedSlidesPolicy`."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ...core.lazy import lazy_exports

if TYPE_CHECKING:
    from .base import NoRegraspPolicy, OrderedSlidesPolicy, Policy  # noqa: F401
    from .paper import PaperPolicy  # noqa: F401
    from .scheduled import ScheduledPolicy  # noqa: F401

__getattr__, __dir__, __all__ = lazy_exports(__name__)

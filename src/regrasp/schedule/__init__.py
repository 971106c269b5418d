"""``regrasp.schedule``: Paper §4, planned: the slides of every contact over the whole trajectory, jointly, with the
physics as constraints (:func:`plan_regrasps`, :class:`RegraspSettings`), the schedule it returns
(:class:`RegraspSchedule`) or why none exists (:class:`NoScheduleError`), and the two-finger slide rule."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..core.lazy import lazy_exports

if TYPE_CHECKING:
    from .planner import plan_regrasps  # noqa: F401
    from .problem import RegraspSettings  # noqa: F401
    from .schedule import NoScheduleError, RegraspSchedule, ScheduleLimit, Slide  # noqa: F401
    from .slide_rule import SlideRange, two_finger_slide_range  # noqa: F401

__getattr__, __dir__, __all__ = lazy_exports(__name__)

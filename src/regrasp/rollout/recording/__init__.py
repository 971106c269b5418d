"""``regrasp.rollout.recording``: Recording rollouts to rerun: an ``.rrd`` file, a live viewer, or both (:class:`RolloutRecorder`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ...core.lazy import lazy_exports

if TYPE_CHECKING:
    from .recorder import RolloutRecorder  # noqa: F401

__getattr__, __dir__, __all__ = lazy_exports(__name__)

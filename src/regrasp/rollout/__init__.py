"""``regrasp.rollout``: A regrasping rollout: a plant driven by the supervisor (:func:`build_rollout`,
:class:`RunSpec`), its result (:class:`RolloutResult`), its compiled stretches, its figures and its rerun recording
(:class:`~regrasp.rollout.recording.RolloutRecorder`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..core.lazy import lazy_exports

if TYPE_CHECKING:
    from .build import POLICIES, Rollout, SupervisorDriver, build_rollout  # noqa: F401
    from .plots import plot_rollout  # noqa: F401
    from .recording.recorder import RolloutRecorder  # noqa: F401
    from .result import RolloutResult  # noqa: F401
    from .spec import RunSpec  # noqa: F401

__getattr__, __dir__, __all__ = lazy_exports(__name__)

"""``regrasp.plants.mujoco``: MuJoCo as a second, independent plant (the ``mujoco`` extra): a scenario as MJCF
(:func:`scenario_to_mjcf`, :class:`MujocoSettings`) stepped by MuJoCo (:class:`MujocoPlant`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ...core.lazy import lazy_exports

if TYPE_CHECKING:
    from .mjcf import MujocoSettings, scenario_to_mjcf  # noqa: F401
    from .plant import MujocoPlant  # noqa: F401

__getattr__, __dir__, __all__ = lazy_exports(__name__)

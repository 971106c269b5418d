"""``regrasp.plants.drake``: Drake as a third, independent plant (the ``drake`` extra): a scenario as a Drake
``MultibodyPlant`` (:class:`DrakeSettings`) stepped by Drake's discrete solver (:class:`DrakePlant`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ...core.lazy import lazy_exports

if TYPE_CHECKING:
    from .model import DrakeSettings  # noqa: F401
    from .plant import DrakePlant  # noqa: F401

__getattr__, __dir__, __all__ = lazy_exports(__name__)

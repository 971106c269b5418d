"""``regrasp.plants.project``: The project's own plant: the hand and the object in full coordinates, with fixed, sliding
and separated contacts and their events (:class:`Plant`), independent of the reduced model the controllers use."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ...core.lazy import lazy_exports

if TYPE_CHECKING:
    from .plant import Plant
    from .state import PlantContact, PlantState, PlantStep

__getattr__, __dir__, __all__ = lazy_exports(__name__)

"""How a finger's links are modelled for collision with the object (:class:`Geometry`): as segments (``ideal``, the
paper's §2 model: :func:`~regrasp.model.collision.segment_hits_polygon`) or as their URDF collision shapes (``urdf``:
:class:`~regrasp.model.collision.UrdfCollisionChecker`). Every setting that chooses one holds a :class:`Geometry`."""

from __future__ import annotations

from enum import Enum

from ..core.exceptions import InvalidParameterError

__all__ = ["Geometry", "as_geometry"]


class Geometry(str, Enum):
    """How links are modelled for collision: segments (``ideal``) or URDF shapes (``urdf``)."""

    IDEAL = "ideal"
    URDF = "urdf"


def as_geometry(name: str, value: object, expected: str = "'ideal' or 'urdf'") -> Geometry:
    """``value`` as a :class:`Geometry` (a member or its string), else an error naming ``name``."""
    try:
        return Geometry(value)
    except (ValueError, TypeError):
        raise InvalidParameterError(name, value, expected) from None

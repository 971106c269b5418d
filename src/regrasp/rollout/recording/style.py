"""The recording's units and colours: the scene's millimetres with y flipped, the fingers' palette, the contact
modes' and the markers' colours, packed as rerun reads them."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ...core.contact import ContactMode

__all__ = ["BAND", "BAND_EDGE", "DANGER", "DANGER_FILL", "FINGER_COLOURS", "FORCE", "GHOST", "MM", "MODE_RGBA",
           "OBJECT", "PREDICTED", "Colour", "colours", "darker", "rgba"]

#: An (r, g, b) or (r, g, b, a) colour, each entry in 0..255.
Colour = tuple[int, ...]

#: Metres (hand frame, y up) -> scene millimetres (y down: rerun's 2-D views draw y downwards).
MM = np.array([1000.0, -1000.0])
#: The fingers' colours, in finger order (repeated past the seventh finger).
FINGER_COLOURS: list[Colour] = [(31, 119, 180), (148, 103, 189), (23, 190, 207), (140, 86, 75), (227, 119, 194),
                                (188, 189, 34), (127, 127, 127)]
MODE_COLOURS: dict[ContactMode, Colour] = {ContactMode.FIXED: (44, 160, 44), ContactMode.SLIDING: (255, 127, 14),
                                           ContactMode.SEPARATED: (160, 160, 160)}
DANGER: Colour = (214, 39, 40)  #: danger zones and failures
FORCE: Colour = (200, 30, 30)  #: the plant's contact forces
PREDICTED: Colour = (255, 152, 150)  #: the controller's predicted forces
OBJECT: Colour = (60, 60, 60)  #: the object
GHOST: Colour = (140, 140, 140, 110)  #: the desired pose
BAND: Colour = (120, 190, 120)  #: a ξ panel's feasible band (the PNG figures' green), filled translucent
BAND_EDGE: Colour = (60, 120, 60)  #: its bounds
DANGER_FILL: Colour = (230, 120, 120)  #: its danger zones (the PNG figures' red), filled translucent


def rgba(colour: Colour, alpha: int = 255) -> int:
    """0xRRGGBBAA of an (r, g, b[, a]) tuple (``alpha`` unless it has its own)."""
    r, g, b = colour[:3]
    a = colour[3] if len(colour) > 3 else alpha
    return (int(r) << 24) | (int(g) << 16) | (int(b) << 8) | int(a)


#: Each contact mode's colour packed (the cones' colours).
MODE_RGBA = {mode: rgba(colour) for mode, colour in MODE_COLOURS.items()}


def colours(values: Sequence[int]) -> np.ndarray:
    """Packed 0xRRGGBBAA colours as the uint32 array rerun reads unambiguously."""
    return np.asarray(values, dtype=np.uint32)


def darker(colour: Colour, factor: float = 0.6) -> Colour:
    """The colour's (r, g, b) scaled by ``factor`` (opaque)."""
    return tuple(int(c * factor) for c in colour[:3])

r"""How soft a compliant plant's contacts are, drawn per run of a study: :class:`SoftnessRanges` (the ranges) draws a
:class:`ContactSoftness` (one run's values).

A real fingertip is a pad, not a point: how far it sinks under load and how fast it settles depend on its material,
which a model knows only roughly. A study on a compliant plant (MuJoCo) therefore draws, per run and uniformly in
each range, the contacts' settling time constant (MuJoCo's ``solref``), the depth over which their impedance builds
up (``solimp``'s width) and the fingertips' sphere radius; the controllers are told the radius (a hand's geometry is
measured) and nothing else.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.exceptions import InvalidParameterError
from ..core.validation import as_positive_float, as_tip_radius

__all__ = ["ContactSoftness", "SoftnessRanges"]


def _check(name: str, value: object) -> float:
    """A softness value: a tip radius (:func:`~regrasp.core.validation.as_tip_radius`), else a number > 0."""
    return as_tip_radius(name, value) if name == "tip_radius" else as_positive_float(name, value)


def _range(name: str, value: object) -> tuple[float, float]:
    if isinstance(value, (str, bytes)) or not hasattr(value, "__len__") or len(value) != 2:
        raise InvalidParameterError(name, value, "a range (low, high)")
    lo, hi = (_check(name, v) for v in value)
    if not lo <= hi:
        raise InvalidParameterError(name, value, "a range (low, high) with low <= high")
    return lo, hi


@dataclass(frozen=True)
class ContactSoftness:
    """One run's contact softness.

    Attributes:
        time_constant: How fast a penetration is undone [s] (MuJoCo's ``solref`` time constant).
        solimp_width: The penetration over which the contact's impedance builds up [m] (``solimp``'s width).
        tip_radius: The fingertips' sphere radius [m].
    """

    time_constant: float
    solimp_width: float
    tip_radius: float

    def __post_init__(self) -> None:
        for name in ("time_constant", "solimp_width", "tip_radius"):
            object.__setattr__(self, name, _check(name, getattr(self, name)))

    def to_json_dict(self) -> dict:
        return {"time_constant": self.time_constant, "solimp_width": self.solimp_width,
                "tip_radius": self.tip_radius}


@dataclass(frozen=True)
class SoftnessRanges:
    """The ranges a study draws each run's :class:`ContactSoftness` from (uniformly).

    Attributes:
        time_constant: [s] (default 0.25 to 2 ms: from a stiff pad to a soft one; MuJoCo needs at least two of its
            0.1 ms steps).
        solimp_width: [m] (default 0.05 to 0.5 mm).
        tip_radius: [m] (default 0.1 to 1 mm).
    """

    time_constant: tuple[float, float] = (2.5e-4, 2e-3)
    solimp_width: tuple[float, float] = (5e-5, 5e-4)
    tip_radius: tuple[float, float] = (1e-4, 1e-3)

    def __post_init__(self) -> None:
        for name in ("time_constant", "solimp_width", "tip_radius"):
            object.__setattr__(self, name, _range(name, getattr(self, name)))

    def draw(self, rng: np.random.Generator) -> ContactSoftness:
        """One run's softness, from ``rng`` (three uniform draws, in the fields' order)."""
        u = rng.uniform(0.0, 1.0, 3).tolist()
        values = [lo + x * (hi - lo) for x, (lo, hi) in zip(u, (self.time_constant, self.solimp_width,
                                                                  self.tip_radius))]
        return ContactSoftness(*values)

    def describe(self) -> str:
        """One line, e.g. ``softness: solref 0.25-2 ms, solimp width 0.05-0.5 mm, tip radius 0.1-1 mm``."""
        (a, b), (c, d), (e, f) = self.time_constant, self.solimp_width, self.tip_radius
        return (f"softness: solref {a * 1e3:g}-{b * 1e3:g} ms, solimp width {c * 1e3:g}-{d * 1e3:g} mm, "
                f"tip radius {e * 1e3:g}-{f * 1e3:g} mm")

r"""The contact's value types: its mode, its Coulomb friction and the cone margin.

* :class:`ContactMode`: a fingertip is ``FIXED`` on the object (it sticks), ``SLIDING`` along the
  edge, or ``SEPARATED`` (no contact). Every module uses this one type.
* :class:`Friction`: a static coefficient :math:`\mu_s` and a kinetic one :math:`\mu_k \le \mu_s`
  (Drake's ``CoulombFriction``). A fixed contact sticks while :math:`|f_t| \le \mu_s f_n`; a sliding
  one carries :math:`|f_t| = \mu_k f_n`, opposing the relative motion.
* :func:`cone_margin`: :math:`\mu f_n - |f_t|` [N], how far a contact force is inside its cone
  (negative: outside).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from enum import Enum

import numpy as np

from .exceptions import InvalidParameterError

__all__ = ["ContactMode", "Friction", "as_frictions", "cone_margin"]


class ContactMode(str, Enum):
    """How a fingertip touches the object."""

    FIXED = "fixed"
    SLIDING = "sliding"
    SEPARATED = "separated"


def _coefficient(name: str, value) -> float:
    if isinstance(value, bool):
        raise InvalidParameterError(name, value, "a friction coefficient >= 0")
    try:
        out = float(value)
    except (TypeError, ValueError, OverflowError):
        raise InvalidParameterError(name, value, "a friction coefficient >= 0") from None
    if not math.isfinite(out) or out < 0.0:
        raise InvalidParameterError(name, value, "a finite friction coefficient >= 0")
    return out


@dataclass(frozen=True)
class Friction:
    r"""Coulomb friction of one fingertip on the object.

    Attributes:
        static: :math:`\mu_s` [-]: a fixed contact sticks while :math:`|f_t| \le \mu_s f_n`.
        kinetic: :math:`\mu_k` [-], :math:`0 \le \mu_k \le \mu_s`: a sliding contact's friction is
            :math:`\mu_k f_n`.

    ``Friction(0.5)`` is :math:`\mu_s = \mu_k = 0.5`.
    """

    static: float
    kinetic: float | None = None

    def __post_init__(self):
        static = _coefficient("mu_static", self.static)
        kinetic = static if self.kinetic is None else _coefficient("mu_kinetic", self.kinetic)
        if kinetic > static:
            raise InvalidParameterError("mu_kinetic", self.kinetic,
                                        f"a kinetic coefficient <= the static one ({static:g})")
        object.__setattr__(self, "static", static)
        object.__setattr__(self, "kinetic", kinetic)

    def coefficient(self, mode: ContactMode) -> float:
        """μ_s for a fixed contact, μ_k for a sliding one (0 for a separated one) [-]."""
        if mode is ContactMode.FIXED:
            return self.static
        if mode is ContactMode.SLIDING:
            return self.kinetic
        return 0.0

    def scaled(self, factor: float) -> "Friction":
        """Both coefficients times ``factor`` (> 0)."""
        return Friction(self.static * factor, self.kinetic * factor)

    def __str__(self) -> str:
        if self.static == self.kinetic:
            return f"mu = {self.static:g}"
        return f"mu_s = {self.static:g}, mu_k = {self.kinetic:g}"


def as_frictions(friction, m: int) -> tuple[Friction, ...]:
    """One :class:`Friction` per contact from a Friction or a number (for all ``m`` contacts), or a
    sequence of ``m`` of them (a number is μ_s = μ_k)."""
    if isinstance(friction, Friction):
        return (friction,) * m
    if isinstance(friction, (str, bytes)) or friction is None:
        raise InvalidParameterError("friction", friction, "a Friction, a coefficient, or one per contact")
    if not isinstance(friction, Sequence) and np.ndim(friction) == 0:
        return (Friction(friction.item() if hasattr(friction, "item") else friction),) * m
    items = list(friction)
    if len(items) != m:
        raise InvalidParameterError("friction", friction, f"one friction per contact ({m})")
    return tuple(f if isinstance(f, Friction) else Friction(f.item() if hasattr(f, "item") else f) for f in items)


def cone_margin(mu: float, f_n: float, f_t: float) -> float:
    r""":math:`\mu f_n - |f_t|` [N]: how far a contact force (normal ``f_n``, tangential ``f_t`` [N]) is
    inside the friction cone of coefficient ``mu`` [-] (negative: outside)."""
    return mu * f_n - abs(f_t)

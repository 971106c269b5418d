r"""The contact's value types: its mode, its Coulomb friction and the cone margin.

* :class:`ContactMode`: a fingertip is ``FIXED`` on the object (it sticks), ``SLIDING`` along the
  edge, or ``SEPARATED`` (no contact). Every module uses this one type.
* :class:`Friction`: a static coefficient :math:`\mu_s` and a kinetic one :math:`\mu_k \le \mu_s`
  (Drake's ``CoulombFriction``). A fixed contact sticks while :math:`|f_t| \le \mu_s f_n`; a sliding
  one carries :math:`|f_t| = \mu_k f_n`, opposing the relative motion.
* :func:`cone_margin`: :math:`\mu f_n - |f_t|` [N], how far a contact force is inside its cone
  (negative: outside); elementwise on numpy arrays too.

Which coefficient applies where (``docs/derivations.md``, "Friction: static and kinetic
coefficients"): :meth:`Friction.coefficient` of the contact's mode, :func:`coefficients` for all
contacts: μ_s bounds a fixed contact's force (its cone; slip when it leaves it), μ_k is the
sliding contact's force ratio.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from collections.abc import Set as AbstractSet
from dataclasses import dataclass
from enum import Enum
from typing import TypeAlias

import numpy as np

from .exceptions import InvalidParameterError
from .validation import as_finite_float, as_positive_float

__all__ = ["DEFAULT_CONE_MARGIN", "DEFAULT_FRICTION", "ContactMode", "Friction", "FrictionLike", "ModesLike",
           "as_frictions", "as_modes", "coefficients", "cone_margin"]

#: The cone margin μ_s f_n - |f_t| [N] the regrasp planner plans with and the supervisor keeps the fixed contacts
#: inside where the forces allow (``RegraspSettings.cone_margin``, ``SupervisorSettings.robust``): 0.2 N costs no
#: slide over 0.1 N on the three-finger scenario (4 per period) and leaves room for a plant 10 % off the model.
DEFAULT_CONE_MARGIN = 0.2


class ContactMode(str, Enum):
    """How a fingertip touches the object (equal to its string value: ``ContactMode.FIXED == "fixed"``)."""

    FIXED = "fixed"
    SLIDING = "sliding"
    SEPARATED = "separated"


_MODES_BY_VALUE = {mode.value: mode for mode in ContactMode}

#: What ``modes`` arguments accept: per contact a :class:`ContactMode` or its string (see :func:`as_modes`).
ModesLike: TypeAlias = Sequence[ContactMode | str]


def as_modes(modes: ModesLike, m: int | None = None) -> tuple[ContactMode, ...]:
    """``modes`` (ContactMode members or their strings ``"fixed"``, ``"sliding"``, ``"separated"``)
    as a tuple of :class:`ContactMode`, ``m`` of them when given."""
    if isinstance(modes, (str, bytes)):
        raise InvalidParameterError("modes", modes, "one contact mode per contact")
    try:
        out = tuple(mode if type(mode) is ContactMode else _MODES_BY_VALUE[mode] for mode in modes)
    except (KeyError, TypeError):
        raise InvalidParameterError("modes", modes, "'fixed', 'sliding' or 'separated' per contact") from None
    if m is not None and len(out) != m:
        raise InvalidParameterError("modes", modes, f"one contact mode per contact ({m})")
    return out


def _coefficient(name: str, value: object) -> float:
    try:
        out = as_finite_float(name, value)
    except InvalidParameterError:
        raise InvalidParameterError(name, value, "a finite friction coefficient >= 0 (a number)") from None
    if out < 0.0:
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
        """Both coefficients times ``factor`` (a number > 0)."""
        factor = as_positive_float("factor", factor)
        if not self.static * factor < math.inf:
            raise InvalidParameterError("factor", factor, f"a factor that keeps mu_s = {self.static:g} finite")
        return Friction(self.static * factor, self.kinetic * factor)

    def __str__(self) -> str:
        if self.static == self.kinetic:
            return f"mu = {self.static:g}"
        return f"mu_s = {self.static:g}, mu_k = {self.kinetic:g}"


#: What ``friction`` arguments accept (see :func:`as_frictions`): a :class:`Friction` or a coefficient [-] for
#: every contact, or one of them per contact.
FrictionLike: TypeAlias = Friction | float | Sequence[Friction | float]

#: A fingertip's friction unless told otherwise: a scenario's default ``mu``, and every ``friction=`` argument's
#: default (a plant's, a controller's, a supervisor's) [-].
DEFAULT_FRICTION = Friction(0.5, 0.5)


def _is_scalar(value: object) -> bool:
    """Whether ``value`` is no sequence or array of more than zero dimensions (a ragged list is not a scalar: numpy's
    ``ndim`` raises on it)."""
    if isinstance(value, (list, tuple, dict, set, frozenset)):
        return False
    try:
        return np.ndim(value) == 0
    except (ValueError, TypeError):
        return False


def as_frictions(friction: FrictionLike, m: int) -> tuple[Friction, ...]:
    """One :class:`Friction` per contact from a Friction or a number (for all ``m`` contacts), or a
    sequence of ``m`` of them (a number is μ_s = μ_k)."""
    if isinstance(friction, Friction):
        return (friction,) * m
    if isinstance(friction, (str, bytes, Mapping, AbstractSet)) or friction is None:
        raise InvalidParameterError("friction", friction, "a Friction, a coefficient, or one per contact")
    if not isinstance(friction, Sequence) and _is_scalar(friction):
        return (Friction(friction.item() if hasattr(friction, "item") else friction),) * m
    items = list(friction)
    if len(items) != m:
        raise InvalidParameterError("friction", friction, f"one friction per contact ({m})")
    if any(not isinstance(f, Friction) and not _is_scalar(f) for f in items):
        raise InvalidParameterError("friction", friction, "one Friction or coefficient per contact (not arrays)")
    return tuple(f if isinstance(f, Friction) else Friction(f.item() if hasattr(f, "item") else f) for f in items)


def coefficients(frictions: Sequence[Friction], modes: Sequence[ContactMode]) -> tuple[float, ...]:
    """Per contact, the coefficient [-] of its mode (:meth:`Friction.coefficient`): μ_s where it is
    fixed, μ_k where it slides, 0 where it is separated."""
    if len(frictions) != len(modes):
        raise InvalidParameterError("modes", modes, f"one mode per friction ({len(frictions)})")
    return tuple(f.coefficient(mode) for f, mode in zip(frictions, modes))


def cone_margin(mu: float | np.ndarray, f_n: float | np.ndarray, f_t: float | np.ndarray) -> float | np.ndarray:
    r""":math:`\mu f_n - |f_t|` [N]: how far a contact force (normal ``f_n``, tangential ``f_t`` [N]) is
    inside the friction cone of coefficient ``mu`` [-] (negative: outside).

    Floats give a float; numpy arrays (of one shape, or broadcasting) give the margins elementwise.
    """
    return mu * f_n - abs(f_t)

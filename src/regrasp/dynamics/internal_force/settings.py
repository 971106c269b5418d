r"""The internal-force QP's settings (paper §3.3, eq. 3.3.7): its margins (:class:`InternalForceSettings`) and the
contacts to put on a friction-cone edge (:class:`ConeEdge`); the QP itself is
:mod:`regrasp.dynamics.internal_force.problem`.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from ...core.exceptions import InvalidParameterError
from ...core.validation import as_finite_float, as_positive_float, check_fields, expect_sequence_of

__all__ = ["ConeEdge", "InternalForceSettings", "as_cone_edges"]


@dataclass(frozen=True)
class InternalForceSettings:
    """Margins of the internal-force QP.

    ``floor(i)`` is contact i's least normal force.

    Attributes:
        f_min: Minimum normal force [N] at every contact, >= 0.
        friction_margin: A ratio [-], >= 0: fixed contacts keep |f_t| <= (μ_s - friction_margin) f_n.
        tolerance: OSQP absolute and relative tolerance, > 0.
        f_max: Maximum normal force [N] at every contact (what the fingers can push), > f_min, or inf.
        target_cone_margin: The smallest cone margin (μ_s - margin) f_n - |f_t| [N] to reach at the fixed
            contacts, >= 0 (:mod:`regrasp.dynamics.internal_force.problem`); 0: the least squeeze only.
        fallback_friction_margin: Where no internal force keeps the fixed contacts ``friction_margin`` inside their
            cones, the solver answers with this smaller friction margin [-] instead of failing (None: it fails). A
            margin that covers an uncertain μ is a preference; the cone of the model's μ is the limit.
        last_friction_margin: Where no internal force keeps even ``fallback_friction_margin``, the solver answers
            with this one [-] (e.g. 0: the model's cone itself) instead of failing (None: it fails); only with a
            ``fallback_friction_margin`` above it.
        floors: Per contact, a larger minimum normal force [N] than ``f_min`` (empty: none; contact i's floor is
            max(f_min, floors[i])): a contact pre-loaded for a neighbour's break-away, or one a reflex loads.
    """

    f_min: float = 0.5
    friction_margin: float = 0.05
    tolerance: float = 1e-9
    f_max: float = float("inf")
    target_cone_margin: float = 0.0
    fallback_friction_margin: float | None = None
    floors: tuple[float, ...] = ()
    last_friction_margin: float | None = None

    def __post_init__(self):
        check_fields(self, as_positive_float, ("f_min", "friction_margin", "target_cone_margin"), allow_zero=True)
        check_fields(self, as_positive_float, ("tolerance",))
        f_max = self.f_max
        if not (isinstance(f_max, float) and f_max == math.inf):  # inf: no upper bound
            try:
                f_max = as_finite_float("f_max", f_max)
            except InvalidParameterError:
                f_max = math.nan  # (the error below says what f_max may be)
        if not f_max > self.f_min:
            raise InvalidParameterError("f_max", self.f_max, f"a maximum normal force > f_min ({self.f_min}) or inf")
        object.__setattr__(self, "f_max", float(f_max))
        floors = expect_sequence_of("floors", self.floors, object, "normal forces [N], one per contact")
        floors = tuple(as_finite_float("floors", v) for v in floors)
        if any(not 0.0 <= v < self.f_max for v in floors):
            raise InvalidParameterError("floors", self.floors, f"normal forces in [0, f_max = {self.f_max:g}) [N]")
        object.__setattr__(self, "floors", floors)
        check_fields(self, as_finite_float, ("fallback_friction_margin",), optional=True)
        fallback = self.fallback_friction_margin
        if fallback is not None and not 0.0 <= fallback < self.friction_margin:
            raise InvalidParameterError("fallback_friction_margin", fallback,
                                        f"None or a friction margin in [0, friction_margin = {self.friction_margin:g})")
        check_fields(self, as_finite_float, ("last_friction_margin",), optional=True)
        last = self.last_friction_margin
        if last is not None and not (fallback is not None and 0.0 <= last < fallback):
            raise InvalidParameterError("last_friction_margin", last,
                                        "None, or a friction margin in [0, fallback_friction_margin) with a "
                                        f"fallback_friction_margin (it is {fallback})")

    def floor(self, i: int) -> float:
        """Contact i's least normal force [N]: ``f_min``, or its larger entry in ``floors``."""
        return max(self.f_min, self.floors[i]) if i < len(self.floors) else self.f_min


@dataclass(frozen=True)
class ConeEdge:
    r"""Put contact ``contact`` on a cone edge: :math:`t \cdot f = \text{sign}\,\mu\, n \cdot f` there.

    Attributes:
        contact: The contact's index.
        sign: The sliding direction, ±1 (the friction on the object points along sign · t).
        mu: The edge's coefficient [-], >= 0, chosen by the caller: the kinetic one for a sliding
            contact, the static one plus an overshoot to make a fixed contact break away, the kinetic
            one minus an undershoot to let a sliding contact slow down and stick.
    """

    contact: int
    sign: float
    mu: float

    def __post_init__(self):
        if self.sign not in (-1, 1, -1.0, 1.0):
            raise InvalidParameterError("cone_edge.sign", self.sign, "+1 or -1")
        if not as_finite_float("cone_edge.mu", self.mu) >= 0.0:
            raise InvalidParameterError("cone_edge.mu", self.mu, "a finite friction coefficient >= 0")
        object.__setattr__(self, "sign", float(self.sign))
        object.__setattr__(self, "mu", float(self.mu))

def as_cone_edges(cone_edge: ConeEdge | Iterable[ConeEdge] | None, m: int) -> tuple[ConeEdge, ...]:
    """``cone_edge`` (None, a :class:`ConeEdge`, or a sequence of them on distinct contacts) as a tuple,
    validated against ``m`` contacts."""
    if cone_edge is None:
        return ()
    edges = (cone_edge,) if isinstance(cone_edge, ConeEdge) else cone_edge
    if isinstance(edges, (str, bytes)) or not hasattr(edges, "__iter__"):
        raise InvalidParameterError("cone_edge", cone_edge, "None, a ConeEdge or a tuple of them")
    edges = tuple(edges)
    if not all(isinstance(edge, ConeEdge) for edge in edges):
        raise InvalidParameterError("cone_edge", cone_edge, "None, a ConeEdge or a tuple of them")
    contacts = [edge.contact for edge in edges]
    if not all(isinstance(j, (int, np.integer)) and 0 <= j < m for j in contacts):
        raise InvalidParameterError("cone_edge", cone_edge, f"contact indices in 0..{m - 1}")
    if len(set(contacts)) != len(contacts):
        raise InvalidParameterError("cone_edge", cone_edge, "cone edges on distinct contacts")
    return edges

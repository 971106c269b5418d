r"""The line geometry of a finger and an edge (paper §2.1–2.2): conditions I–IV and the reachable set.

Frames and parameters (eqs. 2.1.1–2.1.2). Let :math:`o_1` be the finger's first joint
in the hand frame, :math:`n` the edge's inward normal and :math:`x_i` the edge's ξ origin,
both mapped to the hand frame by the object pose :math:`X = (x_o, \beta)`:
:math:`x_i = x_o + R(\beta) c_i`. Then

.. math:: d = (x_i - o_1)^T n, \qquad \lambda = \angle n \text{ in the finger base frame}.

The edge's line is :math:`p(s) = o_1 + d\,n + s\,t` with :math:`t = \perp n` (the ξ
direction); :math:`s = \xi + s_0` with :math:`s_0 = (x_i - o_1)^T t`.

**Reachable set (Definition 2.1, exact form).** A point :math:`p(s)` is reachable in
configuration :math:`\sigma` (+1 left, -1 right) iff :math:`|l_1 - l_2| \le r \le l_1 + l_2`
(:math:`r = |p - o_1| = \sqrt{d^2 + s^2}`) and the elbow of the inverse-kinematics
solution is not in the open interior half-plane :math:`\{y : n^T (y - o_1) > d\}`. With
:math:`a = (l_1^2 - l_2^2 + r^2) / 2r` and :math:`h = \sqrt{l_1^2 - a^2}`, the elbow is
:math:`e = o_1 + a u + \sigma h \perp u` (:math:`u` the unit vector to the tip), and
:math:`n^T(e - o_1) \le d` reduces to

.. math:: g(s) = \sigma\, s\, K(r) - d\,(l_1^2 - l_2^2 - r^2) \ge 0,\qquad
          K(r) = \sqrt{((l_1 + l_2)^2 - r^2)(r^2 - (l_1 - l_2)^2)} = 2 r h.

:math:`g` is continuous on the annulus and vanishes only where the elbow lies on the line,
i.e. where the second link lies on the line: :math:`s = \pm c \pm l_2` with
:math:`c = \sqrt{l_1^2 - d^2}` (only when :math:`|d| \le l_1`). So the interval ends are among

* :math:`\pm\sqrt{(l_1 + l_2)^2 - d^2}` (full stretch: the paper's ξ1, ξ2, ξ4),
* :math:`\pm\sqrt{(l_1 - l_2)^2 - d^2}` (full fold, only when :math:`|d| < |l_1 - l_2|`),
* :math:`\pm c \pm l_2` (second link on the line: ξ3, ξ5, ξ6),

and the sign of :math:`g` between them selects the pieces. For the left configuration
this gives condition II: :math:`[-S, S]`; III: :math:`[c - l_2, S] \cup [-S, -c - l_2]`;
IV: :math:`[l_2 - c, l_2 + c]` (each minus the inner disc when :math:`l_1 \ne l_2`, which may
split it in two), and the right configuration is the mirror image :math:`s \to -s`
(:func:`reachable_on_line`). Isolated points (zero-length pieces) are dropped.
``docs/derivations.md`` has the derivation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

import numpy as np

from ..core.exceptions import InvalidParameterError
from ..core.intervals import Intervals, merge
from ..core.validation import as_finite_float, as_sign

__all__ = [
    "Condition",
    "EdgeLine",
    "condition_of",
    "condition_of_floats",
    "elbow_margin",
    "reachable_on_line",
]


class Condition(str, Enum):
    r"""The paper's conditions I–IV on :math:`d` and :math:`l_1` (§2.2).

    I: :math:`d < -l_1`; II: :math:`d > l_1`; III: :math:`0 \le d \le l_1`;
    IV: :math:`-l_1 \le d < 0`. (The paper uses strict inequalities; the boundaries are
    assigned to the side written here.)
    """

    I = "I"  # noqa: E741
    II = "II"
    III = "III"
    IV = "IV"


def condition_of(d: float, l1: float) -> Condition:
    """The condition (I–IV) for signed line distance ``d`` [m] and first link ``l1`` [m] (> 0)."""
    d, l1 = as_finite_float("d", d), as_finite_float("l1", l1)
    if not l1 > 0.0:
        raise InvalidParameterError("l1", l1, "a link length l1 > 0 [m]")
    return condition_of_floats(d, l1)


def condition_of_floats(d: float, l1: float) -> Condition:
    """:func:`condition_of` of finite floats ``d`` [m] and ``l1`` [m] > 0, without validation (the hot path's)."""
    if d < -l1:
        return Condition.I
    if d > l1:
        return Condition.II
    return Condition.III if d >= 0.0 else Condition.IV


def elbow_margin(s: float, d: float, l1: float, l2: float, sign: int) -> float:
    r"""The reachability function :math:`g(s)` of the module docstring (-inf outside the annulus).

    :math:`g(s) \ge 0` iff the elbow of the configured IK solution for the tip at line
    coordinate ``s`` [m] is not in the open interior half-plane (line at signed distance ``d`` [m], links ``l1``,
    ``l2`` [m], configuration ``sign`` +1 left, -1 right). Kept as an independent check of
    :func:`reachable_on_line`.
    """
    r2 = d * d + s * s
    k2 = ((l1 + l2) ** 2 - r2) * (r2 - (l1 - l2) ** 2)
    if k2 < 0.0:
        return -math.inf
    return sign * s * math.sqrt(k2) - d * (l1 * l1 - l2 * l2 - r2)


def reachable_on_line(d: float, l1: float, l2: float, sign: int) -> Intervals:
    r"""Reachable set (Definition 2.1) on the line at signed distance ``d`` [m], in ``s`` [m].

    ``s`` is measured along :math:`t = \perp n` from the foot of the perpendicular from
    the first joint; ``sign`` is +1 for the left and -1 for the right configuration.
    With :math:`S = \sqrt{(l_1 + l_2)^2 - d^2}`, :math:`c = \sqrt{l_1^2 - d^2}` and
    :math:`S_{in} = \sqrt{(l_1 - l_2)^2 - d^2}`, for the left configuration:

    * I (:math:`d < -l_1`): empty;
    * II (:math:`d > l_1`): :math:`[-S, S]` (ξ1, ξ2);
    * III (:math:`0 \le d \le l_1`): :math:`[c - l_2, S]` (ξ3, ξ4) and the sliver
      :math:`[-S, -c - l_2]` near full stretch on the other side;
    * IV (:math:`-l_1 \le d < 0`): :math:`[l_2 - c, l_2 + c]` (ξ5, ξ6);

    each minus the open inner disc :math:`(-S_{in}, S_{in})` when :math:`|d| < |l_1 - l_2|`
    (which can split an interval in two). The right configuration is the mirror image
    :math:`s \to -s`. Zero-length pieces are dropped.
    """
    d = as_finite_float("d", d)
    for name, length in (("l1", l1), ("l2", l2)):
        if not 0.0 < as_finite_float(name, length) <= 1e3:
            raise InvalidParameterError(name, length, "a link length in (0, 1000] m")
    sign = int(as_sign("sign", sign))
    l1, l2 = float(l1), float(l2)
    outer2 = (l1 + l2) ** 2 - d * d
    if outer2 <= 0.0 or d < -l1:
        return ()
    big = math.sqrt(outer2)
    if d > l1:
        pieces = [(-big, big)]
    else:
        c = math.sqrt(l1 * l1 - d * d)
        pieces = [(c - l2, big), (-big, -c - l2)] if d >= 0.0 else [(l2 - c, l2 + c)]
    inner2 = (l1 - l2) ** 2 - d * d
    if inner2 > 0.0:
        hole = math.sqrt(inner2)
        pieces = [p for lo, hi in pieces for p in ((lo, min(hi, -hole)), (max(lo, hole), hi))]
    if sign < 0:
        pieces = [(-hi, -lo) for lo, hi in pieces]
    return merge(pieces)


@dataclass(frozen=True)
class EdgeLine:
    """The contact edge's line seen from a finger at one object pose (eqs. 2.1.1–2.1.2).

    Attributes:
        d: Signed distance [m] of the line from the first joint along the inward normal.
        lam: Angle λ [rad] of the inward normal in the finger's base frame.
        normal_in_hand: Inward normal n (unit) in the hand frame.
        tangent_in_hand: ξ direction t = ⊥n (unit) in the hand frame.
        s0: Line coordinate s [m] of the edge's ξ origin (s = ξ + s0).
    """

    d: float
    lam: float
    normal_in_hand: np.ndarray
    tangent_in_hand: np.ndarray
    s0: float

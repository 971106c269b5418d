r"""Certified root isolation of a continuous function on an interval, from its values and a bound on its variation.

:func:`sign_changes` finds every sign change of ``f`` on ``[grid[0], grid[-1]]`` given a function
``variation(a, b)`` that bounds the total variation :math:`\int_a^b |f'|` of ``f`` on any cell ``[a, b]`` (a
derivative bound integrated; :mod:`regrasp.envelope.curve` derives one per boundary function from the curve's
turning angle). A cell ``[a, b]`` is

* **certified free** when :math:`f(a)` and :math:`f(b)` have the same sign and
  :math:`|f(a)| + |f(b)| > V(a, b)`: a zero at :math:`x` would give :math:`|f(a)| \le V(a, x)` and
  :math:`|f(b)| \le V(x, b)`, whose sum is at most :math:`V(a, b)`;
* **bracketing** when the signs differ: a root is refined in it (Illinois' regula falsi with a bisection
  safeguard) to a bracket of width ``tol``, and the two sides left over are examined again (a cell may hold three
  roots) unless ``monotone(a, b)`` certifies that ``f`` is strictly monotone on the cell (one root only);
* **certified monotone** (``monotone(a, b)`` true) with the same sign at both ends: no root;
* otherwise split in two, until it is narrower than ``resolution``, where it is left unresolved.

Without the monotonicity certificate the sides of every root are split down to ``resolution`` (the zeroth-order
bound cannot tell a simple root's neighbourhood from a second root), so ``monotone``, when a bound on the
variation of :math:`f'` is known, saves most of the evaluations.

So every sign change is found, except within a cell narrower than ``resolution`` whose ends have the same sign:
what is missed is a pair of roots closer than ``resolution``, i.e. a feature (a piece or a gap) narrower than it.
"Sign" is ``f > 0`` against ``f <= 0``; a zero where ``f`` does not change sign (a tangency) is no breakpoint.
"""

from __future__ import annotations

from collections.abc import Callable

__all__ = ["refine_bracket", "sign_changes"]

#: Steps of the regula falsi after which the bracket must have halved, else the next step bisects.
_SAFEGUARD_STEPS = 3


def refine_bracket(f: Callable[[float], float], a: float, b: float, fa: float, fb: float,
                   tol: float) -> tuple[float, float]:
    """A bracket ``(a', b')`` of width <= ``tol`` inside ``[a, b]`` with ``f(a') > 0`` iff ``fa > 0`` and
    ``f(b') > 0`` iff ``fb > 0`` (these two must differ): the Illinois variant of the regula falsi, a step kept
    at least ``tol / 4`` inside the bracket, and a bisection whenever ``_SAFEGUARD_STEPS`` steps did not halve it."""
    positive_a = fa > 0.0
    ga, gb = fa, fb  # the values the secant uses (Illinois halves the one kept twice)
    kept = 0  # +1: a was kept last step, -1: b was
    steps, width = 0, b - a
    while b - a > tol:
        steps += 1
        if steps % _SAFEGUARD_STEPS == 0:
            bisect = b - a > 0.5 * width
            width = b - a
        else:
            bisect = False
        if bisect or ga == gb:
            x = 0.5 * (a + b)
        else:
            x = a - ga * (b - a) / (gb - ga)
            margin = 0.25 * tol
            x = min(max(x, a + margin), b - margin)
        if not a < x < b:  # the bracket is down to rounding
            break
        fx = f(x)
        if (fx > 0.0) == positive_a:
            a, ga = x, fx
            if kept == 1:
                gb *= 0.5
            kept = 1
        else:
            b, gb = x, fx
            if kept == -1:
                ga *= 0.5
            kept = -1
    return a, b


def sign_changes(f: Callable[[float], float], variation: Callable[[float, float], float], grid: list[float],
                 tol: float, resolution: float,
                 monotone: Callable[[float, float], bool] | None = None) -> list[float]:
    """Every sign change of ``f`` on ``[grid[0], grid[-1]]`` (sorted, each within ``tol`` / 2 of a root), given
    ``variation(a, b)`` >= the total variation of ``f`` on ``[a, b]`` and a sorted starting ``grid``; cells
    narrower than ``resolution`` are not split further; ``monotone(a, b)``: True only if ``f`` is certified
    strictly monotone on ``[a, b]`` (module docstring)."""
    roots: list[float] = []
    stack = [(grid[k], grid[k + 1]) for k in range(len(grid) - 2, -1, -1)]
    while stack:
        a, b = stack.pop()
        if not b > a:
            continue
        fa, fb = f(a), f(b)
        if (fa > 0.0) != (fb > 0.0):
            lo, hi = refine_bracket(f, a, b, fa, fb, tol)
            roots.append(0.5 * (lo + hi))
            if monotone is None or not monotone(a, b):
                stack.append((hi, b))
                stack.append((a, lo))
        elif abs(fa) + abs(fb) > variation(a, b) or b - a <= resolution or (monotone is not None
                                                                              and monotone(a, b)):
            continue
        else:
            m = 0.5 * (a + b)
            stack.append((m, b))
            stack.append((a, m))
    return sorted(roots)

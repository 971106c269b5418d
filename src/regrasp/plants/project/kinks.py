r"""A rigid plant's step on a curve whose curvature jumps (:func:`located_step`): a rounded polygon's, where an arc
meets a straight part.

Such a curve is :math:`C^1`: its point and normal are continuous, its curvature κ is not. A sliding contact's
constraint acceleration :math:`\ddot\psi` has the term :math:`-\kappa (T\cdot u)^2/(1 + \kappa\delta)`
(:mod:`regrasp.plants.project.curve`), which then jumps by :math:`\Delta\kappa\,(T\cdot u)^2` when the foot
crosses such a point. RK4 over a step that holds the jump samples it with the wrong weights: it loses its order
there and the constraint's velocity picks up an error of order :math:`\Delta\kappa (T\cdot u)^2 h`, which the
Baumgarte terms then take some 1/α to remove (some 1e-7 m of drift at 0.1 m/s round a 12 mm corner).

So the step is split at the crossing: a trial RK4 step finds whether a sliding contact's foot crosses a jump; if so,
regula falsi (Illinois) on the substep's length t finds where its foot is at the jump (to 1e-12 m), the state
advances by an RK4 substep of t and then by the rest of the step (split again at a further crossing). Each substep
takes the curvature of its own side of the jump for the crossing contact (a rounded polygon's pieces each have one
curvature), so that RK4 integrates a smooth right-hand side on each and keeps its order. (A plant with pads takes
its RK4 substeps without this split.)
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from ...core.curves import RoundedPolygon
from .curve import CURVE_SLIDING, foot
from .equations import PlantEquations

__all__ = ["Kinks", "crossing", "kinks", "located_step", "rk4"]

#: A curve's jumps of curvature: their ξ [m] over one period, sorted, and the period [m].
Kinks = tuple[tuple[float, ...], float]

#: How close [m] a substep's end comes to the jump's ξ (the regula falsi's tolerance), and its most iterations.
LOCATE_TOL, LOCATE_ITERATIONS = 1e-12, 30
#: A jump closer than this [m] to a substep's start ξ is the one just crossed (not crossed again).
JUST_CROSSED = 1e-9


def kinks(obj: object) -> Kinks | None:
    """The ξ [m] where the object's curvature jumps (a rounded polygon's ends of arcs) and its period, or None (a
    polygon, or a smooth curve)."""
    if isinstance(obj, RoundedPolygon):
        return tuple(sorted(start for _, _, start, _ in obj.piece_ranges())), obj.perimeter
    return None


def crossing(marks: Kinks, a: float, b: float) -> tuple[float, float, float] | None:
    """The first jump going from ξ = ``a`` to ``b`` [m] (unbounded ξ), after ``a`` by more than
    :data:`JUST_CROSSED` and at or before ``b``: (its ξ, the ξ of the jumps before and after it in the direction
    of travel), or None."""
    points, period = marks
    if a == b:
        return None
    direction = 1.0 if b > a else -1.0
    turn = math.floor(a / period) * period
    best = None
    for k in (-1, 0, 1, 2):
        for j, m in enumerate(points):
            x = m + turn + k * period
            if (direction * (x - a) > JUST_CROSSED and direction * (b - x) >= 0.0
                    and (best is None or direction * (x - best[0]) < 0.0)):
                best = (x, j)
    if best is None:
        return None
    x, j = best
    count = len(points)
    gap_before = (points[j] - points[j - 1]) % period or period
    gap_after = (points[(j + 1) % count] - points[j]) % period or period
    if direction > 0:
        return x, x - gap_before, x + gap_after
    return x, x + gap_after, x - gap_before


def rk4(equations: PlantEquations, y: list, k1: list, tau: tuple, specs: tuple, h: float) -> list:
    """One classical RK4 step of ``h`` [s] from the flat state ``y`` whose derivative is ``k1`` (the plant's)."""
    half = h / 2
    k2 = equations.evaluate([a + half * b for a, b in zip(y, k1)], tau, specs)[0]
    k3 = equations.evaluate([a + half * b for a, b in zip(y, k2)], tau, specs)[0]
    k4 = equations.evaluate([a + h * b for a, b in zip(y, k3)], tau, specs)[0]
    return [a + h * ((b1 + 2 * b2 + 2 * b3 + b4) / 6.0) for a, b1, b2, b3, b4 in zip(y, k1, k2, k3, k4)]


def _feet(equations: PlantEquations, specs: tuple, y: list, tips: Sequence[Sequence[float]] | None) -> list:
    """(spec index, foot ξ [m]) of each sliding contact on the curve at the flat state ``y`` (``tips``: the tips
    there, None: from the joints)."""
    n = equations.hand.nq
    X = y[2 * n:2 * n + 3]
    out = []
    for j, spec in enumerate(specs):
        if spec[1] is CURVE_SLIDING:
            i = spec[0]
            tip = (tips[i] if tips is not None else
                   equations.hand.fingers[i].forward_kinematics(y[2 * i:2 * i + 2]).tolist())
            out.append((j, foot(spec[2], X, tip, spec[3]).xi))
    return out


def _with_kappa(specs: tuple, j: int, xi: float) -> tuple:
    """``specs`` with spec j's curvature fixed at the curve's at ξ [m]."""
    spec = specs[j]
    return (*specs[:j], (*spec[:6], spec[2].local_floats(xi)[4]), *specs[j + 1:])


def located_step(equations: PlantEquations, marks: Kinks, y: list, k1: list, tips: Sequence[Sequence[float]],
                 tau: tuple, specs: tuple, h: float) -> list:
    """The flat state after a rigid plant's step of ``h`` [s] from ``y`` (derivative ``k1``, the tips ``tips``
    there) at torques ``tau`` with ``specs``, split where a sliding contact's foot crosses a jump of the
    curvature ``marks`` (module docstring)."""
    done = 0.0
    while True:
        rest = h - done
        trial = rk4(equations, y, k1, tau, specs, rest)
        first = None
        for (j, a), (_, b) in zip(_feet(equations, specs, y, tips), _feet(equations, specs, trial, None)):
            found = crossing(marks, a, b)
            if found is not None and (first is None or (found[0] - a) / (b - a) < first[0]):
                first = ((found[0] - a) / (b - a), j, a, b, found)
        if first is None:
            return trial
        _, j, a, b, (mark, before, after) = first
        direction = 1.0 if b > a else -1.0
        old = _with_kappa(specs, j, 0.5 * (before + mark))
        # regula falsi (Illinois) on g(t) = ±(ξ_j(t) - mark): g(0) < 0 < g(rest)
        lo, g_lo, hi, g_hi = 0.0, direction * (a - mark), rest, direction * (b - mark)
        t, state, side = rest, trial, 0
        for _ in range(LOCATE_ITERATIONS):
            t = (lo * g_hi - hi * g_lo) / (g_hi - g_lo)
            state = rk4(equations, y, k1, tau, old, t)
            g = direction * (dict(_feet(equations, old, state, None))[j] - mark)
            if abs(g) <= LOCATE_TOL:
                break
            if g < 0.0:
                lo, g_lo = t, g
                g_hi = g_hi / 2 if side < 0 else g_hi
                side = -1
            else:
                hi, g_hi = t, g
                g_lo = g_lo / 2 if side > 0 else g_lo
                side = 1
        done += t
        y = state
        specs = _with_kappa(specs, j, 0.5 * (mark + after))
        k1, _, fingers = equations.evaluate(y, tau, specs)
        tips = [f[11:13] for f in fingers]

r"""Whether any contact positions inside given intervals admit a force system: one linear program per mode.

The positions enter the force balance only through the moment, as the products :math:`\xi_i \lambda_i`
(:mod:`regrasp.schedule.force_polytope`). With :math:`g_i = \xi_i \lambda_i` as variables besides the forces, the
moment equation :math:`\sum_i \lambda_i (A_i + r_i B_i) - g_i + \sum_{fixed} \tau_i B_i = I_o \alpha` is linear, and
:math:`\xi_i \in [a_i, b_i]` reads :math:`a_i \lambda_i \le g_i \le b_i \lambda_i` (λ_i ≥ f_min > 0). This
relaxation is exact: a solution gives the positions :math:`\xi_i = g_i / \lambda_i` inside their intervals with the
same forces, and a force system at positions inside the intervals gives a solution. So one linear program (HiGHS)
decides whether positions in the intervals admit forces in a mode; when none of the admissible modes does, no
schedule can hold the object at that time: the decomposition planner's proof of :attr:`ScheduleLimit.FORCES
<regrasp.schedule.schedule.ScheduleLimit.FORCES>`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.optimize
from numpy.typing import ArrayLike

from .force_polytope import ForceGeometry, ForceLimits

__all__ = ["positions_admit_forces"]


def positions_admit_forces(geometry: ForceGeometry, beta: float, acceleration: ArrayLike, intervals: ArrayLike,
                           ratios: Sequence[float | None], static_mu: Sequence[float],
                           limits: ForceLimits) -> np.ndarray | None:
    """Positions ξ [m] (m,) inside ``intervals`` [m] (m, 2) that admit a force system in the mode ``ratios`` (per
    contact None: fixed, or its signed τ/λ on a cone edge) at orientation ``beta`` [rad] and acceleration (a_x, a_y, α)
    ``acceleration``, or None when no positions in the intervals do (the linear program of the module docstring)."""
    m = geometry.m
    box = np.asarray(intervals, dtype=float).reshape(m, 2)
    acc = np.asarray(acceleration, dtype=float).reshape(3)
    fixed = [i for i in range(m) if ratios[i] is None]
    nf = len(fixed)
    d = 2 * m + nf  # x = (λ, τ of the fixed contacts, g)
    g0 = m + nf
    rows, rhs = [], []  # A_ub x <= b_ub
    for i, floor in enumerate(limits.floors(ratios)):
        row = np.zeros(d)
        row[i] = -1.0
        rows.append(row)
        rhs.append(-floor)
        row = np.zeros(d)
        row[i] = 1.0
        rows.append(row)
        rhs.append(limits.f_max)
        for coefficient, sign in ((box[i, 0], -1.0), (-box[i, 1], 1.0)):  # a λ - g <= 0, g - b λ <= 0
            row = np.zeros(d)
            row[i], row[g0 + i] = coefficient, sign
            rows.append(row)
            rhs.append(0.0)
    for k, i in enumerate(fixed):
        for sign in (-1.0, 1.0):  # μ λ ∓ τ >= c
            row = np.zeros(d)
            row[i], row[m + k] = -static_mu[i], -sign
            rows.append(row)
            rhs.append(-limits.cone_margin)
    n, t = geometry.normals, geometry.tangents
    eq = np.zeros((3, d))
    for i in range(m):
        r = 0.0 if ratios[i] is None else float(ratios[i])
        eq[:2, i] = n[i] + r * t[i]
        eq[2, i] = geometry.moment_normal[i] + r * geometry.moment_tangent[i]
        eq[2, g0 + i] = -1.0
    for k, i in enumerate(fixed):
        eq[:2, m + k] = t[i]
        eq[2, m + k] = geometry.moment_tangent[i]
    F = geometry.mass * (acc[:2] - geometry.gravity)
    c, s = np.cos(beta), np.sin(beta)
    b_eq = np.array([c * F[0] + s * F[1], -s * F[0] + c * F[1], geometry.inertia * acc[2]])
    result = scipy.optimize.linprog(np.zeros(d), A_ub=np.array(rows), b_ub=np.array(rhs), A_eq=eq, b_eq=b_eq,
                                    bounds=[(None, None)] * d, method="highs")
    if result.status != 0:
        return None
    lam, g = result.x[:m], result.x[g0:]
    return np.clip(g / lam, box[:, 0], box[:, 1])

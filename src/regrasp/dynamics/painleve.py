r"""When a sliding contact is well-posed: the Painlevé condition on the fingers' sliders.

A sliding contact i pushes on the object with :math:`f_i = \lambda_i (n_i + r_i t_i)`, :math:`r_i = s_i\mu_k` the
signed kinetic ratio (:math:`n_i` the inward normal, :math:`t_i` the edge's ξ direction, :math:`s_i` the sign of the
tip's slide along it). Its normal force is what keeps the tip on the edge: the gap's acceleration is affine in the
sliders' normal forces,

.. math:: \ddot g_S = a_S + A\,\lambda_S, \qquad
    A_{ab} = \delta_{ab}\, n_a^T W_a (n_a + r_a t_a) + (G_a n_a)^T M_c^{-1} G_b (n_b + r_b t_b),

with :math:`W_a = J_a M_a^{-1} J_a^T` finger a's tip mobility [1/kg], :math:`G_a f = (f,\ p_a \times f)` the wrench of
a force at the tip (p_a relative to the object's centre of mass, hand frame) and :math:`M_c` the object's mass
matrix with every fixed (held) contact's finger welded to it at its tip: :math:`M_c = \mathrm{diag}(m, m, I) +
\sum_{j\ \mathrm{fixed}} G_j W_j^{-1} G_j^T` (the Schur complement of the fixed contacts' rows of the Delassus
matrix; ``docs/derivations.md``, "Sliding contacts and Painlevé"). Without friction A is symmetric positive definite.
With it, A can lose that: when A is not a P-matrix the sliding contact problem has no solution or several
(Painlevé's paradox: the contact jams or separates), and as :math:`A_{aa} \to 0` its normal force needs torques known
to a precision that vanishes (:math:`\partial\lambda/\partial\tau \propto 1/A_{aa}`). The ratio
:math:`\rho_a = A_{aa}(r) / A_{aa}(0)` measures how much of the frictionless normal mobility friction leaves.

The planner (:mod:`regrasp.schedule.well_posed`) allows a slide only where A stays a P-matrix with every kinetic
ratio scaled by ``RegraspSettings.sliding_friction_factor``: well-posed with that much more friction than the model's.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from ..core.exceptions import InvalidParameterError
from ..core.validation import as_finite_array

__all__ = ["composite_inverse_mass", "is_p_matrix", "sliding_response", "tip_mobility"]


def tip_mobility(jacobian: ArrayLike, mass: ArrayLike) -> np.ndarray:
    r"""A finger's tip mobility :math:`W = J M^{-1} J^T` [1/kg] (..., 2, 2) from its tip Jacobian J (..., 2, 2) [m]
    and joint mass matrix M (..., 2, 2) [kg m²]: the tip's acceleration per unit force on it."""
    J, M = np.asarray(jacobian, dtype=float), np.asarray(mass, dtype=float)
    return J @ np.linalg.solve(M, np.swapaxes(J, -1, -2))


def _wrench_map(points: np.ndarray) -> np.ndarray:
    """G (..., 3, 2): the object wrench (f, p × f) of a force f at each point p (..., 2)."""
    out = np.zeros(points.shape[:-1] + (3, 2))
    out[..., 0, 0] = out[..., 1, 1] = 1.0
    out[..., 2, 0], out[..., 2, 1] = -points[..., 1], points[..., 0]
    return out


def composite_inverse_mass(object_mass: float, object_inertia: float, points: ArrayLike,
                           mobilities: ArrayLike) -> np.ndarray:
    r""":math:`M_c^{-1}` (..., 3, 3) of the object [kg, kg m²] with fingers welded at ``points`` (..., k, 2) [m]
    (relative to its centre of mass, hand frame), their tip mobilities ``mobilities`` (..., k, 2, 2) [1/kg]:
    :math:`M_c = M_o + \sum_j G_j W_j^{-1} G_j^T`, inverted by Woodbury,
    :math:`M_c^{-1} = M_o^{-1} - M_o^{-1} G (W + G^T M_o^{-1} G)^{-1} G^T M_o^{-1}` (a singular W is fine)."""
    P = np.asarray(points, dtype=float)
    W = np.asarray(mobilities, dtype=float)
    inv_o = np.diag([1.0 / object_mass, 1.0 / object_mass, 1.0 / object_inertia])
    k = P.shape[-2]
    batch = P.shape[:-2]
    if k == 0:
        return np.broadcast_to(inv_o, batch + (3, 3)).copy()
    G = np.swapaxes(_wrench_map(P), -3, -2).reshape(batch + (3, 2 * k))  # columns: the welded tips' forces
    K = np.swapaxes(G, -1, -2) @ inv_o @ G
    for j in range(k):
        K[..., 2 * j:2 * j + 2, 2 * j:2 * j + 2] += W[..., j, :, :]
    right = inv_o @ G
    return inv_o - right @ np.linalg.solve(K, np.swapaxes(right, -1, -2))


def sliding_response(object_mass: float, object_inertia: float, points: ArrayLike, normals: ArrayLike,
                     tangents: ArrayLike, mobilities: ArrayLike, ratios: Sequence[float | None]) -> np.ndarray:
    r"""The sliders' normal response A (..., p, p) [1/kg] (module docstring) of the contacts whose ``ratios`` entry is
    a float (the signed ratio τ/λ = s μ_k [-]); the others (None) are fixed. Per contact: its tip ``points``
    (..., m, 2) [m] relative to the object's centre of mass, ``normals`` (inward) and ``tangents`` (..., m, 2), hand
    frame, and its finger's tip mobility ``mobilities`` (..., m, 2, 2) [1/kg] (:func:`tip_mobility`)."""
    if not object_mass > 0.0 or not object_inertia > 0.0:
        raise InvalidParameterError("object_mass", (object_mass, object_inertia), "a positive mass and inertia")
    P = as_finite_array("points", points)
    N, T = np.asarray(normals, dtype=float), np.asarray(tangents, dtype=float)
    W = np.asarray(mobilities, dtype=float)
    m = P.shape[-2]
    if len(ratios) != m or N.shape != P.shape or T.shape != P.shape or W.shape != P.shape + (2,):
        raise InvalidParameterError("ratios", list(ratios), f"one per contact ({m}), with points, normals, tangents "
                                    "(..., m, 2) and mobilities (..., m, 2, 2)")
    sliders = [i for i, r in enumerate(ratios) if r is not None]
    fixed = [i for i, r in enumerate(ratios) if r is None]
    inv_c = composite_inverse_mass(object_mass, object_inertia, P[..., fixed, :], W[..., fixed, :, :])
    r = np.array([float(ratios[i]) for i in sliders])
    n, t = N[..., sliders, :], T[..., sliders, :]
    push = n + r[:, None] * t  # (..., p, 2): each slider's force per unit normal force
    G = _wrench_map(P[..., sliders, :])  # (..., p, 3, 2)
    gn = np.einsum("...pij,...pj->...pi", G, n)
    gf = np.einsum("...pij,...pj->...pi", G, push)
    A = np.einsum("...ai,...ij,...bj->...ab", gn, inv_c, gf)
    own = np.einsum("...pi,...pij,...pj->...p", n, W[..., sliders, :, :], push)
    idx = np.arange(len(sliders))
    A[..., idx, idx] += own
    return A


def is_p_matrix(A: ArrayLike, tolerance: float = 0.0) -> np.ndarray:
    """Whether each square matrix in ``A`` (..., p, p) is a P-matrix (every principal minor > ``tolerance``), the
    condition for a unique solution of the sliding contact problem (module docstring); bool (...)."""
    A = np.asarray(A, dtype=float)
    p = A.shape[-1]
    ok = np.ones(A.shape[:-2], dtype=bool)
    for size in range(1, p + 1):
        for rows in itertools.combinations(range(p), size):
            sub = A[..., rows, :][..., :, rows]
            ok &= np.linalg.det(sub) > tolerance
    return ok

r"""Joint torque limits as rows of the internal-force QP (:mod:`regrasp.dynamics.internal_force.problem`).

Finger i's joint torques are affine in its contact force :math:`f_i` (the force on the object, hand frame):
:math:`\tau_i = w_i + J_i^T f_i` with :math:`w_i = M_i \ddot q_i + N_i` (``docs/derivations.md``, "Actuator
limits"), where the laws' :math:`\ddot q = H a + \dot H \dot S` does not depend on the internal force. A limit
:math:`|\tau_{ij}| \le e_{ij}` (:attr:`~regrasp.model.hand.Hand.effort_limit`) is two rows on :math:`f_i`,

.. math:: J_{ij}^T f_i \ge -e_{ij} - w_{ij}, \qquad -J_{ij}^T f_i \ge -e_{ij} + w_{ij}

(:math:`J_{ij}` column j of :math:`J_i`), in the QP's row format (:meth:`ConstraintRows.rows_at
<regrasp.dynamics.internal_force.rows.ConstraintRows.rows_at>`: ``(2i, c_x, c_y, lo)``). A joint without a limit
(inf) has none. The solvers add them only where the answer without them exceeds a limit: where it does not, it
is the constrained optimum already.

Where no internal force keeps the torques within the limits, :func:`torque_shortfall` says by how much at the
least: the linear program :math:`\min t` subject to every other row and :math:`|\tau_{ij}| \le e_{ij} + t`, and
the joint at its bound (:class:`TorqueShortfall`, carried by the
:class:`~regrasp.dynamics.internal_force.problem.InternalForceInfeasibleError`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import scipy.optimize

__all__ = ["JointTorques", "TorqueShortfall", "joint_torques", "torque_matrix", "torque_rows", "torque_shortfall",
           "within_limits"]


class JointTorques(NamedTuple):
    """What the torque rows need at one state (plain floats: a control step builds one).

    Attributes:
        jacobians: Per finger its tip Jacobian J_i row-major (a, b, c, d) [m/rad], hand frame.
        wrench: w = M q̈ + N (2m) [N m]: the torques at zero contact force.
        effort: The joints' limits (2m) [N m] (inf: none).
        names: The fingers' names (for messages; empty: "finger i").
    """

    jacobians: Sequence[Sequence[float]]
    wrench: Sequence[float]
    effort: Sequence[float]
    names: Sequence[str] = ()

    def name(self, i: int) -> str:
        return self.names[i] if i < len(self.names) else f"finger {i + 1}"


@dataclass(frozen=True)
class TorqueShortfall:
    """The least amount by which the joint torque limits fall short (:func:`torque_shortfall`).

    Attributes:
        contact: The finger's index.
        finger: Its name.
        joint: 1 (proximal) or 2 (distal).
        needed: The torque [N m] (absolute) that joint needs at the forces that need the least excess.
        effort: Its limit [N m].
        excess: needed - effort [N m], > 0: no internal force needs less beyond any limit.
    """

    contact: int
    finger: str
    joint: int
    needed: float
    effort: float
    excess: float

    def __str__(self) -> str:
        return (f"{self.finger} joint {self.joint} needs at least {self.needed:.6g} N m against its limit of "
                f"{self.effort:.6g} N m ({self.excess:.3g} N m short)")


def joint_torques(torques: JointTorques, forces: Sequence[float]) -> list[float]:
    """τ = w + Jᵀ f (2m) [N m] at contact forces ``forces`` (2m) [N], hand frame."""
    out = []
    for i, (a, b, c, d) in enumerate(torques.jacobians):
        f0, f1 = forces[2 * i], forces[2 * i + 1]
        out += (torques.wrench[2 * i] + a * f0 + c * f1, torques.wrench[2 * i + 1] + b * f0 + d * f1)
    return out


def within_limits(torques: JointTorques, forces: Sequence[float], slack: float = 0.0) -> bool:
    """Whether every |τ_j| <= e_j + ``slack`` [N m] at ``forces`` (the compiled kernel's
    :func:`~regrasp.kernels.force.exceeds_effort` with slack 0)."""
    return all(abs(t) <= e + slack for t, e in zip(joint_torques(torques, forces), torques.effort))


def torque_rows(torques: JointTorques) -> list[tuple[int, float, float, float]]:
    """The limits' rows ``(2i, c_x, c_y, lo)``, meaning c_x f[2i] + c_y f[2i + 1] >= lo (module docstring), two per
    limited joint, finger by finger."""
    rows = []
    for i, (a, b, c, d) in enumerate(torques.jacobians):
        for j, (cx, cy) in enumerate(((a, c), (b, d))):
            e = torques.effort[2 * i + j]
            if math.isfinite(e):
                w = torques.wrench[2 * i + j]
                rows += [(2 * i, cx, cy, -e - w), (2 * i, -cx, -cy, w - e)]
    return rows


def torque_matrix(torques: JointTorques, m: int) -> tuple[np.ndarray, np.ndarray]:
    """:func:`torque_rows` as (C (r, 2m), lo (r,)): C f >= lo."""
    rows = torque_rows(torques)
    C = np.zeros((len(rows), 2 * m))
    for r, (i2, cx, cy, _) in enumerate(rows):
        C[r, i2], C[r, i2 + 1] = cx, cy
    return C, np.array([lo for *_, lo in rows], dtype=float)


def torque_shortfall(null: np.ndarray, motion_forces: np.ndarray, C: np.ndarray, lower: np.ndarray, n_ineq: int,
                     torques: JointTorques) -> TorqueShortfall | None:
    r"""The least excess over the torque limits of any internal force (module docstring), or None where no force
    satisfies the other rows either (the limits are then not the reason) or none exceeds a limit.

    Args:
        null: N_c (2m, k), f = f_m + N_c y.
        motion_forces: f_m (2m,) [N].
        C: The other rows in the hand frame: C f >= lower (the first ``n_ineq``), = lower (the rest).
        lower: Their bounds.
        n_ineq: How many of them are inequalities.
        torques: The torque limits.
    """
    m2, k = null.shape
    limited = [j for j, e in enumerate(torques.effort) if math.isfinite(e)]
    if not limited:
        return None
    # the torques as functions of y: τ = w + Jᵀ f_m + (Jᵀ N_c) y
    jt = np.zeros((m2, m2))
    for i, (a, b, c, d) in enumerate(torques.jacobians):
        jt[2 * i:2 * i + 2, 2 * i:2 * i + 2] = ((a, c), (b, d))
    base = np.asarray(torques.wrench, dtype=float) + jt @ motion_forces
    slope = jt @ null
    cost = np.zeros(k + 1)
    cost[-1] = 1.0
    rows, rhs = [-(C[:n_ineq] @ null)], [C[:n_ineq] @ motion_forces - lower[:n_ineq]]  # -C N y <= C f_m - lo
    for j in limited:  # ±(base + slope y) - t <= e
        for sign in (1.0, -1.0):
            rows.append(np.append(sign * slope[j], -1.0)[None])
            rhs.append(np.array([torques.effort[j] - sign * base[j]]))
    rows[0] = np.hstack([rows[0], np.zeros((n_ineq, 1))])
    A_eq = b_eq = None
    if len(lower) > n_ineq:
        A_eq = np.hstack([C[n_ineq:] @ null, np.zeros((len(lower) - n_ineq, 1))])
        b_eq = lower[n_ineq:] - C[n_ineq:] @ motion_forces
    result = scipy.optimize.linprog(cost, A_ub=np.vstack(rows), b_ub=np.concatenate(rhs), A_eq=A_eq, b_eq=b_eq,
                                    bounds=[(None, None)] * (k + 1), method="highs")
    if result.status != 0 or not result.x[-1] > 1e-12:
        return None
    tau = base + slope @ result.x[:k]
    j = max(limited, key=lambda j: abs(tau[j]) - torques.effort[j])
    needed, effort = float(abs(tau[j])), float(torques.effort[j])
    return TorqueShortfall(j // 2, torques.name(j // 2), j % 2 + 1, needed, effort, needed - effort)

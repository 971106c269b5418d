r"""The joint torques the planned forces need: the regrasp planner's actuator limits.

Contact i's finger holds its tip on the object's point :math:`c = o_i + \xi\, t^o_i` (object frame; on a curve
:math:`c(\xi)`, with the frame at ξ and :math:`\ddot p` gaining :math:`\kappa\dot\xi^2 n`, the centripetal term of
a slide along it: :mod:`regrasp.core.curves`), i.e. at
:math:`p = X + R(\beta) c` in the hand frame, and pushes on the object with :math:`f = \lambda n + \tau t`
(:math:`n = R n^o_i`, :math:`t = R t^o_i`; λ, τ as in :mod:`regrasp.schedule.force_polytope`). Its joint torques
are affine in (λ, τ) (``docs/derivations.md``, "Actuator limits"):

.. math:: \tau_{ij} = w_j + (J_j \cdot n)\,\lambda + (J_j \cdot t)\,\tau, \qquad w = M \ddot q + N(q, \dot q),

with q the inverse kinematics of p (the finger's configuration), :math:`\dot q = J^{-1}\dot p`,
:math:`\ddot q = J^{-1}(\ddot p - \dot J\dot q)` from the object's motion and the contact's slide
(:math:`\dot p = \dot X + \omega E R c + t \dot\xi`,
:math:`\ddot p = \ddot X + \alpha E R c - \omega^2 R c + 2\omega E t\dot\xi + t\ddot\xi`), J the tip Jacobian and
:math:`J_j` its column j. Only contact i's own position and force enter: the limits :math:`|\tau_{ij}| \le e_{ij}`
(the finger's :attr:`~regrasp.model.finger.Finger.effort_limit`) are per contact, but they depend on ξ, unlike the
rest of the force polytope. :class:`TorqueModel` evaluates (w, J·n, J·t) for whole grids of times and positions
(the compiled finger terms, :func:`~regrasp.kernels.finger.finger_terms`); the planner uses it in its lattice (a
necessary condition per cell) and in its verification (exact, a linear program): :mod:`regrasp.schedule.problem`,
:mod:`regrasp.schedule.planner`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..core.exceptions import UnreachableError
from ..dynamics.painleve import tip_mobility
from ..kernels.finger import finger_terms_at
from ..model.hand import Hand
from ..model.scenario import Scenario

if TYPE_CHECKING:
    from ..core.trajectory import TrajectorySample

__all__ = ["ContactTorques", "TorqueModel"]


@dataclass(frozen=True, eq=False)
class ContactTorques:
    r"""One contact's joint torques as affine functions of its force, on a grid of samples: joint j's torque is
    ``wrench[..., j] + normal[..., j] λ + tangential[..., j] τ`` [N m] (λ, τ [N]); NaN where the finger cannot
    reach the point, or only in a singular posture (``reachable`` False)."""

    wrench: np.ndarray
    normal: np.ndarray
    tangential: np.ndarray
    reachable: np.ndarray

    def at(self, lam: float, tau: float) -> np.ndarray:
        """The joint torques [N m] (..., 2) at the force (λ, τ) [N]."""
        return self.wrench + self.normal * lam + self.tangential * tau


def _packed(fv, i: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Contact i's (λ, τ) at the valid vertices of ``fv`` per layer, packed to (layers, V) (a layer with fewer
    repeats one of its own; V: the most any layer has), and which layers have none."""
    valid = fv.valid
    count = valid.sum(axis=1)
    order = np.argsort(~valid, axis=1, kind="stable")[:, :max(1, int(count.max(initial=0)))]
    order = np.where(np.arange(order.shape[1]) < np.maximum(count, 1)[:, None], order, order[:, :1])
    rows = np.arange(len(valid))[:, None]
    return fv.normal[rows, order, i], fv.tangential[rows, order, i], count == 0


class TorqueModel:
    """A scenario's fingers and their joint torque limits, for the regrasp planner (module docstring).

    Attributes:
        effort: The joints' limits [N m], (m, 2) (inf: none).
        limited: Whether any joint has a limit.
    """

    def __init__(self, scenario: Scenario):
        contacts = scenario.contacts
        self.hand = Hand([c.finger for c in contacts], gravity_in_hand=scenario.gravity_in_hand)
        self.effort = self.hand.effort_limit.reshape(len(contacts), 2)
        self.limited = bool(np.isfinite(self.effort).any())
        self._edges = [scenario.polygon.edge(c.edge) for c in contacts]

    def contact(self, i: int, pose: np.ndarray, velocity: np.ndarray, acceleration: np.ndarray, xi: np.ndarray,
                xi_dot: np.ndarray | float = 0.0, xi_ddot: np.ndarray | float = 0.0,
                joints: np.ndarray | None = None) -> ContactTorques:
        """Contact i's :class:`ContactTorques` at T object states (``pose``, ``velocity``, ``acceleration`` (T, 3):
        a trajectory's sample) and contact positions ``xi`` [m] (T, K), sliding at ``xi_dot`` [m/s] and
        ``xi_ddot`` [m/s²] (broadcast to (T, K)); results (T, K, 2). ``joints``: the finger's joint angles there
        (:meth:`joint_angles`), if known."""
        xi = np.asarray(xi, dtype=float)
        T, K = xi.shape
        xi_dot, xi_ddot = np.broadcast_to(xi_dot, (T, K)), np.broadcast_to(xi_ddot, (T, K))
        edge = self._edges[i]
        beta = pose[:, 2:3]
        c, s = np.cos(beta), np.sin(beta)

        def rotate(v):  # R(β) v for object-frame vectors v (..., 2) per time
            return np.stack([c * v[..., 0] - s * v[..., 1], s * v[..., 0] + c * v[..., 1]], axis=-1)

        if getattr(edge, "curved", False):  # on a curve the frame turns with ξ: t' = κ n
            point, normal, kappa = (v.reshape(T, K, *v.shape[1:]) for v in edge.curve.frames(xi.reshape(-1)))
            n, t = rotate(normal), rotate(np.stack([-normal[..., 1], normal[..., 0]], axis=-1))
        else:
            point = edge.xi_origin + xi[..., None] * edge.xi_direction  # (T, K, 2), object frame
            kappa = None
            n = rotate(np.broadcast_to(edge.inward_normal, (T, K, 2)))
            t = rotate(np.broadcast_to(edge.xi_direction, (T, K, 2)))
        r = rotate(point)
        er = np.stack([-r[..., 1], r[..., 0]], axis=-1)  # E R c
        et = np.stack([-t[..., 1], t[..., 0]], axis=-1)
        w, alpha = velocity[:, 2:3, None], acceleration[:, 2:3, None]
        p_dot = velocity[:, None, :2] + w * er + t * xi_dot[..., None]
        p_ddot = (acceleration[:, None, :2] + alpha * er - w * w * r + 2.0 * w * et * xi_dot[..., None]
                  + t * xi_ddot[..., None])
        if kappa is not None:
            p_ddot = p_ddot + (kappa * xi_dot * xi_dot)[..., None] * n
        q = self.joint_angles(i, pose, xi) if joints is None else joints
        reachable = np.isfinite(q[..., 0])
        q = np.where(reachable[..., None], q, 0.0).reshape(-1, 2)
        jac, terms = self._terms(i, q, np.zeros_like(q))
        pd = p_dot.reshape(-1, 2)
        det = jac[:, 0, 0] * jac[:, 1, 1] - jac[:, 0, 1] * jac[:, 1, 0]
        total = (jac ** 2).sum(axis=(1, 2))
        with np.errstate(all="ignore"):  # σ_max/σ_min (Hand.check_singular's): a singular finger reaches nothing
            disc = np.sqrt(np.maximum(total ** 2 - 4.0 * det ** 2, 0.0))
            condition = np.sqrt((total + disc) / (total - disc))
        reachable &= (condition <= self.hand.singular_threshold).reshape(T, K)
        with np.errstate(all="ignore"):
            inv = np.stack([np.stack([jac[:, 1, 1], -jac[:, 0, 1]], -1), np.stack([-jac[:, 1, 0], jac[:, 0, 0]], -1)],
                           1) / det[:, None, None]
            q_dot = np.einsum("kij,kj->ki", inv, pd)
            _, terms = self._terms(i, q, q_dot)
            q_ddot = np.einsum("kij,kj->ki", inv, p_ddot.reshape(-1, 2) - terms["jdv"])
            wrench = np.einsum("kij,kj->ki", terms["M"], q_ddot) + terms["N"]
            normal = np.einsum("kji,kj->ki", jac, n.reshape(-1, 2))  # J_jᵀ n per joint j
            tangential = np.einsum("kji,kj->ki", jac, t.reshape(-1, 2))
        shape = (T, K, 2)
        nan = ~reachable[..., None]
        return ContactTorques(*(np.where(nan, np.nan, v.reshape(shape)) for v in (wrench, normal, tangential)),
                              reachable)

    def joint_angles(self, i: int, pose: np.ndarray, xi: np.ndarray) -> np.ndarray:
        """Finger i's joint angles [rad] (T, K, 2) with its tip on the contact point at positions ``xi`` [m] (T, K)
        at the object's poses ``pose`` (T, 3) (its configuration); NaN where it cannot reach."""
        edge = self._edges[i]
        xi = np.asarray(xi, dtype=float)
        if getattr(edge, "curved", False):
            point = edge.curve.frames(xi.reshape(-1))[0].reshape(xi.shape + (2,))
        else:
            point = edge.xi_origin + xi[..., None] * edge.xi_direction
        c, s = np.cos(pose[:, 2:3]), np.sin(pose[:, 2:3])
        x = pose[:, 0:1] + c * point[..., 0] - s * point[..., 1]
        y = pose[:, 1:2] + s * point[..., 0] + c * point[..., 1]
        finger = self.hand.fingers[i]
        q = np.full(x.shape + (2,), np.nan)
        for index, (px, py) in enumerate(zip(x.reshape(-1).tolist(), y.reshape(-1).tolist())):
            try:
                q.reshape(-1, 2)[index] = finger.joint_angles(px, py)
            except UnreachableError:
                pass
        return q

    def tip_mobility(self, i: int, joints: np.ndarray) -> np.ndarray:
        r"""Finger i's tip mobility :math:`J M^{-1} J^T` [1/kg] (..., 2, 2) at joint angles ``joints`` (..., 2) [rad]
        (:func:`~regrasp.dynamics.painleve.tip_mobility`); NaN where they are NaN (unreachable)."""
        q = np.asarray(joints, dtype=float)
        ok = np.isfinite(q).all(axis=-1)
        jac, terms = self._terms(i, np.where(ok[..., None], q, 0.0).reshape(-1, 2), np.zeros((ok.size, 2)))
        out = tip_mobility(jac, terms["M"]).reshape(q.shape[:-1] + (2, 2))
        out[~ok] = np.nan
        return out

    def _terms(self, i: int, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """J (k, 2, 2) and M (k, 2, 2), N (k, 2), J̇q̇ (k, 2) of finger i at k states (compiled terms, or Pinocchio
        where the hand's kernels disagree with it)."""
        params = self.hand.kernel_parameters
        if params is not None:
            rec = finger_terms_at(np.repeat(params[i:i + 1], len(q)), q.reshape(-1), v.reshape(-1),
                                  self.hand.gravity_in_hand, self.hand.damping_enabled)
            jac = np.stack([np.stack([rec["j00"], rec["j01"]], -1), np.stack([rec["j10"], rec["j11"]], -1)], 1)
            mass = np.stack([np.stack([rec["m00"], rec["m01"]], -1), np.stack([rec["m01"], rec["m11"]], -1)], 1)
            return jac, {"M": mass, "N": np.stack([rec["n0"], rec["n1"]], -1),
                         "jdv": np.stack([rec["jdx"], rec["jdy"]], -1)}
        m = self.hand.m
        jac, mass, nle, jdv = (np.empty((len(q), 2, 2)), np.empty((len(q), 2, 2)), np.empty((len(q), 2)),
                               np.empty((len(q), 2)))
        for k in range(len(q)):
            qs, vs = np.zeros((m, 2)), np.zeros((m, 2))
            qs[i], vs[i] = q[k], v[k]
            dyn = self.hand.dynamics(qs.reshape(-1), vs.reshape(-1))
            sl = slice(2 * i, 2 * i + 2)
            jac[k], mass[k], nle[k], jdv[k] = dyn.jacobian[sl, sl], dyn.mass_matrix[sl, sl], dyn.nonlinear[sl], \
                dyn.jacobian_dot_v[sl]
        return jac, {"M": mass, "N": nle, "jdv": jdv}

    def cell_excess(self, sample: TrajectorySample, grids: list[np.ndarray], combos: np.ndarray, vertices: list,
                    speed: float, joints: list[np.ndarray] | None = None) -> np.ndarray:
        r"""The lattice's necessary condition (:mod:`regrasp.schedule.problem`): per layer, move vector, contact,
        cell and joint, the least :math:`|\tau_{ij}| - e_{ij}` [N m] over the force polytope's vertices at the layer
        (``vertices``: per move vector its :class:`~regrasp.schedule.force_polytope.ForceVertices` at the layers of
        the trajectory's ``sample``), with the contact at the cell, sliding at ``speed`` [m/s] in its move's
        direction; (N + 1, M, m, n_max, 2) float32, NaN where the finger cannot reach the cell or the polytope is
        empty. A cell whose excess is positive for a joint has no force system within that joint's limit, whatever
        the other contacts' positions: the projection of the polytope on one joint's torque is an interval, and
        the moment balance only shrinks the polytope. ``joints``: per contact its finger's joint angles at the layers
        and cells (:meth:`joint_angles`), if known."""
        m, layers, n_max = len(grids), len(sample.time), max(len(g) for g in grids)
        out = np.full((layers, len(combos), m, n_max, 2), np.nan, dtype=np.float32)
        for i, grid in enumerate(grids):
            xi = np.broadcast_to(grid, (layers, len(grid)))
            q = self.joint_angles(i, sample.pose, xi) if joints is None else joints[i]
            per_direction = {d: self.contact(i, sample.pose, sample.velocity, sample.acceleration, xi, d * speed,
                                             joints=q) for d in sorted({int(d) for d in combos[:, i]})}
            effort = self.effort[i].astype(np.float32)
            for mu, d in enumerate(combos):
                torques, (lam, tau, empty) = per_direction[int(d[i])], _packed(vertices[mu], i)
                values = (torques.wrench[..., None] + torques.normal[..., None] * lam[:, None, None]
                          + torques.tangential[..., None] * tau[:, None, None])  # (layers, cells, 2, V)
                least = np.maximum(0.0, np.maximum(values.min(axis=-1), -values.max(axis=-1)))
                least[empty] = np.nan
                out[:, mu, i, :len(grid)] = least - effort
        return out

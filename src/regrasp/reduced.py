r"""Hand–object dynamics in the reduced coordinates S = (x_o, β, ξ) (paper §3.1–3.2, 3.4).

Kinematics (eqs. 3.1.7–3.1.10). With :math:`A = [\,G^T \mid R_f B_v\,]`, the contact
constraints read :math:`J \dot q = A \dot S`, so :math:`\dot q = H \dot S` with
:math:`H = J^{-1} A`. Differentiating, :math:`\ddot q = H \ddot S + \dot H \dot S` with

.. math:: \dot H \dot S = J^{-1}\left(\dot G^T \dot X + \dot R_f B_v \dot\xi - \dot J \dot q\right),

where :math:`\dot G` and :math:`\dot R_f` are exact (:mod:`regrasp.grasp`) and
:math:`\dot J \dot q` comes from Pinocchio.

Dynamics, by virtual power (``docs/derivations.md``). The fingers obey
:math:`M \ddot q + N = \tau - J^T f` and the object
:math:`M_o \ddot X = G f + f_g`, with :math:`f` the contact forces on the object (hand
frame). Premultiplying the fingers' equation by :math:`H^T` (:math:`H^T J^T = A^T`) and
adding the object's equation to the first three rows, the contact forces cancel except
for the tangential force at the sliding contacts:

.. math:: (H^T M H + M_s)\,\ddot S + N_s = H^T \tau + \begin{bmatrix} f_g \\ -f_\xi \end{bmatrix},
   \qquad N_s = H^T M \dot H \dot S + H^T N,\qquad f_\xi = B_v^T R_f^T f.

This is eq. (3.2.11) **without** the paper's extra :math:`+G R_f B_v f_\xi` in the object
rows: the friction force acts on the object through :math:`G f` already, so that term
counts it twice. (Power check: the contacts' net power is :math:`-f_\xi^T \dot\xi`, all of it
friction.) Coulomb friction closes the system: :math:`f_{\xi,j} = \mu\, s_j\, n_j^T f_j` with
:math:`s_j = \mathrm{sign}(\dot\xi_j)` and :math:`f = J^{-T}(\tau - M \ddot q - N)`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .exceptions import InvalidParameterError
from .grasp import Grasp
from .hand import Hand, HandDynamics
from .validation import as_finite_array, as_finite_vectors, as_friction_coefficients, as_positive_float

__all__ = ["ReducedModel", "ReducedState"]


@dataclass(frozen=True)
class ReducedState:
    """Kinematic and dynamic quantities at one reduced state (S, Ṡ).

    Attributes:
        S: (x [m], y [m], β [rad], ξ_sliding [m]...), shape (3 + p,).
        S_dot: Its time derivative.
        xi: ξ [m] of every contact (fixed ones from the model), shape (m,).
        xi_dot: ξ̇ [m/s] of every contact (0 for fixed ones).
        q, q_dot: Joint positions [rad] and velocities [rad/s], (2m,).
        H: (2m, 3 + p), q̇ = H Ṡ (eq. 3.1.10).
        H_dot_S_dot: Ḣ Ṡ, (2m,).
        G: Grasp matrix (3, 2m).
        R_f: Surface rotation (2m, 2m).
        B_v: Sliding directions (2m, p).
        hand: M, N, J, J̇q̇ and the tips at (q, q̇).
    """

    S: np.ndarray
    S_dot: np.ndarray
    xi: np.ndarray
    xi_dot: np.ndarray
    q: np.ndarray
    q_dot: np.ndarray
    H: np.ndarray
    H_dot_S_dot: np.ndarray
    G: np.ndarray
    R_f: np.ndarray
    B_v: np.ndarray
    hand: HandDynamics


class ReducedModel:
    r"""The paper's model of a hand holding a polygon with fixed and sliding contacts.

    Args:
        hand: The fingers (finger i touches contact i of ``grasp``).
        grasp: Contacts, their edges and modes.
        xi: ξ [m] of every contact; fixed contacts stay there, sliding ones start there.
        object_mass: [kg]; default: the polygon's.
        object_inertia: [kg m^2] about the centre of mass; default: the polygon's.
    """

    def __init__(self, hand: Hand, grasp: Grasp, xi, *, object_mass: float | None = None,
                 object_inertia: float | None = None):
        if hand.m != grasp.m:
            raise InvalidParameterError("grasp", grasp.m, f"one contact per finger ({hand.m})")
        self.hand = hand
        self.grasp = grasp
        self.xi = as_finite_array("xi", xi, (grasp.m,)).copy()
        mass = as_positive_float("object_mass", grasp.polygon.mass if object_mass is None else object_mass)
        inertia = as_positive_float("object_inertia",
                                    grasp.polygon.inertia if object_inertia is None else object_inertia)
        self.object_mass = mass
        self.object_inertia = inertia
        self.M_o = np.diag([mass, mass, inertia])
        self.n = 3 + grasp.p
        self.M_s = np.zeros((self.n, self.n))
        self.M_s[:3, :3] = self.M_o
        self._bv = grasp.sliding_directions()
        self._identity = np.eye(hand.nq)
        self._sliding_column = {i: 3 + j for j, i in enumerate(grasp.sliding)}  # contact -> column of S

    @property
    def f_g(self) -> np.ndarray:
        """Gravity wrench on the object at its centre of mass [N, N, N m]."""
        gx, gy = self.hand.gravity_in_hand.tolist()
        return np.array([self.object_mass * gx, self.object_mass * gy, 0.0])

    # ------------------------------------------------------------------ coordinates
    def split(self, S, S_dot=None):
        """(pose, ξ of all contacts[, twist, ξ̇ of all contacts]) from S (and Ṡ)."""
        S = as_finite_array("S", S, (self.n,))
        xi = self.xi.copy()
        xi[list(self.grasp.sliding)] = S[3:]
        if S_dot is None:
            return S[:3], xi
        S_dot = as_finite_array("S_dot", S_dot, (self.n,))
        xi_dot = np.zeros(self.grasp.m)
        xi_dot[list(self.grasp.sliding)] = S_dot[3:]
        return S[:3], xi, S_dot[:3], xi_dot

    def joint_positions(self, S) -> np.ndarray:
        """q (2m,) with every tip on its contact point, in each finger's configuration."""
        pose, xi = self.split(S)
        return self.hand.inverse_kinematics(self.grasp.points(pose, xi))

    def constraint_matrix(self, S) -> np.ndarray:
        """A = [G^T | R_f B_v] (2m x (3 + p)): J q̇ = A Ṡ (eq. 3.1.8)."""
        pose, xi = self.split(S)
        return np.hstack([self.grasp.grasp_matrix(pose, xi).T,
                          self.grasp.surface_rotation(pose) @ self.grasp.sliding_directions()])

    def state(self, S, S_dot) -> ReducedState:
        """All the model's quantities at (S, Ṡ); raises SingularFingerError at a singular finger."""
        S, S_dot = as_finite_vectors(("S", "S_dot"), (S, S_dot), self.n)
        return self._state(S, S_dot)[0]

    def _state(self, S: np.ndarray, S_dot: np.ndarray) -> tuple[ReducedState, np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`state` on validated (n,) arrays (hot paths), with J⁻¹, A and blockdiag(R_fi) of
        every contact's surface frame (2m, 2m).

        The per-contact kinematics is scalar arithmetic (m is 2 or 3: numpy's per-call cost would
        dominate); the matrices are built once from it.
        """
        grasp, hand, m, n, nq = self.grasp, self.hand, self.grasp.m, self.n, self.hand.nq
        s_list, sd_list = S.tolist(), S_dot.tolist()
        x, y, beta = s_list[:3]
        omega = sd_list[2]
        xi, xi_dot = self.xi.tolist(), [0.0] * m
        for i, col in self._sliding_column.items():
            xi[i], xi_dot[i] = s_list[col], sd_list[col]
        c, s = math.cos(beta), math.sin(beta)
        q, tips, a_rows, a_dot = [], [], [], []
        frames = [0.0] * (nq * nq)  # blockdiag(R_fi), row-major
        for i, (ox, oy, tx, ty, nx, ny) in enumerate(grasp._contact_constants):
            cx, cy = ox + xi[i] * tx, oy + xi[i] * ty
            rx, ry = c * cx - s * cy, s * cx + c * cy  # lever arm r_i = R c_i(ξ_i)
            nx, ny = c * nx - s * ny, s * nx + c * ny  # surface frame [n_i t_i] = R [n°_i t°_i]
            tx, ty = c * tx - s * ty, s * tx + c * ty
            tips.append((x + rx, y + ry))  # the contact point, where the tip is
            q.extend(hand.fingers[i]._joint_angles(x + rx, y + ry))
            k = 2 * i * (nq + 1)
            frames[k], frames[k + 1], frames[k + nq], frames[k + nq + 1] = nx, tx, ny, ty
            # rows 2i, 2i+1 of A = [G^T | R_f B_v]: [I_2 | ⊥r_i | t_i in the column of ξ_i if it slides]
            row_x, row_y = [1.0, 0.0, -ry] + [0.0] * (n - 3), [0.0, 1.0, rx] + [0.0] * (n - 3)
            col = self._sliding_column.get(i)
            if col is not None:
                row_x[col], row_y[col] = tx, ty
            a_rows += (row_x, row_y)
            # Ȧ Ṡ = Ġ^T Ẋ + Ṙ_f B_v ξ̇: ω ⊥ṙ_i + ω ξ̇_i ⊥t_i with ṙ_i = ω ⊥r_i + ξ̇_i t_i
            a_dot += (-omega * omega * rx - 2.0 * omega * xi_dot[i] * ty,
                      -omega * omega * ry + 2.0 * omega * xi_dot[i] * tx)
        qs = np.array(q).reshape(m, 2)
        J = hand._jacobian(qs)
        rows = J.tolist()
        blocks = [(rows[2 * i][2 * i], rows[2 * i][2 * i + 1], rows[2 * i + 1][2 * i], rows[2 * i + 1][2 * i + 1])
                  for i in range(m)]
        hand._check_singular_blocks(qs, blocks)
        J_inv = [0.0] * (nq * nq)  # blockdiag(J_i^{-1}), row-major
        for i, (a, b, c_, d) in enumerate(blocks):
            det, k = a * d - b * c_, 2 * i * (nq + 1)
            J_inv[k], J_inv[k + 1], J_inv[k + nq], J_inv[k + nq + 1] = d / det, -b / det, -c_ / det, a / det
        J_inv = np.array(J_inv).reshape(nq, nq)
        A = np.array(a_rows)
        H = J_inv.dot(A)  # (ndarray.dot: matmul's ufunc machinery costs ~1 us per call here)
        q_dot = H.dot(S_dot)
        dyn = hand._dynamics(qs, q_dot.reshape(m, 2), (J, np.array(tips)))
        H_dot_S_dot = J_inv.dot(np.array(a_dot) - dyn.jacobian_dot_v)
        frames = np.array(frames).reshape(nq, nq)
        R_f = self._identity.copy()
        for i in grasp.sliding:
            R_f[2 * i:2 * i + 2, 2 * i:2 * i + 2] = frames[2 * i:2 * i + 2, 2 * i:2 * i + 2]
        if grasp.p:
            xi, xi_dot = np.array(xi), np.array(xi_dot)
        else:  # (cheaper than converting the lists)
            xi, xi_dot = self.xi.astype(float), np.zeros(m)
        st = ReducedState(S, S_dot, xi, xi_dot, qs.reshape(-1), q_dot, H, H_dot_S_dot, A[:, :3].T, R_f, self._bv, dyn)
        return st, J_inv, A, frames

    # ------------------------------------------------------------------ dynamics
    def mass_matrix(self, st: ReducedState) -> np.ndarray:
        """H^T M H + M_s ((3 + p) square, eq. 3.2.11)."""
        return st.H.T @ st.hand.mass_matrix @ st.H + self.M_s

    def bias(self, st: ReducedState) -> np.ndarray:
        """N_s = H^T M Ḣ Ṡ + H^T N (eq. 3.2.12)."""
        return st.H.T @ (st.hand.mass_matrix @ st.H_dot_S_dot + st.hand.nonlinear)

    def contact_forces(self, st: ReducedState, tau, S_ddot) -> np.ndarray:
        r"""Contact forces on the object (m, 2) [N], hand frame: :math:`f = J^{-T}(\tau - M\ddot q - N)`."""
        tau = as_finite_array("tau", tau, (self.hand.nq,))
        q_ddot = st.H @ as_finite_array("S_ddot", S_ddot, (self.n,)) + st.H_dot_S_dot
        f = np.linalg.solve(st.hand.jacobian.T, tau - st.hand.mass_matrix @ q_ddot - st.hand.nonlinear)
        return f.reshape(self.grasp.m, 2)

    def contact_generalized_force(self, st: ReducedState, forces) -> np.ndarray:
        r"""The generalized force on S of contact forces ``forces`` (m, 2) [N] acting on the object:
        :math:`[0;\ -B_v^T R_f^T f]`: all but the sliding contacts' friction cancel (virtual power)."""
        f = as_finite_array("forces", forces, (self.grasp.m, 2)).reshape(-1)
        out = np.zeros(self.n)
        out[3:] = -(st.B_v.T @ st.R_f.T @ f)
        return out

    def forward_dynamics(self, st: ReducedState, tau, mu=0.0, *, signs=None,
                         paper_friction_term: bool = False) -> tuple[np.ndarray, np.ndarray]:
        r"""S̈ and the contact forces (m, 2) [N] for joint torques ``tau`` and Coulomb friction ``mu``
        (one coefficient, or one per contact).

        Solves :math:`(H^T M H + M_s)\ddot S + N_s = H^T\tau + [f_g; -f_\xi]` with
        :math:`f_{\xi,j} = \mu s_j n_j^T f_j` and :math:`f = J^{-T}(\tau - M(H\ddot S + \dot H\dot S) - N)`,
        which is linear in :math:`\ddot S`. ``signs`` default to sign(ξ̇) of the sliding contacts
        (which must then be non-zero). ``paper_friction_term=True`` adds the paper's
        :math:`+G R_f B_v f_\xi` to the object rows (eq. 3.2.11 as printed), to show it is wrong.
        """
        tau = as_finite_array("tau", tau, (self.hand.nq,))
        mu = as_friction_coefficients(mu, self.grasp.m)
        p = self.grasp.p
        if signs is None:
            signs = np.sign(st.S_dot[3:])
            if p and np.any(mu[list(self.grasp.sliding)] > 0) and np.any(signs == 0):
                raise InvalidParameterError("signs", signs, "a sliding direction: ξ̇ = 0 at a sliding contact")
        signs = as_finite_array("signs", signs, (p,))
        M, J = st.hand.mass_matrix, st.hand.jacobian
        # f(S̈) = f0 - K S̈
        K = np.linalg.solve(J.T, M @ st.H)
        f0 = np.linalg.solve(J.T, tau - M @ st.H_dot_S_dot - st.hand.nonlinear)
        # f_xi = mu * s_j * n_j^T f_j = Sn f, row j selects sliding contact j
        frames = self.grasp.surface_frames(st.S[:3])
        Sn = np.zeros((p, self.hand.nq))
        for j, i in enumerate(self.grasp.sliding):
            Sn[j, 2 * i:2 * i + 2] = mu[i] * signs[j] * frames[i][:, 0]
        lhs = self.mass_matrix(st)
        rhs = st.H.T @ tau - self.bias(st)
        rhs[:3] += self.f_g
        # -f_xi in the xi rows: -(Sn f0 - Sn K S̈)
        lhs[3:] -= Sn @ K
        rhs[3:] -= Sn @ f0
        if paper_friction_term and p:
            grb = st.G @ st.R_f @ st.B_v  # (3, p): + G R_f B_v f_xi in the object rows
            lhs[:3] += grb @ Sn @ K
            rhs[:3] += grb @ Sn @ f0
        S_ddot = np.linalg.solve(lhs, rhs)
        forces = (f0 - K @ S_ddot).reshape(self.grasp.m, 2)
        return S_ddot, forces

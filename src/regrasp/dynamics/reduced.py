r"""Hand–object dynamics in the reduced coordinates S = (x_o, β, ξ) (paper §3.1–3.2, 3.4).

Kinematics (eqs. 3.1.7–3.1.10). With :math:`A = [\,G^T \mid R_f B_v\,]`, the contact
constraints read :math:`J \dot q = A \dot S`, so :math:`\dot q = H \dot S` with
:math:`H = J^{-1} A`. Differentiating, :math:`\ddot q = H \ddot S + \dot H \dot S` with

.. math:: \dot H \dot S = J^{-1}\left(\dot G^T \dot X + \dot R_f B_v \dot\xi - \dot J \dot q\right),

where :math:`\dot G` and :math:`\dot R_f` are exact (:mod:`regrasp.dynamics.grasp`) and
:math:`\dot J \dot q` comes from Pinocchio.

On a curved object (:mod:`regrasp.core.curves`) A keeps its form, with the contact point and frame at ξ, and
:math:`\dot R_f B_v \dot\xi` gains :math:`\kappa_i \dot\xi_i^2 n_i` per sliding contact (the tangent turns
as the contact moves: :math:`t' = \kappa n`; ``docs/derivations.md``, "Contacts on curves").

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
friction.) Coulomb friction closes the system: :math:`f_{\xi,j} = \mu_{k,j}\, s_j\, n_j^T f_j` (the
kinetic coefficient of :class:`~regrasp.core.contact.Friction`) with :math:`s_j = \mathrm{sign}(\dot\xi_j)`
and :math:`f = J^{-T}(\tau - M \ddot q - N)`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from ..core.contact import DEFAULT_FRICTION, FrictionLike, as_frictions
from ..core.exceptions import InvalidParameterError, UnreachableError
from ..core.validation import as_finite_array, as_finite_vectors, as_inertia, as_mass, expect_type
from ..kernels.reduced import UNREACHABLE, contact_edges, ik_parameters, reduced_terms
from ..model.hand import Hand, HandDynamics
from .grasp import Grasp

__all__ = ["ReducedModel", "ReducedState", "ReducedTerms"]


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


class ReducedTerms(NamedTuple):
    """:class:`ReducedState`'s quantities as floats (hot paths; H as an array), hand frame, SI units as there:
    per contact ``xi``, ``xi_dot``; per joint ``q``, ``q_dot``, ``h_dot_s_dot`` (Ḣ Ṡ), ``nonlinear`` (N) and
    ``jdv`` (J̇ q̇, two per finger); ``a_rows`` the rows of A = [G^T | R_f B_v]; per finger: ``tips``,
    ``tip_velocities`` (x, y); ``jacobians``, ``inverses`` J_i and J_i^{-1} as row-major (a, b, c, d);
    ``masses`` M_i's (m00, m01, m11); ``frames`` the surface frame (n_x, n_y, t_x, t_y)."""

    xi: list
    xi_dot: list
    q: list
    q_dot: list
    tips: list
    tip_velocities: list
    a_rows: list
    H: np.ndarray
    h_dot_s_dot: list
    jacobians: list
    inverses: list
    masses: list
    nonlinear: list
    jdv: list
    frames: list


class ReducedModel:
    r"""The paper's model of a hand holding a polygon with fixed and sliding contacts.

    Args:
        hand: The fingers (finger i touches contact i of ``grasp``).
        grasp: Contacts, their edges and modes.
        xi: ξ [m] of every contact; fixed contacts stay there, sliding ones start there.
        object_mass: [kg]; default: the polygon's.
        object_inertia: [kg m^2] about the centre of mass; default: the polygon's.
        compiled: Evaluate the terms with the compiled kernel (:mod:`regrasp.kernels.reduced`; the same
            equations, ``tests/kernels/test_finger_and_plant.py`` checks it against the reference path). None
            (default): when the hand's kernels agree with Pinocchio; False: the reference path (Pinocchio, plain
            floats).
    """

    def __init__(self, hand: Hand, grasp: Grasp, xi: ArrayLike, *, object_mass: float | None = None,
                 object_inertia: float | None = None, compiled: bool | None = None):
        expect_type("hand", hand, Hand, "a Hand")
        expect_type("grasp", grasp, Grasp, "a Grasp")
        if hand.m != grasp.m:
            raise InvalidParameterError("grasp", grasp.m, f"one contact per finger ({hand.m})")
        self.hand = hand
        self.grasp = grasp
        self.xi = as_finite_array("xi", xi, (grasp.m,)).copy()
        mass = as_mass("object_mass", grasp.polygon.mass if object_mass is None else object_mass)
        inertia = as_inertia("object_inertia",
                                    grasp.polygon.inertia if object_inertia is None else object_inertia)
        self.object_mass = mass
        self.object_inertia = inertia
        self.M_o = np.diag([mass, mass, inertia])
        self.n = 3 + grasp.p
        self.M_s = np.zeros((self.n, self.n))
        self.M_s[:3, :3] = self.M_o
        self._m_s_diagonal = [mass, mass, inertia] + [0.0] * grasp.p
        self._bv = grasp.sliding_directions()
        self._identity = np.eye(hand.nq)
        self._sliding_column = {i: 3 + j for j, i in enumerate(grasp.sliding)}  # contact -> column of S
        if grasp.curved and compiled:
            raise InvalidParameterError("compiled", compiled, "False or None for a curved object (the compiled "
                                        "kernels take straight edges; the reference path takes curves)")
        #: Whether the terms come from the compiled kernel (never on a curved object).
        self.compiled = hand.use_kernels(compiled) and not grasp.curved
        self._kernel_constants = None if not self.compiled else (
            hand.kernel_parameters, ik_parameters(hand.fingers),
            contact_edges([e.xi_origin for e in grasp.edges], [e.xi_direction for e in grasp.edges],
                          [e.inward_normal for e in grasp.edges]),
            np.array([self._sliding_column.get(i, -1) for i in range(grasp.m)], dtype=np.int64))

    @property
    def kernel_constants(self) -> tuple | None:
        """The compiled kernels' constant arguments (finger parameters, inverse kinematics, contact edges,
        each contact's column of S or -1; :func:`~regrasp.kernels.reduced.reduced_terms`), None when not
        compiled."""
        return self._kernel_constants

    @property
    def m_s_diagonal(self) -> list[float]:
        """diag(M_s): the object's mass [kg] twice, its inertia [kg m^2], then a zero per slider."""
        return list(self._m_s_diagonal)

    @property
    def f_g(self) -> np.ndarray:
        """Gravity wrench on the object at its centre of mass [N, N, N m]."""
        gx, gy = self.hand.gravity_in_hand.tolist()
        return np.array([self.object_mass * gx, self.object_mass * gy, 0.0])

    # ------------------------------------------------------------------ coordinates
    def split(self, S: ArrayLike, S_dot: ArrayLike | None = None) -> tuple[np.ndarray, ...]:
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

    def joint_positions(self, S: ArrayLike) -> np.ndarray:
        """q (2m,) with every tip on its contact point, in each finger's configuration."""
        pose, xi = self.split(S)
        return self.hand.inverse_kinematics(self.grasp.points(pose, xi))

    def constraint_matrix(self, S: ArrayLike) -> np.ndarray:
        """A = [G^T | R_f B_v] (2m x (3 + p)): J q̇ = A Ṡ (eq. 3.1.8)."""
        pose, xi = self.split(S)
        return np.hstack([self.grasp.grasp_matrix(pose, xi).T,
                          self.grasp.surface_rotation(pose, xi) @ self.grasp.sliding_directions()])

    def state(self, S: ArrayLike, S_dot: ArrayLike) -> ReducedState:
        """All the model's quantities at (S, Ṡ); raises SingularFingerError at a singular finger."""
        S, S_dot = as_finite_vectors(("S", "S_dot"), (S, S_dot), self.n)
        return self._state(S, S_dot)

    def _state(self, S: np.ndarray, S_dot: np.ndarray) -> ReducedState:
        """:meth:`state` on validated (n,) arrays."""
        return self.state_from_terms(S, S_dot, self.terms(S.tolist(), S_dot.tolist()))

    def terms(self, s_list: list[float], sd_list: list[float]) -> ReducedTerms:
        r"""The model's quantities at (S, Ṡ) (lists of n floats, not validated) as floats (hot paths; see
        :class:`ReducedTerms`); raises UnreachableError or SingularFingerError as :meth:`state` does.

        Scalar arithmetic (m is 2 or 3: numpy's per-call cost would dominate). Each finger is a planar
        chain of revolute joints about z (validated by :class:`~regrasp.model.finger.Finger`), so its tip
        Jacobian's columns are :math:`e_z \times (p - o_1)` and :math:`e_z \times (p - o_2)` (o_1 joint
        1's axis, o_2 the elbow, p the tip, on its contact point) and :math:`\dot J\dot q = -\dot q_1^2
        (o_2 - o_1) - (\dot q_1 + \dot q_2)^2 (p - o_2)`; M and N come from Pinocchio
        (:meth:`~regrasp.model.hand.Hand.mass_blocks_and_bias`).
        """
        if self.compiled:
            return self._terms_compiled(np.array(s_list), np.array(sd_list))
        grasp, hand, m, n = self.grasp, self.hand, self.grasp.m, self.n
        x, y, beta = s_list[:3]
        vx, vy, omega = sd_list[:3]
        xi, xi_dot = self.xi.tolist(), [0.0] * m
        for i, col in self._sliding_column.items():
            xi[i], xi_dot[i] = s_list[col], sd_list[col]
        c, s = math.cos(beta), math.sin(beta)
        zeros = [0.0] * (n - 3)
        q, q_dot, tips, tip_velocities, a_rows, h_rows, a_dot, jacobians, inverses, frames, elbows = (
            [], [], [], [], [], [], [], [], [], [], [])
        for i, constants in enumerate(grasp.contact_constants):
            if constants is None:  # on a curve: its point and frame at ξ, and its curvature
                cx, cy, nx, ny, kappa = grasp.polygon.local_floats(xi[i])
                tx, ty = -ny, nx
            else:
                ox, oy, tx, ty, nx, ny = constants
                cx, cy = ox + xi[i] * tx, oy + xi[i] * ty
                kappa = 0.0
            rx, ry = c * cx - s * cy, s * cx + c * cy  # lever arm r_i = R c_i(ξ_i)
            nx, ny = c * nx - s * ny, s * nx + c * ny  # surface frame [n_i t_i] = R [n°_i t°_i]
            tx, ty = c * tx - s * ty, s * tx + c * ty
            px, py = x + rx, y + ry  # the contact point, where the tip is
            finger = hand.fingers[i]
            q1, q2, ex, ey = finger.joint_angles(px, py, elbow=True)
            o1x, o1y = finger.joint1_in_hand_floats
            ja, jb, jc, jd = o1y - py, ey - py, px - o1x, px - ex  # J_i = [e_z x (p - o_1), e_z x (p - o_2)]
            det = ja * jd - jb * jc
            i00, i01, i10, i11 = jd / det, -jb / det, -jc / det, ja / det
            # rows 2i, 2i+1 of A = [G^T | R_f B_v]: [I_2 | ⊥r_i | t_i in the column of ξ_i if it slides],
            # and of H = J^-1 A
            row_x, row_y = [1.0, 0.0, -ry, *zeros], [0.0, 1.0, rx, *zeros]
            hx, hy = [i00, i01, i01 * rx - i00 * ry, *zeros], [i10, i11, i11 * rx - i10 * ry, *zeros]
            # q̇_i = H_i Ṡ
            v0 = i00 * vx + i01 * vy + hx[2] * omega
            v1 = i10 * vx + i11 * vy + hy[2] * omega
            col = self._sliding_column.get(i)
            if col is not None:
                row_x[col], row_y[col] = tx, ty
                hx[col], hy[col] = i00 * tx + i01 * ty, i10 * tx + i11 * ty
                v0 += hx[col] * sd_list[col]
                v1 += hy[col] * sd_list[col]
            q += (q1, q2)
            q_dot += (v0, v1)
            tips.append((px, py))
            tip_velocities.append((ja * v0 + jb * v1, jc * v0 + jd * v1))
            elbows.append((o1x, o1y, ex, ey))
            frames.append((nx, ny, tx, ty))
            a_rows += (row_x, row_y)
            h_rows += (hx, hy)
            jacobians.append((ja, jb, jc, jd))
            inverses.append((i00, i01, i10, i11))
            # Ȧ Ṡ = Ġ^T Ẋ + Ṙ_f B_v ξ̇: ω ⊥ṙ_i + ω ξ̇_i ⊥t_i with ṙ_i = ω ⊥r_i + ξ̇_i t_i
            a_dot += (-omega * omega * rx - 2.0 * omega * xi_dot[i] * ty,
                      -omega * omega * ry + 2.0 * omega * xi_dot[i] * tx)
            if kappa and xi_dot[i]:  # on a curve the tangent turns too: t' = κ n, so (d/dt) t ξ̇ gains κ ξ̇² n
                a_dot[-2] += kappa * xi_dot[i] * xi_dot[i] * nx
                a_dot[-1] += kappa * xi_dot[i] * xi_dot[i] * ny
        hand.check_singular_blocks(q, jacobians)
        masses, nonlinear = hand.mass_blocks_and_bias(q, q_dot)
        jdv, h_dot_s_dot = [], []
        for i, ((i00, i01, i10, i11), (px, py), (o1x, o1y, ex, ey)) in enumerate(zip(inverses, tips, elbows)):
            v0, v1 = q_dot[2 * i], q_dot[2 * i + 1]
            w1, w2 = v0 * v0, (v0 + v1) * (v0 + v1)
            j0, j1 = -w1 * (ex - o1x) - w2 * (px - ex), -w1 * (ey - o1y) - w2 * (py - ey)
            jdv += (j0, j1)
            b0, b1 = a_dot[2 * i] - j0, a_dot[2 * i + 1] - j1
            h_dot_s_dot += (i00 * b0 + i01 * b1, i10 * b0 + i11 * b1)  # Ḣ Ṡ = J^-1 (Ȧ Ṡ - J̇ q̇)
        return ReducedTerms(xi, xi_dot, q, q_dot, tips, tip_velocities, a_rows, np.array(h_rows), h_dot_s_dot,
                            jacobians, inverses, masses, nonlinear, jdv, frames)

    def _terms_compiled(self, s: np.ndarray, sd: np.ndarray) -> ReducedTerms:
        """:meth:`terms` from the compiled kernel (:func:`~regrasp.kernels.reduced.reduced_terms`)."""
        fingers, iks, edges, columns = self._kernel_constants
        hand = self.hand
        (status, bad, distance, xi, xi_dot, q, q_dot, tips, tip_vel, a_rows, h_rows, h_dot, jac, inv, mass, nonlinear,
         jdv, frames, conds) = reduced_terms(fingers, iks, edges, hand.gravity_in_hand, hand.damping_enabled, self.xi,
                                             columns, s, sd)
        if status == UNREACHABLE:
            k = iks[bad]
            raise UnreachableError(hand.fingers[bad].name, self._contact_point(s, xi, bad),
                                   float(distance), (float(k["inner"]), float(k["outer"])))
        q_list, jacobians = q.tolist(), jac.tolist()
        if not (conds <= hand.singular_threshold).all():  # (NaN too)
            hand.check_singular_blocks(q_list, jacobians)
        return ReducedTerms(xi.tolist(), xi_dot.tolist(), q_list, q_dot.tolist(), tips.tolist(), tip_vel.tolist(),
                      a_rows.tolist(), h_rows, h_dot.tolist(), jacobians, inv.tolist(), mass.tolist(),
                      nonlinear.tolist(), jdv.tolist(), frames.tolist())

    def _contact_point(self, s: np.ndarray, xi: np.ndarray, i: int) -> np.ndarray:
        """Contact i's point [m] (hand frame) at the pose of S with the contacts at ``xi``."""
        return self.grasp.points(s[:3], xi)[i]

    def state_from_terms(self, S: np.ndarray, S_dot: np.ndarray, terms: ReducedTerms) -> ReducedState:
        """The :class:`ReducedState` at (S, Ṡ) ((n,) arrays, not validated) of their :meth:`terms`."""
        nq = self.hand.nq
        A = np.array(terms.a_rows)
        R_f = self._identity.copy()
        for i in self.grasp.sliding:
            nx, ny, tx, ty = terms.frames[i]
            R_f[2 * i:2 * i + 2, 2 * i:2 * i + 2] = ((nx, tx), (ny, ty))
        mass = np.zeros((nq, nq))
        jacobian = np.zeros((nq, nq))
        for i, ((m00, m01, m11), block) in enumerate(zip(terms.masses, terms.jacobians)):
            mass[2 * i:2 * i + 2, 2 * i:2 * i + 2] = ((m00, m01), (m01, m11))
            jacobian[2 * i:2 * i + 2, 2 * i:2 * i + 2] = np.reshape(block, (2, 2))
        dyn = HandDynamics(mass, np.array(terms.nonlinear), jacobian, np.array(terms.jdv), np.array(terms.tips),
                           np.array(terms.tip_velocities))
        return ReducedState(S, S_dot, np.array(terms.xi), np.array(terms.xi_dot), np.array(terms.q),
                            np.array(terms.q_dot), terms.H, np.array(terms.h_dot_s_dot), A[:, :3].T,
                            R_f, self._bv, dyn)

    # ------------------------------------------------------------------ dynamics
    def mass_matrix(self, st: ReducedState) -> np.ndarray:
        """H^T M H + M_s ((3 + p) square, eq. 3.2.11)."""
        return st.H.T @ st.hand.mass_matrix @ st.H + self.M_s

    def bias(self, st: ReducedState) -> np.ndarray:
        """N_s = H^T M Ḣ Ṡ + H^T N (eq. 3.2.12)."""
        return st.H.T @ (st.hand.mass_matrix @ st.H_dot_S_dot + st.hand.nonlinear)

    def contact_forces(self, st: ReducedState, tau: ArrayLike, S_ddot: ArrayLike) -> np.ndarray:
        r"""Contact forces on the object (m, 2) [N], hand frame: :math:`f = J^{-T}(\tau - M\ddot q - N)`."""
        tau = as_finite_array("tau", tau, (self.hand.nq,))
        q_ddot = st.H @ as_finite_array("S_ddot", S_ddot, (self.n,)) + st.H_dot_S_dot
        f = np.linalg.solve(st.hand.jacobian.T, tau - st.hand.mass_matrix @ q_ddot - st.hand.nonlinear)
        return f.reshape(self.grasp.m, 2)

    def contact_generalized_force(self, st: ReducedState, forces: ArrayLike) -> np.ndarray:
        r"""The generalized force on S of contact forces ``forces`` (m, 2) [N] acting on the object:
        :math:`[0;\ -B_v^T R_f^T f]`: all but the sliding contacts' friction cancel (virtual power)."""
        f = as_finite_array("forces", forces, (self.grasp.m, 2)).reshape(-1)
        out = np.zeros(self.n)
        out[3:] = -(st.B_v.T @ st.R_f.T @ f)
        return out

    def forward_dynamics(self, st: ReducedState, tau: ArrayLike, friction: FrictionLike = DEFAULT_FRICTION, *,
                         signs: ArrayLike | None = None,
                         paper_friction_term: bool = False) -> tuple[np.ndarray, np.ndarray]:
        r"""S̈ and the contact forces (m, 2) [N] for joint torques ``tau`` [N m] and Coulomb friction
        ``friction`` (a :class:`~regrasp.core.contact.Friction` or a coefficient [-] for all contacts, or one
        per contact): the sliding contacts carry their kinetic coefficient μ_k.

        Solves :math:`(H^T M H + M_s)\ddot S + N_s = H^T\tau + [f_g; -f_\xi]` with
        :math:`f_{\xi,j} = \mu_{k,j} s_j n_j^T f_j` and :math:`f = J^{-T}(\tau - M(H\ddot S + \dot H\dot S) - N)`,
        which is linear in :math:`\ddot S`. ``signs`` default to sign(ξ̇) of the sliding contacts
        (which must then be non-zero). ``paper_friction_term=True`` adds the paper's
        :math:`+G R_f B_v f_\xi` to the object rows (eq. 3.2.11 as printed), to show it is wrong.
        """
        tau = as_finite_array("tau", tau, (self.hand.nq,))
        kinetic = [f.kinetic for f in as_frictions(friction, self.grasp.m)]
        p = self.grasp.p
        if signs is None:
            signs = np.sign(st.S_dot[3:])
            if p and any(kinetic[i] > 0 for i in self.grasp.sliding) and np.any(signs == 0):
                raise InvalidParameterError("signs", signs, "a sliding direction: ξ̇ = 0 at a sliding contact")
        signs = as_finite_array("signs", signs, (p,))
        M, J = st.hand.mass_matrix, st.hand.jacobian
        # f(S̈) = f0 - K S̈
        K = np.linalg.solve(J.T, M @ st.H)
        f0 = np.linalg.solve(J.T, tau - M @ st.H_dot_S_dot - st.hand.nonlinear)
        # f_xi = mu_k * s_j * n_j^T f_j = Sn f, row j selects sliding contact j
        frames = self.grasp.surface_frames(st.S[:3], st.xi)
        Sn = np.zeros((p, self.hand.nq))
        for j, i in enumerate(self.grasp.sliding):
            Sn[j, 2 * i:2 * i + 2] = kinetic[i] * signs[j] * frames[i][:, 0]
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

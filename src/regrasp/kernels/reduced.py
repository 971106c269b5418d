r"""The reduced model's terms at (S, Ṡ), compiled: :meth:`regrasp.dynamics.reduced.ReducedModel.terms` in one call.

Per contact i at the object pose (x, y, β) and its ξ: the contact point :math:`p_i = x_o + R(\beta) c_i(\xi_i)`
(where the tip is), the finger's joint angles there (its inverse kinematics in its configuration, as
:meth:`regrasp.model.finger.Finger.inverse_kinematics`), its Jacobian :math:`J_i = [e_z \times (p - o_1),\
e_z \times (p - o_2)]` and inverse, the rows of :math:`A = [G^T \mid R_f B_v]` and of :math:`H = J^{-1} A`
(eq. 3.1.10), :math:`\dot q = H\dot S`, M and N (:func:`~regrasp.kernels.finger.finger_terms`, the
Pinocchio-checked terms), :math:`\dot J\dot q` and :math:`\dot H\dot S = J^{-1}(\dot A\dot S - \dot J\dot q)`
(``docs/derivations.md``; the reference path's docstrings give each formula).

An unreachable contact point is reported, not raised (``status`` 1 with the finger and its distance): the
caller raises :class:`~regrasp.core.exceptions.UnreachableError`; the Jacobians' condition numbers are returned
for the caller's singularity check.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .finger import FINGER_TERMS, condition_2x2, finger_terms_into

__all__ = ["CONTACT_EDGE", "FINGER_IK", "REACHABLE", "UNREACHABLE", "contact_edges", "ik_parameters",
           "reduced_terms"]

_F8 = np.float64

#: A finger's inverse kinematics: joint 1's axis (hand frame) [m], the elbow's sign σ = ±1, the workspace
#: annulus (inner, outer radius and slack) [m], the link lengths [m] and the angle offsets [rad].
FINGER_IK = np.dtype([
    ("ox", _F8), ("oy", _F8), ("sigma", _F8), ("inner", _F8), ("outer", _F8), ("slack", _F8),
    ("l1", _F8), ("l2", _F8), ("psi1_offset", _F8), ("theta2_offset", _F8),
], align=True)

#: A contact's edge (object frame): its ξ origin, ξ direction and inward normal.
CONTACT_EDGE = np.dtype([("ox", _F8), ("oy", _F8), ("tx", _F8), ("ty", _F8), ("nx", _F8), ("ny", _F8)],
                        align=True)

#: ``status`` of :func:`reduced_terms`.
REACHABLE, UNREACHABLE = 0, 1


def ik_parameters(fingers) -> np.ndarray:
    """The (m,) :data:`FINGER_IK` records of :class:`~regrasp.model.finger.Finger` s (their public geometry)."""
    out = np.zeros(len(fingers), dtype=FINGER_IK)
    for i, f in enumerate(fingers):
        l1, l2 = f.link_lengths
        out[i] = (f.joint1_in_hand[0], f.joint1_in_hand[1], -f.configuration.sign, abs(l1 - l2), l1 + l2,
                  1e-12 * (l1 + l2), l1, l2, f.psi1_offset, f.theta2_offset)
    return out


def contact_edges(origins, directions, normals) -> np.ndarray:
    """The (m,) :data:`CONTACT_EDGE` records of the contacts' ξ origins, ξ directions and inward normals."""
    out = np.zeros(len(origins), dtype=CONTACT_EDGE)
    for i, (o, t, n) in enumerate(zip(origins, directions, normals)):
        out[i] = (o[0], o[1], t[0], t[1], n[0], n[1])
    return out


@numba.njit(cache=True)
def _wrap(angle):
    """An angle [rad] wrapped to (-π, π] (:func:`regrasp.core.planar.wrap_angle`)."""
    wrapped = (angle + math.pi) % (2.0 * math.pi) - math.pi
    return math.pi if wrapped == -math.pi else wrapped


@numba.njit(cache=True)
def reduced_terms(fingers, iks, edges, gravity, damped, xi_model, slide_column, s, sd):
    """The reduced model's terms at ``s`` = S, ``sd`` = Ṡ (module docstring). ``xi_model``: every contact's ξ
    (the fixed ones' are used); ``slide_column``: each contact's column of S, or -1 when fixed.

    Returns (status, finger, distance, xi, xi_dot, q, q_dot, tips (m, 2), tip velocities (m, 2), A (2m, n),
    H (2m, n), Ḣ Ṡ (2m), J_i row-major (m, 4), J_i^-1 (m, 4), M_i (m, 3), N (2m), J̇q̇ (2m), surface frames
    (n_x, n_y, t_x, t_y) (m, 4), condition numbers (m))."""
    m = fingers.shape[0]
    n = s.shape[0]
    x, y, beta = s[0], s[1], s[2]
    vx, vy, omega = sd[0], sd[1], sd[2]
    xi = xi_model.copy()
    xi_dot = np.zeros(m)
    for i in range(m):
        if slide_column[i] >= 0:
            xi[i], xi_dot[i] = s[slide_column[i]], sd[slide_column[i]]
    c, sn = math.cos(beta), math.sin(beta)
    q, q_dot = np.zeros(2 * m), np.zeros(2 * m)
    tips, tip_vel = np.zeros((m, 2)), np.zeros((m, 2))
    a_rows, h_rows = np.zeros((2 * m, n)), np.zeros((2 * m, n))
    a_dot, h_dot = np.zeros(2 * m), np.zeros(2 * m)
    jac, inv, mass, frames = np.zeros((m, 4)), np.zeros((m, 4)), np.zeros((m, 3)), np.zeros((m, 4))
    nonlinear, jdv, conds = np.zeros(2 * m), np.zeros(2 * m), np.zeros(m)
    elbows = np.zeros((m, 2))
    status, bad, distance = REACHABLE, -1, 0.0
    for i in range(m):
        e, k = edges[i], iks[i]
        cx, cy = e.ox + xi[i] * e.tx, e.oy + xi[i] * e.ty
        rx, ry = c * cx - sn * cy, sn * cx + c * cy  # lever arm r_i = R c_i(ξ_i)
        nx, ny = c * e.nx - sn * e.ny, sn * e.nx + c * e.ny
        tx, ty = c * e.tx - sn * e.ty, sn * e.tx + c * e.ty
        px, py = x + rx, y + ry
        dx, dy = px - k.ox, py - k.oy
        dist = math.hypot(dx, dy)
        if dist > k.outer + k.slack or dist < k.inner - k.slack:
            status, bad, distance = UNREACHABLE, i, dist
            break
        l1, l2 = k.l1, k.l2
        cos2 = min(max((dist ** 2 - l1 ** 2 - l2 ** 2) / (2.0 * l1 * l2), -1.0), 1.0)
        theta2 = k.sigma * math.acos(cos2)
        psi1 = math.atan2(dy, dx) - math.atan2(l2 * math.sin(theta2), l1 + l2 * math.cos(theta2))
        q[2 * i], q[2 * i + 1] = _wrap(psi1 - k.psi1_offset), _wrap(theta2 - k.theta2_offset)
        ex, ey = k.ox + l1 * math.cos(psi1), k.oy + l1 * math.sin(psi1)
        ja, jb, jc, jd = k.oy - py, ey - py, px - k.ox, px - ex
        det = ja * jd - jb * jc
        i00, i01, i10, i11 = jd / det, -jb / det, -jc / det, ja / det
        r0, r1 = 2 * i, 2 * i + 1
        a_rows[r0, 0], a_rows[r0, 2] = 1.0, -ry
        a_rows[r1, 1], a_rows[r1, 2] = 1.0, rx
        h_rows[r0, 0], h_rows[r0, 1], h_rows[r0, 2] = i00, i01, i01 * rx - i00 * ry
        h_rows[r1, 0], h_rows[r1, 1], h_rows[r1, 2] = i10, i11, i11 * rx - i10 * ry
        v0 = i00 * vx + i01 * vy + h_rows[r0, 2] * omega
        v1 = i10 * vx + i11 * vy + h_rows[r1, 2] * omega
        col = slide_column[i]
        if col >= 0:
            a_rows[r0, col], a_rows[r1, col] = tx, ty
            h_rows[r0, col], h_rows[r1, col] = i00 * tx + i01 * ty, i10 * tx + i11 * ty
            v0 += h_rows[r0, col] * sd[col]
            v1 += h_rows[r1, col] * sd[col]
        q_dot[r0], q_dot[r1] = v0, v1
        tips[i, 0], tips[i, 1] = px, py
        tip_vel[i, 0], tip_vel[i, 1] = ja * v0 + jb * v1, jc * v0 + jd * v1
        elbows[i, 0], elbows[i, 1] = ex, ey
        frames[i, 0], frames[i, 1], frames[i, 2], frames[i, 3] = nx, ny, tx, ty
        jac[i, 0], jac[i, 1], jac[i, 2], jac[i, 3] = ja, jb, jc, jd
        inv[i, 0], inv[i, 1], inv[i, 2], inv[i, 3] = i00, i01, i10, i11
        conds[i] = condition_2x2(ja, jb, jc, jd)
        # Ȧ Ṡ = Ġ^T Ẋ + Ṙ_f B_v ξ̇
        a_dot[r0] = -omega * omega * rx - 2.0 * omega * xi_dot[i] * ty
        a_dot[r1] = -omega * omega * ry + 2.0 * omega * xi_dot[i] * tx
    if status == REACHABLE:
        terms = np.empty(m, dtype=FINGER_TERMS)
        for i in range(m):
            r0, r1 = 2 * i, 2 * i + 1
            finger_terms_into(fingers[i], q[r0], q[r1], q_dot[r0], q_dot[r1], gravity[0], gravity[1], damped, terms[i])
            t = terms[i]
            mass[i, 0], mass[i, 1], mass[i, 2] = t.m00, t.m01, t.m11
            nonlinear[r0], nonlinear[r1] = t.n0, t.n1
            v0, v1 = q_dot[r0], q_dot[r1]
            w1, w2 = v0 * v0, (v0 + v1) * (v0 + v1)
            k = iks[i]
            ex, ey, px, py = elbows[i, 0], elbows[i, 1], tips[i, 0], tips[i, 1]
            j0, j1 = -w1 * (ex - k.ox) - w2 * (px - ex), -w1 * (ey - k.oy) - w2 * (py - ey)
            jdv[r0], jdv[r1] = j0, j1
            b0, b1 = a_dot[r0] - j0, a_dot[r1] - j1
            h_dot[r0] = inv[i, 0] * b0 + inv[i, 1] * b1  # Ḣ Ṡ = J^-1 (Ȧ Ṡ - J̇ q̇)
            h_dot[r1] = inv[i, 2] * b0 + inv[i, 3] * b1
    return (status, bad, distance, xi, xi_dot, q, q_dot, tips, tip_vel, a_rows, h_rows, h_dot, jac, inv, mass,
            nonlinear, jdv, frames, conds)

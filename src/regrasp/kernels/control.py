r"""The computed-torque control step, compiled: :class:`regrasp.dynamics.control.ComputedTorqueController` in one call.

For the laws whose friction estimate does not depend on the state (the fixed-contact law and Proposition 1,
:math:`\hat f_\xi` given), one call does what the reference path does in Python around the reduced model's
terms (:func:`.reduced.reduced_terms`, called from here):

.. math::
    a = \ddot S_d + K_v \dot E + K_s E, \quad \tau_m = (H^T)^+\left[(H^T M H + M_s) a + N_s
    - [f_g; -\hat f_\xi]\right],\quad f_m = J^{-T}(\tau_m - M \ddot q - N),

with :math:`\ddot q = H a + \dot H \dot S` (:func:`regrasp.dynamics.control._computed_torque`, the paper's (3.2.12)
as corrected in ``docs/derivations.md``), then the internal force (:func:`.force.internal_force_into`),
:math:`\tau = \tau_m + J^T f_c` (the QP keeping every :math:`|\tau_j|` within the finger records' ``effort``),
the predicted forces in each surface frame and their cone margins
:math:`\mu f_n - |f_t|`. Anything but the plain case (an unreachable contact, a finger near a singularity, a
QP the kernel does not settle) is reported, and the caller takes the reference path, which raises or falls
back exactly as before. :func:`sliding_step_into` is Proposition 3 with m > 2 (the sliders on their kinetic
cone edges, the QP in the null space of those equations). ``tests/kernels/test_control.py`` checks the outputs
against the reference paths.
"""

from __future__ import annotations

import numba
import numpy as np

from .force import FORCE_SOLVED, internal_force_into
from .qp import back_substitute, matmul, matvec
from .reduced import REACHABLE, reduced_terms

__all__ = ["CONTROL_OK", "CONTROL_REFERENCE", "control_layout", "control_step_into", "sliding_step_into"]

#: statuses of :func:`control_step_into`: OK, or REFERENCE (the caller takes the reference path)
CONTROL_OK, CONTROL_REFERENCE = 0, 1


def control_layout(m: int, n: int) -> dict[str, slice]:
    """Where each output lies in the ``out`` of :func:`control_step_into` and :func:`sliding_step_into` (m
    contacts, n reduced coordinates): τ (2m), the command a, E, Ė (n each), f (2m, hand frame), (f_n, f_t) per
    contact (2m), the cone margins (m), f_c (2m), the sliding law's f̂_ξ (n - 3); the last entry's ``stop`` is
    the size."""
    sizes = (("tau", 2 * m), ("command", n), ("error", n), ("error_rate", n), ("forces", 2 * m),
             ("surface", 2 * m), ("margins", m), ("f_c", 2 * m), ("f_hat", n - 3))
    layout, start = {}, 0
    for name, size in sizes:
        layout[name] = slice(start, start + size)
        start += size
    return layout


@numba.njit(cache=True)
def _solve_spd(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a⁻¹ b for a symmetric positive definite a (n, n), by Cholesky in loops; empty if a is not (numerically)
    positive definite."""
    n = a.shape[0]
    low = np.zeros((n, n))
    for j in range(n):
        d = a[j, j]
        for k in range(j):
            d -= low[j, k] * low[j, k]
        if not d > 1e-13 * abs(a[j, j]) or d <= 0.0:
            return np.empty(0)
        low[j, j] = np.sqrt(d)
        for i in range(j + 1, n):
            acc = a[i, j]
            for k in range(j):
                acc -= low[i, k] * low[j, k]
            low[i, j] = acc / low[j, j]
    y = np.empty(n)
    for i in range(n):
        acc = b[i]
        for k in range(i):
            acc -= low[i, k] * y[k]
        y[i] = acc / low[i, i]
    return back_substitute(low.T, y)


@numba.njit(cache=True)
def _begin(fingers, iks, edges, gravity, damped, xi_model, slide_column, s, sd, s_d, s_d_dot, s_d_ddot, kv, ks,
           singular_threshold, out):
    """The reduced terms and the law's command, E and Ė (written into ``out``); ``ok`` False where the
    reference path must answer (an unreachable contact, a finger near a singularity)."""
    m, n = fingers.shape[0], s.shape[0]
    (status, _, _, _, _, _, _, _, _, a_rows, h_rows, h_dot, jac, inv, mass, nonlinear, _, frames,
     conds) = reduced_terms(fingers, iks, edges, gravity, damped, xi_model, slide_column, s, sd)
    ok = status == REACHABLE
    for i in range(m):
        if not conds[i] <= singular_threshold:
            ok = False
    command = np.empty(n)
    o_cmd, o_err, o_rate = 2 * m, 2 * m + n, 2 * m + 2 * n
    for j in range(n):
        e, r = s_d[j] - s[j], s_d_dot[j] - sd[j]
        out[o_err + j], out[o_rate + j] = e, r
        command[j] = s_d_ddot[j] + kv[j] * r + ks[j] * e
        out[o_cmd + j] = command[j]
    return ok, a_rows, h_rows, h_dot, jac, inv, mass, nonlinear, frames, command


@numba.njit(cache=True)
def _wrench(h_rows, h_dot, mass, nonlinear, command):
    """M q̈ + N with q̈ = H a + Ḣ Ṡ (M block diagonal, per finger (m00, m01, m11))."""
    m2 = h_rows.shape[0]
    q_ddot = matvec(h_rows, command)
    wrench = np.empty(m2)
    for i in range(m2 // 2):
        a0, a1 = q_ddot[2 * i] + h_dot[2 * i], q_ddot[2 * i + 1] + h_dot[2 * i + 1]
        m00, m01, m11 = mass[i, 0], mass[i, 1], mass[i, 2]
        wrench[2 * i] = m00 * a0 + m01 * a1 + nonlinear[2 * i]
        wrench[2 * i + 1] = m01 * a0 + m11 * a1 + nonlinear[2 * i + 1]
    return wrench


@numba.njit(cache=True)
def _add_jt(tau, jac, forces):
    """τ + Jᵀ f per finger (J_i row-major (a, b, c, d)), in place."""
    for i in range(tau.shape[0] // 2):
        f0, f1 = forces[2 * i], forces[2 * i + 1]
        tau[2 * i] += jac[i, 0] * f0 + jac[i, 2] * f1
        tau[2 * i + 1] += jac[i, 1] * f0 + jac[i, 3] * f1


@numba.njit(cache=True)
def _finish(tau, forces, f_c, frames, margin_mu, n, out):
    """τ, f, f_c, the surface forces and the cone margins into ``out`` (:func:`control_layout`)."""
    m2 = tau.shape[0]
    m = m2 // 2
    o_forces = m2 + 3 * n
    o_surface, o_margins = o_forces + m2, o_forces + 2 * m2
    o_fc = o_margins + m
    for i in range(m):
        fx, fy = forces[2 * i], forces[2 * i + 1]
        f_n = frames[i, 0] * fx + frames[i, 1] * fy
        f_t = frames[i, 2] * fx + frames[i, 3] * fy
        out[o_surface + 2 * i], out[o_surface + 2 * i + 1] = f_n, f_t
        out[o_margins + i] = margin_mu[i] * f_n - abs(f_t)
    for i in range(m2):
        out[i] = tau[i]
        out[o_forces + i] = forces[i]
        out[o_fc + i] = f_c[i]


@numba.njit(cache=True)
def _effort(fingers):
    """The joints' torque limits (2m) [N m] of the fingers' records (inf: none)."""
    effort = np.empty(2 * fingers.shape[0])
    for i in range(fingers.shape[0]):
        effort[2 * i], effort[2 * i + 1] = fingers[i].effort1, fingers[i].effort2
    return effort


@numba.njit(cache=True)
def _internal_force(use_qp, A, f_m, frames, coefficients, lower, n_ineq, is_cone, target, margin_column, weight,
                    aim, jac, wrench, fingers):
    """(whether settled, k, the QP's cone margin, f_c, f = f_m + f_c): the internal force of
    :func:`.force.internal_force_into` in the null space of Aᵀ, within the fingers' joint torque limits
    (τ = ``wrench`` + Jᵀ f), or none (f = f_m) without ``use_qp``."""
    f_c = np.zeros(f_m.size)
    forces = f_m.copy()
    if not use_qp:
        return True, 0, np.nan, f_c, forces
    status, k, margin = internal_force_into(A, f_m, frames, coefficients, lower, n_ineq, is_cone, target,
                                            margin_column, weight, aim, jac, wrench, _effort(fingers), f_c, forces)
    return status == FORCE_SOLVED, k, margin, f_c, forces


@numba.njit(cache=True)
def control_step_into(fingers, iks, edges, gravity, damped, xi_model, slide_column, s, sd, s_d, s_d_dot, s_d_ddot,
                      kv, ks, m_s_diagonal, object_mass, f_hat, singular_threshold, margin_mu, use_qp, coefficients,
                      lower, n_ineq, is_cone, target, margin_column, weight, aim, out):
    r"""One control step into ``out`` (:func:`control_layout`); returns (status, k, the QP's cone margin [N]).

    ``fingers`` .. ``sd``: :func:`.reduced.reduced_terms`'s arguments; ``s_d``, ``s_d_dot``, ``s_d_ddot``: the
    desired S and its rates; ``kv``, ``ks``: the gains (n); ``m_s_diagonal``: diag(M_s) (the object's mass,
    mass, inertia, then zeros); ``f_hat``: :math:`\hat f_\xi` (p) [N]; ``singular_threshold``: the largest
    finger-Jacobian condition number served here; ``margin_mu``: μ per contact (μ_s fixed, μ_k sliding);
    ``use_qp`` and the rest: the internal force (:func:`.force.internal_force_into`'s row arguments).
    """
    n = s.shape[0]
    ok, a_rows, h_rows, h_dot, jac, inv, mass, nonlinear, frames, command = _begin(
        fingers, iks, edges, gravity, damped, xi_model, slide_column, s, sd, s_d, s_d_dot, s_d_ddot, kv, ks,
        singular_threshold, out)
    if not ok:
        return CONTROL_REFERENCE, 0, np.nan
    m2 = h_rows.shape[0]
    wrench = _wrench(h_rows, h_dot, mass, nonlinear, command)
    rhs = matvec(h_rows, wrench, True)
    for j in range(n):
        rhs[j] += m_s_diagonal[j] * command[j]
    rhs[0] -= object_mass * gravity[0]
    rhs[1] -= object_mass * gravity[1]
    for j in range(3, n):
        rhs[j] += f_hat[j - 3]
    x = _solve_spd(matmul(h_rows, h_rows, True), rhs)
    if x.size == 0:
        return CONTROL_REFERENCE, 0, np.nan  # (HᵀH singular: the reference path raises)
    tau = matvec(h_rows, x)
    f_m = np.empty(m2)
    for i in range(m2 // 2):  # f = J^-T (τ - M q̈ - N)
        d0, d1 = tau[2 * i] - wrench[2 * i], tau[2 * i + 1] - wrench[2 * i + 1]
        f_m[2 * i] = inv[i, 0] * d0 + inv[i, 2] * d1
        f_m[2 * i + 1] = inv[i, 1] * d0 + inv[i, 3] * d1
    solved, k, qp_margin, f_c, forces = _internal_force(use_qp, a_rows, f_m, frames, coefficients, lower, n_ineq,
                                                        is_cone, target, margin_column, weight, aim, jac, wrench,
                                                        fingers)
    if not solved:
        return CONTROL_REFERENCE, k, qp_margin
    if use_qp:
        _add_jt(tau, jac, f_c)
    _finish(tau, forces, f_c, frames, margin_mu, n, out)
    return CONTROL_OK, k, qp_margin


@numba.njit(cache=True)
def sliding_step_into(fingers, iks, edges, gravity, damped, xi_model, slide_column, s, sd, s_d, s_d_dot, s_d_ddot,
                      kv, ks, m_o_diagonal, object_mass, sliders, kinetic, directions, reversible, sample_time,
                      singular_threshold, margin_mu, use_qp, coefficients, lower, n_ineq, is_cone, target,
                      margin_column, weight, aim, out):
    r"""One step of Proposition 3 with m > 2 (:meth:`regrasp.dynamics.laws.Proposition3Controller.distributed_torque`)
    into ``out`` (:func:`control_layout`); returns (status, k, the QP's cone margin [N]).

    The sliders' directions :math:`s_j` (``directions``, updated in place as the reference path does: the sign
    of ξ̇ over the next ``sample_time`` [s], unless ``reversible`` is False), the equations
    :math:`G f = M_o a_X - f_g`, :math:`(t_j - s_j\mu_{k,j}n_j)^T f_j = 0` (``sliders``: the sliding contacts,
    ``kinetic``: their μ_k), their least-norm solution :math:`f_p`, the internal force in their null space,
    :math:`\tau = M(Ha + \dot H\dot S) + N + J^T f` and :math:`\hat f_\xi = (t_j^T f_j)_j`. The other arguments
    as :func:`control_step_into` (``m_o_diagonal``: the object's mass, mass and inertia).
    """
    n = s.shape[0]
    ok, a_rows, h_rows, h_dot, jac, inv, mass, nonlinear, frames, command = _begin(
        fingers, iks, edges, gravity, damped, xi_model, slide_column, s, sd, s_d, s_d_dot, s_d_ddot, kv, ks,
        singular_threshold, out)
    if not ok:
        return CONTROL_REFERENCE, 0, np.nan
    m2 = h_rows.shape[0]
    if reversible:
        for c in range(sliders.size):
            xi_dot, xi_ddot = sd[3 + c], command[3 + c]
            after = xi_dot + xi_ddot * sample_time
            if xi_dot * after <= 0.0 and xi_ddot != 0.0:
                directions[c] = 1.0 if xi_ddot > 0.0 else -1.0
            elif xi_dot != 0.0:
                directions[c] = 1.0 if xi_dot > 0.0 else -1.0
    edge = a_rows.copy()
    edge[:, 3:] = 0.0
    for c in range(sliders.size):
        j = sliders[c]
        mu = directions[c] * kinetic[c]
        edge[2 * j, 3 + c] = frames[j, 2] - mu * frames[j, 0]
        edge[2 * j + 1, 3 + c] = frames[j, 3] - mu * frames[j, 1]
    rhs = np.zeros(n)
    for j in range(3):
        rhs[j] = m_o_diagonal[j] * command[j]
    rhs[0] -= object_mass * gravity[0]
    rhs[1] -= object_mass * gravity[1]
    x = _solve_spd(matmul(edge, edge, True), rhs)
    if x.size == 0:
        return CONTROL_REFERENCE, 0, np.nan
    particular = matvec(edge, x)  # the least-norm f_p
    tau = _wrench(h_rows, h_dot, mass, nonlinear, command)
    solved, k, qp_margin, f_c, forces = _internal_force(use_qp, edge, particular, frames, coefficients, lower,
                                                        n_ineq, is_cone, target, margin_column, weight, aim, jac, tau,
                                                        fingers)
    if not solved:
        return CONTROL_REFERENCE, k, qp_margin
    _add_jt(tau, jac, forces)
    _finish(tau, forces, f_c, frames, margin_mu, n, out)
    o_hat = 4 * m2 + 3 * n + m2 // 2
    for c in range(sliders.size):
        j = sliders[c]
        out[o_hat + c] = frames[j, 2] * forces[2 * j] + frames[j, 3] * forces[2 * j + 1]
    return CONTROL_OK, k, qp_margin

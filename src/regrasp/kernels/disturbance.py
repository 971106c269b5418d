r"""A run's disturbance in compiled code: :class:`regrasp.plants.disturbance.Disturbance`'s ``measure`` and ``actuate``
on a step's drawn standard normals (:meth:`~regrasp.plants.disturbance.Disturbance.stretch_noise`), with the slip
sensor's and the actuation delay's deques as arrays, oldest first, for :func:`.stretch.stretch_into`. The same
arithmetic as the reference (numpy's ``normal(loc, scale)`` is ``loc + scale`` times the next standard normal);
``tests/rollout/test_stretch.py`` runs noisy rollouts both ways.
"""

from __future__ import annotations

import math

import numba

from .arrays import copy_into
from .plant import SLIDING

__all__ = ["actuate_into", "measure_into"]


@numba.njit(cache=True)
def measure_into(settings, st, contacts, y, last, xi, z, slips, slips_new, X_m, V_m, xi_m, xi_dot_m, fn_m, ft_m,
             slides_m):
    """What the controller senses (:meth:`regrasp.plants.disturbance.Disturbance.measure`, the same arithmetic): the
    truth plus each drawn term, the slip sensor's oldest reading; the slip deque's new length."""
    m = xi.shape[0]
    size = y.shape[0]
    n2 = 2 * m
    for a in range(3):
        X_m[a], V_m[a] = y[2 * n2 + a], y[2 * n2 + 3 + a]
    for i in range(m):
        xi_m[i], xi_dot_m[i] = xi[i], last[size + 7 * m + i]
        fn_m[i], ft_m[i] = last[size + 2 * i], last[size + 2 * i + 1]
        slides_m[i] = contacts[i].mode == SLIDING
    if not settings.sensed:
        return st.slips
    depth = slips.shape[0]
    count = st.slips
    copy_into(slips_new, slips)
    if count == depth:  # (a full deque drops its oldest)
        for d in range(depth - 1):
            copy_into(slips_new[d], slips_new[d + 1])
        count -= 1
    for i in range(m):
        if math.isnan(settings.slip_threshold):
            slips_new[count, i] = slides_m[i]
        else:
            slips_new[count, i] = abs(xi_dot_m[i]) > settings.slip_threshold
    count += 1
    for i in range(m):
        slides_m[i] = slips_new[0, i]
    sigma = (settings.position, settings.position, settings.angle)
    if settings.o_pose >= 0:
        for a in range(3):
            X_m[a] = X_m[a] + (0.0 + 1.0 * z[settings.o_pose + a]) * sigma[a]
    else:
        for a in range(3):
            X_m[a] = X_m[a] + 0.0
    sigma = (settings.velocity, settings.velocity, settings.angular_velocity)
    if settings.o_twist >= 0:
        for a in range(3):
            V_m[a] = V_m[a] + (0.0 + 1.0 * z[settings.o_twist + a]) * sigma[a]
    for i in range(m):
        if settings.o_normal >= 0:
            fn_m[i] = fn_m[i] + (0.0 + settings.force_sigma * z[settings.o_normal + i])
        if settings.o_xi >= 0:
            xi_m[i] = xi_m[i] + (0.0 + settings.xi_sigma * z[settings.o_xi + i])
        if settings.o_xi_dot >= 0:
            xi_dot_m[i] = xi_dot_m[i] + (0.0 + settings.xi_dot_sigma * z[settings.o_xi_dot + i])
        if settings.o_friction >= 0:
            ft_m[i] = ft_m[i] + (0.0 + settings.force_sigma * z[settings.o_friction + i])
    return count


@numba.njit(cache=True)
def actuate_into(settings, st, tau, z, commands, commands_new, applied):
    """The torques the plant gets (:meth:`regrasp.plants.disturbance.Disturbance.actuate`: the command of ``delay``
    steps ago, plus the drawn noise); the command deque's new length."""
    n2 = tau.shape[0]
    if not settings.delayed:
        copy_into(applied, tau)
        return st.commands
    depth = commands.shape[0]
    count = st.commands
    copy_into(commands_new, commands)
    if count == 0:  # (before the run the hand held the first command)
        for d in range(depth - 1):
            copy_into(commands_new[d], tau)
        count = depth - 1
    if count == depth:
        for d in range(depth - 1):
            copy_into(commands_new[d], commands_new[d + 1])
        count -= 1
    copy_into(commands_new[count], tau)
    count += 1
    copy_into(applied, commands_new[0])
    if settings.o_torque >= 0:
        for j in range(n2):
            applied[j] = applied[j] + (0.0 + settings.torque_sigma * z[settings.o_torque + j])
    return count

r"""The full-coordinate plant's step, compiled: the same equations as :class:`~regrasp.plants.project.plant.Plant`'s
reference path (its module docstring), in one call per step.

Per evaluation: the fingers' terms (:func:`~regrasp.kernels.finger.finger_terms`), every active contact's
constraint rows with their Baumgarte right-hand sides and force columns, the Delassus system
:math:`C M^{-1} W \lambda = b - C M^{-1}(\tau - N, f_g)` (``np.linalg.solve``), then
:math:`\ddot q`, :math:`\ddot X` and the powers of the torques, the damping and the contact forces.
A step is classical RK4 over the state ``y = (q, v, X, V, works)``, then one evaluation at its end,
which gives what the event checks read: each contact's surface force (normal, tangential), its ξ and
ξ̇, and the largest constraint violation.

Contacts are :data:`PLANT_CONTACT` records: the mode (:data:`FIXED`, :data:`SLIDING`,
:data:`SEPARATED`), a fixed contact's ξ, a sliding one's direction s, μ_k, and the edge's inward normal
n, ξ direction t, ξ origin o, n·o and ξ range (object frame). The plant's constants are one
:data:`PLANT_PARAMETERS` record.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .finger import FINGER_TERMS, condition_2x2, finger_terms_into
from .lapack import checked_fortran_copy, gesv

__all__ = ["FIXED", "PLANT_CONTACT", "PLANT_PARAMETERS", "SATURATION_TOLERANCE", "SEPARATED", "SLIDING", "output_size",
           "plant_evaluate", "plant_step_into"]

_F8 = np.float64

#: Contact modes as the kernels' integers (:class:`~regrasp.core.contact.ContactMode` in Python).
FIXED, SLIDING, SEPARATED = 0, 1, 2

#: One contact: its mode, ξ [m] (fixed), s = ±1 (sliding), μ_s and μ_k [-], and its edge (object frame).
PLANT_CONTACT = np.dtype([
    ("mode", np.int64), ("xi", _F8), ("sign", _F8), ("mu_static", _F8), ("mu_kinetic", _F8),
    ("nx", _F8), ("ny", _F8), ("tx", _F8), ("ty", _F8), ("ox", _F8), ("oy", _F8), ("offset", _F8),
    ("lo", _F8), ("hi", _F8),
], align=True)

#: The plant's constants: object mass [kg] and inertia [kg m^2], gravity [m/s^2] (hand frame), the
#: Baumgarte α [1/s], whether N has the joints' damping, the step [s], whether contacts switch modes
#: (separation, slip, stick) and the condition number of a tip Jacobian above which a finger is singular.
PLANT_PARAMETERS = np.dtype([
    ("mass", _F8), ("inertia", _F8), ("gx", _F8), ("gy", _F8), ("alpha", _F8), ("damped", np.bool_), ("dt", _F8),
    ("contact_events", np.bool_), ("singular_threshold", _F8),
], align=True)

#: The tolerance [N] of the separation and slip tests (the reference path's).
_TOL = 1e-9
#: A torque that exceeds its limit by at most this [relative to max(1, limit)] is clipped but not called saturated:
#: a controller that keeps the limit puts its torque on it up to round-off (:mod:`regrasp.plants.saturation`).
SATURATION_TOLERANCE = 1e-9


@numba.njit(cache=True)
def _solve(a, b):
    """``np.linalg.solve(a, b)`` for a (k, k) and b (k,) (LAPACK's ``dgesv``, :func:`~regrasp.kernels.lapack.gesv`,
    as numba's ``solve`` calls it, without compiling numba's general ``solve``: about 2 s of a cold compile): its
    answer, and its ``LinAlgError`` for a non-finite or singular a."""
    n = b.size
    fortran = np.empty((n, n))  # (a's copy in Fortran order: fortran.T; dgesv destroys it)
    x = np.empty(n)
    checked_fortran_copy(a, b, fortran, x)
    if n > 0 and gesv(fortran, x) != 0:
        raise np.linalg.LinAlgError("Matrix is singular to machine precision.")
    return x


@numba.njit(cache=True)
def _evaluate(fingers, plant, contacts, y, tau, terms, dy, forces):
    """dy/dt of the flat state ``y`` into ``dy``, the contact forces on the object (m, 2, hand frame) into
    ``forces`` and the fingers' terms into ``terms``."""
    m = fingers.shape[0]
    n = 2 * m
    x, yo, beta = y[2 * n], y[2 * n + 1], y[2 * n + 2]
    vx, vy, w = y[2 * n + 3], y[2 * n + 4], y[2 * n + 5]
    gx, gy = plant.gx, plant.gy
    for i in range(m):
        finger_terms_into(fingers[i], y[2 * i], y[2 * i + 1], y[n + 2 * i], y[n + 2 * i + 1], gx, gy, plant.damped,
                          terms[i])
    # per finger: τ - N and the tip's free acceleration J M^-1 (τ - N) + J̇q̇ - g
    res = np.empty((m, 2))
    acc = np.empty((m, 2))
    for i in range(m):
        t = terms[i]
        r0, r1 = tau[2 * i] - t.n0, tau[2 * i + 1] - t.n1
        u0, u1 = t.i00 * r0 + t.i01 * r1, t.i01 * r0 + t.i11 * r1
        res[i, 0], res[i, 1] = r0, r1
        acc[i, 0] = t.j00 * u0 + t.j01 * u1 + t.jdx - gx
        acc[i, 1] = t.j10 * u0 + t.j11 * u1 + t.jdy - gy
    c, s = math.cos(beta), math.sin(beta)
    a2, asq, wsq = 2.0 * plant.alpha, plant.alpha * plant.alpha, w * w
    # rows: finger, d (2), c (3); columns: f (2), o (3); at most two per contact
    finger_of = np.empty(n, np.int64)
    row = np.empty((n, 5))
    col = np.empty((n, 5))
    rhs = np.empty(n)
    k = 0
    for i in range(m):
        ct = contacts[i]
        if ct.mode == SEPARATED:
            continue
        t = terms[i]
        rx, ry = t.px - x, t.py - yo
        if ct.mode == FIXED:
            ux, uy = ct.ox + ct.xi * ct.tx, ct.oy + ct.xi * ct.ty
            rcx, rcy = c * ux - s * uy, s * ux + c * uy
            finger_of[k], finger_of[k + 1] = i, i
            row[k, 0], row[k, 1], row[k, 2], row[k, 3], row[k, 4] = 1.0, 0.0, -1.0, 0.0, rcy
            row[k + 1, 0], row[k + 1, 1], row[k + 1, 2], row[k + 1, 3], row[k + 1, 4] = 0.0, 1.0, 0.0, -1.0, -rcx
            rhs[k] = -wsq * rcx - a2 * (t.vx - vx + w * rcy) - asq * (rx - rcx) - acc[i, 0]
            rhs[k + 1] = -wsq * rcy - a2 * (t.vy - vy - w * rcx) - asq * (ry - rcy) - acc[i, 1]
            col[k, 0], col[k, 1], col[k, 2], col[k, 3], col[k, 4] = 1.0, 0.0, 1.0, 0.0, -ry
            col[k + 1, 0], col[k + 1, 1], col[k + 1, 2], col[k + 1, 3], col[k + 1, 4] = 0.0, 1.0, 0.0, 1.0, rx
            k += 2
        else:
            nx, ny = c * ct.nx - s * ct.ny, s * ct.nx + c * ct.ny
            nr, tr = nx * rx + ny * ry, nx * ry - ny * rx
            rvx, rvy = t.vx - vx, t.vy - vy
            psi_dot = w * tr + (nx * rvx + ny * rvy)
            drift = -wsq * nr + 2.0 * w * (nx * rvy - ny * rvx)
            finger_of[k] = i
            row[k, 0], row[k, 1], row[k, 2], row[k, 3], row[k, 4] = nx, ny, -nx, -ny, tr
            rhs[k] = -drift - a2 * psi_dot - asq * (nr - ct.offset) - (nx * acc[i, 0] + ny * acc[i, 1])
            mus = ct.mu_kinetic * ct.sign
            fx, fy = nx - mus * ny, ny + mus * nx
            col[k, 0], col[k, 1], col[k, 2], col[k, 3], col[k, 4] = fx, fy, fx, fy, rx * fy - ry * fx
            k += 1
    for i in range(m):
        forces[i, 0] = 0.0
        forces[i, 1] = 0.0
    o0 = o1 = o2 = 0.0
    if k > 0:
        im, ii = 1.0 / plant.mass, 1.0 / plant.inertia
        a = np.empty((k, k))
        for r in range(k):
            t = terms[finger_of[r]]
            dx, dy_ = row[r, 0], row[r, 1]
            ux, uy = dx * t.l00 + dy_ * t.l01, dx * t.l01 + dy_ * t.l11
            for q in range(k):
                value = row[r, 2] * im * col[q, 2] + row[r, 3] * im * col[q, 3] + row[r, 4] * ii * col[q, 4]
                if finger_of[q] == finger_of[r]:
                    value -= ux * col[q, 0] + uy * col[q, 1]
                a[r, q] = value
        lam = _solve(a, rhs[:k])
        for q in range(k):
            i = finger_of[q]
            forces[i, 0] += col[q, 0] * lam[q]
            forces[i, 1] += col[q, 1] * lam[q]
            o0 += col[q, 2] * lam[q]
            o1 += col[q, 3] * lam[q]
            o2 += col[q, 4] * lam[q]
    torque = damp = power = 0.0
    for i in range(m):
        t = terms[i]
        fx, fy = forces[i, 0], forces[i, 1]
        r0, r1 = res[i, 0] - (t.j00 * fx + t.j10 * fy), res[i, 1] - (t.j01 * fx + t.j11 * fy)
        u0, u1 = y[n + 2 * i], y[n + 2 * i + 1]
        dy[2 * i], dy[2 * i + 1] = u0, u1
        dy[n + 2 * i], dy[n + 2 * i + 1] = t.i00 * r0 + t.i01 * r1, t.i01 * r0 + t.i11 * r1
        torque += tau[2 * i] * u0 + tau[2 * i + 1] * u1
        if plant.damped:
            damp -= fingers[i].damping1 * u0 * u0 + fingers[i].damping2 * u1 * u1
        if fx != 0.0 or fy != 0.0:
            rx, ry = t.px - x, t.py - yo
            power += fx * (vx - w * ry - t.vx) + fy * (vy + w * rx - t.vy)
    dy[2 * n], dy[2 * n + 1], dy[2 * n + 2] = vx, vy, w
    dy[2 * n + 3], dy[2 * n + 4], dy[2 * n + 5] = gx + o0 / plant.mass, gy + o1 / plant.mass, o2 / plant.inertia
    dy[2 * n + 6], dy[2 * n + 7], dy[2 * n + 8] = torque, damp, power


@numba.njit(cache=True)
def plant_evaluate(fingers, plant, contacts, y, tau):
    """(dy/dt, forces (m, 2) on the object, the fingers' terms) at the flat state ``y`` (2n + 9: q, v, X, V,
    the works) for torques ``tau``."""
    m = fingers.shape[0]
    terms = np.empty(m, dtype=FINGER_TERMS)
    dy = np.empty(y.shape[0])
    forces = np.empty((m, 2))
    _evaluate(fingers, plant, contacts, y, tau, terms, dy, forces)
    return dy, forces, terms


@numba.njit(cache=True)
def _surface(ct, c, s, fx, fy):
    """A force on the object (hand frame) in the contact's surface frame (normal, tangential)."""
    return ((c * ct.nx - s * ct.ny) * fx + (s * ct.nx + c * ct.ny) * fy,
            (c * ct.tx - s * ct.ty) * fx + (s * ct.tx + c * ct.ty) * fy)


def output_size(m: int) -> int:
    """The length of :func:`plant_step_into`'s ``out`` for m fingers: the new state (4m + 9), then (m, 2) each
    of the start's surface forces, the end's forces and the end's surface forces, then (m,) each of ξ and ξ̇."""
    return 4 * m + 9 + 8 * m


@numba.njit(cache=True)
def plant_step_into(fingers, plant, contacts, y, tau, certificates, radii, out, terms, needs_coal, posture):
    """One RK4 step of ``plant.dt`` from the flat state ``y`` with constant torques ``tau`` saturated at the joints'
    limits (clip(τ, -effort, effort), the finger records' ``effort1``, ``effort2``), written into
    ``out`` (:func:`output_size`: the new state, the surface forces (normal, tangential) at the step's start
    (its first stage, at the start pose), and at its end the forces on the object (hand frame), their surface
    components, every contact's ξ [m] and ξ̇ [m/s] on its edge's line), ``terms`` (the fingers' terms at the
    end), ``needs_coal`` and ``posture``.

    ``certificates`` (m, 9) and ``radii`` (m, 2) are the collision check's (see
    :meth:`regrasp.plants.project.plant.Plant._collisions`; a NaN row: none): ``needs_coal`` says which fingers' links
    may have reached the object since their certificate, ``posture`` each finger's (q_1, q_2, β, joint 1 and the elbow
    in the object frame: a new certificate's first seven entries).

    Returns the largest violation [m] of the active constraints, whether an event may have happened (a contact
    that separates, slips, may stick or left its edge, a singular finger, or a saturated torque: the caller's
    event logic then
    runs; collisions are the caller's), and whether any finger needs coal. No array is allocated for the
    caller (numba's boxing of returned arrays costs more than the step's arithmetic)."""
    m = fingers.shape[0]
    size = y.shape[0]
    n = 2 * m
    h = plant.dt
    attention = False
    applied = np.empty(n)  # the motors' torques: clip(τ, -effort, effort) (the finger records' limits)
    for i in range(m):
        for j in range(2):
            e = fingers[i].effort1 if j == 0 else fingers[i].effort2
            applied[2 * i + j] = min(max(tau[2 * i + j], -e), e)
            if abs(tau[2 * i + j]) - e > SATURATION_TOLERANCE * max(1.0, e):
                attention = True  # (saturated: the caller's event logic logs it; not a round-off at the limit)
    tau = applied
    forces0 = out[size:size + 2 * m].reshape((m, 2))  # (the start's forces, then their surface components)
    forces = out[size + 2 * m:size + 4 * m].reshape((m, 2))
    k1, k2, k3, k4 = np.empty(size), np.empty(size), np.empty(size), np.empty(size)
    stage = np.empty(size)
    _evaluate(fingers, plant, contacts, y, tau, terms, k1, forces0)
    for j in range(size):
        stage[j] = y[j] + 0.5 * h * k1[j]
    _evaluate(fingers, plant, contacts, stage, tau, terms, k2, forces)
    for j in range(size):
        stage[j] = y[j] + 0.5 * h * k2[j]
    _evaluate(fingers, plant, contacts, stage, tau, terms, k3, forces)
    for j in range(size):
        stage[j] = y[j] + h * k3[j]
    _evaluate(fingers, plant, contacts, stage, tau, terms, k4, forces)
    new = out[:size]
    for j in range(size):
        new[j] = y[j] + h * ((k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]) / 6.0)
    _evaluate(fingers, plant, contacts, new, tau, terms, k1, forces)
    surface0 = forces0  # (rotated in place below)
    surface = out[size + 4 * m:size + 6 * m].reshape((m, 2))
    xi = out[size + 6 * m:size + 7 * m]
    xi_dot = out[size + 7 * m:size + 8 * m]
    c0, s0 = math.cos(y[2 * n + 2]), math.sin(y[2 * n + 2])
    x, yo, beta = new[2 * n], new[2 * n + 1], new[2 * n + 2]
    vx, vy, w = new[2 * n + 3], new[2 * n + 4], new[2 * n + 5]
    c, s = math.cos(beta), math.sin(beta)
    worst = 0.0
    any_coal = False
    for i in range(m):
        _posture(fingers[i], terms[i], new[2 * i], new[2 * i + 1], x, yo, beta, c, s, posture[i])
        needs_coal[i] = not _certified(posture[i], certificates[i], radii[i])
        any_coal = any_coal or needs_coal[i]
    for i in range(m):
        ct = contacts[i]
        surface0[i, 0], surface0[i, 1] = _surface(ct, c0, s0, forces0[i, 0], forces0[i, 1])
        surface[i, 0], surface[i, 1] = _surface(ct, c, s, forces[i, 0], forces[i, 1])
        t = terms[i]
        rx, ry = t.px - x, t.py - yo
        xi[i] = ct.tx * ((c * rx + s * ry) - ct.ox) + ct.ty * ((c * ry - s * rx) - ct.oy)
        ux, uy = t.vx - (vx - w * ry), t.vy - (vy + w * rx)
        xi_dot[i] = ct.tx * (c * ux + s * uy) + ct.ty * (c * uy - s * ux)
        if ct.mode == FIXED:
            px, py = ct.ox + ct.xi * ct.tx, ct.oy + ct.xi * ct.ty
            ex, ey = rx - (c * px - s * py), ry - (s * px + c * py)
            worst = max(worst, math.sqrt(ex * ex + ey * ey))
        elif ct.mode == SLIDING:
            worst = max(worst, abs((c * ct.nx - s * ct.ny) * rx + (s * ct.nx + c * ct.ny) * ry - ct.offset))
        if not condition_2x2(t.j00, t.j01, t.j10, t.j11) <= plant.singular_threshold:  # (NaN too)
            attention = True
        if ct.mode == SEPARATED:
            continue
        if not ct.lo <= xi[i] <= ct.hi:
            attention = True
        if plant.contact_events:
            fn, ft = surface[i, 0], surface[i, 1]
            if fn < -_TOL:
                attention = True
            elif ct.mode == FIXED and ct.mu_static * fn - abs(ft) < -_TOL * max(1.0, abs(fn)):
                attention = True
            elif ct.mode == SLIDING and xi_dot[i] * ct.sign <= 0.0:
                attention = True
    return worst, attention, any_coal


@numba.njit(cache=True)
def _posture(p, t, q1, q2, x, y, beta, c, s, out):
    """A finger's (q_1, q_2, β, joint 1 (x, y), elbow (x, y)), the points in the object frame."""
    out[0], out[1], out[2] = q1, q2, beta
    out[3], out[4] = c * (p.o1x - x) + s * (p.o1y - y), c * (p.o1y - y) - s * (p.o1x - x)
    out[5], out[6] = c * (t.ex - x) + s * (t.ey - y), c * (t.ey - y) - s * (t.ex - x)


@numba.njit(cache=True)
def _certified(posture, cert, radii):
    """Whether a finger's links cannot have reached the object since its certificate ``cert`` (a NaN: none):
    each link's points moved relative to the object by less than the distance coal found then, less its
    margin (:meth:`regrasp.plants.project.plant.Plant._collisions`)."""
    if math.isnan(cert[0]):
        return False
    turn1 = abs(posture[0] - cert[0] - (posture[2] - cert[2]))
    turn2 = abs(posture[0] - cert[0] + posture[1] - cert[1] - (posture[2] - cert[2]))
    return (math.hypot(posture[3] - cert[3], posture[4] - cert[4]) + turn1 * radii[0] < cert[7]
            and math.hypot(posture[5] - cert[5], posture[6] - cert[6]) + turn2 * radii[1] < cert[8])

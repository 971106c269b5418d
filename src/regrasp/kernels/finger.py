r"""A planar 2R finger's dynamics in closed form (compiled), with parameters read from its Pinocchio model.

**Parameters** (:data:`FINGER_PARAMETERS`, one record per finger, read by :func:`finger_parameters`):
joint 1's axis :math:`o_1` and angle :math:`a_1` in the hand frame (the URDF's origin composed with the
finger's base pose), joint 2's origin :math:`d_2` and angle :math:`a_2` in joint 1's frame, per link k its
mass :math:`m_k`, centre of mass :math:`c_k` (joint frame) and rotational inertia :math:`I_k` about the
z axis through :math:`c_k`, the tip :math:`t` in joint 2's frame, the joints' armature and viscous damping, and
their torque limits (``effortLimit``; inf where it is 0 or less: none).
Pinocchio merges fixed links into their parent body, so two bodies describe the finger exactly.

**Terms** at (q, q̇) (:data:`FINGER_TERMS`, :func:`finger_terms`). With the link angles
:math:`\phi_1 = a_1 + q_1`, :math:`\phi_2 = \phi_1 + a_2 + q_2`, the world vectors
:math:`r_1 = R(\phi_1) c_1`, :math:`e = R(\phi_1) d_2`, :math:`r_2 = R(\phi_2) c_2`,
:math:`\rho = R(\phi_2) t`, :math:`E` the rotation by +90° and :math:`\sigma = e \times r_2`:

.. math::

    M = \begin{pmatrix} m_1|r_1|^2 + I_1 + m_2|e + r_2|^2 + I_2 + a_{r,1} & m_2 (e + r_2)\cdot r_2 + I_2 \\
        \cdot & m_2 |r_2|^2 + I_2 + a_{r,2}\end{pmatrix},\qquad
    N = \begin{pmatrix} -m_2\sigma(2\dot q_1\dot q_2 + \dot q_2^2) - g\cdot E(m_1 r_1 + m_2(e + r_2)) + b_1\dot q_1 \\
        m_2\sigma\dot q_1^2 - m_2\, g\cdot E r_2 + b_2\dot q_2 \end{pmatrix},

the tip :math:`p = o_1 + e + \rho`, :math:`J = (E(e + \rho),\ E\rho)`, and
:math:`\dot J\dot q = -\dot q_1^2 e - (\dot q_1 + \dot q_2)^2\rho`. (b: the damping, zero when the hand's
damping is off; g: gravity in the hand frame.) :func:`check_finger_terms` compares them with Pinocchio's
``crba``, ``nonLinearEffects``, frame Jacobian and classical acceleration at random states.
"""

from __future__ import annotations

import math

import numba
import numpy as np
import pinocchio as pin

__all__ = ["FINGER_PARAMETERS", "FINGER_TERMS", "condition_2x2", "finger_parameters", "finger_terms",
           "finger_terms_at", "finger_terms_into", "reference_terms"]

_F8 = np.float64

#: One finger's constants (lengths [m], angles [rad], masses [kg], inertias [kg m^2], damping [N m s/rad]).
FINGER_PARAMETERS = np.dtype([
    ("o1x", _F8), ("o1y", _F8), ("a1", _F8),  # joint 1 in the hand frame
    ("d2x", _F8), ("d2y", _F8), ("a2", _F8),  # joint 2 in joint 1's frame
    ("m1", _F8), ("c1x", _F8), ("c1y", _F8), ("i1", _F8),  # link 1: mass, centre of mass, inertia about it
    ("m2", _F8), ("c2x", _F8), ("c2y", _F8), ("i2", _F8),  # link 2
    ("tx", _F8), ("ty", _F8),  # the tip in joint 2's frame
    ("armature1", _F8), ("armature2", _F8), ("damping1", _F8), ("damping2", _F8),
    ("effort1", _F8), ("effort2", _F8),  # the joints' torque limits [N m] (inf: none)
], align=True)

#: One finger's dynamics at a state: M (upper triangle), N (Coriolis, gravity, damping), the tip Jacobian J
#: (row-major), J̇q̇, the tip p and its velocity J q̇, the elbow (joint 2's axis), M⁻¹ (upper triangle) and
#: :math:`J M^{-1} J^T` (upper triangle); hand frame.
FINGER_TERMS = np.dtype([
    ("m00", _F8), ("m01", _F8), ("m11", _F8), ("n0", _F8), ("n1", _F8),
    ("j00", _F8), ("j01", _F8), ("j10", _F8), ("j11", _F8), ("jdx", _F8), ("jdy", _F8),
    ("px", _F8), ("py", _F8), ("vx", _F8), ("vy", _F8), ("ex", _F8), ("ey", _F8),
    ("i00", _F8), ("i01", _F8), ("i11", _F8), ("l00", _F8), ("l01", _F8), ("l11", _F8),
], align=True)


def _planar_angle(placement: pin.SE3) -> float:
    return math.atan2(placement.rotation[1, 0], placement.rotation[0, 0])


def finger_parameters(model: pin.Model, tip_frame: int, first_joint: int = 1) -> np.ndarray:
    """The record (:data:`FINGER_PARAMETERS`) of the planar 2R chain ``first_joint``, ``first_joint + 1`` of
    ``model`` (a finger's model, or a whole hand's) with tip frame ``tip_frame``."""
    j1, j2 = first_joint, first_joint + 1
    out = np.zeros((), dtype=FINGER_PARAMETERS)
    p1, p2 = model.jointPlacements[j1], model.jointPlacements[j2]
    tip = model.frames[tip_frame].placement.translation
    values = {"o1x": p1.translation[0], "o1y": p1.translation[1], "a1": _planar_angle(p1),
              "d2x": p2.translation[0], "d2y": p2.translation[1], "a2": _planar_angle(p2), "tx": tip[0], "ty": tip[1]}
    for k, j in ((1, j1), (2, j2)):
        inertia = model.inertias[j]
        values.update({f"m{k}": inertia.mass, f"c{k}x": inertia.lever[0], f"c{k}y": inertia.lever[1],
                       f"i{k}": inertia.inertia[2, 2], f"armature{k}": model.armature[model.idx_vs[j]],
                       f"damping{k}": model.damping[model.idx_vs[j]]})
        effort = float(model.effortLimit[model.idx_vs[j]])
        values[f"effort{k}"] = effort if math.isfinite(effort) and effort > 0.0 else math.inf
    for name, value in values.items():
        out[name] = float(value)
    return out


@numba.njit(cache=True)
def condition_2x2(a: float, b: float, c: float, d: float) -> float:
    r"""The condition number σ_max/σ_min of [[a, b], [c, d]] in closed form (inf when singular):
    :math:`\sigma^2_{max,min} = (s \pm \sqrt{s^2 - 4 \det^2})/2` with :math:`s = a^2 + b^2 + c^2 + d^2`."""
    total = a * a + b * b + c * c + d * d
    det = a * d - b * c
    disc = math.sqrt(max(total * total - 4.0 * det * det, 0.0))
    small = 0.5 * (total - disc)
    if small <= 0.0:
        return math.inf
    return math.sqrt(0.5 * (total + disc) / small)


@numba.njit(cache=True)
def finger_terms_into(p, q1, q2, v1, v2, gx, gy, damped, out):
    """:func:`finger_terms` of one finger (record ``p``, :data:`FINGER_PARAMETERS`) at joint positions ``q1``, ``q2``
    [rad] and velocities ``v1``, ``v2`` [rad/s], gravity (``gx``, ``gy``) [m/s^2] in the hand frame (``damped``: with
    the joints' viscous damping), into the record ``out`` (:data:`FINGER_TERMS`); inlined into the compiled callers."""
    phi1 = p.a1 + q1
    phi2 = phi1 + p.a2 + q2
    c1, s1, c2, s2 = math.cos(phi1), math.sin(phi1), math.cos(phi2), math.sin(phi2)
    r1x, r1y = c1 * p.c1x - s1 * p.c1y, s1 * p.c1x + c1 * p.c1y
    ex, ey = c1 * p.d2x - s1 * p.d2y, s1 * p.d2x + c1 * p.d2y
    r2x, r2y = c2 * p.c2x - s2 * p.c2y, s2 * p.c2x + c2 * p.c2y
    rhx, rhy = c2 * p.tx - s2 * p.ty, s2 * p.tx + c2 * p.ty
    m1, m2 = p.m1, p.m2
    ax, ay = ex + r2x, ey + r2y
    m00 = m1 * (r1x * r1x + r1y * r1y) + p.i1 + m2 * (ax * ax + ay * ay) + p.i2 + p.armature1
    m01 = m2 * (ax * r2x + ay * r2y) + p.i2
    m11 = m2 * (r2x * r2x + r2y * r2y) + p.i2 + p.armature2
    sigma = m2 * (ex * r2y - ey * r2x)
    # g . E r = g_y r_x - g_x r_y
    n0 = -sigma * (2.0 * v1 * v2 + v2 * v2) - (gy * (m1 * r1x + m2 * ax) - gx * (m1 * r1y + m2 * ay))
    n1 = sigma * v1 * v1 - m2 * (gy * r2x - gx * r2y)
    if damped:
        n0 += p.damping1 * v1
        n1 += p.damping2 * v2
    bx, by = ex + rhx, ey + rhy
    j00, j01, j10, j11 = -by, -rhy, bx, rhx
    w1, w2 = v1 * v1, (v1 + v2) * (v1 + v2)
    det = m00 * m11 - m01 * m01
    i00, i01, i11 = m11 / det, -m01 / det, m00 / det
    k00, k01 = j00 * i00 + j01 * i01, j00 * i01 + j01 * i11  # J M^-1
    k10, k11 = j10 * i00 + j11 * i01, j10 * i01 + j11 * i11
    out.m00, out.m01, out.m11, out.n0, out.n1 = m00, m01, m11, n0, n1
    out.j00, out.j01, out.j10, out.j11 = j00, j01, j10, j11
    out.jdx, out.jdy = -w1 * ex - w2 * rhx, -w1 * ey - w2 * rhy
    out.px, out.py = p.o1x + bx, p.o1y + by
    out.vx, out.vy = j00 * v1 + j01 * v2, j10 * v1 + j11 * v2
    out.ex, out.ey = p.o1x + ex, p.o1y + ey
    out.i00, out.i01, out.i11 = i00, i01, i11
    out.l00, out.l01, out.l11 = k00 * j00 + k01 * j01, k00 * j10 + k01 * j11, k10 * j10 + k11 * j11


@numba.njit(cache=True)
def finger_terms(params, q, v, gravity, damped):
    """Every finger's terms (:data:`FINGER_TERMS`, (m,)) at joint positions ``q`` (2m) [rad] and velocities
    ``v`` (2m) [rad/s]; ``params``: (m,) :data:`FINGER_PARAMETERS`; ``gravity`` (2) [m/s^2] in the hand
    frame; ``damped``: add the joints' viscous damping to N."""
    out = np.empty(params.shape[0], dtype=FINGER_TERMS)
    for i in range(params.shape[0]):
        finger_terms_into(params[i], q[2 * i], q[2 * i + 1], v[2 * i], v[2 * i + 1], gravity[0], gravity[1], damped,
                          out[i])
    return out


def finger_terms_at(params: np.ndarray, q, v, gravity, damped: bool) -> np.ndarray:
    """:func:`finger_terms` for arrays of any float type (converted)."""
    return finger_terms(params, np.ascontiguousarray(q, dtype=float), np.ascontiguousarray(v, dtype=float),
                        np.ascontiguousarray(gravity, dtype=float), bool(damped))


def reference_terms(model: pin.Model, data: pin.Data, tip_frame: int, first_joint: int, q: np.ndarray,
                    v: np.ndarray, damped: bool) -> dict[str, np.ndarray]:
    """Pinocchio's M (2x2 block), N, J (2x2 block), J̇q̇ and tip of the chain at ``first_joint`` (the
    reference the compiled terms are checked against); ``q``, ``v``: the model's whole configuration."""
    r = model.idx_vs[first_joint]
    mass = pin.crba(model, data, q)
    mass = np.triu(mass) + np.triu(mass, 1).T
    nle = pin.nonLinearEffects(model, data, q, v).copy()
    if damped:
        nle += np.asarray(model.damping) * v
    pin.computeJointJacobians(model, data, q)
    pin.forwardKinematics(model, data, q, v, np.zeros(model.nv))
    pin.updateFramePlacements(model, data)
    jac = pin.getFrameJacobian(model, data, tip_frame, pin.LOCAL_WORLD_ALIGNED)[:2, r:r + 2]
    jdv = pin.getFrameClassicalAcceleration(model, data, tip_frame, pin.LOCAL_WORLD_ALIGNED).linear[:2]
    return {"M": mass[r:r + 2, r:r + 2], "N": nle[r:r + 2], "J": jac, "Jdv": jdv,
            "tip": data.oMf[tip_frame].translation[:2].copy()}


def largest_disagreement(model: pin.Model, tip_frames, params: np.ndarray, gravity, damped: bool, *, states: int = 16,
                         seed: int = 0) -> tuple[float, str]:
    """The largest difference between the compiled terms of every chain of ``model`` (a whole hand: finger i
    on joints 2i + 1, 2i + 2 with tip frame ``tip_frames[i]``) and Pinocchio's, over ``states`` random
    states (q within ±π, q̇ within ±10 rad/s), relative to max(1, |Pinocchio's value|); and the
    term it occurs in (``"M"``, ``"N"``, ``"J"``, ``"Jdv"`` or ``"tip"``)."""
    rng = np.random.default_rng(seed)
    data = model.createData()
    saved = model.gravity
    model.gravity = pin.Motion(np.array([gravity[0], gravity[1], 0.0, 0.0, 0.0, 0.0]))
    worst, where = 0.0, "M"
    try:
        with np.errstate(all="ignore"):  # (a model whose terms overflow gives NaN: counted as the worst)
            for _ in range(states):
                q = rng.uniform(-np.pi, np.pi, model.nq)
                v = rng.uniform(-10.0, 10.0, model.nv)
                terms = finger_terms_at(params, q, v, gravity, damped)
                for i, tip in enumerate(tip_frames):
                    ref = reference_terms(model, data, tip, 2 * i + 1, q, v, damped)
                    t = terms[i]
                    mine = {"M": np.array([[t["m00"], t["m01"]], [t["m01"], t["m11"]]]),
                            "N": np.array([t["n0"], t["n1"]]),
                            "J": np.array([[t["j00"], t["j01"]], [t["j10"], t["j11"]]]),
                            "Jdv": np.array([t["jdx"], t["jdy"]]), "tip": np.array([t["px"], t["py"]])}
                    for key, value in mine.items():
                        err = float(np.max(np.abs(value - ref[key]) / np.maximum(1.0, np.abs(ref[key]))))
                        if not err <= worst:  # (a NaN counts as the worst)
                            worst, where = (err if math.isfinite(err) else math.inf), key
    finally:
        model.gravity = saved
    return worst, where

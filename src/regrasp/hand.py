r"""A planar hand: m two-joint fingers and their dynamics from Pinocchio (paper eq. 3.2.1–3.2.2).

.. math:: M(q)\ddot q + N(q, \dot q) = \tau + \sigma

with M = blockdiag(M_i) (``pin.crba``), N = Coriolis + gravity (``pin.nonLinearEffects``)
+ viscous joint damping from the URDF (``model.damping``), J = blockdiag(J_i) (the 2x2 tip
Jacobians) and :math:`\dot J \dot q` (the tip's classical acceleration at zero joint
acceleration, ``pin.getFrameClassicalAcceleration``). Gravity is a vector in the hand frame,
so "the hand upside down" is ``gravity_in_hand = (0, +9.81)``.

The hand keeps its own copies of the finger models (with the hand's gravity); the fingers
passed in are not modified.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .exceptions import InvalidParameterError, SingularFingerError
from .finger import Finger
from .validation import as_finite_array, as_positive_float

__all__ = ["Hand", "HandDynamics"]


@dataclass(frozen=True)
class HandDynamics:
    """Everything the controller and the reduced model need at one hand state (q, q̇).

    Attributes:
        mass_matrix: M(q), (2m, 2m), block diagonal [kg m^2].
        nonlinear: N(q, q̇) = Coriolis + gravity + damping torques, (2m,) [N m].
        jacobian: J(q) = blockdiag(J_i), (2m, 2m) [m/rad].
        jacobian_dot_v: J̇ q̇, (2m,) [m/s^2]: the tips' accelerations at q̈ = 0.
        tips: Tip positions, (m, 2) [m], hand frame.
        tip_velocities: J q̇, (m, 2) [m/s].
    """

    mass_matrix: np.ndarray
    nonlinear: np.ndarray
    jacobian: np.ndarray
    jacobian_dot_v: np.ndarray
    tips: np.ndarray
    tip_velocities: np.ndarray


class Hand:
    r"""m planar fingers sharing a hand frame and a gravity vector.

    Args:
        fingers: The fingers (each a planar 2R chain, validated by :class:`~regrasp.finger.Finger`).
        gravity_in_hand: Gravity [m/s^2] in the hand frame.
        damping: Whether N includes the URDF's viscous joint damping.
        singular_threshold: Condition number of a tip Jacobian above which the finger is
            declared singular (:class:`~regrasp.exceptions.SingularFingerError`).
        link_mass_scale: Multiplies every link's mass and rotational inertia (the centres
            of mass stay): a plant whose links differ from the controller's model.
    """

    def __init__(
        self,
        fingers: Sequence[Finger],
        *,
        gravity_in_hand=(0.0, -9.81),
        damping: bool = True,
        singular_threshold: float = 1e4,
        link_mass_scale: float = 1.0,
    ):
        if len(fingers) == 0:
            raise InvalidParameterError("fingers", fingers, "at least one finger")
        names = [f.name for f in fingers]
        if len(set(names)) != len(names):
            raise InvalidParameterError("fingers", names, "distinct finger names")
        self.fingers = tuple(fingers)
        self.m = len(self.fingers)
        self.nq = 2 * self.m
        self.singular_threshold = as_positive_float("singular_threshold", singular_threshold)
        self.damping_enabled = bool(damping)
        self.link_mass_scale = as_positive_float("link_mass_scale", link_mass_scale)
        self._models = [pin.Model(f.model) for f in self.fingers]
        if self.link_mass_scale != 1.0:
            for model in self._models:
                for j in range(1, model.njoints):
                    inertia = model.inertias[j]
                    model.inertias[j] = pin.Inertia(inertia.mass * self.link_mass_scale, inertia.lever,
                                                    inertia.inertia * self.link_mass_scale)
        self._datas = [model.createData() for model in self._models]
        self._tip_ids = [f.tip_frame_id for f in self.fingers]
        self.gravity_in_hand = np.zeros(2)
        self.set_gravity(gravity_in_hand)

    def set_gravity(self, gravity_in_hand) -> None:
        """Set the gravity vector [m/s^2] in the hand frame."""
        g = as_finite_array("gravity_in_hand", gravity_in_hand, (2,))
        self.gravity_in_hand = g
        for model in self._models:
            model.gravity = pin.Motion(np.array([g[0], g[1], 0.0, 0.0, 0.0, 0.0]))

    @property
    def damping(self) -> np.ndarray:
        """Viscous joint damping [N m s/rad] of every joint, (2m,) (zeros when disabled)."""
        if not self.damping_enabled:
            return np.zeros(self.nq)
        return np.concatenate([np.asarray(model.damping, dtype=float) for model in self._models])

    def _split(self, name: str, value) -> np.ndarray:
        return as_finite_array(name, value, (self.nq,)).reshape(self.m, 2)

    def dynamics(self, q, v) -> HandDynamics:
        """M, N, J, J̇q̇ and the tips at joint positions ``q`` [rad] and velocities ``v`` [rad/s]."""
        return self._dynamics(self._split("q", q), self._split("v", v))

    def _dynamics(self, qs: np.ndarray, vs: np.ndarray) -> HandDynamics:
        """:meth:`dynamics` on already validated (m, 2) arrays (hot paths)."""
        mass = np.zeros((self.nq, self.nq))
        jac = np.zeros((self.nq, self.nq))
        nle = np.empty(self.nq)
        jdv = np.empty(self.nq)
        tips = np.empty((self.m, 2))
        zero = np.zeros(2)
        for i, (model, data, fid) in enumerate(zip(self._models, self._datas, self._tip_ids)):
            sl = slice(2 * i, 2 * i + 2)
            qi, vi = qs[i], vs[i]
            pin.crba(model, data, qi)
            mass[sl, sl] = data.M  # crba fills the upper triangle: mirror it
            mass[2 * i + 1, 2 * i] = mass[2 * i, 2 * i + 1]
            nle[sl] = pin.nonLinearEffects(model, data, qi, vi)
            if self.damping_enabled:
                nle[sl] += np.asarray(model.damping) * vi
            pin.forwardKinematics(model, data, qi, vi, zero)
            pin.updateFramePlacement(model, data, fid)
            tips[i] = data.oMf[fid].translation[:2]
            jdv[sl] = pin.getFrameClassicalAcceleration(model, data, fid, pin.LOCAL_WORLD_ALIGNED).linear[:2]
            jac[sl, sl] = pin.computeFrameJacobian(model, data, qi, fid, pin.LOCAL_WORLD_ALIGNED)[:2, :]
        tip_vel = (jac @ vs.reshape(-1)).reshape(self.m, 2)
        return HandDynamics(mass, nle, jac, jdv, tips, tip_vel)

    def jacobian(self, q) -> np.ndarray:
        """J(q) = blockdiag(J_i), (2m, 2m) [m/rad]."""
        return self._jacobian(self._split("q", q))

    def _jacobian(self, qs: np.ndarray) -> np.ndarray:
        jac = np.zeros((self.nq, self.nq))
        for i, (model, data, fid) in enumerate(zip(self._models, self._datas, self._tip_ids)):
            jac[2 * i:2 * i + 2, 2 * i:2 * i + 2] = pin.computeFrameJacobian(
                model, data, qs[i], fid, pin.LOCAL_WORLD_ALIGNED)[:2, :]
        return jac

    def tip_positions(self, q) -> np.ndarray:
        """Tip positions [m], (m, 2), hand frame."""
        qs = self._split("q", q)
        out = np.empty((self.m, 2))
        for i, (model, data, fid) in enumerate(zip(self._models, self._datas, self._tip_ids)):
            pin.forwardKinematics(model, data, qs[i])
            out[i] = pin.updateFramePlacement(model, data, fid).translation[:2]
        return out

    def potential_energy(self, q) -> float:
        """Gravitational potential energy [J] of the fingers (zero at the hand frame's origin)."""
        qs = self._split("q", q)
        return float(sum(pin.computePotentialEnergy(model, data, qs[i])
                         for i, (model, data) in enumerate(zip(self._models, self._datas))))

    def kinetic_energy(self, q, v) -> float:
        """Kinetic energy [J] of the fingers."""
        qs, vs = self._split("q", q), self._split("v", v)
        return float(sum(pin.computeKineticEnergy(model, data, qs[i], vs[i])
                         for i, (model, data) in enumerate(zip(self._models, self._datas))))

    def check_singular(self, q, jacobian: np.ndarray | None = None) -> np.ndarray:
        """Condition numbers of the fingers' tip Jacobians; raises SingularFingerError above the threshold."""
        qs = self._split("q", q)
        return self._check_singular(qs, self._jacobian(qs) if jacobian is None else jacobian)

    def _check_singular(self, qs: np.ndarray, jacobian: np.ndarray) -> np.ndarray:
        conds = np.array([condition_2x2(jacobian[2 * i:2 * i + 2, 2 * i:2 * i + 2]) for i in range(self.m)])
        for i, c in enumerate(conds):
            if not c <= self.singular_threshold:  # also catches inf/nan
                raise SingularFingerError(self.fingers[i].name, qs[i], float(c), self.singular_threshold)
        return conds

    def inverse_kinematics(self, tips_in_hand) -> np.ndarray:
        """Joint positions q (2m,) putting each tip at ``tips_in_hand`` (m, 2), keeping configurations."""
        return self._inverse_kinematics(as_finite_array("tips_in_hand", tips_in_hand, (self.m, 2)))

    def _inverse_kinematics(self, tips: np.ndarray) -> np.ndarray:
        return np.concatenate([f._inverse_kinematics(p) for f, p in zip(self.fingers, tips)])


def condition_2x2(a: np.ndarray) -> float:
    r"""Condition number σ_max/σ_min of a 2x2 matrix in closed form (inf when singular).

    :math:`\sigma^2_{max,min} = (s \pm \sqrt{s^2 - 4 \det^2})/2` with :math:`s = \|a\|_F^2`.
    """
    s = float(a[0, 0] ** 2 + a[0, 1] ** 2 + a[1, 0] ** 2 + a[1, 1] ** 2)
    det = float(a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0])
    disc = np.sqrt(max(s * s - 4.0 * det * det, 0.0))
    small = 0.5 * (s - disc)
    if small <= 0.0:
        return float("inf")
    return float(np.sqrt(0.5 * (s + disc) / small))

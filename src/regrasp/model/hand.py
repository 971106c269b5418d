r"""A planar hand: m two-joint fingers and their dynamics from Pinocchio (paper eq. 3.2.1–3.2.2).

.. math:: M(q)\ddot q + N(q, \dot q) = \tau + \sigma

with M = blockdiag(M_i) (``pin.crba``), N = Coriolis + gravity (``pin.nonLinearEffects``)
+ viscous joint damping from the URDF (``model.damping``), J = blockdiag(J_i) (the 2x2 tip
Jacobians) and :math:`\dot J \dot q` (the tip's classical acceleration at zero joint
acceleration, ``pin.getFrameClassicalAcceleration``). Gravity is a vector in the hand frame,
so "the hand upside down" is ``gravity_in_hand = (0, +9.81)``.

The hand keeps its own copies of the finger models (with the hand's gravity); the fingers
passed in are not modified. The hot paths run them as one Pinocchio model of the whole hand
(each finger a chain from the hand frame, ``pin.appendModel``): one ``pin.computeAllTerms`` pass
gives every block of M and N at once.

**Compiled terms.** The hand also reads each finger's constants from that model
(:func:`~regrasp.kernels.finger.finger_parameters`) for the compiled kernels (:mod:`regrasp.kernels`), and
checks the kernels against Pinocchio at 16 seeded random states (M, N, J, J̇q̇ and the tip, to 1e-12
relative to max(1, |value|)). Where they disagree, it warns (:class:`KernelMismatchWarning`) and
``kernel_parameters`` is None: every consumer then keeps the Pinocchio path.
"""

from __future__ import annotations

import functools
import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..core.exceptions import InvalidParameterError, SingularFingerError
from ..core.validation import (
    MAX_ANGLE,
    MAX_SPEED,
    as_bounded_array,
    as_finite_array,
    as_flag,
    as_positive_float,
    expect_sequence_of,
)
from ..kernels.finger import condition_2x2 as _compiled_condition
from .finger import Finger

__all__ = ["Hand", "HandDynamics", "KERNEL_TOLERANCE", "KernelMismatchWarning"]

#: The largest disagreement between the compiled terms and Pinocchio's a hand accepts [relative to
#: max(1, |value|)].
KERNEL_TOLERANCE = 1e-12


class KernelMismatchWarning(UserWarning):
    """The compiled kernels disagree with Pinocchio on a hand's model: the hand keeps the Pinocchio path."""


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
        fingers: The fingers (each a planar 2R chain, validated by :class:`~regrasp.model.finger.Finger`).
        gravity_in_hand: Gravity [m/s^2] in the hand frame.
        damping: Whether N includes the URDF's viscous joint damping.
        singular_threshold: Condition number of a tip Jacobian above which the finger is
            declared singular (:class:`~regrasp.core.exceptions.SingularFingerError`).
        link_mass_scale: Multiplies every link's mass and rotational inertia (the centres
            of mass stay): a plant whose links differ from the controller's model.
    """

    def __init__(
        self,
        fingers: Sequence[Finger],
        *,
        gravity_in_hand: ArrayLike = (0.0, -9.81),
        damping: bool = True,
        singular_threshold: float = 1e4,
        link_mass_scale: float = 1.0,
    ):
        from .finger import Finger

        fingers = expect_sequence_of("fingers", fingers, Finger, "Finger (Finger.from_urdf)")
        if len(fingers) == 0:
            raise InvalidParameterError("fingers", fingers, "at least one finger")
        names = [f.name for f in fingers]
        if len(set(names)) != len(names):
            raise InvalidParameterError("fingers", names, "distinct finger names")
        self.fingers = tuple(fingers)
        self.m = len(self.fingers)
        self.nq = 2 * self.m
        self.singular_threshold = as_positive_float("singular_threshold", singular_threshold)
        self.damping_enabled = as_flag("damping", damping)
        self.link_mass_scale = as_positive_float("link_mass_scale", link_mass_scale)
        #: Each finger's own Pinocchio model (a copy, with the hand's gravity and link masses), in finger order.
        self.finger_models: tuple[pin.Model, ...] = tuple(pin.Model(f.model) for f in self.fingers)
        if self.link_mass_scale != 1.0:
            for model in self.finger_models:
                for j in range(1, model.njoints):
                    inertia = model.inertias[j]
                    model.inertias[j] = pin.Inertia(inertia.mass * self.link_mass_scale, inertia.lever,
                                                    inertia.inertia * self.link_mass_scale)
        self._datas = [model.createData() for model in self.finger_models]
        self._tip_ids = [f.tip_frame_id for f in self.fingers]
        # the hot paths run one model of the whole hand (every finger a chain from the hand frame):
        # one Pinocchio pass instead of one per finger
        whole, tips = _whole_hand(self.finger_models, self._tip_ids)
        #: The Pinocchio model of the whole hand: finger i a chain from the hand frame (the universe) on joints
        #: 2i + 1, 2i + 2, its names prefixed "<i>/" (module docstring).
        self.pinocchio_model: pin.Model = whole
        #: Each finger's tip frame id in :attr:`pinocchio_model`, in finger order.
        self.tip_frame_ids: tuple[int, ...] = tuple(tips)
        self._hand_data = self.pinocchio_model.createData()
        self._damping = np.concatenate([np.asarray(model.damping, dtype=float) for model in self.finger_models])
        self._damping_list = self._damping.tolist()
        upper = [2 * i * self.nq + 2 * i + 1 for i in range(self.m)]  # (2i, 2i + 1), row-major
        self._mass_mirror = (np.array([u + self.nq - 1 for u in upper]), np.array(upper))
        # whether this Pinocchio's computeAllTerms leaves M's lower triangle to us (crba does)
        pin.computeAllTerms(self.pinocchio_model, self._hand_data, np.full(self.nq, 0.5), np.zeros(self.nq))
        self._mirror_mass = not np.array_equal(self._hand_data.M, self._hand_data.M.T)
        self.gravity_in_hand = np.zeros(2)
        self.set_gravity(gravity_in_hand)
        #: Each finger's constants for the compiled kernels ((m,) :data:`~regrasp.kernels.FINGER_PARAMETERS`),
        #: or None where the kernels disagree with Pinocchio (module docstring).
        self.kernel_parameters: np.ndarray | None = None
        #: The largest disagreement found by the check, and the term it was in.
        self.kernel_disagreement: tuple[float, str] = (math.inf, "")
        self._build_kernels()

    def _build_kernels(self) -> None:
        from ..kernels.finger import finger_parameters, largest_disagreement

        params = np.stack([finger_parameters(self.pinocchio_model, tip, 2 * i + 1)
                           for i, tip in enumerate(self.tip_frame_ids)])
        found = largest_disagreement(self.pinocchio_model, self.tip_frame_ids, params, self.gravity_in_hand,
                                     self.damping_enabled)
        self.kernel_disagreement = found
        if found[0] <= KERNEL_TOLERANCE:
            self.kernel_parameters = params
        else:
            warnings.warn(f"the compiled finger kernels disagree with Pinocchio by {found[0]:.3g} (relative) in "
                          f"{found[1]}, more than {KERNEL_TOLERANCE:g}: this hand keeps the Pinocchio path",
                          KernelMismatchWarning, stacklevel=3)

    def use_kernels(self, compiled: bool | None) -> bool:
        """Whether a consumer (a plant, a reduced model) runs the compiled kernels, given its ``compiled``
        argument: None, when they agree with Pinocchio; True, they must (else an
        :class:`~regrasp.core.exceptions.InvalidParameterError`); False, never."""
        if compiled is None:
            return self.kernel_parameters is not None
        if as_flag("compiled", compiled) and self.kernel_parameters is None:
            raise InvalidParameterError("compiled", compiled, "False for this hand: its compiled kernels disagree "
                                        f"with Pinocchio ({self.kernel_disagreement[1]})")
        return bool(compiled)

    def set_gravity(self, gravity_in_hand: ArrayLike) -> None:
        """Set the gravity vector [m/s^2] in the hand frame."""
        g = as_finite_array("gravity_in_hand", gravity_in_hand, (2,))
        self.gravity_in_hand = g
        for model in (*self.finger_models, self.pinocchio_model):
            model.gravity = pin.Motion(np.array([g[0], g[1], 0.0, 0.0, 0.0, 0.0]))

    @property
    def effort_limit(self) -> np.ndarray:
        """Every joint's torque limit [N m], (2m,), finger by finger: |τ_j| <= effort_limit[j] (inf: none); from each
        finger's :attr:`~regrasp.model.finger.Finger.effort_limit` (the URDF's ``effort`` or the scenario's)."""
        return np.concatenate([np.asarray(model.effortLimit, dtype=float)[:2] for model in self.finger_models])

    @property
    def damping(self) -> np.ndarray:
        """Viscous joint damping [N m s/rad] of every joint, (2m,) (zeros when disabled)."""
        if not self.damping_enabled:
            return np.zeros(self.nq)
        return np.concatenate([np.asarray(model.damping, dtype=float) for model in self.finger_models])

    def _split(self, name: str, value, limit: float = MAX_ANGLE, unit: str = "rad") -> np.ndarray:
        """Joint positions [rad] (at most ``MAX_ANGLE``), or velocities with ``limit = MAX_SPEED`` [rad/s]
        (:mod:`~regrasp.core.validation`: beyond them an energy or the Coriolis terms overflow), as (m, 2)."""
        return as_bounded_array(name, value, (self.nq,), limit, unit).reshape(self.m, 2)

    def dynamics(self, q: ArrayLike, v: ArrayLike) -> HandDynamics:
        """M, N, J, J̇q̇ and the tips at joint positions ``q`` [rad] and velocities ``v`` [rad/s]."""
        return self._dynamics(self._split("q", q), self._split("v", v, MAX_SPEED, "rad/s"))

    def _dynamics(self, qs: np.ndarray, vs: np.ndarray, kinematics=None) -> HandDynamics:
        """:meth:`dynamics` on already validated (m, 2) arrays (hot paths); ``kinematics``: J and the
        tips at ``qs``, when the caller has them already."""
        model, data = self.pinocchio_model, self._hand_data
        v = vs.reshape(-1)
        # one pass: M (crba), N (rnea at q̈ = 0), the joint Jacobians and the bodies' velocities and
        # accelerations at q̈ = 0
        pin.computeAllTerms(model, data, qs.reshape(-1), v)
        jac, tips = (self._frame_jacobian(), self._frame_tips()) if kinematics is None else kinematics
        mass = data.M.copy()
        if self._mirror_mass:  # crba fills the upper triangle
            lower, upper = self._mass_mirror
            mass.reshape(-1)[lower] = mass.reshape(-1)[upper]
        nle = data.nle + self._damping * v if self.damping_enabled else data.nle.copy()
        jdv = np.empty(self.nq)
        for i, fid in enumerate(self.tip_frame_ids):
            jdv[2 * i:2 * i + 2] = pin.getFrameClassicalAcceleration(model, data, fid,
                                                                     pin.LOCAL_WORLD_ALIGNED).linear[:2]
        return HandDynamics(mass, nle, jac, jdv, tips, jac.dot(v).reshape(self.m, 2))

    def _frame_jacobian(self) -> np.ndarray:
        """J (2m, 2m) from the joint Jacobians of the last pass."""
        model, data = self.pinocchio_model, self._hand_data
        jac = np.empty((self.nq, self.nq))
        for i, fid in enumerate(self.tip_frame_ids):
            # finger i's rows: its 2x2 block, zeros elsewhere (the chains are independent)
            jac[2 * i:2 * i + 2] = pin.getFrameJacobian(model, data, fid, pin.LOCAL_WORLD_ALIGNED)[:2]
        return jac

    def _frame_tips(self) -> np.ndarray:
        """The tips (m, 2) from the placements of the last pass."""
        model, data = self.pinocchio_model, self._hand_data
        return np.array([pin.updateFramePlacement(model, data, fid).translation[:2] for fid in self.tip_frame_ids])

    def jacobian(self, q: ArrayLike) -> np.ndarray:
        """J(q) = blockdiag(J_i), (2m, 2m) [m/rad]."""
        return self._jacobian(self._split("q", q))

    def _jacobian(self, qs: np.ndarray) -> np.ndarray:
        pin.computeJointJacobians(self.pinocchio_model, self._hand_data, qs.reshape(-1))
        return self._frame_jacobian()

    def tip_positions(self, q: ArrayLike) -> np.ndarray:
        """Tip positions [m], (m, 2), hand frame."""
        qs = self._split("q", q)
        out = np.empty((self.m, 2))
        for i, (model, data, fid) in enumerate(zip(self.finger_models, self._datas, self._tip_ids)):
            pin.forwardKinematics(model, data, qs[i])
            out[i] = pin.updateFramePlacement(model, data, fid).translation[:2]
        return out

    def potential_energy(self, q: ArrayLike) -> float:
        """Gravitational potential energy [J] of the fingers (zero at the hand frame's origin)."""
        qs = self._split("q", q)
        return float(sum(pin.computePotentialEnergy(model, data, qs[i])
                         for i, (model, data) in enumerate(zip(self.finger_models, self._datas))))

    def kinetic_energy(self, q: ArrayLike, v: ArrayLike) -> float:
        """Kinetic energy [J] of the fingers."""
        qs, vs = self._split("q", q), self._split("v", v, MAX_SPEED, "rad/s")
        return float(sum(pin.computeKineticEnergy(model, data, qs[i], vs[i])
                         for i, (model, data) in enumerate(zip(self.finger_models, self._datas))))

    def check_singular(self, q: ArrayLike, jacobian: np.ndarray | None = None) -> np.ndarray:
        """Condition numbers of the fingers' tip Jacobians; raises SingularFingerError above the threshold."""
        qs = self._split("q", q)
        return self._check_singular(qs, self._jacobian(qs) if jacobian is None else jacobian)

    def _check_singular(self, qs: np.ndarray, jacobian: np.ndarray) -> np.ndarray:
        blocks = [jacobian[2 * i:2 * i + 2, 2 * i:2 * i + 2].reshape(-1).tolist() for i in range(self.m)]
        return np.array(self.check_singular_blocks(qs.reshape(-1).tolist(), blocks))

    def check_singular_blocks(self, q: Sequence[float], blocks: Sequence[Sequence[float]]) -> list[float]:
        """:meth:`check_singular` in scalar arithmetic (hot paths; not validated): the condition numbers of the
        fingers' tip Jacobians given as (a, b, c, d) = row-major 2x2 blocks [m/rad] (floats); ``q``: the joint
        positions (2m) [rad] (floats), for the error. Raises SingularFingerError above the threshold."""
        conds = [_condition(*block) for block in blocks]
        for i, c in enumerate(conds):
            if not c <= self.singular_threshold:  # also catches inf/nan
                raise SingularFingerError(self.fingers[i].name, np.array(q[2 * i:2 * i + 2]), c,
                                          self.singular_threshold)
        return conds

    def mass_blocks_and_bias(self, q: Sequence[float], v: Sequence[float]) -> tuple[list[tuple[float, float, float]],
                                                                                   list[float]]:
        """Each finger's (m00, m01, m11) of M [kg m^2] and N (2m) [N m] at joint positions ``q`` [rad] and velocities
        ``v`` [rad/s] (2m floats, not validated), as floats (hot paths): ``pin.crba`` and ``pin.nonLinearEffects``
        on the whole hand (:attr:`pinocchio_model`), plus the joints' damping when enabled."""
        model, data = self.pinocchio_model, self._hand_data
        q = np.array(q)
        v_array = np.array(v)
        rows = pin.crba(model, data, q).tolist()  # (its upper triangle: the lower one may be left unset)
        nle = pin.nonLinearEffects(model, data, q, v_array).tolist()
        if self.damping_enabled:
            nle = [n + d * u for n, d, u in zip(nle, self._damping_list, v)]
        masses = [(rows[2 * i][2 * i], rows[2 * i][2 * i + 1], rows[2 * i + 1][2 * i + 1]) for i in range(self.m)]
        return masses, nle

    def inverse_kinematics(self, tips_in_hand: ArrayLike) -> np.ndarray:
        """Joint positions q (2m,) putting each tip at ``tips_in_hand`` (m, 2), keeping configurations."""
        return self._inverse_kinematics(as_finite_array("tips_in_hand", tips_in_hand, (self.m, 2)))

    def _inverse_kinematics(self, tips: np.ndarray) -> np.ndarray:
        return np.array([angle for f, (x, y) in zip(self.fingers, tips.tolist()) for angle in f.joint_angles(x, y)])


def _whole_hand(models: Sequence[pin.Model], tip_ids: Sequence[int]) -> tuple[pin.Model, list[int]]:
    """One model with every finger model a chain from the universe (the hand frame), and its tip
    frames. Names get a prefix "<i>/" (Pinocchio wants them unique)."""
    whole, tips = None, []
    for i, model in enumerate(models):
        model = pin.Model(model)
        tip_name = f"{i}/{model.frames[tip_ids[i]].name}"
        for k in range(len(model.frames)):
            frame = model.frames[k]
            frame.name = f"{i}/{frame.name}"
            model.frames[k] = frame
        for k in range(len(model.names)):
            model.names[k] = f"{i}/{model.names[k]}"
        whole = model if whole is None else pin.appendModel(whole, model, 0, pin.SE3.Identity())
        tips.append(tip_name)
    return whole, [whole.getFrameId(name) for name in tips]


@functools.cache
def _block_positions(m: int) -> np.ndarray:
    """Flat positions of the 2x2 diagonal blocks of a (2m, 2m) array, block by block, row-major."""
    return np.array([(2 * i + r) * 2 * m + 2 * i + c for i in range(m) for r in range(2) for c in range(2)])


def block_diagonal(blocks: np.ndarray) -> np.ndarray:
    """The (2m, 2m) block-diagonal matrix of m 2x2 ``blocks`` (m, 2, 2)."""
    m = len(blocks)
    out = np.zeros((2 * m, 2 * m))
    out.reshape(-1)[_block_positions(m)] = blocks.reshape(-1)
    return out


def condition_2x2(a: np.ndarray) -> float:
    r"""Condition number σ_max/σ_min of a 2x2 matrix in closed form (inf when singular).

    :math:`\sigma^2_{max,min} = (s \pm \sqrt{s^2 - 4 \det^2})/2` with :math:`s = \|a\|_F^2`.
    """
    return float(_condition(*np.asarray(a, dtype=float).reshape(-1).tolist()))


#: :func:`condition_2x2` of [[a, b], [c, d]] from four floats (compiled: the hot paths' and the kernels' one).
_condition = _compiled_condition

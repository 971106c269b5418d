r"""A planar two-link finger loaded from URDF through Pinocchio.

A finger is a URDF (a serial chain of two revolute joints about z whose links lie in
the xy-plane, with a ``tip`` frame on the second link) plus its base pose in the hand
frame plus a configuration:

* ``left``: :math:`-\pi < \theta_2 < 0`, the elbow lies on the left of the ray from the
  first joint to the fingertip;
* ``right``: :math:`0 < \theta_2 < \pi`, the elbow lies on the right of that ray.

:math:`\theta_2` is the *geometric* angle from the first link's direction (joint 1 →
joint 2) to the second link's direction (joint 2 → tip). For URDFs whose links lie
along x with identity joint origins it equals the joint coordinate ``q2``; otherwise it
differs by a constant offset read from the model (see :attr:`Finger.theta2_offset`).

**Actuator limits.** Each joint's torque limit [N m] is the URDF's ``effort`` (Pinocchio's
``model.effortLimit``); an ``effort`` of 0 or less, or none, means no limit (inf). ``effort_limit`` overrides
it (a scenario's ``effort`` key): one value for both joints or one per joint, each > 0 (inf: no limit). The
finger's own model carries the limits in its ``effortLimit``, so a :class:`~regrasp.model.hand.Hand` and the
compiled kernels read them from there (:attr:`Finger.effort_limit`).

All positions are in the hand frame [m]. The caller's ``pin.Model`` is never mutated:
the finger keeps its own copy with the base pose folded into the first joint's
placement. The model is parsed and checked by :mod:`regrasp.model.finger_model`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum
from pathlib import Path

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..core.exceptions import FingerModelError, InvalidParameterError, UnreachableError
from ..core.planar import se3_from_planar, wrap_angle
from ..core.validation import as_finite_array, as_name, expect_type, file_problem
from .finger_model import parse_finger_urdf, planar_angle, validate_finger_model

__all__ = ["Configuration", "Finger", "LinkShape", "as_effort_limit", "urdf_effort_limit"]


def as_effort_limit(name: str, value: object) -> np.ndarray:
    """``value`` (one number for both joints, or one per joint) as a (2,) array of torque limits [N m], each > 0
    (inf: no limit); else an :class:`~regrasp.core.exceptions.InvalidParameterError` naming ``name``."""
    expected = "a joint torque limit > 0 [N m] (inf: none), or one per joint (2)"
    try:
        items = [value] if np.ndim(value) == 0 else list(value)
        if len(items) != (1 if np.ndim(value) == 0 else 2) or any(isinstance(v, (bool, np.bool_))
                                           or not isinstance(v, (int, float, np.integer, np.floating)) for v in items):
            raise TypeError
        floats = [float(v) for v in items]
    except (TypeError, ValueError, OverflowError):
        raise InvalidParameterError(name, value, expected) from None
    if not all(v > 0.0 for v in floats):  # (NaN fails too)
        raise InvalidParameterError(name, value, expected)
    return np.array(floats * (2 // len(floats)))


def urdf_effort_limit(model: pin.Model) -> np.ndarray:
    """The (2,) torque limits [N m] of a finger's model, from its ``effortLimit`` (the URDF's ``effort``): inf
    where it is 0 or less, or not finite (no limit)."""
    effort = np.asarray(model.effortLimit, dtype=float)[:2].copy()
    effort[~(np.isfinite(effort) & (effort > 0.0))] = np.inf
    return effort


class Configuration(str, Enum):
    """Elbow configuration of a two-link finger (paper §2.2)."""

    LEFT = "left"
    RIGHT = "right"

    @property
    def sign(self) -> int:
        r"""+1 for left (elbow left of the joint-1→tip ray), -1 for right."""
        return 1 if self is Configuration.LEFT else -1

    @classmethod
    def parse(cls, value: "Configuration | str") -> "Configuration":
        """Accept an enum member or its name (``"left"``/``"right"``)."""
        if isinstance(value, Configuration):
            return value
        try:
            return cls(str(value).lower())
        except ValueError:
            raise InvalidParameterError("configuration", value, "'left' or 'right'") from None


@dataclass(frozen=True)
class LinkShape:
    """One collision shape of a finger link, from the URDF's collision geometry.

    Attributes:
        link: 0 for the proximal link (moved by joint 1), 1 for the distal link.
        name: Geometry object name in the URDF.
        geometry: The coal collision geometry.
        placement_in_joint: Placement of the shape in its parent joint frame.
    """

    link: int
    name: str
    geometry: object
    placement_in_joint: pin.SE3


class Finger:
    r"""A planar two-link finger: URDF model, base pose in the hand frame and configuration.

    Args:
        model: The finger's Pinocchio model (copied, never mutated).
        collision_model: Its collision geometry (copied), or None.
        base_in_hand: Base pose ``(x [m], y [m], theta [rad])`` in the hand frame; it is
            composed with the URDF's first joint origin.
        configuration: ``"left"`` or ``"right"`` (see the module docstring).
        name: Finger name used in messages and results.
        tip_frame: Name of the fingertip frame.
        source: Where the model came from (for error messages).
        effort_limit: The joints' torque limits [N m], one for both or one per joint, > 0 (inf: none); None: the
            model's ``effortLimit`` (the URDF's ``effort``; 0 or less: none). See the module docstring.
    """

    def __init__(
        self,
        model: pin.Model,
        collision_model: pin.GeometryModel | None = None,
        *,
        base_in_hand: ArrayLike = (0.0, 0.0, 0.0),
        configuration: Configuration | str = Configuration.LEFT,
        name: str = "finger",
        tip_frame: str = "tip",
        source: str | Path = "<model>",
        effort_limit: ArrayLike | None = None,
    ):
        self.source = str(source)
        expect_type("model", model, pin.Model, "a Pinocchio model (pin.Model)")
        validate_finger_model(model, self.source, as_name("tip_frame", tip_frame))
        self.name = as_name("name", name)
        self.configuration = Configuration.parse(configuration)
        self.base_in_hand = as_finite_array("base_in_hand", base_in_hand, (3,))
        self.tip_frame = tip_frame

        self._model_unplaced = pin.Model(model)
        effort = urdf_effort_limit(model) if effort_limit is None else as_effort_limit("effort_limit", effort_limit)
        self._model_unplaced.effortLimit = effort.copy()
        self.model = pin.Model(self._model_unplaced)
        self.model.jointPlacements[1] = se3_from_planar(self.base_in_hand) * self.model.jointPlacements[1]
        self.data = self.model.createData()
        self.tip_frame_id = self.model.getFrameId(tip_frame)
        self.collision_model = collision_model.copy() if collision_model is not None else None

        joint1 = self.model.jointPlacements[1]
        elbow_in_j1 = self.model.jointPlacements[2].translation[:2].copy()
        tip_in_j2 = self.model.frames[self.tip_frame_id].placement.translation[:2].copy()
        #: Position [m] of joint 1's axis in the hand frame.
        self.joint1_in_hand = joint1.translation[:2].copy()
        self.joint1_in_hand_floats = tuple(self.joint1_in_hand.tolist())  # (hot paths)
        self._l1 = float(np.linalg.norm(elbow_in_j1))
        self._l2 = float(np.linalg.norm(tip_in_j2))
        for label, length in (("link 1 (joint 1 to joint 2)", self._l1), ("link 2 (joint 2 to the tip)", self._l2)):
            if not 1e-6 <= length <= 10.0:
                raise FingerModelError(f"{label} is {length:.6g} m long: expected 1e-6 to 10 m", source=self.source)
        self._alpha1 = float(np.arctan2(elbow_in_j1[1], elbow_in_j1[0]))
        alpha2 = float(np.arctan2(tip_in_j2[1], tip_in_j2[0]))
        gamma2 = planar_angle(self.model.jointPlacements[2])
        #: Absolute angle [rad] of link 1 at q1 = 0 in the hand frame.
        self.psi1_offset = planar_angle(joint1) + self._alpha1
        #: Geometric elbow angle theta2 [rad] minus q2.
        self.theta2_offset = float(wrap_angle(gamma2 + alpha2 - self._alpha1))
        l1, l2 = self._l1, self._l2
        self._ik_constants = (float(self.joint1_in_hand[0]), float(self.joint1_in_hand[1]),
                              float(-self.configuration.sign), abs(l1 - l2), l1 + l2, 1e-12 * (l1 + l2))

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_urdf(
        cls,
        path: str | Path,
        *,
        base_in_hand: ArrayLike = (0.0, 0.0, 0.0),
        configuration: Configuration | str = Configuration.LEFT,
        name: str | None = None,
        tip_frame: str = "tip",
        effort_limit: ArrayLike | None = None,
    ) -> "Finger":
        """Load a finger from a URDF file (kinematics, dynamics, torque limits and collision geometry)."""
        if not isinstance(path, (str, Path)):
            raise InvalidParameterError("path", path, "a URDF file's path (str or pathlib.Path)")
        path = Path(path)
        problem = file_problem(path, "URDF file")
        if problem is not None:
            raise FingerModelError(problem, source=path)
        model, geom = parse_finger_urdf(lambda: pin.buildModelFromUrdf(str(path)),
                                  lambda model: pin.buildGeomFromUrdf(model, str(path), pin.GeometryType.COLLISION),
                                  path)
        return cls(
            model,
            geom,
            base_in_hand=base_in_hand,
            configuration=configuration,
            name=name if name is not None else path.stem,
            tip_frame=tip_frame,
            source=path,
            effort_limit=effort_limit,
        )

    @classmethod
    def from_urdf_string(
        cls,
        urdf: str,
        *,
        base_in_hand: ArrayLike = (0.0, 0.0, 0.0),
        configuration: Configuration | str = Configuration.LEFT,
        name: str = "finger",
        tip_frame: str = "tip",
        effort_limit: ArrayLike | None = None,
    ) -> "Finger":
        """Build a finger from URDF text (for generated fingers, see :mod:`regrasp.model.finger_urdf`)."""
        if not isinstance(urdf, str):
            raise InvalidParameterError("urdf", urdf, "URDF text (a str)")
        model, geom = parse_finger_urdf(lambda: pin.buildModelFromXML(urdf),
                                  lambda model: pin.buildGeomFromUrdfString(model, urdf, pin.GeometryType.COLLISION),
                                  "<string>")
        return cls(
            model,
            geom,
            base_in_hand=base_in_hand,
            configuration=configuration,
            name=name,
            tip_frame=tip_frame,
            source="<string>",
            effort_limit=effort_limit,
        )

    def with_placement(self, base_in_hand: ArrayLike | None = None, configuration: Configuration | str | None = None,
                       name: str | None = None, effort_limit: ArrayLike | None = None) -> "Finger":
        """A copy of this finger with another base pose, configuration, name or torque limits [N m]."""
        return Finger(
            self._model_unplaced,
            self.collision_model,
            base_in_hand=self.base_in_hand if base_in_hand is None else base_in_hand,
            configuration=self.configuration if configuration is None else configuration,
            name=self.name if name is None else name,
            tip_frame=self.tip_frame,
            source=self.source,
            effort_limit=self.effort_limit if effort_limit is None else effort_limit,
        )

    # ------------------------------------------------------------------ geometry
    @property
    def effort_limit(self) -> np.ndarray:
        """The joints' torque limits (2,) [N m]: |τ_j| <= effort_limit[j] (inf: none); module docstring."""
        return np.asarray(self.model.effortLimit, dtype=float)[:2].copy()

    @property
    def link_lengths(self) -> tuple[float, float]:
        """(l1, l2) [m]: joint 1 to joint 2, and joint 2 to the tip frame, read from the model."""
        return (self._l1, self._l2)

    @property
    def reach(self) -> tuple[float, float]:
        """Inner and outer radii [m] of the workspace annulus, |l1 - l2| and l1 + l2."""
        return (abs(self._l1 - self._l2), self._l1 + self._l2)

    def link_shapes(self) -> tuple[LinkShape, ...]:
        """The URDF collision shapes of both links (empty if the model has none)."""
        if self.collision_model is None:
            return ()
        return tuple(
            LinkShape(
                link=obj.parentJoint - 1,
                name=obj.name,
                geometry=obj.geometry,
                placement_in_joint=obj.placement,
            )
            for obj in self.collision_model.geometryObjects
            if obj.parentJoint in (1, 2)
        )

    def _check_q(self, q) -> np.ndarray:
        return as_finite_array("q", q, (2,))

    def theta2(self, q: ArrayLike) -> float:
        """Geometric elbow angle theta2 [rad] in (-pi, pi] for joint positions ``q``."""
        q = self._check_q(q)
        return float(wrap_angle(q[1] + self.theta2_offset))

    def configuration_of(self, q: ArrayLike) -> Configuration | None:
        """The configuration ``q`` is in, or None when the finger is stretched or folded."""
        t2 = self.theta2(q)
        if 0.0 < -t2 < np.pi:
            return Configuration.LEFT
        if 0.0 < t2 < np.pi:
            return Configuration.RIGHT
        return None

    def joint_positions_in_hand(self, q: ArrayLike) -> np.ndarray:
        """(3, 2) array [m]: joint 1, joint 2 (elbow) and the tip in the hand frame (closed form)."""
        q = self._check_q(q)
        psi1 = self.psi1_offset + q[0]
        psi2 = psi1 + q[1] + self.theta2_offset
        o1 = self.joint1_in_hand
        elbow = o1 + self._l1 * np.array([np.cos(psi1), np.sin(psi1)])
        tip = elbow + self._l2 * np.array([np.cos(psi2), np.sin(psi2)])
        return np.stack([o1, elbow, tip])

    def forward_kinematics(self, q: ArrayLike) -> np.ndarray:
        """Tip position [m] in the hand frame, computed by Pinocchio."""
        q = self._check_q(q)
        pin.forwardKinematics(self.model, self.data, q)
        return pin.updateFramePlacement(self.model, self.data, self.tip_frame_id).translation[:2].copy()

    def tip_jacobian(self, q: ArrayLike) -> np.ndarray:
        r"""The 2x2 tip Jacobian :math:`J = \partial p_{tip} / \partial q` [m/rad] in the hand frame."""
        q = self._check_q(q)
        jac = pin.computeFrameJacobian(self.model, self.data, q, self.tip_frame_id, pin.LOCAL_WORLD_ALIGNED)
        return jac[:2, :].copy()

    def inverse_kinematics(self, tip_in_hand: ArrayLike) -> np.ndarray:
        r"""Joint positions ``q`` [rad] that put the tip at ``tip_in_hand`` in this configuration.

        Closed form: with :math:`r = p - o_1`,
        :math:`\cos\theta_2 = (|r|^2 - l_1^2 - l_2^2) / (2 l_1 l_2)`, :math:`\theta_2 = -\sigma
        \arccos(\cdot)` (:math:`\sigma = +1` left, :math:`-1` right) and
        :math:`\psi_1 = \mathrm{atan2}(r) - \mathrm{atan2}(l_2 \sin\theta_2, l_1 + l_2\cos\theta_2)`.
        Angles are wrapped to (-pi, pi]; joint limits are not applied.

        Raises:
            UnreachableError: the target is outside the annulus |l1 - l2| <= |r| <= l1 + l2
                (a relative slack of 1e-12 is accepted and clamped onto the boundary).
        """
        return self._inverse_kinematics(as_finite_array("tip_in_hand", tip_in_hand, (2,)))

    def _inverse_kinematics(self, target: np.ndarray) -> np.ndarray:
        """:meth:`inverse_kinematics` on a validated (2,) target (hot paths)."""
        return np.array(self.joint_angles(float(target[0]), float(target[1])))

    def joint_angles(self, x: float, y: float, elbow: bool = False) -> tuple[float, ...]:
        """:meth:`inverse_kinematics` in scalar arithmetic (hot paths; ``x``, ``y`` not validated): (q1, q2)
        [rad] for the tip at (x [m], y [m]) in the hand frame; with ``elbow``, (q1, q2, e_x, e_y), e the elbow
        (joint 2's axis) [m] in the hand frame. Raises UnreachableError as :meth:`inverse_kinematics` does."""
        ox, oy, sigma, inner, outer, slack = self._ik_constants
        rx, ry = x - ox, y - oy
        dist = math.hypot(rx, ry)
        l1, l2 = self._l1, self._l2
        if dist > outer + slack or dist < inner - slack:
            raise UnreachableError(self.name, np.array([x, y]), dist, (inner, outer))
        cos2 = min(max((dist**2 - l1**2 - l2**2) / (2.0 * l1 * l2), -1.0), 1.0)
        theta2 = sigma * math.acos(cos2)
        psi1 = math.atan2(ry, rx) - math.atan2(l2 * math.sin(theta2), l1 + l2 * math.cos(theta2))
        if elbow:  # psi1: link 1's direction in the hand frame
            return (wrap_angle(psi1 - self.psi1_offset), wrap_angle(theta2 - self.theta2_offset),
                    ox + l1 * math.cos(psi1), oy + l1 * math.sin(psi1))
        return wrap_angle(psi1 - self.psi1_offset), wrap_angle(theta2 - self.theta2_offset)

    def joint_positions_from_points(self, elbow_in_hand: np.ndarray, tip_in_hand: np.ndarray) -> np.ndarray:
        """Joint positions q [rad] that place the elbow and the tip at the given points.

        The points must be consistent (|elbow - joint 1| = l1, |tip - elbow| = l2); this is
        the cheap inverse of :meth:`joint_positions_in_hand` used on hot paths where the
        elbow is already known, and it does not validate its input.
        """
        v1 = elbow_in_hand - self.joint1_in_hand
        v2 = tip_in_hand - elbow_in_hand
        psi1 = np.arctan2(v1[1], v1[0])
        psi2 = np.arctan2(v2[1], v2[0])
        return np.array([wrap_angle(psi1 - self.psi1_offset), wrap_angle(psi2 - psi1 - self.theta2_offset)])

    def __repr__(self) -> str:
        l1, l2 = self.link_lengths
        return (
            f"Finger(name={self.name!r}, l1={l1:.4g} m, l2={l2:.4g} m, "
            f"base_in_hand={self.base_in_hand.tolist()}, configuration={self.configuration.value!r})"
        )


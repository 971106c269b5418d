r"""A finger's Pinocchio model: parsed from URDF (:func:`parse_finger_urdf`, the links' inertial values checked) and
checked to be a planar two-link finger (:func:`validate_finger_model`): a serial chain of two revolute joints about
+z whose origins lie in the xy-plane, with a tip frame on the second link (:class:`~regrasp.model.finger.Finger`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..core.capture import captured_fd
from ..core.exceptions import FingerModelError
from ..core.validation import MAX_INERTIA, MAX_MASS

__all__ = ["parse_finger_urdf", "planar_angle", "validate_finger_model"]

_PLANAR_TOL = 1e-9

#: The largest condition number a finger's joint-space mass matrix may have, at any elbow angle: past it the matrix is
#: singular to rounding (its links' inertias too far apart, a distal link of 1e300 kg m^2 on one of 1e-6) and no plant
#: can step the finger (the shipped finger's is at most about 100).
MAX_MASS_CONDITION = 1e10


def planar_angle(placement: pin.SE3) -> float:
    """The rotation angle [rad] about z of a placement in the xy-plane."""
    return float(np.arctan2(placement.rotation[1, 0], placement.rotation[0, 0]))


def _is_planar(placement: pin.SE3) -> bool:
    rot, trans = placement.rotation, placement.translation
    return (
        abs(trans[2]) <= _PLANAR_TOL
        and abs(rot[2, 2] - 1.0) <= _PLANAR_TOL
        and np.allclose(rot[2, :2], 0.0, atol=_PLANAR_TOL)
        and np.allclose(rot[:2, 2], 0.0, atol=_PLANAR_TOL)
    )


_JOINT_KIND = {
    "JointModelRZ": None,
    "JointModelRUBZ": "is continuous; declare it 'revolute' with limits (a planar finger needs nq = 1 per joint)",
    "JointModelRX": "rotates about x; a planar finger's joints must rotate about +z",
    "JointModelRY": "rotates about y; a planar finger's joints must rotate about +z",
    "JointModelRevoluteUnaligned": "has an axis other than +z; a planar finger's joints must rotate about +z",
    "JointModelRUBX": "is continuous about x; a planar finger's joints must be revolute about +z",
    "JointModelRUBY": "is continuous about y; a planar finger's joints must be revolute about +z",
    "JointModelPX": "is prismatic; a planar 2R finger has revolute joints only",
    "JointModelPY": "is prismatic; a planar 2R finger has revolute joints only",
    "JointModelPZ": "is prismatic; a planar 2R finger has revolute joints only",
    "JointModelPrismaticUnaligned": "is prismatic; a planar 2R finger has revolute joints only",
}


def validate_finger_model(model: pin.Model, source: str, tip_frame: str) -> None:
    """Raise FingerModelError (naming ``source`` and the joint) unless ``model`` is a planar serial 2R chain with a
    unique tip frame named ``tip_frame`` on its second link."""
    for jid in range(1, model.njoints):
        name = model.names[jid]
        kind = model.joints[jid].shortname()
        if kind not in _JOINT_KIND:
            raise FingerModelError(
                f"joint type {kind} is not supported; a planar 2R finger has revolute joints about +z",
                source=source,
                joint=name,
            )
        if _JOINT_KIND[kind] is not None:
            raise FingerModelError(f"this joint {_JOINT_KIND[kind]}", source=source, joint=name)
        if jid > 2:
            raise FingerModelError(
                f"a planar 2R finger has exactly two actuated joints; this is actuated joint number {jid}",
                source=source,
                joint=name,
            )
        if model.parents[jid] != jid - 1:
            raise FingerModelError(
                "the joints do not form a serial chain (this joint hangs off "
                f"'{model.names[model.parents[jid]]}')",
                source=source,
                joint=name,
            )
        if not _is_planar(model.jointPlacements[jid]):
            raise FingerModelError(
                "the joint origin leaves the xy-plane (non-zero z offset or a roll/pitch rotation)",
                source=source,
                joint=name,
            )
    if model.njoints != 3:
        raise FingerModelError(
            f"a planar 2R finger has exactly two actuated joints; found {model.njoints - 1}", source=source
        )
    if not model.existFrame(tip_frame):
        raise FingerModelError(
            f"no frame named '{tip_frame}' (add a fixed joint to a link named '{tip_frame}' at the fingertip)",
            source=source,
            joint=tip_frame,
        )
    named = [f for f in model.frames if f.name == tip_frame]
    if len(named) > 1:
        raise FingerModelError(
            f"{len(named)} frames are named '{tip_frame}' (a joint and a link, say): the tip frame's name must be "
            "unique",
            source=source,
            joint=tip_frame,
        )
    frame = named[0]
    if frame.parentJoint != 2:
        raise FingerModelError(
            f"the tip frame must hang off the second joint, not '{model.names[frame.parentJoint]}'",
            source=source,
            joint=tip_frame,
        )
    if abs(frame.placement.translation[2]) > _PLANAR_TOL:
        raise FingerModelError("the tip frame leaves the xy-plane", source=source, joint=tip_frame)
    if np.linalg.norm(model.jointPlacements[2].translation[:2]) <= _PLANAR_TOL:
        raise FingerModelError("the first link has zero length", source=source, joint=model.names[2])
    if np.linalg.norm(frame.placement.translation[:2]) <= _PLANAR_TOL:
        raise FingerModelError("the second link has zero length", source=source, joint=tip_frame)
    _check_mass_matrix(model, source)


def _check_mass_matrix(model: pin.Model, source: str) -> None:
    """The joint-space mass matrix of the 2R ``model`` is positive definite with a condition number of at most
    :data:`MAX_MASS_CONDITION` at every elbow angle (sampled; it does not depend on the first joint's)."""
    data = model.createData()
    for elbow in np.linspace(-np.pi, np.pi, 12, endpoint=False):
        mass = pin.crba(model, data, np.array([0.0, elbow]))
        eig = np.linalg.eigvalsh(0.5 * (mass + mass.T)) if np.isfinite(mass).all() else np.full(2, np.nan)
        if not (eig[0] > 0.0 and eig[1] <= MAX_MASS_CONDITION * eig[0]):
            raise FingerModelError(f"the joint-space mass matrix is singular or ill-conditioned at elbow angle "
                                   f"{elbow:.3g} rad (eigenvalues {eig[0]:.3g}, {eig[1]:.3g} kg m^2; a condition "
                                   f"number of at most {MAX_MASS_CONDITION:g} expected): the links' inertias are too "
                                   "far apart", source=source)


def parse_finger_urdf(build_model: Callable[[], pin.Model], build_geometry: Callable[[pin.Model], pin.GeometryModel],
                      source: str | Path) -> tuple[pin.Model, pin.GeometryModel]:
    """(model, collision geometry) from Pinocchio's ``build_model()`` and ``build_geometry(model)``, urdfdom's own
    lines on fd 2 kept off the terminal (its first line joins the FingerModelError, naming ``source``, when parsing
    fails), and the links' inertial values checked (every frame within 10 m of its joint, a finite mass > 0 and a
    non-zero, positive semi-definite inertia per link)."""
    with captured_fd(2) as printed:
        try:
            model = build_model()
            geom = build_geometry(model)
        except Exception as exc:  # Pinocchio raises bare ValueError/RuntimeError
            error = exc
        else:
            error = None
    if error is not None:
        said = next((" ".join(line.split()) for line in printed.text.splitlines() if line.strip()), "")
        raise FingerModelError(f"Pinocchio could not parse the URDF: {' '.join(str(error).split())}"
                               + (f" (urdfdom: {said})" if said else ""), source=source) from error
    for frame in model.frames:  # before the inertias, which Pinocchio sums over the links fixed to a joint
        offset = math.hypot(*frame.placement.translation)  # (no overflow, unlike a sum of squares)
        if not offset <= 10.0:
            raise FingerModelError(f"frame {frame.name!r} is placed {offset:.6g} m from its joint: expected at "
                                   "most 10 m", source=source)
    for j in range(1, model.njoints):
        inertia = model.inertias[j]
        rotational = np.asarray(inertia.inertia, dtype=float)
        mass = float(inertia.mass)
        moments = np.linalg.eigvalsh(0.5 * (rotational + rotational.T)) if np.isfinite(rotational).all() \
            else np.full(3, np.nan)
        if not (np.isfinite(mass) and 0.0 < mass <= MAX_MASS and np.isfinite(moments).all() and moments.min() >= 0.0
                and 0.0 < moments.max() <= MAX_INERTIA and np.isfinite(inertia.lever).all()):
            raise FingerModelError(f"link of joint {model.names[j]!r}: expected a mass in (0, {MAX_MASS:g}] kg and a "
                                   f"non-zero, positive semi-definite inertia of at most {MAX_INERTIA:g} kg m^2, got "
                                   f"mass {mass:.6g} kg, principal moments "
                                   f"{', '.join(f'{m:.3g}' for m in moments)} kg m^2", source=source,
                                   joint=model.names[j])
    return model, geom

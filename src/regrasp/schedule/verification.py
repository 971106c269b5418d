"""The regrasp planner's own check of a schedule (:func:`verify`): the envelopes at the schedule's exact positions, the
forces in the exact modes (the polytope's vertex test on polygons; on a curve the exact test at each position,
:func:`~regrasp.schedule.curve_tables.forces_exist`), the joint torque limits, the break-aways and the slides'
well-posedness (:mod:`regrasp.schedule.well_posed`), with the exact margins on a finer time grid."""

from __future__ import annotations

import itertools
from typing import TYPE_CHECKING

import numpy as np

from .curve_tables import forces_exist, required_wrench
from .force_polytope import force_vertices, torque_excess
from .problem import Problem, breakaway_limits, slide_ratios
from .schedule import RegraspSchedule, ScheduleSample, first_minimum
from .torque import TorqueModel
from .well_posed import violations as well_posed_violations

if TYPE_CHECKING:
    from ..core.trajectory import TrajectorySample

__all__ = ["schedule_torques", "verify"]


def verify(problem: Problem, schedule: RegraspSchedule, substeps: int) -> tuple[list, tuple]:
    """The planner's own check of ``schedule`` on ``substeps`` samples per step, with the exact margins:
    (violations as (time [s], what, contact index or None), (smallest envelope margin [m], (time, name)))."""
    settings = problem.settings
    traj = problem.scenario.trajectory
    n = int(round((schedule.t_end - schedule.t_start) / problem.dt * substeps))
    times = schedule.t_start + (schedule.t_end - schedule.t_start) * np.arange(n + 1) / max(n, 1)
    at = schedule.at(times)
    sample = traj.sample(np.clip(times, traj.t_start, traj.t_end))
    violations = []
    q = problem.settings.envelope_substeps
    step = substeps // q if substeps % q == 0 else 0  # every step-th time is a lattice sub-sample

    def envelope(i: int, j: int):
        if step and j % step == 0 and j // step < len(problem.sub_samples[i]):
            return problem.sub_samples[i][j // step]
        if problem.curved:  # (the window about the planned position: ξ is unwrapped)
            return problem.envelopes[i].at(sample.pose[j], float(times[j]), near=float(at.xi[j, i]))
        return problem.envelopes[i].at(sample.pose[j], float(times[j]))

    margins = np.array([[envelope(i, j).margin(float(at.xi[j, i])) for i in range(len(problem.envelopes))]
                        for j in range(len(times))])
    for k, i in zip(*np.nonzero(margins < settings.envelope_margin - 1e-12)):
        violations.append((float(times[k]), "envelope", int(i)))
    limits = settings.force_limits()
    mu_s = [f.static for f in problem.friction]
    starts = []
    for s in schedule.slides:  # break-away: the slider primed past its static edge as it starts, with any other
        t = np.array([s.start])  # slide that starts with it (the executor primes them together)
        st = schedule.at(t + 1e-9)
        together = [o.contact for o in schedule.slides if abs(o.start - s.start) <= 1e-9]
        starts.append((s, together, float(s.start), st.direction[0], schedule.at(t).xi[0], traj.sample(
            np.clip(t, traj.t_start, traj.t_end))))
    groups: dict[tuple, list] = {}  # the sample times by mode
    for k in range(len(times)):
        groups.setdefault(tuple(at.direction[k]), []).append(k)
    torque = problem.torque if problem.torque is not None and problem.torque.limited else None
    if torque is not None:  # each contact's torques at the schedule's exact positions, rates and accelerations
        torques = schedule_torques(torque, sample, at)
    for direction, ks in groups.items():
        ks = np.array(ks)
        spread = _spread(direction, settings.position_margin)
        if problem.curved:  # (no polytope independent of ξ: the exact test at each position)
            for k in ks:
                why = _curve_violation(problem, torque, None if torque is None else torques[k], sample, k, at.xi[k],
                                       slide_ratios(direction, problem.friction), spread, limits)
                if why is not None:
                    violations.append((float(times[k]), *why))
            continue
        fv = force_vertices(problem.geometry, sample.pose[ks, 2], sample.acceleration[ks],
                            slide_ratios(direction, problem.friction), mu_s, limits)
        for j, k in enumerate(ks):
            if not _holds(*fv.at(j), at.xi[k], spread):
                violations.append((float(times[k]), "forces", None))
            elif torque is not None:
                why = _torque_violation(problem, torque, fv, j, torques[k], sample.pose[k, 2], sample.acceleration[k],
                                        at.xi[k], slide_ratios(direction, problem.friction), mu_s, limits)
                if why is not None:
                    violations.append((float(times[k]), *why))
    factor = settings.sliding_friction_factor
    if factor is not None:
        violations += well_posed_violations(problem.torque, problem.scenario, times, sample.pose, at.xi, at.direction,
                                            problem.friction, factor)
    for s, together, t, direction, xi, smp in starts:
        if problem.curved:
            ratios = slide_ratios(direction, problem.friction, breaking=together, overshoot=settings.prime_overshoot)
            if _curve_violation(problem, None, None, smp, 0, xi, ratios, _spread(direction, settings.position_margin),
                                breakaway_limits(limits)) is not None:
                violations.append((t, "breakaway", s.contact))
            continue
        fv = force_vertices(problem.geometry, smp.pose[:, 2], smp.acceleration,
                            slide_ratios(direction, problem.friction, breaking=together,
                                         overshoot=settings.prime_overshoot), mu_s, breakaway_limits(limits))
        if not _holds(*fv.at(0), xi, _spread(direction, settings.position_margin)):
            violations.append((t, "breakaway", s.contact))
    return sorted(violations), first_minimum(margins, times, problem.names)


def schedule_torques(torque: TorqueModel, sample: TrajectorySample, at: ScheduleSample) -> np.ndarray:
    """Per sample, contact and joint the torque map (w, a, b) of :class:`~regrasp.schedule.torque.ContactTorques` at
    the schedule's positions, rates and accelerations ``at``: (n, m, 2, 3)."""
    out = np.empty((len(at.xi), at.xi.shape[1], 2, 3))
    for i in range(at.xi.shape[1]):
        c = torque.contact(i, sample.pose, sample.velocity, sample.acceleration, at.xi[:, i:i + 1],
                           at.xi_dot[:, i:i + 1], at.xi_ddot[:, i:i + 1])
        out[:, i] = np.stack([c.wrench[:, 0], c.normal[:, 0], c.tangential[:, 0]], axis=-1)
    return out


def _torque_violation(problem: Problem, torque: TorqueModel, fv, j: int, torques: np.ndarray, beta: float,
                      acceleration: np.ndarray, xi: np.ndarray, ratios, mu_s, limits) -> tuple[str, int] | None:
    """Whether no force system at positions ``xi`` keeps the joints within their torque limits (``torques``
    (m, 2, 3) as :func:`schedule_torques` gives them): (what, contact) of the violation, or None. Where every
    vertex of the polytope (``fv`` at its sample j) keeps them, every force system does (|τ_j| is convex); else a
    linear program decides (:func:`~regrasp.schedule.force_polytope.torque_excess`)."""
    keep = fv.valid[j]
    lam, tau = fv.normal[j, keep], fv.tangential[j, keep]  # (V, m)
    values = torques[None, :, :, 0] + torques[None, :, :, 1] * lam[:, :, None] + torques[None, :, :, 2] \
        * tau[:, :, None]
    if np.all(np.abs(values) <= torque.effort[None]):
        return None
    found = torque_excess(problem.geometry, beta, acceleration, xi, ratios, mu_s, limits, torques, torque.effort)
    if not found.excess > 1e-9:
        return None
    if found.contact < 0:  # (no force system at all: the forces check's business)
        return None
    i, joint = found.contact, found.joint
    return (f"torque limit ({problem.names[i]} joint {joint + 1} needs at least {found.torque:.4f} N m, "
            f"its limit is {torque.effort[i, joint]:.4f} N m)", i)


def _curve_violation(problem: Problem, torque: TorqueModel | None, torques: np.ndarray | None, sample, k: int,
                     xi: np.ndarray, ratios, spread: np.ndarray | None, limits) -> tuple[str, int | None] | None:
    """On a curved object, whether positions ``xi`` (and ``xi`` + each row of ``spread``) admit no force system in the
    mode ``ratios`` at ``sample``'s k-th time (``("forces", None)``), or none within the joints' torque limits at
    ``xi`` (``torques`` (m, 2, 3): what, contact), or None (:func:`~regrasp.schedule.curve_tables.forces_exist`)."""
    obj = problem.scenario.polygon
    mu_s = [f.static for f in problem.friction]
    wrench = required_wrench(obj.mass, obj.inertia, problem.scenario.gravity_in_hand, sample)[k]
    for offset in (np.zeros((1, len(xi))) if spread is None else spread):
        if not forces_exist(obj, xi + offset, ratios, mu_s, limits, wrench):
            return "forces", None
    if torque is None or forces_exist(obj, xi, ratios, mu_s, limits, wrench, torques, torque.effort):
        return None
    found = torque_excess(problem.geometry_at(xi), sample.pose[k, 2], sample.acceleration[k], xi, ratios, mu_s, limits,
                          torques, torque.effort)
    i, joint = max(found.contact, 0), max(found.joint, 0)
    return (f"torque limit ({problem.names[i]} joint {joint + 1} needs at least {found.torque:.4f} N m, "
            f"its limit is {torque.effort[i, joint]:.4f} N m)", i)


def _holds(lam: np.ndarray, offset: np.ndarray, xi: np.ndarray, spread: np.ndarray | None = None) -> bool:
    """Whether positions ``xi`` (and ``xi`` + each row of ``spread``) admit a force system of the polytope with
    vertices (λ, q)."""
    if len(lam) == 0:
        return False
    points = xi[None] if spread is None else xi[None] + spread
    phi = lam @ points.T - offset[:, None]
    return bool(np.all((phi.min(axis=0) <= 1e-10) & (phi.max(axis=0) >= -1e-10)))


def _spread(direction, margin: float) -> np.ndarray | None:
    """The offsets of the positions a force system must also hold at: every contact that moves in ``direction`` where
    planned or ``margin`` behind (``RegraspSettings.position_margin``: a slide that lags), the others where planned,
    (2^p, m); None without a margin or a slider."""
    sliders = [i for i, d in enumerate(direction) if d != 0]
    if margin <= 0.0 or not sliders:
        return None
    out = np.zeros((2 ** len(sliders), len(direction)))
    back = -margin * np.array([direction[i] for i in sliders], dtype=float)
    out[:, sliders] = np.array(list(itertools.product((0.0, 1.0), repeat=len(sliders)))) * back
    return out

r"""The grasp planner (paper §2): is a trajectory feasible, and where may each finger touch?

For every finger, its edge and configuration, and every time sample of the object
trajectory, :class:`~regrasp.envelope.finger_envelope.FingerEnvelope` gives d(t), the condition I–IV,
the reachable set and the feasible set. The planner adds:

* the verdict: feasible iff every finger's feasible set is non-empty at every sample;
* the infeasible time intervals per finger: maximal runs of consecutive infeasible
  samples with the same reason (``start``/``end`` are the first and last infeasible
  sample times, so the true interval extends at most one sample spacing further);
* the initial grasp the envelope suggests. **Rule:** the contact that stays outside every danger zone
  longest. Let :math:`F_k` be the feasible set at sample :math:`k` and :math:`D_k` the same less each
  interval's danger zones (``danger_fraction`` of its width at each end,
  :data:`~regrasp.core.intervals.DANGER_FRACTION`: where the paper's policy would already slide). The prefix
  intersections :math:`P_k = F_0 \cap \dots \cap F_k` shrink with :math:`k`; when the last one is non-empty,
  one fixed grasp survives the whole trajectory (``fixed_grasp`` is then :math:`P_K`, otherwise empty) and no
  regrasp is needed. The candidates :math:`C` are that fixed grasp if there is one, else the whole edge; take
  the last non-empty :math:`S_K = C \cap D_0 \cap \dots \cap D_K` and choose the midpoint of its widest
  interval (the most central such contact): it is outside the danger zones up to ``initial_xi_safe_until`` =
  :math:`t_K` and, among the candidates, none stays out longer. Only when :math:`C \cap D_0` is empty (the
  feasible set has no width at the start) the start lies in a danger zone: then the midpoint of the widest
  interval of the last non-empty :math:`P_k` (the contact that stays feasible longest), and
  ``initial_xi_safe_until`` is None. ``initial_xi_feasible_until`` is the last sample up to which the chosen
  contact stays feasible.

**Curved objects** (:class:`~regrasp.core.curves.CurvedObject`): each sample's sets lie in a window of one
perimeter about the foot of the finger's first joint, and each sample passes its foot to the next as ``near``
(:meth:`FingerEnvelope.at <regrasp.envelope.finger_envelope.FingerEnvelope.at>`), so ξ is unwrapped continuously
along the trajectory and the prefix intersections above compare the same material points.
"""

from __future__ import annotations

import time as _time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ..core.curves import CurvedObject
from ..core.exceptions import InvalidParameterError
from ..core.intervals import DANGER_FRACTION, Intervals, contains, intersect, widest, without_danger_zones
from ..core.polygon import ConvexPolygon
from ..core.trajectory import Trajectory
from ..core.validation import MAX_SAMPLES, as_finite_array, as_sample_count, expect_sequence_of, expect_type
from ..model.geometry import Geometry
from ..model.scenario import FingerContact, Scenario
from .finger_envelope import EnvelopeSample, FingerEnvelope

__all__ = ["FingerPlan", "InfeasibleInterval", "PlanResult", "motion_between_samples", "plan", "plan_scenario"]

Progress = Callable[[int, int], None]

#: A plan warns (:attr:`PlanResult.sampling_warning`) when the object may move more than this fraction of
#: its smallest width between two consecutive samples: what happens between them is then not seen.
COARSE_SAMPLING_FRACTION = 0.25


def _outline(polygon: ConvexPolygon | CurvedObject) -> np.ndarray:
    """The object's vertices (n, 2) [m], or a curve's outline points (object frame)."""
    return polygon.outline() if isinstance(polygon, CurvedObject) else polygon.vertices


def motion_between_samples(trajectory: Trajectory, polygon: ConvexPolygon | CurvedObject, times: np.ndarray) -> float:
    r"""How far [m] a point of the object may move between two consecutive samples (first order):

    .. math:: \max_k \; (t_{k+1} - t_k) \max_{j \in \{k, k+1\}} \left(|v(t_j)| + |\dot\beta(t_j)|\, r\right),

    with :math:`r` the largest distance of a vertex (a curve: of its outline's points) from the object frame's
    origin. Zero for one sample.
    """
    if len(times) < 2:
        return 0.0
    twist = trajectory.velocity(times)
    r = float(np.max(np.linalg.norm(_outline(polygon), axis=1)))
    speed = np.hypot(twist[:, 0], twist[:, 1]) + np.abs(twist[:, 2]) * r
    return float(np.max(np.abs(np.diff(times)) * np.maximum(speed[:-1], speed[1:])))


@dataclass(frozen=True)
class InfeasibleInterval:
    """A run of consecutive samples where a finger has no feasible contact.

    Attributes:
        start: First infeasible sample time [s].
        end: Last infeasible sample time [s].
        reason: ``"condition I"``, ``"out of reach"``, ``"off the edge"`` or ``"collision"``.
    """

    start: float
    end: float
    reason: str


@dataclass(frozen=True)
class FingerPlan:
    """The planner's result for one finger.

    Attributes:
        name: Finger name.
        edge: Contact edge index.
        configuration: ``"left"`` or ``"right"``.
        base_in_hand: Base pose (x [m], y [m], theta [rad]) in the hand frame.
        link_lengths: (l1, l2) [m].
        xi_origin_in_object: ξ origin of the edge [m], object frame (a curve: its point at ξ = 0).
        xi_direction_in_object: ξ direction of the edge (unit), object frame (a curve: its tangent at ξ = 0).
        samples: One envelope per time sample.
        infeasible_intervals: Where the feasible set is empty, and why.
        initial_xi: Suggested initial contact ξ [m], or None if the first sample is infeasible.
        initial_xi_feasible_until: Last sample time [s] up to which ``initial_xi`` stays feasible.
        initial_xi_safe_until: Last sample time [s] up to which ``initial_xi`` stays outside the danger zones
            (None: it starts inside one, as only a feasible set with no width at the start forces).
        fixed_grasp: ξ-intervals feasible at every sample (empty when a regrasp is needed).
        tip_clearance: Tip clearance [m] used by the ``urdf`` geometry, else None.
    """

    name: str
    edge: int
    configuration: str
    base_in_hand: np.ndarray
    link_lengths: tuple[float, float]
    xi_origin_in_object: np.ndarray
    xi_direction_in_object: np.ndarray
    samples: tuple[EnvelopeSample, ...]
    infeasible_intervals: tuple[InfeasibleInterval, ...]
    initial_xi: float | None
    initial_xi_feasible_until: float | None
    fixed_grasp: Intervals
    tip_clearance: float | None
    initial_xi_safe_until: float | None = None

    @property
    def feasible(self) -> bool:
        """Whether this finger has a feasible contact at every sample."""
        return not self.infeasible_intervals


@dataclass(frozen=True)
class PlanResult:
    """The planner's verdict for a trajectory.

    Attributes:
        feasible: Every finger has a feasible contact at every sample.
        times: Sample times [s], shape (n,).
        poses: Object poses (x [m], y [m], beta [rad]) in the hand frame, shape (n, 3).
        polygon: The object (a polygon or a curved object).
        fingers: One plan per finger.
        geometry: The collision geometry used (``ideal`` or ``urdf``).
        seconds_per_sample: Median wall time [s] of one finger's envelope at one sample.
        scenario: The scenario's name, if the plan came from one.
        motion_between_samples: How far [m] the object may move between two samples
            (:func:`motion_between_samples`).
    """

    feasible: bool
    times: np.ndarray
    poses: np.ndarray
    polygon: ConvexPolygon | CurvedObject
    fingers: tuple[FingerPlan, ...]
    geometry: Geometry
    seconds_per_sample: float
    scenario: str | None = None
    motion_between_samples: float = 0.0

    @property
    def sampling_warning(self) -> str | None:
        """A one-line warning when the samples are too far apart to see the object's motion (it may move more
        than :data:`COARSE_SAMPLING_FRACTION` of its smallest width between two), else None."""
        width = self.polygon.width
        if self.motion_between_samples <= COARSE_SAMPLING_FRACTION * width:
            return None
        return (f"{len(self.times)} samples over {self.times[-1] - self.times[0]:.4g} s are too few: the object may "
                f"move {self.motion_between_samples * 1e3:.4g} mm between two, more than "
                f"{COARSE_SAMPLING_FRACTION:.0%} of its {width * 1e3:.4g} mm width, and the plan does not see "
                f"what happens in between (raise the samples)")

    def to_json_dict(self) -> dict:
        """A JSON-serialisable dict (the ``regrasp plan --json`` document)."""

        def ivs(intervals):
            return [[float(lo), float(hi)] for lo, hi in intervals]

        return {
            "scenario": self.scenario,
            "feasible": bool(self.feasible),
            "geometry": self.geometry.value,
            "times": self.times.tolist(),
            "object": {
                "vertices_in_object": _outline(self.polygon).tolist(),
                "mass": self.polygon.mass,
                "inertia": self.polygon.inertia,
            },
            "poses": self.poses.tolist(),
            "seconds_per_sample": self.seconds_per_sample,
            "motion_between_samples": self.motion_between_samples,
            "warnings": [w for w in (self.sampling_warning,) if w is not None],
            "fingers": [
                {
                    "name": f.name,
                    "edge": f.edge,
                    "configuration": f.configuration,
                    "base_in_hand": f.base_in_hand.tolist(),
                    "link_lengths": list(f.link_lengths),
                    "xi_origin_in_object": f.xi_origin_in_object.tolist(),
                    "xi_direction_in_object": f.xi_direction_in_object.tolist(),
                    "edge_range": list(f.samples[0].edge_range),
                    "tip_clearance": f.tip_clearance,
                    "d": [s.d for s in f.samples],
                    "lambda": [s.lam for s in f.samples],
                    "condition": [s.condition.value for s in f.samples],
                    "reachable": [ivs(s.reachable) for s in f.samples],
                    "feasible": [ivs(s.feasible) for s in f.samples],
                    "infeasible_intervals": [
                        {"start": iv.start, "end": iv.end, "reason": iv.reason} for iv in f.infeasible_intervals
                    ],
                    "initial_xi": f.initial_xi,
                    "initial_xi_feasible_until": f.initial_xi_feasible_until,
                    "initial_xi_safe_until": f.initial_xi_safe_until,
                    "fixed_grasp": ivs(f.fixed_grasp),
                }
                for f in self.fingers
            ],
        }


def _infeasible_intervals(samples: Sequence[EnvelopeSample]) -> tuple[InfeasibleInterval, ...]:
    runs: list[InfeasibleInterval] = []
    for k, s in enumerate(samples):
        if s.reason is None:
            continue
        if runs and k > 0 and samples[k - 1].reason == s.reason:
            runs[-1] = InfeasibleInterval(runs[-1].start, s.time, s.reason)
        else:
            runs.append(InfeasibleInterval(s.time, s.time, s.reason))
    return tuple(runs)


def _last_prefix(sets: Sequence[Intervals]) -> tuple[Intervals, int]:
    """The last non-empty prefix intersection of ``sets`` and its index (-1, () when the first set is empty)."""
    prefix, last = sets[0], 0
    if not prefix:
        return (), -1
    for k in range(1, len(sets)):
        nxt = intersect(prefix, sets[k])
        if not nxt:
            break
        prefix, last = nxt, k
    return prefix, last


def _stays_until(sets: Sequence[Intervals], samples: Sequence[EnvelopeSample], xi: float) -> float | None:
    """The last sample time [s] up to which ``xi`` [m] lies in every one of ``sets`` (None: not in the first)."""
    until = None
    for s, sample in zip(sets, samples):
        if not contains(s, xi):
            break
        until = sample.time
    return until


def _initial_grasp(samples: Sequence[EnvelopeSample],
                   fraction: float) -> tuple[float | None, float | None, float | None, Intervals]:
    """The rule of the module docstring: (xi, feasible_until, safe_until, fixed_grasp)."""
    feasible = [s.feasible for s in samples]
    prefix, last = _last_prefix(feasible)
    if last < 0:
        return None, None, None, ()
    fixed = prefix if last == len(samples) - 1 else ()
    safe = [without_danger_zones(f, fraction) for f in feasible]
    safe[0] = intersect(fixed, safe[0]) if fixed else safe[0]
    candidates, _ = _last_prefix(safe)
    lo, hi = widest(candidates or prefix)
    xi = 0.5 * (lo + hi)
    return xi, _stays_until(feasible, samples, xi), _stays_until(safe, samples, xi), fixed


def _xi_axis(env: FingerEnvelope) -> tuple[np.ndarray, np.ndarray]:
    """The ξ origin [m] and direction (unit) of the envelope's face, object frame (a curve: at ξ = 0)."""
    if env.curved:
        point = env.edge.local(0.0)
        return point.point, point.tangent
    return env.edge.xi_origin.copy(), env.edge.xi_direction.copy()


def plan(
    contacts: Sequence[FingerContact],
    polygon: ConvexPolygon | CurvedObject,
    trajectory: Trajectory,
    *,
    samples: int = 401,
    times: np.ndarray | None = None,
    geometry: Geometry | str = Geometry.IDEAL,
    progress: Progress | None = None,
    scenario: str | None = None,
    danger_fraction: float = DANGER_FRACTION,
) -> PlanResult:
    """Run the grasp planner.

    Args:
        contacts: The fingers and their edges.
        polygon: The object: a polygon, or a curved object (module docstring).
        trajectory: The object trajectory X(t) in the hand frame.
        samples: Number of uniformly spaced samples over the trajectory's domain
            (ignored when ``times`` is given).
        times: Explicit sample times [s].
        geometry: ``"ideal"`` or ``"urdf"``.
        progress: Called as ``progress(done, total)`` after each finger-sample.
        scenario: Name recorded in the result.
        danger_fraction: The danger zones' share of a feasible interval's width at each end [-], in (0, 0.5): the
            suggested initial contact keeps out of them longest (module docstring).
    """
    contacts = expect_sequence_of("contacts", contacts, FingerContact, "FingerContact")
    expect_type("polygon", polygon, (ConvexPolygon, CurvedObject), "a ConvexPolygon or a CurvedObject")
    expect_type("trajectory", trajectory, Trajectory, "a Trajectory")
    if not contacts:
        raise InvalidParameterError("contacts", contacts, "at least one finger")
    if isinstance(danger_fraction, bool) or not isinstance(danger_fraction, (int, float)) \
            or not 0.0 < danger_fraction < 0.5:
        raise InvalidParameterError("danger_fraction", danger_fraction, "a fraction in (0, 0.5)")
    if times is None:
        times = trajectory.times(as_sample_count("samples", samples))
    else:
        times = as_finite_array("times", times, (-1,))
        if not 1 <= len(times) <= MAX_SAMPLES:
            raise InvalidParameterError("times", f"{len(times)} times", f"1 to {MAX_SAMPLES} sample times")
    poses = trajectory.pose(times)
    envelopes = [
        FingerEnvelope(c.finger, polygon, c.edge, geometry=geometry, tip_clearance=c.tip_clearance)
        for c in contacts
    ]
    total, done = len(times) * len(envelopes), 0
    plans, durations = [], []
    for contact, env in zip(contacts, envelopes):
        per_sample = []
        near = None  # (a curve: the previous foot, so that ξ stays unwrapped)
        for t, pose in zip(times, poses):
            start = _time.perf_counter()
            per_sample.append(env.at(pose, float(t), near=near))
            durations.append(_time.perf_counter() - start)
            near = per_sample[-1].xi_foot
            done += 1
            if progress is not None:
                progress(done, total)
        per_sample = tuple(per_sample)
        xi0, until, safe_until, fixed = _initial_grasp(per_sample, float(danger_fraction))
        finger = contact.finger
        plans.append(
            FingerPlan(
                name=finger.name,
                edge=env.edge.index,
                configuration=finger.configuration.value,
                base_in_hand=finger.base_in_hand.copy(),
                link_lengths=finger.link_lengths,
                xi_origin_in_object=_xi_axis(env)[0],
                xi_direction_in_object=_xi_axis(env)[1],
                samples=per_sample,
                infeasible_intervals=_infeasible_intervals(per_sample),
                initial_xi=xi0,
                initial_xi_feasible_until=until,
                initial_xi_safe_until=safe_until,
                fixed_grasp=fixed,
                tip_clearance=env.tip_clearance,
            )
        )
    return PlanResult(
        feasible=all(p.feasible for p in plans),
        times=times,
        poses=poses,
        polygon=polygon,
        fingers=tuple(plans),
        geometry=envelopes[0].geometry,
        seconds_per_sample=float(np.median(durations)),
        scenario=scenario,
        motion_between_samples=motion_between_samples(trajectory, polygon, times),
    )


def plan_scenario(
    scenario: Scenario,
    *,
    samples: int | None = None,
    geometry: Geometry | str | None = None,
    progress: Progress | None = None,
    danger_fraction: float = DANGER_FRACTION,
) -> PlanResult:
    """Run the planner on a loaded scenario (``samples``/``geometry`` override its settings; ``danger_fraction`` as in
    :func:`plan`)."""
    expect_type("scenario", scenario, Scenario, "a Scenario (regrasp.load_scenario)")
    if samples is not None:
        samples = as_sample_count("samples", samples)
    return plan(
        scenario.contacts,
        scenario.polygon,
        scenario.trajectory,
        samples=scenario.samples if samples is None else int(samples),
        geometry=scenario.geometry if geometry is None else scenario.check_geometry(geometry),
        progress=progress,
        scenario=scenario.name,
        danger_fraction=danger_fraction,
    )

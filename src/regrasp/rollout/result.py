"""A finished rollout's result, built from the simulation loop's records (:mod:`regrasp.plants.simulation`)."""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from ..core.contact import ContactMode, Friction, cone_margin
from ..core.events import Event, EventSource, Failure
from ..core.health import ContactHealth, HealthMonitor
from ..plants.simulation import SimulationOutcome, StepRecord
from ..schedule.schedule import RegraspSchedule
from ..supervisor.types import ContactPhase

__all__ = ["TRANSIENT", "RolloutResult", "RolloutRows"]

#: Tracking errors are reported after this transient [s].
TRANSIENT = 0.5


def _num(x):
    return None if x is None or not np.isfinite(x) else float(x)


@dataclass(frozen=True)
class RolloutResult:
    """A finished rollout, with the checks a reviewer needs.

    Attributes:
        success: Ran to the end with no failure.
        failure: When and why it failed (:class:`~regrasp.core.events.Failure`), or None.
        duration: Requested duration [s].
        steps: Control steps run.
        object_width: Largest extent of the object [m] (the error scale).
        max_object_error_after_transient: max |x_o - x_d| over t > 0.5 s [m] (NaN if none).
        max_orientation_error_after_transient: max |β - β_d| over t > 0.5 s [rad].
        regrasps: Completed slides per finger.
        events: Plant events and supervisor decisions (:class:`~regrasp.core.events.Event`), in time order.
        min_cone_margin: Smallest μ_s f_n - |f_t| of a contact the supervisor holds fixed, in the plant [N] ...
        min_cone_margin_at: ... when [s] and which finger.
        min_envelope_margin: Smallest distance of a contact to its feasible bounds [m] ...
        min_envelope_margin_at: ... when [s] and which finger.
        times: Step start times [s], (k,).
        xi: Each contact's ξ at each step [m], (k, m).
        bounds: The feasible interval around each contact [m], (k, m, 2).
        planned_xi: Where the policy's plan puts each contact [m] (NaN without a plan), (k, m).
        phases: Each contact's supervisor phase per step, (k, m) strings.
        object_error: X_d - X per step, (k, 3).
        poses: The plant's object pose after each step (x, y, β) [m, rad], (k, 3).
        joint_positions: The plant's joint angles after each step [rad], (k, 2m).
        forces_surface: The plant's contact forces (normal, tangential) [N], (k, m, 2).
        supervisor_seconds, control_seconds, plant_seconds: Wall time per step [s], (k,).
        wall_seconds: Wall time of the whole run [s].
        names: Finger names.
        policy: The policy's name.
        replans: Re-plans of the schedule.
        schedule: The schedule the run started with, or None.
        rrd: Path of the recording, or None.
        health: Each contact's :class:`~regrasp.core.health.ContactHealth`: the least force it carried held and
            sliding, its longest time without force, its largest slip while held.
    """

    success: bool
    failure: Failure | None
    duration: float
    steps: int
    object_width: float
    max_object_error_after_transient: float
    max_orientation_error_after_transient: float
    regrasps: dict[str, int]
    events: tuple[Event, ...]
    min_cone_margin: float
    min_cone_margin_at: tuple[float, str]
    min_envelope_margin: float
    min_envelope_margin_at: tuple[float, str]
    times: np.ndarray
    xi: np.ndarray
    bounds: np.ndarray
    planned_xi: np.ndarray
    phases: np.ndarray
    object_error: np.ndarray
    poses: np.ndarray
    joint_positions: np.ndarray
    forces_surface: np.ndarray
    supervisor_seconds: np.ndarray
    control_seconds: np.ndarray
    plant_seconds: np.ndarray
    wall_seconds: float
    names: tuple[str, ...]
    policy: str = "paper"
    replans: int = 0
    schedule: RegraspSchedule | None = None
    rrd: str | None = None
    health: tuple[ContactHealth, ...] = ()

    @property
    def simulated_seconds(self) -> float:
        return float(self.steps * (self.times[1] - self.times[0])) if self.steps > 1 else 0.0

    @property
    def realtime_factor(self) -> float:
        """Simulated seconds per wall-clock second."""
        return self.simulated_seconds / self.wall_seconds if self.wall_seconds > 0 else float("nan")

    def plant_event_counts(self) -> dict[str, int]:
        """How many events of each kind the plant reported."""
        return dict(Counter(e.kind.value for e in self.events if e.source is EventSource.PLANT))

    def to_json_dict(self) -> dict:
        """The summary as plain JSON types (the ``regrasp simulate --json`` document)."""
        return {
            "success": self.success,
            "failure": None if self.failure is None else self.failure.to_json_dict(),
            "policy": self.policy,
            "duration": self.duration,
            "simulated": self.simulated_seconds,
            "steps": self.steps,
            "object_width": self.object_width,
            "max_object_error_after_transient": _num(self.max_object_error_after_transient),
            "max_orientation_error_after_transient": _num(self.max_orientation_error_after_transient),
            "regrasps": dict(self.regrasps),
            "replans": self.replans,
            "events": [e.to_json_dict() for e in self.events],
            "plant_events": self.plant_event_counts(),
            "min_cone_margin": _num(self.min_cone_margin),
            "min_cone_margin_at": {"time": _num(self.min_cone_margin_at[0]), "contact": self.min_cone_margin_at[1]},
            "min_envelope_margin": _num(self.min_envelope_margin),
            "min_envelope_margin_at": {"time": _num(self.min_envelope_margin_at[0]),
                                       "contact": self.min_envelope_margin_at[1]},
            "wall_seconds": self.wall_seconds,
            "realtime_factor": _num(self.realtime_factor),
            "schedule": None if self.schedule is None else schedule_summary(self.schedule),
            "rrd": self.rrd,
            "contact_health": [h.to_json_dict() for h in self.health],
        }


def schedule_summary(schedule: RegraspSchedule) -> dict:
    """The schedule's summary (``regrasp simulate --json``'s ``"schedule"``): its slides and margins."""
    return {
        "periodic": schedule.periodic,
        "t_start": schedule.t_start,
        "t_end": schedule.t_end,
        "slides": [s.to_json_dict() for s in schedule.slides],
        "slides_per_contact": schedule.slides_per_contact(),
        "slides_lower_bound": schedule.slides_lower_bound,
        "min_envelope_margin": _num(schedule.min_envelope_margin),
        "min_cone_margin": _num(schedule.min_cone_margin),
        "required_envelope_margin": schedule.required_envelope_margin,
        "required_cone_margin": schedule.required_cone_margin,
        "planning_seconds": schedule.planning_seconds,
    }


class RolloutRows:
    """The per-step series of a run, in buffers allocated once (a consumer of the loop's records)."""

    def __init__(self, total: int, m: int, frictions: tuple[Friction, ...]):
        self.n = 0
        self.static = [f.static for f in frictions]  # the fixed contacts' cones
        self.times = np.empty(total)
        self.xi = np.empty((total, m))
        self.bounds = np.empty((total, m, 2))
        self.planned_xi = np.empty((total, m))
        self.phases = np.empty((total, m), dtype=object)
        self.object_error = np.empty((total, 3))
        self.poses = np.empty((total, 3))
        self.joint_positions = np.empty((total, 2 * m))
        self.forces_surface = np.empty((total, m, 2))
        self.envelope_margin = np.empty((total, m))
        self.cone_margin = np.empty((total, m))
        self.slip = np.empty((total, m))
        self.supervisor_seconds = np.empty(total)
        self.control_seconds = np.empty(total)
        self.plant_seconds = np.empty(total)
        self.plant_events: list[Event] = []

    def add(self, record: StepRecord) -> None:
        k = self.n
        out = record.supervision
        forces = record.plant.forces_surface
        self.times[k] = record.t
        self.xi[k] = record.truth.xi
        self.bounds[k] = out.bounds
        self.planned_xi[k] = out.planned_xi
        self.phases[k] = [p.value for p in out.phases]
        self.object_error[k] = record.object_error
        self.poses[k] = record.plant.state.X
        self.joint_positions[k] = record.plant.state.q
        self.forces_surface[k] = forces
        self.slip[k] = record.plant.slip
        self.envelope_margin[k] = out.margins
        # the plant's static cone margins μ_s f_n - |f_t| at the contacts the supervisor holds fixed (a
        # contact being primed slips on purpose); NaN elsewhere
        fixed = ContactMode.FIXED
        self.cone_margin[k] = [cone_margin(mu, fn, ft) if mode is fixed and phase is ContactPhase.FIXED else math.nan
                               for mu, (fn, ft), mode, phase in zip(self.static, forces.tolist(), record.plant.modes,
                                                                    out.phases)]
        self.supervisor_seconds[k] = out.supervisor_seconds
        self.control_seconds[k] = out.control_seconds
        self.plant_seconds[k] = record.plant_seconds
        self.plant_events.extend(e for e in record.events if e.source is EventSource.PLANT)
        self.n = k + 1

    def _minimum(self, values: np.ndarray, names) -> tuple[float, tuple[float, str]]:
        v = values[:self.n]
        finite = np.where(np.isfinite(v), v, np.inf)
        if not np.isfinite(finite).any():
            return math.inf, (math.nan, "")
        k, i = np.unravel_index(int(np.argmin(finite)), finite.shape)
        return float(finite[k, i]), (float(self.times[k]), names[i])

    def result(self, outcome: SimulationOutcome, *, duration: float, object_width: float, names: Sequence[str],
               regrasps: dict[str, int], supervisor_events: Iterable[Event], policy: str, replans: int,
               schedule: RegraspSchedule | None, rrd: str | None,
               health: tuple[ContactHealth, ...] = ()) -> RolloutResult:
        n = self.n
        times = self.times[:n].copy()
        err = self.object_error[:n].copy()
        late = times > TRANSIENT
        pos_err = np.hypot(err[late, 0], err[late, 1])
        events = sorted(list(supervisor_events) + self.plant_events, key=lambda e: e.time)
        cone, cone_at = self._minimum(self.cone_margin, names)
        env, env_at = self._minimum(self.envelope_margin, names)
        return RolloutResult(
            success=outcome.failure is None, failure=outcome.failure, duration=duration, steps=n,
            object_width=object_width,
            max_object_error_after_transient=float(pos_err.max()) if pos_err.size else float("nan"),
            max_orientation_error_after_transient=float(np.abs(err[late, 2]).max()) if late.any() else float("nan"),
            regrasps=regrasps, events=tuple(events), min_cone_margin=cone, min_cone_margin_at=cone_at,
            min_envelope_margin=env, min_envelope_margin_at=env_at, times=times, xi=self.xi[:n].copy(),
            bounds=self.bounds[:n].copy(), planned_xi=self.planned_xi[:n].copy(), phases=self.phases[:n].copy(),
            object_error=err, poses=self.poses[:n].copy(), joint_positions=self.joint_positions[:n].copy(),
            forces_surface=self.forces_surface[:n].copy(),
            supervisor_seconds=self.supervisor_seconds[:n].copy(), control_seconds=self.control_seconds[:n].copy(),
            plant_seconds=self.plant_seconds[:n].copy(), wall_seconds=outcome.wall_seconds, names=tuple(names),
            policy=policy, replans=replans, schedule=schedule, rrd=rrd, health=health)

    def judge(self, monitor: HealthMonitor, start: int) -> tuple[int, Failure | None]:
        """Hand the rows from ``start`` on to the health ``monitor`` (a contact in phase fixed is held); (the next
        row to hand, the first contact lost or None)."""
        fixed = ContactPhase.FIXED.value
        for k in range(start, self.n):
            lost = monitor.observe(float(self.times[k]), self.forces_surface[k, :, 0].tolist(), self.slip[k].tolist(),
                                   [p == fixed for p in self.phases[k]])
            if lost is not None:
                return k + 1, lost
        return self.n, None

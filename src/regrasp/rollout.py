"""A regrasping rollout: the independent plant driven by the supervisor and its control laws.

:func:`build_rollout` sets up a plant (full coordinates, :mod:`regrasp.plant`) and a
:class:`~regrasp.supervisor.RegraspSupervisor` (which never sees the plant: it gets a
:class:`~regrasp.supervisor.Measurement` per step) from a scenario, with every contact fixed at
the planner's initial grasp. :meth:`Rollout.run` runs it at the plant's step (1 kHz by default,
zero-order hold) until the end or the first failure:

* the plant stops (separation, a contact leaving its edge, a link–object collision, a singular
  finger);
* a contact slips that the supervisor did not set sliding (an *unplanned slip*);
* a fixed contact leaves its feasible envelope;
* no internal force keeps the contacts in their cones (the QP is infeasible), or the controller's
  model meets a singular finger.

A failure is a result, not an exception: :class:`RolloutResult` says when and why.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from .contact import ContactMode, Friction, cone_margin
from .exceptions import InvalidParameterError, RegraspError
from .grasp import Grasp
from .hand import Hand
from .plant import Plant, PlantContact, PlantStep
from .planner import plan_scenario
from .reduced import ReducedModel
from .scenario import Scenario
from .supervisor import ContactPhase, Measurement, RegraspSupervisor, SupervisorOutput, SupervisorSettings
from .validation import as_finite_array, as_positive_float

__all__ = ["Rollout", "RolloutEvent", "RolloutFailure", "RolloutResult", "build_rollout"]

#: Tracking errors are reported after this transient [s].
TRANSIENT = 0.5


@dataclass(frozen=True)
class RolloutEvent:
    """A plant event or a supervisor decision, in one log.

    Attributes:
        time: [s].
        contact: Finger name.
        kind: The plant's kind (``slip``, ``stick``, ``separation``...) or the supervisor's
            (``danger``, ``slide_rejected``, ``prime``, ``slide``, ``arrived``...).
        detail: Numbers and reasons.
        source: ``"plant"`` or ``"supervisor"``.
    """

    time: float
    contact: str
    kind: str
    detail: str
    source: str

    def to_json_dict(self) -> dict:
        return {"time": self.time, "contact": self.contact, "kind": self.kind, "detail": self.detail,
                "source": self.source}


@dataclass(frozen=True)
class RolloutFailure:
    """Why and when a rollout failed."""

    time: float
    reason: str


@dataclass(frozen=True)
class RolloutResult:
    """A finished rollout, with the checks a reviewer needs.

    Attributes:
        success: Ran to the end with no failure.
        failure: When and why it failed, or None.
        duration: Requested duration [s].
        steps: Control steps run.
        object_width: Largest extent of the object [m] (the error scale).
        max_object_error_after_transient: max |x_o - x_d| over t > 0.5 s [m] (NaN if none).
        max_orientation_error_after_transient: max |β - β_d| over t > 0.5 s [rad].
        regrasps: Completed slides per finger.
        events: Plant events and supervisor decisions, in time order.
        min_cone_margin: Smallest μ_s f_n - |f_t| of a fixed contact in the plant [N].
        min_envelope_margin: Smallest distance of a contact to its feasible bounds [m].
        times: Step start times [s], (k,).
        xi: Each contact's ξ at each step [m], (k, m).
        bounds: The feasible interval around each contact [m], (k, m, 2).
        phases: Each contact's supervisor phase per step, (k, m) strings.
        object_error: X_d - X per step, (k, 3).
        forces_surface: The plant's contact forces (normal, tangential) [N], (k, m, 2).
        supervisor_seconds, control_seconds, plant_seconds: Wall time per step [s], (k,).
        wall_seconds: Wall time of the whole run [s].
        rrd: Path of the recording, or None.
        names: Finger names.
    """

    success: bool
    failure: RolloutFailure | None
    duration: float
    steps: int
    object_width: float
    max_object_error_after_transient: float
    max_orientation_error_after_transient: float
    regrasps: dict[str, int]
    events: tuple[RolloutEvent, ...]
    min_cone_margin: float
    min_envelope_margin: float
    times: np.ndarray
    xi: np.ndarray
    bounds: np.ndarray
    phases: np.ndarray
    object_error: np.ndarray
    forces_surface: np.ndarray
    supervisor_seconds: np.ndarray
    control_seconds: np.ndarray
    plant_seconds: np.ndarray
    wall_seconds: float
    names: tuple[str, ...]
    rrd: str | None = None

    @property
    def realtime_factor(self) -> float:
        """Simulated seconds per wall-clock second."""
        simulated = self.steps * (self.times[1] - self.times[0]) if self.steps > 1 else 0.0
        return simulated / self.wall_seconds if self.wall_seconds > 0 else float("nan")

    def to_json_dict(self) -> dict:
        """The summary as plain JSON types (the ``regrasp simulate --json`` document)."""
        def num(x):
            return None if not np.isfinite(x) else float(x)

        return {
            "success": self.success,
            "failure": None if self.failure is None else {"time": self.failure.time, "reason": self.failure.reason},
            "duration": self.duration,
            "steps": self.steps,
            "object_width": self.object_width,
            "max_object_error_after_transient": num(self.max_object_error_after_transient),
            "max_orientation_error_after_transient": num(self.max_orientation_error_after_transient),
            "regrasps": dict(self.regrasps),
            "events": [e.to_json_dict() for e in self.events],
            "min_cone_margin": num(self.min_cone_margin),
            "min_envelope_margin": num(self.min_envelope_margin),
            "rrd": self.rrd,
        }


@dataclass
class Rollout:
    """A plant and a supervisor, ready to run (see :func:`build_rollout`)."""

    plant: Plant
    supervisor: RegraspSupervisor
    duration: float
    names: tuple[str, ...]

    def measure(self, last: PlantStep | None) -> Measurement:
        """What the hand's sensors read now (from the last plant step, or the plant's state)."""
        plant = self.plant
        st = plant.state
        contacts = plant.contacts
        if last is None:
            m = plant.hand.m
            xi = np.array([plant.contact_xi(st, i) for i in range(m)])
            xi, xi_dot, friction = xi[:, 0], xi[:, 1], np.zeros(m)
        else:
            xi, xi_dot, friction = last.xi, last.xi_dot, last.forces_surface[:, 1]
        modes = [c.mode for c in contacts]
        sliding = np.array([mode is ContactMode.SLIDING for mode in modes])
        # a fixed contact's ξ is where it is held (the plant's projection differs by the drift)
        xi = np.array([c.xi if mode is ContactMode.FIXED else x for c, mode, x in zip(contacts, modes, xi.tolist())])
        return Measurement(st.t, st.X.copy(), st.V.copy(), xi, xi_dot, sliding, friction)

    def run(self, *, recorder=None, progress: Callable[[int, int], None] | None = None) -> RolloutResult:
        """Run to ``duration`` or the first failure.

        Args:
            recorder: A :class:`~regrasp.recording.RolloutRecorder` for this rollout's plant, made
                with ``sliding=[]`` (default when all contacts start fixed): each step is logged
                with the object's tracking error; the caller closes it. Or None.
            progress: Called as ``progress(done, total)`` every 50 steps and at the end.
        """
        plant, sup = self.plant, self.supervisor
        dt = plant.dt
        total = int(round(self.duration / dt))
        log: list[RolloutEvent] = []
        rows = _Rows(total, plant.hand.m, plant.friction)
        failure: RolloutFailure | None = None
        last: PlantStep | None = None
        wall0 = time.perf_counter()
        if recorder is not None:
            recorder.log_step(plant, None, desired_pose=sup.trajectory.pose(plant.state.t))
        for k in range(total):
            meas = self.measure(last)
            t = meas.t
            seen = len(sup.events)
            try:
                out = sup.step(meas, dt)
            except RegraspError as exc:
                log.extend(RolloutEvent(e.time, e.contact, e.kind, e.detail, "supervisor") for e in sup.events[seen:])
                failure = RolloutFailure(t, f"control failed: {exc}")
                break
            if out.events:
                log.extend(RolloutEvent(e.time, e.contact, e.kind, e.detail, "supervisor") for e in out.events)
                left = [e for e in out.events if e.kind == "left_envelope"]
                if left:
                    failure = RolloutFailure(t, f"{left[0].contact} left its feasible envelope: {left[0].detail}")
                    break
            t0 = time.perf_counter()
            step = plant.step(out.tau)
            plant_seconds = time.perf_counter() - t0
            last = step
            rows.add(meas, out, step, plant_seconds)
            if recorder is not None:
                # the recorder's error series are the object's (the sliding set changes with each slide)
                control = replace(out.control, error=out.control.error[:3])
                recorder.log_step(plant, control, desired_pose=sup.trajectory.pose(plant.state.t), plant_step=step)
            if step.events:
                for e in step.events:
                    log.append(RolloutEvent(e.time, e.contact, e.kind, e.detail, "plant"))
                failure = self._check_events(step, out)
                if failure is not None:
                    break
            if progress is not None and (k + 1) % 50 == 0:
                progress(k + 1, total)
        if progress is not None:
            progress(rows.n, total)
        return self._result(rows, log, failure, time.perf_counter() - wall0, recorder)

    def _check_events(self, step: PlantStep, out: SupervisorOutput) -> RolloutFailure | None:
        if not step.events:
            return None
        index = {n: i for i, n in enumerate(self.names)}
        for e in step.events:
            i = index[e.contact]
            if e.kind == "slip" and out.phases[i] not in (ContactPhase.PRIMING, ContactPhase.SLIDING):
                return RolloutFailure(e.time, f"unplanned slip of {e.contact}: {e.detail}")
            if e.kind in self.plant.stop_on:
                return RolloutFailure(e.time, f"{e.kind} of {e.contact}: {e.detail}")
        return None

    def _result(self, rows: _Rows, log, failure, wall, recorder) -> RolloutResult:
        n = rows.n
        times = rows.times[:n].copy()
        err = rows.object_error[:n].copy()
        late = times > TRANSIENT
        pos_err = np.hypot(err[late, 0], err[late, 1])
        log.sort(key=lambda e: e.time)
        return RolloutResult(
            success=failure is None,
            failure=failure,
            duration=self.duration,
            steps=n,
            object_width=self.plant.polygon.scale,
            max_object_error_after_transient=float(pos_err.max()) if pos_err.size else float("nan"),
            max_orientation_error_after_transient=float(np.abs(err[late, 2]).max()) if late.any() else float("nan"),
            regrasps={name: c for name, c in zip(self.names, self.supervisor.regrasps)},
            events=tuple(log),
            min_cone_margin=float(min(rows.cone_margin[:n].tolist(), default=np.inf)),
            min_envelope_margin=float(min(rows.envelope_margin[:n].tolist(), default=np.inf)),
            times=times,
            xi=rows.xi[:n].copy(),
            bounds=rows.bounds[:n].copy(),
            phases=rows.phases[:n].copy(),
            object_error=err,
            forces_surface=rows.forces_surface[:n].copy(),
            supervisor_seconds=rows.supervisor_seconds[:n].copy(),
            control_seconds=rows.control_seconds[:n].copy(),
            plant_seconds=rows.plant_seconds[:n].copy(),
            wall_seconds=wall,
            names=self.names,
            rrd=None if recorder is None or recorder.rrd_path is None else str(recorder.rrd_path),
        )


class _Rows:
    """The per-step series of a run, in buffers allocated once for the whole run."""

    def __init__(self, total: int, m: int, frictions: tuple[Friction, ...]):
        self.n = 0
        self.static = [f.static for f in frictions]  # the fixed contacts' cones
        self.times = np.empty(total)
        self.xi = np.empty((total, m))
        self.bounds = np.empty((total, m, 2))
        self.phases = np.empty((total, m), dtype=object)
        self.object_error = np.empty((total, 3))
        self.forces_surface = np.empty((total, m, 2))
        self.envelope_margin = np.empty(total)
        self.cone_margin = np.empty(total)
        self.supervisor_seconds = np.empty(total)
        self.control_seconds = np.empty(total)
        self.plant_seconds = np.empty(total)

    def add(self, meas: Measurement, out: SupervisorOutput, step: PlantStep, plant_seconds: float) -> None:
        k = self.n
        forces = step.forces_surface
        self.times[k] = meas.t
        self.xi[k] = meas.xi
        self.bounds[k] = out.bounds
        self.phases[k] = [p.value for p in out.phases]
        self.object_error[k] = out.control.error[:3]  # the control law's E = S_d - S starts with X_d - X
        self.forces_surface[k] = forces
        self.envelope_margin[k] = out.margins.min()
        # the plant's static cone margins μ_s f_n - |f_t| at the contacts the supervisor holds fixed (a
        # contact being primed slips on purpose)
        fixed = ContactMode.FIXED
        cone = [cone_margin(mu, fn, ft) for mu, (fn, ft), mode, phase
                in zip(self.static, forces.tolist(), step.modes, out.phases)
                if mode is fixed and phase is ContactPhase.FIXED]
        if not cone:
            self.cone_margin[k] = np.inf
        elif any(c != c for c in cone):  # NaN propagates, as numpy's min does
            self.cone_margin[k] = np.nan
        else:
            self.cone_margin[k] = min(cone)
        self.supervisor_seconds[k] = out.supervisor_seconds
        self.control_seconds[k] = out.control_seconds
        self.plant_seconds[k] = plant_seconds
        self.n = k + 1


def build_rollout(scenario: Scenario, *, duration: float | None = None, settings: SupervisorSettings | None = None,
                  dt: float = 1e-3, xi0=None, plant_friction=None) -> Rollout:
    """Plant + supervisor for ``scenario``, every contact fixed at the planner's initial grasp.

    Args:
        scenario: The scenario (fingers, edges, object, trajectory, gravity, friction).
        duration: Simulated time [s]; default: the trajectory's whole domain.
        settings: Supervisor settings (default :class:`SupervisorSettings`).
        dt: Control and plant step [s].
        xi0: Initial contact positions [m] (default: the planner's ``initial_xi``).
        plant_friction: The plant's friction, anything :class:`~regrasp.plant.Plant` takes (default:
            the scenario's, which the controllers and the predicate also assume).
    """
    if settings is None:  # the supervisor's runtime envelopes use the scenario's planner geometry
        settings = SupervisorSettings(geometry=scenario.geometry.value)
    traj = scenario.trajectory
    duration = traj.t_end - traj.t_start if duration is None else as_positive_float("duration", duration)
    if duration > traj.t_end - traj.t_start + 1e-9:
        raise InvalidParameterError("duration", duration, f"at most the trajectory's domain, "
                                    f"{traj.t_end - traj.t_start:.6g} s")
    m = len(scenario.contacts)
    plan = plan_scenario(scenario)
    if xi0 is None:
        missing = [p.name for p in plan.fingers if p.initial_xi is None]
        if missing:
            raise InvalidParameterError("scenario", scenario.name,
                                        f"a feasible initial grasp; none for {', '.join(missing)} at t = "
                                        f"{traj.t_start:.6g} s")
        xi0 = [p.initial_xi for p in plan.fingers]
    xi0 = as_finite_array("xi0", xi0, (m,))
    hand = Hand([c.finger for c in scenario.contacts], gravity_in_hand=scenario.gravity_in_hand)
    edges = [c.edge for c in scenario.contacts]
    friction = scenario.friction
    supervisor = RegraspSupervisor(hand, scenario.polygon, edges, traj, xi0, friction,
                                   tip_clearance=[c.tip_clearance for c in scenario.contacts], plan=plan,
                                   settings=settings)
    X0, V0 = traj.pose(traj.t_start), traj.velocity(traj.t_start)
    st = ReducedModel(hand, Grasp(scenario.polygon, edges, [ContactMode.FIXED] * m), xi0).state(X0, V0)
    plant = Plant(hand, scenario.polygon, [PlantContact(e, ContactMode.FIXED, x) for e, x in zip(edges, xi0)],
                  friction=friction if plant_friction is None else plant_friction, dt=dt)
    plant.reset(st.q, st.q_dot, X0, V0, t=traj.t_start)
    return Rollout(plant, supervisor, float(duration), tuple(f.name for f in hand.fingers))

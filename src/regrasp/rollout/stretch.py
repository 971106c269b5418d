r"""Compiled stretches: a rollout's steps between the supervisor's decisions in one compiled call.

The regrasp supervisor decides at events and at a lower rate (the schedule-following policy every
``decision_period``, the monitor every ``envelope_every``-th step); between, each step does the same
continuous work: sense, read the held envelope samples, filter, compute the law's torques, step the plant.
:class:`CompiledStretches` hands such runs of steps to :func:`~regrasp.kernels.stretch.stretch_into`, which
does them in one call and stops *before* any step where the reference loop would do something discrete
(its module docstring lists what); the loop (:func:`~regrasp.plants.simulation.simulate`) then takes that step on the
reference path, with the supervisor, the policy, the plant's event logic and every consumer. A stretch writes
its steps' rows into the rollout's :class:`~regrasp.rollout.result.RolloutRows` itself, and hands a recorder
the steps it logs (:meth:`~regrasp.rollout.recording.recorder.RolloutRecorder.log_stretch_step`: what the record of that
step would give it).

**The participants** (:class:`StretchParticipant`): each gives a stretch what the kernel reads of it now, packed in
its bundle of :mod:`regrasp.kernels.stretch_layout` (``stretch_view``; None where only the reference path serves),
and takes back the state the kernel left (``take_stretch``). No participant reads another's state, and this module
reads none of theirs but through these two methods (and the law's and the envelopes' kernel arguments):

=====================================================  =====================================  ==================
participant                                            ``stretch_view`` gives                 ``take_stretch``
=====================================================  =====================================  ==================
:class:`~regrasp.supervisor.executor.SlideExecutor`    ``StretchExecutor`` (held contacts,    slip flags, μ̂,
                                                       filtered ξ, integrals, sliders)        integrals, clock
:class:`~regrasp.supervisor.monitor.EnvelopeMonitor`   held intervals, bounds, rates, reads   reads, evaluation
:class:`~regrasp.supervisor.policies.scheduled.        the decision terms and the schedule's  the next decision
ScheduledPolicy`                                       planned margins
:class:`~regrasp.plants.project.compiled.PlantKernel`  ``StretchPlant``'s arrays              the step reached
:class:`~regrasp.plants.disturbance.Disturbance`       ``StretchDisturbance`` (the draws and  the generator and
                                                       the deques)                            the deques
=====================================================  =====================================  ==================

So the compiled path changes how fast a rollout runs, not what it does: ``tests/rollout/test_stretch.py`` runs the
three-finger rollout both ways (with and without sensing noise, a slip sensor and an actuation delay: a
stretch draws the run's noise from its generator in the same order) and compares every row and event. Where a stretch
cannot serve (MuJoCo or a reference plant, a contact being primed or settling, a policy without ``quiet_until``, a law
without a compiled step), the loop runs every step on the reference path, as before.

Wall times in the rows: a stretch's steps share its wall time, half to the control and half to the plant
(the kernel is not timed per step); their supervisor time is 0 (the supervisor did not run).
"""

from __future__ import annotations

import math
import time
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np

from ..core.contact import coefficients, cone_margin
from ..dynamics.laws import FixedContactController, Proposition3Controller
from ..kernels.control import control_layout
from ..kernels.decimation import logged_steps
from ..kernels.monitor import envelope_arguments
from ..kernels.stretch import STRETCH_COAL, STRETCH_DONE, stretch_into
from ..kernels.stretch_layout import (
    STRETCH_SETTINGS,
    STRETCH_STATE,
    StretchDisturbance,
    StretchLaw,
    StretchLog,
    StretchMonitor,
    StretchPlant,
    StretchRows,
    StretchSchedule,
    stretch_log,
)
from ..plants.project.plant import Plant
from ..plants.project.state import PlantStep
from ..supervisor.supervisor import RegraspSupervisor
from .result import RolloutRows

if TYPE_CHECKING:
    from ..plants.disturbance import Disturbance
    from .recording.recorder import RolloutRecorder

__all__ = ["CompiledStretches", "StretchParticipant"]


@runtime_checkable
class StretchParticipant(Protocol):
    """What a compiled stretch needs of each participant (module docstring's table): ``stretch_view(...)``, what the
    kernel reads of it now (its bundle, or None where only the reference path serves), and ``take_stretch(...)``,
    the state the kernel left."""

    def stretch_view(self, *args: Any) -> Any: ...

    def take_stretch(self, *args: Any) -> Any: ...

#: The shortest stretch worth the call, and the longest in one call (the loop's progress reports and Ctrl-C
#: checks come between calls) [steps].
MIN_STRETCH, MAX_STRETCH = 2, 1000


class CompiledStretches:
    """Runs stretches of a supervised rollout's steps in compiled code (module docstring).

    Args:
        supervisor: The rollout's supervisor.
        plant: Its plant (a compiled :class:`~regrasp.plants.project.plant.Plant`; otherwise no stretch runs).
        rows: The rollout's rows (the stretches write theirs).
        total: The run's steps (the stretches precompute every step's time and desired state).
        recorder: The rollout's recorder (a stretch hands it the steps it logs), or None.
        disturbance: The run's disturbance (a stretch draws its noise and keeps its deques), or None.
        force_floor: The health criteria's force floor [N]: a step that leaves a contact's normal force below it is
            the reference path's (:class:`~regrasp.core.health.HealthCriteria`).
    """

    def __init__(self, supervisor: RegraspSupervisor, plant: Plant, rows: RolloutRows, total: int, *,
                 recorder: RolloutRecorder | None = None, disturbance: Disturbance | None = None,
                 force_floor: float = 0.0):
        self.supervisor = supervisor
        self.plant = plant
        self.rows = rows
        self.recorder = recorder
        self.disturbance = disturbance
        self.enabled = isinstance(plant, Plant) and plant.compiled and plant.state is not None and total > 0
        self._ranges: list[tuple[int, int]] = []  # (first row, rows) of each stretch: their planned ξ (finish())
        if self.enabled:
            # every step's start time on the plant's clock (t + dt per step) and the desired state there, at once
            times = [float(plant.state.t)]
            for _ in range(total - 1):
                times.append(times[-1] + plant.dt)
            self._times = np.array(times)
            desired = supervisor.trajectory.sample(self._times)
            self._desired = np.column_stack((desired.pose, desired.velocity, desired.acceleration))
        #: Steps run in stretches, and the stretches run.
        self.steps = 0
        self.calls = 0
        ex = supervisor.executor.settings
        self._settings = np.zeros((), dtype=STRETCH_SETTINGS)
        for name, value in (
                ("hold_gain", 1.0 if ex.hold_filter_time is None
                 else min(1.0, ex.control_period / ex.hold_filter_time)),
                ("hold_resolution", math.nan if ex.hold_resolution is None else ex.hold_resolution),
                ("integral", ex.integral),
                ("friction_gain", math.nan if ex.friction_filter_time is None
                 else min(1.0, ex.control_period / ex.friction_filter_time)),
                ("friction_min_force", ex.friction_min_force), ("friction_resolution", ex.friction_resolution),
                ("arrive_tolerance", ex.arrive_tolerance), ("arrive_speed", ex.arrive_speed),
                ("max_slide_time", ex.max_slide_time), ("control_omega", ex.control_omega),
                ("slide_omega", ex.slide_omega), ("dt", plant.dt), ("force_floor", force_floor),
                ("reflex_below", ex.reflex_below)):
            self._settings[name] = value
        self._static = np.array([f.static for f in plant.friction]) if self.enabled else None
        for name, value in (("every", supervisor.monitor.every), ("max_bound_step", supervisor.monitor.max_bound_step)):
            self._settings[name] = value
        # the envelopes the kernel evaluates (all compiled, none tracked), else it hands their evaluations over
        envelopes = [e.compiled_arguments for e in supervisor.monitor.envelopes]
        self.evaluates = (self.enabled and supervisor.monitor.trackers is None and all(a is not None for a in envelopes)
                          and all(np.array_equal(a[2], envelopes[0][2]) and np.array_equal(a[3], envelopes[0][3])
                                  for a in envelopes))
        self._envelopes = envelope_arguments(envelopes if self.evaluates else None, plant.hand.m)
        self._schedule = (np.zeros(1), np.zeros((1, plant.hand.m)))
        m = plant.hand.m
        if disturbance is not None:
            sensor, actuator = disturbance.sensor, disturbance.actuator
            layout = disturbance.stretch_layout(m)
            for name, value in (
                    ("sensed", not sensor.ideal),
                    ("slip_threshold", math.nan if sensor.slip_threshold is None else sensor.slip_threshold),
                    ("position", sensor.position), ("angle", sensor.angle), ("velocity", sensor.velocity),
                    ("angular_velocity", sensor.angular_velocity), ("xi_sigma", sensor.xi),
                    ("xi_dot_sigma", sensor.xi_dot), ("force_sigma", sensor.force), ("delayed", not actuator.ideal),
                    ("torque_sigma", actuator.torque)):
                self._settings[name] = value
            for name in ("pose", "twist", "normal", "xi", "xi_dot", "friction", "torque"):
                self._settings["o_" + name] = layout[name]
        else:
            for name in ("pose", "twist", "normal", "xi", "xi_dot", "friction", "torque"):
                self._settings["o_" + name] = -1

    def _policy_terms(self, t0: float, n: int, k: int) -> tuple[int, bool]:
        """Write the policy's terms into the settings; (the steps the stretch may take, whether it decides)."""
        terms = getattr(self.supervisor.policy, "stretch_view", None)
        terms = None if terms is None else terms(t0)
        settings = self._settings
        settings["decide"] = terms is not None
        if terms is None:
            return n, False
        for name in ("decision_period", "slide_due", "replan", "cooldown_until", "margin_fraction", "schedule_start",
                     "schedule_end", "periodic"):
            settings[name] = terms[name]
        self._schedule = (np.ascontiguousarray(terms["times"], dtype=float),
                          np.ascontiguousarray(terms["margins"], dtype=float))
        if math.isfinite(terms["end"]):  # (not past the schedule period's end: other slides come into view there)
            n = min(n, int(np.searchsorted(self._times[k:k + n], terms["end"], side="left")))
        return n, True

    def run(self, last: PlantStep | None, k: int, limit: int) -> tuple[int, PlantStep | None]:
        """Run a stretch from step ``k`` (at most ``limit`` steps) after the plant's ``last`` step; returns the
        steps taken (0: the next step is the reference path's) and the new last step."""
        if not self.enabled or last is None or self.plant.stopped or last.events:
            return 0, last
        sup = self.supervisor
        n = min(limit, MAX_STRETCH)
        if n < MIN_STRETCH:
            return 0, last
        ex, monitor = sup.executor, sup.monitor
        quiet = getattr(sup.policy, "quiet_until", None)
        decision = -math.inf if quiet is None else quiet(ex.phases)
        t0 = float(self.plant.state.t)
        n, decides = self._policy_terms(t0, n, k)
        evaluates = self.evaluates
        if n < MIN_STRETCH or (not t0 < decision and not decides) or (monitor.held_reads() == 0 and not evaluates):
            return 0, last  # (the first step would be handed over)
        state = ex.stretch_view()
        if state is None:
            return 0, last
        law = ex.law()
        compiled = law.compiled_arguments
        fixed = type(law) is FixedContactController
        if compiled is None or not (fixed or (isinstance(law, Proposition3Controller) and len(compiled) == 5)):
            return 0, last
        held, xi_model, xi_sensed, integral_x, sliders = state
        if self._times[k] != t0:
            raise RuntimeError(f"stretch clock {self._times[k]!r} s != the plant's {t0!r} s at step {k}")  # (a bug)
        times, desired = self._times[k:k + n], self._desired[k:k + n]
        dt = self.plant.dt
        rows = self.rows
        k0 = rows.n
        self._settings["fixed_law"], self._settings["evaluate"] = fixed, evaluates
        settings = self._settings[()]  # (the record)
        if fixed:
            head, tail, _, size = compiled
            kv, ks, diagonal, mass, f_hat, threshold, margin_mu, use_qp, *qp = tail
            directions, reversible, sample_time = np.zeros(0), False, 0.0
        else:
            head, sliding_tail, rest, _, size = compiled
            kv, ks, diagonal, mass = sliding_tail[:4]
            threshold, margin_mu, use_qp, *qp = rest
            f_hat, directions = np.zeros(0), np.array(law.directions)
            reversible, sample_time = law.reversible, law.sample_time
        intervals, counts, previous_bounds, rates, bound_speed, previous_time, calls = monitor.stretch_view()
        disturbance = self.disturbance
        if disturbance is None:
            drawn, rng_state, slip_count, command_count = StretchDisturbance(
                np.zeros((n, 0)), np.zeros((1, held.size), np.bool_), np.zeros((1, 2 * held.size))), None, 0, 0
        else:
            drawn, rng_state, slip_count, command_count = disturbance.stretch_view(held.size, n)
        noise, slips, commands = drawn
        run_state = np.zeros(1, dtype=STRETCH_STATE)
        run_state[0] = (decision, previous_time, calls, False, False, slip_count, command_count)
        evaluation_counts = np.zeros((held.size, 3), np.int64)
        schedule_times, schedule_margins = self._schedule
        fingers, plant_record, contacts, y, certificates, radii, out, terms, needs_coal, posture = \
            self.plant.kernel.stretch_view(self.plant.state, self.plant.contacts)
        last_out = np.concatenate((y, last.forces_surface.reshape(-1), np.zeros(4 * held.size), last.xi,
                                   last.xi_dot))
        control_out = np.empty(size)
        geometry, samples, scratch = self._envelopes
        every = 0 if self.recorder is None else self.recorder.decimation
        log = stretch_log(0 if every == 0 else n // every + 1, held.size, intervals.shape[1])
        executor = state
        monitored = StretchMonitor(intervals, counts, previous_bounds, rates, bound_speed, geometry, samples, scratch,
                                   evaluation_counts)
        schedule = StretchSchedule(schedule_times, schedule_margins)
        law_arguments = StretchLaw(head, kv, ks, diagonal, mass, f_hat, directions, reversible, sample_time, threshold,
                                   margin_mu, use_qp, *qp, control_out)
        plant_arguments = StretchPlant(fingers, plant_record, contacts, y, last_out, certificates, radii, out, terms,
                                       needs_coal, posture)
        start = time.perf_counter()
        done, cleared, worst, last_error = 0, False, 0.0, 0.0
        while done < n:
            s = slice(k0 + done, k0 + n)
            entries = len(logged_steps(k + 1, k + done + 1, every))  # (logged so far)
            rows_out = StretchRows(rows.xi[s], rows.bounds[s], rows.envelope_margin[s], rows.object_error[s],
                                   rows.poses[s], rows.joint_positions[s], rows.forces_surface[s], rows.cone_margin[s],
                                   rows.slip[s], self._static)
            taken, status, w, e = stretch_into(
                settings, run_state, times[done:], desired[done:], executor, monitored, schedule, law_arguments,
                plant_arguments, rows_out, StretchLog(*(a[entries:] for a in log)), every, k + done,
                StretchDisturbance(noise[done:], slips, commands), cleared)
            if taken:
                worst, last_error = max(worst, w), e
            done += taken
            cleared = status == STRETCH_COAL and self.plant.kernel.clear_collisions(out, needs_coal, posture)
            if status == STRETCH_DONE or not cleared:
                break
        if disturbance is not None:  # (its generator as if it had drawn these steps' noise, and its deques)
            disturbance.take_stretch(done, rng_state, noise.shape[1], slips, int(run_state[0]["slips"]), commands,
                                     int(run_state[0]["commands"]))
        if done == 0:
            return 0, last
        seconds = time.perf_counter() - start
        rows.phases[k0:k0 + done] = [[p.value for p in ex.phases]] * done
        rows.times[k0:k0 + done] = times[:done]
        rows.supervisor_seconds[k0:k0 + done] = 0.0
        rows.control_seconds[k0:k0 + done] = rows.plant_seconds[k0:k0 + done] = 0.5 * seconds / done
        rows.n = k0 + done
        self._ranges.append((k0, done))
        surface = control_out[control_layout(held.size, 3 + len(sliders))["surface"]]
        ex.take_stretch(sliders, times[done - 1], surface[0::2])  # (the last step's predicted normal forces)
        if not fixed:
            law.directions = directions.tolist()
        record = run_state[0]
        evaluated, clobbered = bool(record["evaluated"]), bool(record["clobbered"])
        if evaluated and not clobbered:  # (the envelope samples of its last evaluation, for the monitor)
            scalars, reach, feasible = samples
            t_eval = float(record["previous_time"])
            samples = [env.sample_from(scalars[i], reach[i, :c[0]], c[1] > 0, feasible[i, :c[2]], t_eval)
                       for i, (env, c) in enumerate(zip(monitor.envelopes, evaluation_counts.tolist()))]
        else:
            samples = None
        monitor.take_stretch(intervals, counts, previous_bounds, rates, bound_speed, float(record["previous_time"]),
                             int(record["calls"]), evaluated, samples)
        if decides:
            sup.policy.take_stretch(float(record["decision_time"]))
        if every:
            self._log(k, k0, done, log)
        self.steps += done
        self.calls += 1
        step = self.plant.kernel.take_stretch(y, last_out, float(times[done - 1] + dt), self.plant.contacts, last_error)
        self.plant.adopt(step.state, worst)
        return done, step

    def _log(self, k: int, k0: int, done: int, log: tuple) -> None:
        """Hand the recorder the stretch's logged steps (steps k .. k + done - 1, rows k0 ..)."""
        recorder, rows, sup = self.recorder, self.rows, self.supervisor
        every = recorder.decimation
        indices = logged_steps(k + 1, k + done + 1, every) - 1  # (the records' indices: step = index + 1)
        if not indices.size:
            return
        predicted, surface, cone, error, xi, reference, intervals, counts = log
        phases = tuple(sup.executor.phases)
        modes = [c.mode for c in self.plant.contacts]
        rows_at = k0 + indices - k
        forces = rows.forces_surface[rows_at]
        plant_cone = cone_margin(np.array(coefficients(self.plant.friction, modes)), forces[..., 0], forces[..., 1])
        after = self._times[indices] + self.plant.dt  # (the plant's clock after each logged step)
        last = indices + 1 >= self._times.size
        desired = self._desired[np.minimum(indices + 1, self._times.size - 1), :3]  # (at the next step's start)
        if last.any():
            trajectory = sup.trajectory
            desired[last] = trajectory.pose(np.minimum(after[last], trajectory.t_end))
        series = getattr(sup.policy, "planned_xi_series", None)
        planned = series(self._times[indices]) if series is not None else [sup.policy.planned_xi(float(t))
                                                                          for t in self._times[indices]]
        m = len(modes)
        for j, (index, row) in enumerate(zip(indices.tolist(), rows_at.tolist())):
            feasible = [tuple(map(tuple, intervals[j, i, :counts[j, i]].tolist())) for i in range(m)]
            recorder.log_stretch_step(index + 1, float(after[j]), rows.poses[row], rows.joint_positions[row],
                                      desired[j], forces[j], predicted[j], surface[j], feasible, phases, xi[j],
                                      error[j], plant_cone[j], cone[j], rows.bounds[row], reference[j], planned[j])

    def finish(self) -> None:
        """Fill in the stretches' planned ξ (at the run's end: one evaluation for all of them)."""
        if not self._ranges:
            return
        rows = np.concatenate([np.arange(k0, k0 + n) for k0, n in self._ranges])
        times = self.rows.times[rows]
        policy = self.supervisor.policy
        series = getattr(policy, "planned_xi_series", None)
        self.rows.planned_xi[rows] = series(times) if series is not None else [policy.planned_xi(float(t))
                                                                               for t in times]
        self._ranges = []

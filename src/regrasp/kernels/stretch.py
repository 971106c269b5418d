r"""A stretch of control steps in one call: the supervisor's continuous work between its decisions, compiled.

Between two decisions of the regrasp supervisor (:mod:`regrasp.supervisor.supervisor`) nothing discrete happens at most
steps: every contact stays in its phase (fixed, or sliding along its planned profile), the law stays the
same, the monitor holds its last envelope samples and the plant's contacts keep their modes. Such a stretch
of steps is this kernel: per step it does exactly what the reference loop (:func:`regrasp.plants.simulation.simulate`
around :meth:`regrasp.supervisor.supervisor.RegraspSupervisor.step`) does, in the same order and arithmetic:

1. sense (:func:`regrasp.plants.simulation.sense`): a fixed plant contact's ξ is where it is held, the rest from the
   last plant step; the last step's surface forces;
2. the monitor's margins and bounds from its held samples (:meth:`regrasp.supervisor.monitor.EnvelopeMonitor.read`);
3. the executor's advance (:meth:`regrasp.supervisor.executor.SlideExecutor.advance`): the held contacts' filter, the
   sliders' slip flags and friction estimates;
4. the sliders' references (:meth:`regrasp.schedule.schedule.Slide.profile_at`), the integral action and the control
   law (:func:`.control.control_step_into` or :func:`.control.sliding_step_into`);
5. the plant's step (:func:`.plant.plant_step_into`) and the rollout's per-step rows.

Before it changes anything, each step checks whether the reference loop would do something discrete there:
a held contact outside its envelope, a held position moving past ``hold_resolution`` (a new law), a slide
that arrives, sticks or times out, a friction estimate that rounds to a new law, a decision or monitor
evaluation due, a law the kernel does not settle (:data:`.control.CONTROL_REFERENCE`), a plant step that
may have an event (its ``attention`` flag), one that leaves a contact's normal force below the health floor
(``force_floor``: :mod:`regrasp.core.health` judges such steps), or a sensed normal force that starts the executor's
reflex (``reflex_below``). It then stops *before* that step
(:data:`STRETCH_HANDOFF`), and the caller takes the step on the reference path. A plant step whose collision
certificate expired stops with :data:`STRETCH_COAL`, uncommitted: the caller asks coal and, with no collision, calls
again with ``coal_cleared``. So a rollout with stretches takes the same steps as one without
(``tests/rollout/test_stretch.py``).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .arrays import copy_into
from .control import CONTROL_OK, control_step_into, sliding_step_into
from .decimation import logged
from .disturbance import actuate_into, measure_into
from .envelope import envelope_sample_into
from .monitor import reading_at
from .plant import FIXED, SLIDING, plant_step_into

__all__ = ["STRETCH_COAL", "STRETCH_DONE", "STRETCH_HANDOFF", "stretch_into"]

#: How :func:`stretch_into` stopped: all steps done; a step for the reference path; a step that needs coal.
STRETCH_DONE, STRETCH_HANDOFF, STRETCH_COAL = 0, 1, 2

@numba.njit(cache=True)
def _profile(sl, t):
    """(ξ, ξ̇, ξ̈) of a slider's profile at time t [s] (:meth:`regrasp.schedule.schedule.Slide.profile_at` at
    t - offset)."""
    t = t - sl.offset
    T, r, v, s = sl.end - sl.start, sl.ramp, sl.speed, sl.direction
    u = min(max(t - sl.start, 0.0), T)
    if u < r:
        travelled, speed, accel = v * u * u / (2 * r), v * u / r, v / r
    elif u > T - r:
        distance = abs(sl.end_xi - sl.start_xi)
        travelled, speed, accel = distance - v * (T - u) ** 2 / (2 * r), v * (T - u) / r, -v / r
    else:
        travelled, speed, accel = v * (u - r / 2), v, 0.0
    if sl.start < t < sl.end:
        return sl.start_xi + s * travelled, s * speed, s * accel
    return sl.start_xi + s * travelled, 0.0, 0.0


@numba.njit(cache=True)
def _finite(a):
    for v in a:
        if not math.isfinite(v):
            return False
    return True


@numba.njit(cache=True)
def stretch_into(settings, state, times, desired, executor, monitor, schedule, law, plant, rows, log, log_every,
                 first_index, disturbance, coal_cleared):
    r"""Up to ``times.size`` steps from the plant's state (module docstring); returns (steps taken, status, the
    largest constraint violation of those steps [m], the last one's [m]).

    ``settings`` (:data:`~.stretch_layout.STRETCH_SETTINGS`) and ``state`` (:data:`~.stretch_layout.STRETCH_STATE`, one
    record) are the executor's, monitor's, policy's and disturbance's constants and what the stretch changes of them;
    ``times`` the steps' start times [s] and ``desired`` (steps, 9) the desired pose, twist and acceleration there. Each
    participant's arrays come in its bundle (:mod:`.stretch_layout`: :class:`~.stretch_layout.StretchExecutor`,
    ``StretchMonitor``, ``StretchSchedule``, ``StretchLaw``, ``StretchPlant``, ``StretchRows``, ``StretchLog``,
    ``StretchDisturbance``: each names and documents its fields). ``log_every`` and ``first_index``: the
    steps logged are those :func:`~regrasp.kernels.decimation.logged` says of step ``first_index`` + k + 1;
    ``coal_cleared``: coal found no collision at the first step's end. The arrays of the executor, the plant's
    ``y`` and ``last``, the monitor's, the rows, the log and the disturbance's are updated for the steps taken and
    for them only.
    """
    held, xi_model, xi_sensed, integral_x, sliders = executor
    intervals, counts, previous_bounds, rates, bound_speed, geometry, samples, scratch, evaluation_counts = monitor
    schedule_times, schedule_margins = schedule
    (head, kv, ks, diagonal, object_mass, f_hat, directions, reversible, sample_time, singular_threshold, margin_mu,
     use_qp, coefficients, lower, n_ineq, is_cone, target, margin_column, weight, aim, control_out) = law
    fingers, plant_record, contacts, y, last, certificates, radii, plant_out, terms, needs_coal, posture = plant
    rows_xi, rows_bounds, rows_margin, rows_error, rows_pose, rows_q, rows_surface, rows_cone, rows_slip, \
        static_mu = rows
    noise, slips, commands = disturbance
    m = fingers.shape[0]
    n2 = 2 * m
    size = y.shape[0]
    p = sliders.shape[0]
    n = 3 + p
    dt = settings.dt
    worst = last_err = 0.0
    sensed = np.empty(m)
    xi = np.empty(m)
    mu_new = np.empty(p)
    s_now, s_dot, s_d, s_d_dot, s_d_ddot = np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    integral_new = np.empty(n)
    trial_directions = directions.copy()
    st = state[0]
    new_intervals = np.empty_like(intervals)
    new_counts = np.empty_like(counts)
    new_rates = np.empty_like(rates)
    new_speed = np.empty_like(bound_speed)
    new_evaluation = np.empty_like(evaluation_counts)
    margins = np.empty(m)
    reference = np.empty(p)
    entry = 0
    X_m, V_m, xi_m, xi_dot_m, fn_m, ft_m = np.empty(3), np.empty(3), np.empty(m), np.empty(m), np.empty(m), np.empty(m)
    slides_m = np.empty(m, np.bool_)
    slips_new, commands_new = np.empty_like(slips), np.empty_like(commands)
    applied = np.empty(n2)
    log_predicted, log_surface, log_cone, log_error, log_xi, log_reference, log_intervals, log_counts = log
    o_error, o_forces = n2 + n, n2 + 3 * n
    for k in range(times.size):
        t = times[k]
        # 1. sense: the truth (simulation.sense), and what the disturbance makes of it (Disturbance.measure)
        for i in range(m):
            xi[i] = contacts[i].xi if contacts[i].mode == FIXED else last[size + 6 * m + i]
        slip_count = measure_into(settings, st, contacts, y, last, xi, noise[k],
                              slips, slips_new, X_m, V_m, xi_m, xi_dot_m, fn_m, ft_m, slides_m)
        for i in range(m):  # (a sensed force that starts the executor's reflex: the reference path's)
            if fn_m[i] < settings.reflex_below:
                return k, STRETCH_HANDOFF, worst, last_err
        # 2. the monitor: a decision reads fresh envelopes, as does every every-th read
        deciding = not t < st.decision_time
        fresh = deciding or st.calls >= settings.every
        if fresh:
            if not settings.evaluate or (deciding and not (settings.decide and t < settings.slide_due)):
                return k, STRETCH_HANDOFF, worst, last_err
            x, yo, beta = X_m[0], X_m[1], X_m[2]
            params, shapes, shape_starts, vertices, normals = geometry
            scalars, reach, feasible_all = samples
            base, starts, flip_counts, flips, work = scratch
            for i in range(m):
                feasible = feasible_all[i]
                n_reach, n_base, n_feasible = envelope_sample_into(
                    params[i:i + 1], shapes[shape_starts[i]:shape_starts[i + 1]], vertices, normals, x, yo, beta,
                    scalars[i], reach[i], base, starts, flip_counts, flips, feasible, work)
                if n_feasible > new_intervals.shape[1]:
                    return k, STRETCH_HANDOFF, worst, last_err
                new_counts[i] = n_feasible
                new_evaluation[i, 0], new_evaluation[i, 1], new_evaluation[i, 2] = n_reach, n_base, n_feasible
                for j in range(n_feasible):
                    new_intervals[i, j, 0], new_intervals[i, j, 1] = feasible[j, 0], feasible[j, 1]
            if st.evaluated:
                st.clobbered = True  # (until this step is committed)
            active, active_counts = new_intervals, new_counts
        else:
            active, active_counts = intervals, counts
        for i in range(m):
            margin, lo, hi = reading_at(active, active_counts, i, xi_m[i])
            if held[i] and margin < 0.0:  # (a held contact outside its envelope: LEFT_ENVELOPE)
                return k, STRETCH_HANDOFF, worst, last_err
            margins[i] = margin
            rows_margin[k, i], rows_bounds[k, i, 0], rows_bounds[k, i, 1] = margin, lo, hi
        if fresh:  # the bounds' rates (EnvelopeMonitor.read)
            copy_into(new_rates, rates)
            copy_into(new_speed, bound_speed)
            if not math.isnan(st.previous_time) and t > st.previous_time:
                for i in range(m):
                    fastest = 0.0
                    for b in range(2):
                        change = rows_bounds[k, i, b] - previous_bounds[i, b]
                        rate = change / (t - st.previous_time)
                        smooth = math.isfinite(rate) and abs(change) <= settings.max_bound_step * settings.every
                        new_rates[i, b] = rate if smooth else 0.0
                        fastest = max(fastest, abs(new_rates[i, b]))
                    new_speed[i] = max(bound_speed[i], fastest)
        if deciding and settings.replan and t >= settings.cooldown_until:  # (ScheduledPolicy._decide)
            local = min(max(t, settings.schedule_start), settings.schedule_end)
            if settings.periodic:
                local = settings.schedule_start + (t - settings.schedule_start) % (settings.schedule_end
                                                                                   - settings.schedule_start)
            row = min(np.searchsorted(schedule_times, local), schedule_times.size - 1)
            for i in range(m):
                if margins[i] < settings.margin_fraction * schedule_margins[row, i]:
                    return k, STRETCH_HANDOFF, worst, last_err  # (a re-plan is due)
        # 3. the executor's advance
        for i in range(m):
            sliding = slides_m[i]
            if held[i] and not sliding:
                sensed[i] = xi_sensed[i] + settings.hold_gain * (xi_m[i] - xi_sensed[i])
                if not math.isnan(settings.hold_resolution) and abs(sensed[i] - xi_model[i]) > settings.hold_resolution:
                    return k, STRETCH_HANDOFF, worst, last_err  # (the law moves its held position)
            else:
                sensed[i] = xi_m[i]
        for c in range(p):
            sl = sliders[c]
            j = sl.contact
            sliding = slides_m[j]
            fn, ft = fn_m[j], ft_m[j]
            mu = sl.mu_hat
            if not math.isnan(settings.friction_gain) and sliding and fn > settings.friction_min_force:
                ratio = abs(ft) / fn
                mu = ratio if math.isnan(mu) else mu + settings.friction_gain * (ratio - mu)
            mu_new[c] = mu
            x, x_dot = xi_m[j], xi_dot_m[j]
            near = abs(x - sl.target) < settings.arrive_tolerance
            if near and abs(x_dot) < settings.arrive_speed and (not sliding or math.isnan(sl.planned_end)
                                                                 or t >= sl.planned_end):
                return k, STRETCH_HANDOFF, worst, last_err  # (arrived)
            if (sl.slipped or sliding) and not sliding:
                return k, STRETCH_HANDOFF, worst, last_err  # (stuck)
            if t - sl.phase_start > settings.max_slide_time:
                return k, STRETCH_HANDOFF, worst, last_err  # (timed out)
            kinetic = sl.model_kinetic
            if not math.isnan(mu):
                r = settings.friction_resolution
                kinetic = max(0.0, np.rint(mu / r) * r)
            if kinetic != sl.law_kinetic:
                return k, STRETCH_HANDOFF, worst, last_err  # (a law with the new estimate)
        # 4. the references, the integral action and the law
        for a in range(3):
            s_now[a], s_dot[a] = X_m[a], V_m[a]
            s_d[a], s_d_dot[a], s_d_ddot[a] = desired[k, a], desired[k, 3 + a], desired[k, 6 + a]
        for c in range(p):
            j = sliders[c].contact
            s_now[3 + c], s_dot[3 + c] = xi_m[j], xi_dot_m[j]
            s_d[3 + c], s_d_dot[3 + c], s_d_ddot[3 + c] = _profile(sliders[c], t)
            reference[c] = s_d[3 + c]
        for a in range(3):
            rows_error[k, a] = s_d[a] - y[2 * n2 + a]  # (the truth's)
        if settings.integral > 0.0:
            for a in range(n):
                e = s_d[a] - s_now[a]
                integral_new[a] = (integral_x[a] if a < 3 else sliders[a - 3].integral) + e * dt
            for a in range(n):
                omega = settings.control_omega if a < 3 else settings.slide_omega
                s_d[a] = s_d[a] + settings.integral * omega * integral_new[a]
        if not (_finite(s_now) and _finite(s_dot) and _finite(s_d) and _finite(s_d_dot) and _finite(s_d_ddot)):
            return k, STRETCH_HANDOFF, worst, last_err
        fingers_r, iks, edges, gravity, damped, xi_law, columns = head
        if settings.fixed_law:
            status, _, _ = control_step_into(fingers_r, iks, edges, gravity, damped, xi_law, columns, s_now, s_dot,
                                             s_d, s_d_dot, s_d_ddot, kv, ks, diagonal, object_mass, f_hat,
                                             singular_threshold, margin_mu, use_qp, coefficients, lower, n_ineq,
                                             is_cone, target, margin_column, weight, aim, control_out)
        else:
            copy_into(trial_directions, directions)
            indices = np.empty(p, np.int64)
            kinetics = np.empty(p)
            for c in range(p):
                indices[c], kinetics[c] = sliders[c].contact, sliders[c].law_kinetic
            status, _, _ = sliding_step_into(fingers_r, iks, edges, gravity, damped, xi_law, columns, s_now, s_dot,
                                             s_d, s_d_dot, s_d_ddot, kv, ks, diagonal, object_mass, indices,
                                             kinetics, trial_directions, reversible, sample_time, singular_threshold,
                                             margin_mu, use_qp, coefficients, lower, n_ineq, is_cone, target,
                                             margin_column, weight, aim, control_out)
        if status != CONTROL_OK:
            return k, STRETCH_HANDOFF, worst, last_err
        tau = control_out[:n2]
        if not _finite(tau):
            return k, STRETCH_HANDOFF, worst, last_err
        command_count = actuate_into(settings, st, tau, noise[k], commands,
                                 commands_new, applied)
        # 5. the plant
        err, attention, any_coal = plant_step_into(fingers, plant_record, contacts, y, applied, certificates, radii,
                                                   plant_out, terms, needs_coal, posture)
        if attention:
            return k, STRETCH_HANDOFF, worst, last_err
        for i in range(m):  # (a contact below the health floor: the health monitor judges it on the reference path)
            if plant_out[size + 2 * i] < settings.force_floor:
                return k, STRETCH_HANDOFF, worst, last_err
        if any_coal and not (k == 0 and coal_cleared):
            return k, STRETCH_COAL, worst, last_err
        # commit the step
        worst, last_err = max(worst, err), err
        for i in range(m):
            xi_sensed[i] = sensed[i]
            rows_xi[k, i] = xi[i]
            fn, ft = plant_out[size + 2 * i], plant_out[size + 2 * i + 1]
            rows_surface[k, i, 0], rows_surface[k, i, 1] = fn, ft
            rows_cone[k, i] = static_mu[i] * fn - abs(ft) if held[i] and contacts[i].mode == FIXED else np.nan
            rows_slip[k, i] = plant_out[size + 7 * m + i] * dt if contacts[i].mode == SLIDING else 0.0
        if settings.integral > 0.0:
            for a in range(3):
                integral_x[a] = integral_new[a]
        for c in range(p):
            sl = sliders[c]
            sl.slipped = sl.slipped or contacts[sl.contact].mode == SLIDING
            sl.mu_hat = mu_new[c]
            if settings.integral > 0.0:
                sl.integral = integral_new[3 + c]
        if not settings.fixed_law:
            copy_into(directions, trial_directions)
        for a in range(3):
            rows_pose[k, a] = plant_out[2 * n2 + a]
        for a in range(n2):
            rows_q[k, a] = plant_out[a]
        copy_into(last, plant_out)
        copy_into(y, plant_out[:size])
        if fresh:
            copy_into(intervals, new_intervals)
            copy_into(counts, new_counts)
            for i in range(m):
                previous_bounds[i, 0], previous_bounds[i, 1] = rows_bounds[k, i, 0], rows_bounds[k, i, 1]
            copy_into(rates, new_rates)
            copy_into(bound_speed, new_speed)
            st.previous_time = t
            st.calls = 0
            st.evaluated, st.clobbered = True, False
            copy_into(evaluation_counts, new_evaluation)
        if deciding:
            st.decision_time = min(t + settings.decision_period - 1e-9, settings.slide_due)
        st.calls += 1
        if settings.sensed:
            copy_into(slips, slips_new)
            st.slips = slip_count
        if settings.delayed:
            copy_into(commands, commands_new)
            st.commands = command_count
        if logged(first_index + k + 1, log_every):
            for i in range(m):
                for b in range(2):
                    log_predicted[entry, i, b] = control_out[o_forces + 2 * i + b]
                    log_surface[entry, i, b] = control_out[o_forces + n2 + 2 * i + b]
                log_cone[entry, i] = control_out[o_forces + 2 * n2 + i]
                log_xi[entry, i] = plant_out[size + 6 * m + i]  # (the plant step's ξ after it)
                log_reference[entry, i] = np.nan
                log_counts[entry, i] = counts[i]
                for j in range(counts[i]):
                    for b in range(2):
                        log_intervals[entry, i, j, b] = intervals[i, j, b]
            for a in range(3):
                log_error[entry, a] = control_out[o_error + a]
            for c in range(p):
                log_reference[entry, sliders[c].contact] = reference[c]
            entry += 1
    return times.size, STRETCH_DONE, worst, last_err

"""What a stretch of control steps takes (:func:`~regrasp.kernels.stretch.stretch_into`): the records of the
constants and of what a stretch changes (:data:`STRETCH_SETTINGS`, :data:`STRETCH_STATE`, :data:`SLIDER`) and one
bundle per participant, each field named and documented (:class:`StretchExecutor`, :class:`StretchMonitor`,
:class:`StretchSchedule`, :class:`StretchLaw`, :class:`StretchPlant`, :class:`StretchRows`, :class:`StretchLog`,
:class:`StretchDisturbance`). The participants fill them (:mod:`regrasp.rollout.stretch` says who gives what)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["SLIDER", "STRETCH_SETTINGS", "STRETCH_STATE", "StretchDisturbance", "StretchExecutor", "StretchLaw",
           "StretchLog", "StretchMonitor", "StretchPlant", "StretchRows", "StretchSchedule", "stretch_log"]

_F8 = np.float64

#: The executor's, monitor's and policy's constants for a stretch: the held contacts' filter gain and resolution
#: [m] (NaN: none), the integral action's K_i / K_s per ω [-], the friction filter's gain (NaN: no estimate), its
#: least normal force [N] and the laws' friction resolution [-], a slide's arrival tolerance [m] and speed
#: [m/s], its longest sliding phase [s], the law's ω of the pose and of a slider [rad/s], the step [s], whether
#: the fixed law runs (else Proposition 3, m > 2); the monitor's ``every`` and ``max_bound_step`` [m] and whether
#: the kernel evaluates the envelopes (else it hands such a step over); whether it takes the policy's decisions
#: (:class:`regrasp.supervisor.policies.scheduled.ScheduledPolicy`: else it hands them over), their period [s], when the
#: next slide is due [s], whether it re-plans on a low margin, from when [s] and below which fraction of the planned
#: margin, and the schedule's start, end [s] and whether it repeats; a disturbance
#: (:class:`regrasp.plants.disturbance.Disturbance`): whether the sensor is not ideal, its slip threshold [m/s] (NaN:
#: the plant's modes) and standard deviations (pose [m], [rad], twist [m/s], [rad/s], ξ [m], ξ̇ [m/s], forces
#: [N]), whether the actuator is not ideal and its torque noise [N m]; where each noise term lies in a
#: step's row of standard normals (-1: not drawn; :meth:`regrasp.plants.disturbance.Disturbance.stretch_noise`); and the
#: contact-health force floor [N] (:class:`regrasp.core.health.HealthCriteria`: a step that leaves any contact below it
#: is handed over, so the health monitor sees it on the reference path) and the executor's reflex threshold [N] (a step
#: whose sensed normal force is below it is the reference path's).
STRETCH_SETTINGS = np.dtype([
    ("hold_gain", _F8), ("hold_resolution", _F8), ("integral", _F8), ("friction_gain", _F8),
    ("friction_min_force", _F8), ("friction_resolution", _F8), ("arrive_tolerance", _F8), ("arrive_speed", _F8),
    ("max_slide_time", _F8), ("control_omega", _F8), ("slide_omega", _F8), ("dt", _F8), ("fixed_law", np.bool_),
    ("every", np.int64), ("max_bound_step", _F8), ("evaluate", np.bool_),
    ("decide", np.bool_), ("decision_period", _F8), ("slide_due", _F8), ("replan", np.bool_),
    ("cooldown_until", _F8), ("margin_fraction", _F8), ("schedule_start", _F8), ("schedule_end", _F8),
    ("periodic", np.bool_),
    ("sensed", np.bool_), ("slip_threshold", _F8), ("position", _F8), ("angle", _F8), ("velocity", _F8),
    ("angular_velocity", _F8), ("xi_sigma", _F8), ("xi_dot_sigma", _F8), ("force_sigma", _F8),
    ("delayed", np.bool_), ("torque_sigma", _F8),
    ("o_pose", np.int64), ("o_twist", np.int64), ("o_normal", np.int64), ("o_xi", np.int64), ("o_xi_dot", np.int64),
    ("o_friction", np.int64), ("o_torque", np.int64), ("force_floor", _F8), ("reflex_below", _F8),
], align=True)

#: What a stretch changes of the monitor and the policy (one record): the next decision's time [s], the last
#: evaluation's time [s] (NaN: none yet), the reads since it, whether this call committed an evaluation and
#: whether a step it handed over evaluated the envelopes after that (its outputs are then not the committed ones);
#: how many entries the disturbance's slip sensor and actuation delay hold (their deques' lengths).
STRETCH_STATE = np.dtype([
    ("decision_time", _F8), ("previous_time", _F8), ("calls", np.int64), ("evaluated", np.bool_),
    ("clobbered", np.bool_), ("slips", np.int64), ("commands", np.int64),
], align=True)

#: A sliding contact: its index, slip flag, friction estimate μ̂ (NaN: none yet), sliding phase's start [s],
#: target [m], planned end [s] (NaN: none), its planned profile (:class:`regrasp.schedule.schedule.Slide`: start, end
#: [s], ξ from, to [m], ramp [s], cruise speed [m/s], direction ±1, time offset [s]), the μ_k its law uses and the
#: model's μ_k, and ∫(ξ_d - ξ) dt [m s] of its integral action.
SLIDER = np.dtype([
    ("contact", np.int64), ("slipped", np.bool_), ("mu_hat", _F8), ("integral", _F8), ("phase_start", _F8),
    ("target", _F8),
    ("planned_end", _F8), ("start", _F8), ("end", _F8), ("start_xi", _F8), ("end_xi", _F8), ("ramp", _F8),
    ("speed", _F8), ("direction", _F8), ("offset", _F8), ("law_kinetic", _F8), ("model_kinetic", _F8),
], align=True)


class StretchExecutor(NamedTuple):
    """What a stretch reads and updates of the executor (:class:`regrasp.supervisor.executor.SlideExecutor`)."""

    held: np.ndarray        #: (m,) bool: the contacts it holds fixed
    xi_model: np.ndarray    #: (m,) the held positions its law was built with [m]
    xi_sensed: np.ndarray   #: (m,) the filtered sensed positions [m] (updated)
    integral_x: np.ndarray  #: (3,) ∫(X_d - X) dt of the pose (updated)
    sliders: np.ndarray     #: :data:`SLIDER` records (updated)


class StretchMonitor(NamedTuple):
    """What a stretch reads and updates of the envelope monitor (:class:`regrasp.supervisor.monitor.EnvelopeMonitor`)
    and its envelopes (:func:`.monitor.envelope_arguments`)."""

    intervals: np.ndarray          #: (m, k, 2) the held samples' feasible intervals [m], room for any evaluation's
    counts: np.ndarray             #: (m,) how many each holds
    previous_bounds: np.ndarray    #: (m, 2) the bounds at the last evaluation [m]
    rates: np.ndarray              #: (m, 2) their rates [m/s]
    bound_speed: np.ndarray        #: (m,) the fastest each contact's bounds moved [m/s]
    geometry: tuple                #: the envelopes' parameters, shapes and polygon
    samples: tuple                 #: their samples' outputs
    scratch: tuple                 #: their work arrays
    evaluation_counts: np.ndarray  #: (m, 3) :func:`.envelope.envelope_sample_into`'s counts at the last evaluation


class StretchSchedule(NamedTuple):
    """The scheduled policy's planned envelope margins
    (:class:`regrasp.supervisor.policies.scheduled.ScheduledPolicy`)."""

    times: np.ndarray    #: (k,) the schedule's sample times [s]
    margins: np.ndarray  #: (k, m) the planned envelope margin of each contact there [m]


class StretchLaw(NamedTuple):
    """The control law's kernel arguments (:meth:`regrasp.dynamics.control.ComputedTorqueController.compiled_arguments`)
    and its output: ``head`` is :func:`.control.control_step_into`'s first seven arguments, then its gains, the
    object's mass matrix diagonal and mass, the fixed law's ``f_hat`` or Proposition 3's sliders' ``directions``
    (updated), the internal-force QP's rows and settings."""

    head: tuple
    kv: np.ndarray
    ks: np.ndarray
    diagonal: np.ndarray
    object_mass: float
    f_hat: np.ndarray
    directions: np.ndarray
    reversible: bool
    sample_time: float
    singular_threshold: float
    margin_mu: np.ndarray
    use_qp: bool
    coefficients: np.ndarray
    lower: np.ndarray
    n_ineq: int
    is_cone: np.ndarray
    target: float
    margin_column: np.ndarray
    weight: float
    aim: float
    out: np.ndarray


class StretchPlant(NamedTuple):
    """The plant's kernel arguments (:class:`regrasp.plants.project.compiled.PlantKernel`), its last step's output
    and a step's workspace."""

    fingers: np.ndarray       #: :data:`~.finger.FINGER_PARAMETERS` records
    parameters: np.ndarray    #: a :data:`~.plant.PLANT_PARAMETERS` record
    contacts: np.ndarray      #: :data:`~.plant.PLANT_CONTACT` records
    y: np.ndarray             #: the flat state (updated)
    last: np.ndarray          #: the last step's output: its ξ, ξ̇ and surface forces are sensed (updated)
    certificates: np.ndarray  #: (m, 9) the collision certificates
    radii: np.ndarray         #: (m, 2) the links' radii [m]
    out: np.ndarray           #: a step's output
    terms: np.ndarray         #: :data:`~.finger.FINGER_TERMS` workspace
    needs_coal: np.ndarray    #: (m,) bool workspace
    posture: np.ndarray       #: (m, 7) workspace


class StretchRows(NamedTuple):
    """The rollout's rows the stretch writes (:class:`regrasp.rollout.result.RolloutRows`), one per step."""

    xi: np.ndarray           #: (steps, m) [m]
    bounds: np.ndarray       #: (steps, m, 2) [m]
    margin: np.ndarray       #: (steps, m) envelope margins [m]
    error: np.ndarray        #: (steps, 3) X_d - X
    pose: np.ndarray         #: (steps, 3)
    q: np.ndarray            #: (steps, 2m) [rad]
    surface: np.ndarray      #: (steps, m, 2) surface forces [N]
    cone: np.ndarray         #: (steps, m) cone margins of the held fixed contacts [N] (NaN elsewhere)
    slip: np.ndarray         #: (steps, m) each contact's slip during the step [m] (``PlantStep.slip``)
    static_mu: np.ndarray    #: (m,) the plant's μ_s


class StretchLog(NamedTuple):
    """What a recorder logs of the logged steps, one entry each in order (:func:`stretch_log`)."""

    predicted: np.ndarray  #: (·, m, 2) the law's predicted forces, hand frame [N]
    surface: np.ndarray    #: (·, m, 2) the same in each surface frame [N]
    cone: np.ndarray       #: (·, m) its cone margins [N]
    error: np.ndarray      #: (·, 3) its pose error
    xi: np.ndarray         #: (·, m) ξ after the step [m]
    reference: np.ndarray  #: (·, m) the sliders' reference ξ [m] (NaN elsewhere)
    intervals: np.ndarray  #: (·, m, k, 2) the held envelopes' feasible intervals [m]
    counts: np.ndarray     #: (·, m) how many each holds


class StretchDisturbance(NamedTuple):
    """A disturbance's draws and deques (:class:`regrasp.plants.disturbance.Disturbance`)."""

    noise: np.ndarray     #: (steps, k) the standard normals each step draws
    slips: np.ndarray     #: (d + 1, m) the slip sensor's readings, oldest first (updated)
    commands: np.ndarray  #: (delay + 1, 2m) the commanded torques, oldest first (updated)


def stretch_log(entries: int, m: int, capacity: int) -> StretchLog:
    """An empty ``log`` for :func:`stretch_into`: ``entries`` logged steps of m contacts whose envelopes have at
    most ``capacity`` intervals each."""
    return StretchLog(np.empty((entries, m, 2)), np.empty((entries, m, 2)), np.empty((entries, m)),
                      np.empty((entries, 3)), np.empty((entries, m)), np.empty((entries, m)),
                      np.zeros((entries, m, capacity, 2)), np.zeros((entries, m), np.int64))

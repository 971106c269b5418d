"""Closed loop: a controller driving the plant (the controller never sees the plant's equations).

At each step the reduced state is *measured* from the plant (object pose and twist, and the
position and rate of each sliding contact along its edge), the controller computes torques,
and the plant integrates one step with them (zero-order hold). For Proposition 2 the friction
"measurement" is the plant's tangential contact force of the previous step, optionally with
Gaussian noise.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ..core.events import Event
from ..core.exceptions import InvalidParameterError
from ..core.trajectory import TrajectorySample
from ..core.validation import as_duration, as_positive_float, expect_type, step_count
from ..dynamics.control import ComputedTorqueController, ControlOutput
from ..dynamics.laws import Proposition2Controller
from ..dynamics.reduced import ReducedModel
from .simulation import Command, PlantLike, StepRecord, sense_projected, simulate

__all__ = ["ClosedLoopLog", "measure_reduced_state", "run_closed_loop"]

Reference = Callable[[float], tuple[np.ndarray, np.ndarray, np.ndarray]]


def measure_reduced_state(plant: PlantLike, model: ReducedModel) -> tuple[np.ndarray, np.ndarray]:
    """(S, Ṡ) of ``model``'s coordinates, read from the plant's state."""
    expect_type("plant", plant, PlantLike, "a plant (regrasp.Plant or a MujocoPlant)")
    expect_type("model", model, ReducedModel, "a ReducedModel")
    st = plant.state
    if st is None:
        raise InvalidParameterError("plant", plant, "a plant with a state (call Plant.reset first)")
    xi = [plant.contact_xi(st, i) for i in model.grasp.sliding]
    S = np.concatenate([st.X, [x for x, _ in xi]])
    S_dot = np.concatenate([st.V, [v for _, v in xi]])
    return S, S_dot


def _initial_tangential_force(plant: PlantLike, controller, reference: Reference, sliding) -> np.ndarray:
    """The friction sensor's reading before the first step: the plant's tangential force at the
    sliding contacts under the torque the controller would apply (two passes, so the reading and
    the torque are consistent)."""
    force = np.zeros(len(sliding))
    S, S_dot = measure_reduced_state(plant, controller.model)
    for _ in range(2):
        out = controller(S, S_dot, *reference(plant.state.t), tangential_force=force)
        _, _, forces = plant.accelerations(plant.state, out.tau)
        force = plant.surface_forces(plant.state, forces)[sliding, 1].copy()
    return force


@dataclass(frozen=True)
class ClosedLoopLog:
    """A closed-loop run, one row per control step.

    Attributes:
        times: Step start times [s], (k,).
        S, S_desired: Measured and desired reduced coordinates, (k, 3 + p).
        errors: S_d - S, (k, 3 + p).
        plant_forces: The plant's contact forces in surface frames (normal, tangential), (k, m, 2).
        predicted_forces: The controller's predicted contact forces, same layout.
        cone_margins: The plant's μ f_n - |f_t| per contact, (k, m), with the coefficient of the
            contact's mode during the step (μ_s fixed, μ_k sliding, 0 separated).
        internal_forces: The commanded internal forces f_c, (k, 2m).
        control_seconds: Wall time of each control step [s], (k,).
        events: The plant's events.
        max_constraint_error: The plant's largest constraint violation [m].
        stopped: Whether the plant stopped on an event.
    """

    times: np.ndarray
    S: np.ndarray
    S_desired: np.ndarray
    errors: np.ndarray
    plant_forces: np.ndarray
    predicted_forces: np.ndarray
    cone_margins: np.ndarray
    internal_forces: np.ndarray
    control_seconds: np.ndarray
    events: tuple[Event, ...]
    max_constraint_error: float
    stopped: bool

    @classmethod
    def from_records(cls, records: Sequence[StepRecord], plant: PlantLike, n_forces: int, n: int) -> "ClosedLoopLog":
        """The log of a run's :class:`~regrasp.plants.simulation.StepRecord` s (``n_forces`` = 2m, ``n`` = 3 + p)."""
        def rows(get, shape):
            return np.array([get(r) for r in records]) if records else np.zeros((0, *shape))

        return cls(
            times=np.array([r.t for r in records]),
            S=rows(lambda r: r.command.S_desired - r.command.control.error, (n,)),
            S_desired=rows(lambda r: r.command.S_desired, (n,)),
            errors=rows(lambda r: r.command.control.error, (n,)),
            plant_forces=rows(lambda r: r.plant.forces_surface, (n_forces // 2, 2)),
            predicted_forces=rows(lambda r: r.command.control.contact_forces_surface, (n_forces // 2, 2)),
            cone_margins=rows(lambda r: r.cone_margins, (n_forces // 2,)),
            internal_forces=rows(lambda r: r.command.control.internal.f_c if r.command.control.internal is not None
                                 else np.zeros(n_forces), (n_forces,)),
            control_seconds=np.array([r.command.control.seconds for r in records]),
            events=tuple(plant.events),
            max_constraint_error=plant.max_constraint_error,
            stopped=plant.stopped,
        )


class _ControllerDriver:
    """The simulation loop's driver around one control law and its reference."""

    def __init__(self, controller: ComputedTorqueController, reference: Reference, force0, force_noise: float,
                 rng: np.random.Generator):
        self.controller = controller
        self.reference = reference
        self.sliding = list(controller.model.grasp.sliding)
        self.tangential_force = force0
        self.noise = force_noise
        self.rng = rng

    def step(self, meas, dt: float) -> Command:
        sliding = self.sliding
        S = np.concatenate([meas.X, meas.xi[sliding]])
        S_dot = np.concatenate([meas.V, meas.xi_dot[sliding]])
        S_d, S_d_dot, S_d_ddot = self.reference(meas.t)
        kwargs = {}
        if isinstance(self.controller, Proposition2Controller):
            force = self.tangential_force if self.tangential_force is not None else meas.tangential_force[sliding]
            self.tangential_force = None  # later steps read the last plant step's friction force
            kwargs["tangential_force"] = force + (self.noise * self.rng.standard_normal(len(sliding)) if self.noise
                                                  else 0.0)
        out = self.controller(S, S_dot, S_d, S_d_dot, S_d_ddot, **kwargs)
        S_d = np.asarray(S_d, dtype=float)
        desired = TrajectorySample(float(meas.t), S_d[:3], np.asarray(S_d_dot, dtype=float)[:3],
                                   np.asarray(S_d_ddot, dtype=float)[:3])
        return Command(out.tau, out, self.controller.law, desired, S_d)


def run_closed_loop(
    plant: PlantLike,
    controller: ComputedTorqueController,
    reference: Reference,
    duration: float,
    *,
    force_noise: float = 0.0,
    rng: np.random.Generator | None = None,
    on_step: Callable[[float, ControlOutput], None] | None = None,
) -> ClosedLoopLog:
    """Run ``controller`` on ``plant`` for ``duration`` [s] (or until the plant stops), with the one
    simulation loop (:func:`~regrasp.plants.simulation.simulate`, the sensor
    :func:`~regrasp.plants.simulation.sense_projected`).

    Args:
        reference: t -> (S_d, Ṡ_d, S̈_d).
        force_noise: Standard deviation [N] of the noise added to the measured friction force
            (Proposition 2).
        rng: Random generator for that noise.
        on_step: Called after each control step with (t, output).

    Raises:
        RegraspError: the control law failed (e.g. its internal-force QP is infeasible): the
            controller's own error.
    """
    if not isinstance(plant, PlantLike):
        raise InvalidParameterError("plant", plant,
                                    "a plant (regrasp.Plant or regrasp.plants.mujoco.plant.MujocoPlant)")
    if not isinstance(controller, ComputedTorqueController):
        raise InvalidParameterError("controller", controller, "a control law (regrasp.dynamics.control)")
    if not callable(reference):
        raise InvalidParameterError("reference", reference, "a function t -> (S_d, S_d_dot, S_d_ddot)")
    steps = step_count("duration", as_duration("duration", duration), plant.dt)
    force_noise = as_positive_float("force_noise", force_noise, allow_zero=True)
    model = controller.model
    sliding = list(model.grasp.sliding)
    rng = rng if rng is not None else np.random.default_rng(0)
    force0 = None
    if isinstance(controller, Proposition2Controller) and sliding:
        force0 = _initial_tangential_force(plant, controller, reference, sliding)
    driver = _ControllerDriver(controller, reference, force0, force_noise, rng)
    records: list[StepRecord] = []
    consumers = [records.append]
    if on_step is not None:  # after the plant's step, as the recorder's hook expects
        consumers.append(lambda record: on_step(record.t, record.command.control))
    simulate(plant, driver, steps, consumers=consumers, sensor=sense_projected,
             control_failures=False)
    return ClosedLoopLog.from_records(records, plant, 2 * model.grasp.m, model.n)

"""Closed loop: a controller driving the plant (the controller never sees the plant's equations).

At each step the reduced state is *measured* from the plant (object pose and twist, and the
position and rate of each sliding contact along its edge), the controller computes torques,
and the plant integrates one step with them (zero-order hold). For Proposition 2 the friction
"measurement" is the plant's tangential contact force of the previous step, optionally with
Gaussian noise.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .contact import coefficients, cone_margin
from .control import ComputedTorqueController, ControlOutput, Proposition2Controller
from .plant import Plant, PlantEvent
from .reduced import ReducedModel

__all__ = ["ClosedLoopLog", "measure_reduced_state", "run_closed_loop"]

Reference = Callable[[float], tuple[np.ndarray, np.ndarray, np.ndarray]]


def measure_reduced_state(plant: Plant, model: ReducedModel) -> tuple[np.ndarray, np.ndarray]:
    """(S, Ṡ) of ``model``'s coordinates, read from the plant's state."""
    st = plant.state
    xi = [plant.contact_xi(st, i) for i in model.grasp.sliding]
    S = np.concatenate([st.X, [x for x, _ in xi]])
    S_dot = np.concatenate([st.V, [v for _, v in xi]])
    return S, S_dot


def _initial_friction_reading(plant: Plant, controller, reference: Reference, sliding) -> np.ndarray:
    """The friction sensor's reading before the first step: the plant's tangential force at the
    sliding contacts under the torque the controller would apply (two passes, so the reading and
    the torque are consistent)."""
    friction = np.zeros(len(sliding))
    S, S_dot = measure_reduced_state(plant, controller.model)
    for _ in range(2):
        out = controller(S, S_dot, *reference(plant.state.t), friction=friction)
        _, _, forces = plant.accelerations(plant.state, out.tau)
        friction = plant.surface_forces(plant.state, forces)[sliding, 1].copy()
    return friction


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
    events: tuple[PlantEvent, ...]
    max_constraint_error: float
    stopped: bool


def run_closed_loop(
    plant: Plant,
    controller: ComputedTorqueController,
    reference: Reference,
    duration: float,
    *,
    friction_noise: float = 0.0,
    rng: np.random.Generator | None = None,
    on_step: Callable[[float, ControlOutput], None] | None = None,
) -> ClosedLoopLog:
    """Run ``controller`` on ``plant`` for ``duration`` [s] (or until the plant stops).

    Args:
        reference: t -> (S_d, Ṡ_d, S̈_d).
        friction_noise: Standard deviation [N] of the noise added to the friction measurement
            (Proposition 2).
        rng: Random generator for that noise.
        on_step: Called after each control step with (t, output).
    """
    model = controller.model
    sliding = list(model.grasp.sliding)
    rng = rng if rng is not None else np.random.default_rng(0)
    rows = []
    friction = np.zeros(len(sliding))
    if isinstance(controller, Proposition2Controller) and sliding:
        friction = _initial_friction_reading(plant, controller, reference, sliding)
    steps = int(round(duration / plant.dt))
    for _ in range(steps):
        if plant.stopped:
            break
        t = plant.state.t
        S, S_dot = measure_reduced_state(plant, model)
        S_d, S_d_dot, S_d_ddot = reference(t)
        kwargs = {}
        if isinstance(controller, Proposition2Controller):
            kwargs["friction"] = friction + (friction_noise * rng.standard_normal(len(sliding)) if friction_noise else 0.0)
        out = controller(S, S_dot, S_d, S_d_dot, S_d_ddot, **kwargs)
        step = plant.step(out.tau)
        friction = step.forces_surface[sliding, 1].copy()
        margins = cone_margin(np.array(coefficients(plant.friction, step.modes)), step.forces_surface[:, 0],
                              step.forces_surface[:, 1])
        rows.append((t, S, np.asarray(S_d, dtype=float), out.error, step.forces_surface, out.contact_forces_surface,
                     margins, out.internal.f_c if out.internal is not None else np.zeros(2 * model.grasp.m),
                     out.seconds))
        if on_step is not None:
            on_step(t, out)
    cols = list(zip(*rows)) if rows else [[] for _ in range(9)]
    return ClosedLoopLog(
        times=np.array(cols[0]),
        S=np.array(cols[1]),
        S_desired=np.array(cols[2]),
        errors=np.array(cols[3]),
        plant_forces=np.array(cols[4]),
        predicted_forces=np.array(cols[5]),
        cone_margins=np.array(cols[6]),
        internal_forces=np.array(cols[7]),
        control_seconds=np.array(cols[8]),
        events=tuple(plant.events),
        max_constraint_error=plant.max_constraint_error,
        stopped=plant.stopped,
    )

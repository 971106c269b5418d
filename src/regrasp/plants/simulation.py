r"""One simulation loop and one per-step record, for every consumer.

:func:`simulate` runs a *driver* (a supervisor, or one control law with its reference) on the
plant at the plant's step (zero-order hold): at each step it senses a :class:`Measurement`
(:func:`sense`, what a hand could read), asks the driver for a :class:`Command`, steps the plant,
and hands one frozen :class:`StepRecord` to each consumer: the rollout's result
(:class:`~regrasp.rollout.build.RolloutResult`), the closed-loop log
(:class:`~regrasp.plants.closed_loop.ClosedLoopLog`) and the recorder
(:meth:`~regrasp.rollout.recording.recorder.RolloutRecorder.log_record`) all read the same records and recompute
nothing.

The loop stops at the end, when ``check`` returns a :class:`~regrasp.core.events.Failure` for a record,
when the driver's control law fails (:class:`~regrasp.core.exceptions.RegraspError` or a singular
model: a ``CONTROL`` failure, never an exception out of the loop), or, with ``interruptible``, on
Ctrl-C (an ``INTERRUPTED`` failure: the records so far are intact). The first Ctrl-C is deferred to the
end of the step in progress (:class:`InterruptAtStepEnd`), so it never lands inside a consumer (a recorder
half-way through a write) or a compiler; a second one raises at once.

A :class:`~regrasp.plants.disturbance.Disturbance` (optional) stands between the plant and the driver: the driver
senses its noisy, delayed reading of the truth and the plant gets its delayed, noisy torques. A record keeps
both sides (``measurement`` and ``truth``, ``command.tau`` and ``applied_tau``); the errors, the checks and
the results read the truth.
"""

from __future__ import annotations

import signal
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from ..core.contact import ContactMode, Friction, coefficients, cone_margin
from ..core.events import Event, EventKind, Failure, FailureKind
from ..core.exceptions import InvalidParameterError, RegraspError
from ..core.measurement import Measurement
from ..core.polygon import ConvexPolygon
from ..core.trajectory import TrajectorySample
from ..dynamics.control import ControlOutput
from ..model.hand import Hand
from .disturbance import Disturbance
from .project.state import PlantContact, PlantState, PlantStep

if TYPE_CHECKING:  # (the loop carries a supervisor's output; it never reads more of it than its events)
    from ..supervisor.types import SupervisorOutput

__all__ = ["Command", "Driver", "InterruptAtStepEnd", "PlantLike", "SimulationOutcome", "StepRecord", "sense",
           "sense_projected", "simulate"]


@runtime_checkable
class PlantLike(Protocol):
    """What the simulation loop, the rollout, the closed loop and the recorder read from a plant: the
    project's :class:`~regrasp.plants.project.plant.Plant`, MuJoCo's :class:`~regrasp.plants.mujoco.plant.MujocoPlant`
    and Drake's :class:`~regrasp.plants.drake.plant.DrakePlant`.

    Attributes:
        hand: The fingers (names, URDFs, base poses; the recorder draws them).
        polygon: The object.
        contacts: One :class:`~regrasp.plants.project.state.PlantContact` per finger: its edge, its mode now, and for a
            fixed contact the ξ [m] it is held at (what :func:`sense` reads).
        friction: The friction the plant has, one :class:`~regrasp.core.contact.Friction` per contact.
        dt: The control step [s] (:meth:`step` advances by it).
        state: The state now, or None before :meth:`reset`.
        events: The events since the last reset.
        stopped: Whether an event in ``stop_on`` stopped it.
        stop_on: The event kinds that stop it.
        max_constraint_error: The largest constraint violation [m] since the last reset.
    """

    hand: Hand
    polygon: ConvexPolygon
    contacts: list[PlantContact]
    friction: tuple[Friction, ...]
    dt: float
    state: PlantState | None
    events: list[Event]
    stopped: bool
    stop_on: frozenset[EventKind]
    max_constraint_error: float

    def reset(self, q: ArrayLike, v: ArrayLike, X: ArrayLike, V: ArrayLike, t: float = 0.0,
              contacts: Sequence[PlantContact] | None = None) -> PlantState: ...

    def step(self, tau: ArrayLike) -> PlantStep: ...

    def contact_xi(self, st: PlantState, i: int, tip: Sequence[float] | np.ndarray | None = None,
                   tip_vel: Sequence[float] | np.ndarray | None = None) -> tuple[float, float]: ...

    def surface_forces(self, st: PlantState, forces: np.ndarray) -> np.ndarray: ...

    def accelerations(self, st: PlantState, tau: ArrayLike,
                      modes: Sequence[PlantContact] | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]: ...


@dataclass(frozen=True)
class Command:
    """A driver's answer for one step.

    Attributes:
        tau: Joint torques [N m], (2m,).
        control: The control law's output.
        law: The law's name.
        desired: The desired object state at the step's start.
        S_desired: The law's desired reduced coordinates S_d = (x, y, β, ξ of each slider), (3 + p,).
        supervision: The supervisor's output, or None (a bare control law).
    """

    tau: np.ndarray
    control: ControlOutput
    law: str
    desired: TrajectorySample
    S_desired: np.ndarray
    supervision: SupervisorOutput | None = None


class Stretches(Protocol):
    def run(self, last: PlantStep | None, k: int, limit: int) -> tuple[int, PlantStep | None]: ...


class Driver(Protocol):
    def step(self, meas: Measurement, dt: float) -> Command: ...


@dataclass(frozen=True)
class StepRecord:
    """One control step: what was sensed, decided and commanded, and what the plant did.

    Attributes:
        index: Step number (0 first).
        t: The step's start time [s].
        measurement: What the driver sensed at ``t``.
        command: What the driver answered.
        plant: The plant's step: the state after it, the contact forces at its start, the modes
            during it, the events after it.
        cone_margins: The plant's μ f_n - |f_t| per contact [N], with the coefficient of each contact's
            mode during the step (μ_s fixed, μ_k sliding, 0 separated), (m,).
        events: The supervisor's decisions and the plant's events of this step, in that order.
        plant_seconds: Wall time of the plant step [s].
        truth: The noise-free reading at ``t`` (``measurement`` itself without a disturbance).
        applied_tau: The joint torques the plant got during the step [N m], (2m,) (``command.tau`` without a
            disturbance).
    """

    index: int
    t: float
    measurement: Measurement
    command: Command
    plant: PlantStep
    cone_margins: np.ndarray
    events: tuple[Event, ...]
    plant_seconds: float
    truth: Measurement | None = None
    applied_tau: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.truth is None:
            object.__setattr__(self, "truth", self.measurement)
        if self.applied_tau is None:
            object.__setattr__(self, "applied_tau", self.command.tau)

    @property
    def object_error(self) -> np.ndarray:
        """X_d - X at the step's start (the true X), (3,) [m, m, rad]."""
        return self.command.desired.pose - self.truth.X

    @property
    def supervision(self) -> SupervisorOutput | None:
        return self.command.supervision


@dataclass(frozen=True)
class SimulationOutcome:
    """How :func:`simulate` ended: ``steps`` run, ``failure`` (None: ran to the end), ``wall_seconds``."""

    steps: int
    failure: Failure | None
    wall_seconds: float


def _modes_sliding(plant: PlantLike) -> np.ndarray:
    return np.array([c.mode is ContactMode.SLIDING for c in plant.contacts])


def sense(plant: PlantLike, last: PlantStep | None) -> Measurement:
    """What a hand's sensors read now: the object pose and twist, each contact's ξ and ξ̇ (a fixed
    contact's ξ is where it is held), a slip sensor and the contact forces of the last step."""
    st = plant.state
    contacts = plant.contacts
    if last is None:
        xi = np.array([plant.contact_xi(st, i) for i in range(plant.hand.m)])
        xi, xi_dot, friction, normal = xi[:, 0], xi[:, 1], np.zeros(plant.hand.m), None
    else:
        xi, xi_dot, friction, normal = last.xi, last.xi_dot, last.forces_surface[:, 1], last.forces_surface[:, 0]
    modes = [c.mode for c in contacts]
    xi = np.array([c.xi if mode is ContactMode.FIXED else x for c, mode, x in zip(contacts, modes, xi.tolist())])
    return Measurement(st.t, st.X.copy(), st.V.copy(), xi, xi_dot, _modes_sliding(plant), friction, normal)


def sense_projected(plant: PlantLike, last: PlantStep | None) -> Measurement:
    """Like :func:`sense`, with every ξ, ξ̇ the tip's projection on its edge at the current state
    (``Plant.contact_xi``; a fixed contact's drifts by the constraint error)."""
    st = plant.state
    xi = np.array([plant.contact_xi(st, i) for i in range(plant.hand.m)])
    friction = np.zeros(plant.hand.m) if last is None else last.forces_surface[:, 1]
    normal = None if last is None else last.forces_surface[:, 0]
    return Measurement(st.t, st.X.copy(), st.V.copy(), xi[:, 0].copy(), xi[:, 1].copy(), _modes_sliding(plant),
                       friction, normal)


class InterruptAtStepEnd:
    """Defer the first Ctrl-C (SIGINT) to a point the loop chooses: while active, the first SIGINT only sets
    :attr:`requested` and a second one raises :class:`KeyboardInterrupt` at once (a way out of a step that never
    ends). With ``active=False`` it does nothing. Installed only from the main thread (elsewhere Python delivers
    no signals); the previous handler is restored on exit. Nested inside another one (a command that defers
    Ctrl-C from before it opens its recording until it has closed it), it shares the outer one's request.
    """

    def __init__(self, active: bool = True) -> None:
        self.active = active
        self._requested = False
        self._outer: InterruptAtStepEnd | None = None
        self._previous: object = None
        self._installed = False

    @property
    def requested(self) -> bool:
        """Whether Ctrl-C was pressed while this (or the one it is nested in) was active."""
        return self._outer.requested if self._outer is not None else self._requested

    def _handle(self, signum: int, frame: object) -> None:
        if self._requested:
            raise KeyboardInterrupt
        self._requested = True

    def __enter__(self) -> InterruptAtStepEnd:
        if not self.active or threading.current_thread() is not threading.main_thread():
            return self
        current = signal.getsignal(signal.SIGINT)
        outer = getattr(current, "__self__", None)
        if isinstance(outer, InterruptAtStepEnd):
            self._outer = outer
        else:
            self._previous = signal.signal(signal.SIGINT, self._handle)
            self._installed = True
        return self

    def __exit__(self, *exc: object) -> None:
        if self._installed:
            signal.signal(signal.SIGINT, self._previous)  # type: ignore[arg-type]
            self._installed = False


def simulate(plant: PlantLike, driver: Driver, steps: int, *,
             consumers: Sequence[Callable[[StepRecord], None]] = (),
             check: Callable[[StepRecord], Failure | None] | None = None,
             sensor: Callable[[PlantLike, PlantStep | None], Measurement] = sense,
             progress: Callable[[int, int], None] | None = None,
             interruptible: bool = False, control_failures: bool = True,
             disturbance: Disturbance | None = None, stretches: Stretches | None = None) -> SimulationOutcome:
    """Run ``driver`` on ``plant`` for ``steps`` steps (module docstring).

    Args:
        consumers: Each is called with every :class:`StepRecord`, in order.
        check: Called with every record after the consumers; a Failure stops the loop.
        sensor: Measurement model: :func:`sense` or :func:`sense_projected`.
        progress: Called as ``progress(done, steps)`` every 50 steps and at the end.
        interruptible: Turn Ctrl-C into an ``INTERRUPTED`` failure instead of raising it.
        control_failures: Turn the driver's errors into a ``CONTROL`` failure (else they propagate).
        disturbance: Sensing noise, a slip sensor and the actuation between the driver and the plant (module
            docstring); None: the driver reads the truth and its torques are applied at once.
        stretches: Runs stretches of steps in compiled code between the driver's decisions
            (:class:`~regrasp.rollout.stretch.CompiledStretches`: it writes its steps' rows itself, and the consumers
            see only the other steps), or None; built with ``disturbance`` (it draws the same noise).
    """
    if stretches is not None and getattr(stretches, "disturbance", None) is not disturbance:
        raise InvalidParameterError("stretches", stretches, "stretches built with this run's disturbance (they draw "
                                    "its noise)")
    dt = plant.dt
    mus = None
    last: PlantStep | None = None
    failure: Failure | None = None
    done = 0
    wall0 = time.perf_counter()
    interrupt = InterruptAtStepEnd(active=interruptible)
    with interrupt:
        try:
            k = 0
            while k < steps:
                if plant.stopped or interrupt.requested:
                    break
                if stretches is not None:
                    taken, last = stretches.run(last, k, steps - k)
                    if taken:
                        if progress is not None and (k + taken) // 50 > k // 50:
                            progress((k + taken) // 50 * 50, steps)
                        k = done = k + taken
                        continue
                truth = sensor(plant, last)
                meas = truth if disturbance is None else disturbance.measure(truth)
                try:
                    command = driver.step(meas, dt)
                except (RegraspError, np.linalg.LinAlgError) as exc:
                    if not control_failures:
                        raise
                    failure = Failure(float(meas.t), FailureKind.CONTROL, f"control failed: {exc}")
                    break
                tau = command.tau if disturbance is None else disturbance.actuate(command.tau)
                t0 = time.perf_counter()
                step = plant.step(tau)
                plant_seconds = time.perf_counter() - t0
                last = step
                if mus is None:
                    mus = plant.friction
                forces = step.forces_surface
                margins = cone_margin(np.array(coefficients(mus, step.modes)), forces[:, 0], forces[:, 1])
                events = (() if command.supervision is None else command.supervision.events) + step.events
                record = StepRecord(k, float(meas.t), meas, command, step, margins, events, plant_seconds, truth, tau)
                for consume in consumers:
                    consume(record)
                k = done = k + 1
                if progress is not None and done % 50 == 0:
                    progress(done, steps)
                if check is not None:
                    failure = check(record)
                    if failure is not None:
                        break
        except KeyboardInterrupt:
            if not interruptible:
                raise
            failure = Failure(float(plant.state.t), FailureKind.INTERRUPTED, "interrupted (Ctrl-C)")
    if interrupt.requested and failure is None:
        failure = Failure(float(plant.state.t), FailureKind.INTERRUPTED, "interrupted (Ctrl-C)")
    if progress is not None:
        progress(done, steps)
    return SimulationOutcome(done, failure, time.perf_counter() - wall0)

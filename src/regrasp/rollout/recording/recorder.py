r"""Record rollouts to rerun: an ``.rrd`` file, a live viewer (spawned or connected to), or both.

A :class:`RolloutRecorder` turns each control step of a supervised rollout
(:meth:`Rollout.run(recorder=...) <regrasp.rollout.build.Rollout.run>`, one
:class:`~regrasp.plants.simulation.StepRecord` per step) or of :func:`~regrasp.plants.closed_loop.run_closed_loop`
into a rerun recording a reviewer can scrub through: the hand and the object with the events
log on the left, each finger's ξ panel (the paper's Figure 4.3, live) and the phases in the
middle, the other time series on the right (the blueprint is stored in the file). It uses its own
``rerun.RecordingStream`` (never rerun's global or thread-local recording), so several recorders
can run side by side, and it needs no viewer: ``rrd_path`` alone writes a file headless. What a
recording holds (its timelines, entities, units, colours and cost) is described in :mod:`regrasp.rollout.recording`.

::

    with RolloutRecorder(rollout.plant, rrd_path="rollout.rrd", decimation=10) as rec:
        rollout.run(recorder=rec)
    # or, a bare control law:
    with RolloutRecorder(plant, rrd_path="rollout.rrd") as rec:
        run_closed_loop(plant, controller, reference, 1.0, on_step=rec.hook(plant, reference))
    # then: rerun rollout.rrd

The values a recording holds and where they come from (a supervised record, a compiled stretch's step, or the
plant measured here) are in :mod:`regrasp.rollout.recording`'s docstring ("Two sources"); the rows are made by
:mod:`~regrasp.rollout.recording.rows` and :mod:`~regrasp.rollout.recording.measure`, drawn by
:mod:`~regrasp.rollout.recording.scene` and sent in blocks by :mod:`~regrasp.rollout.recording.writer`.

**Robustness.** :meth:`~RolloutRecorder.close` sends what is buffered, flushes and finalises the
file (footer included), and is idempotent; the context manager calls it also when the block
raises, so an interrupted rollout leaves a complete, readable file with the steps logged so far
(a step whose logging raised leaves no row: a row is buffered whole or not at all).
A recorder that is never closed is closed when it is garbage-collected or at interpreter exit
(a ``weakref.finalize`` tied to the recorder; nothing else is registered). A process killed
outright (SIGKILL, ``os._exit``) cannot finalise its file.
"""

from __future__ import annotations

import time as _time
import uuid
import warnings
import weakref
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import rerun as rr
from numpy.typing import ArrayLike

from ...core.events import EventSource
from ...core.exceptions import InvalidParameterError
from ...core.intervals import DANGER_FRACTION
from ...dynamics.control import ControlOutput
from ...kernels.decimation import logged
from ...plants.project.state import PlantStep
from ...plants.simulation import PlantLike
from ...supervisor.types import ContactPhase
from .blueprint import blueprint
from .events import WARN_KINDS, PlantEventCursor, event_line, failure_line
from .hand import HandDrawing
from .measure import PlantMeasure
from .options import checked_desired, checked_options, checked_plant_state, checked_step, checked_time
from .outline import closed_outline
from .rows import MODE_CODES, PHASE_CODES, Layout, StepRow, SupervisedStep, supervised_row
from .scene import Scene, failure_marker
from .static import log_static
from .writer import ColumnWriter, close_quietly, connect_sinks

if TYPE_CHECKING:
    from ...core.events import Failure
    from ...plants.simulation import StepRecord

__all__ = ["MODE_CODES", "PHASE_CODES", "WARN_KINDS", "RolloutRecorder"]


class RolloutRecorder:
    r"""Stream and/or save a closed-loop rollout to rerun (see :mod:`regrasp.rollout.recording` for the scene,
    the plots and the units).

    Args:
        plant: The plant being simulated (its hand, object, contacts and friction set up the recording).
        envelope_edges: Which feasible envelopes to draw: one entry per finger, each an edge
            index, a sequence of edge indices or None (none for that finger). Default: each
            finger's current contact edge (``plant.contacts[i].edge``, followed if it changes).
        rrd_path: Write the recording to this ``.rrd`` file (its directory must exist and take a new file).
        spawn: Start a rerun viewer and stream to it (with ``rrd_path``: both).
        connect: Stream to a running viewer (or ``rerun --serve-grpc`` server) at this gRPC URL,
            e.g. ``"rerun+http://127.0.0.1:9876/proxy"`` (with ``rrd_path``: both; not with ``spawn``).
        application_id: Rerun application id.
        recording_name: Name shown in the viewer (default: the file's stem, or "rollout").
        danger_fraction: Width of each danger zone as a fraction of its feasible interval, in
            [0, 0.5) (default :data:`~regrasp.core.intervals.DANGER_FRACTION`, the zones the paper policy and the
            PNG figures use; :func:`~regrasp.core.intervals.danger_zones`).
        decimation: Log every n-th step only (1 <= n <= 10**6).
        sliding: Contacts whose ξ are the reduced coordinates S[3:] (the controller's
            ``grasp.sliding``), for naming the error series. Default: the contacts in mode
            ``ContactMode.SLIDING`` now.
        envelope_geometry: ``"ideal"`` (segments, ~60 µs per envelope) or ``"urdf"`` (coal,
            ~1 ms), see :class:`~regrasp.envelope.finger_envelope.FingerEnvelope`.
        force_scale: Arrow length per newton [mm/N].
        cone_length: Length of the friction-cone rays [mm].
        plant_forces: Without a ``PlantStep``, recompute the plant's contact forces at the
            logged state (one KKT solve per logged step, ~150 µs); False: draw and plot the
            controller's predicted forces only.
        envelope_tolerance: Reuse an edge's envelope while the object has moved less than this
            [m] (each coordinate, and β times the object's diameter) since it was computed;
            0 recomputes it at every logged step.
        flush_every: Send the buffered rows every this many logged steps (the cost of a send is
            mostly per entity, so larger blocks are cheaper per step; a live viewer sees the
            data in blocks of this many steps). Default: 5000 for a file alone (one chunk per entity for a
            rollout of up to 5000 logged steps), 500 with a viewer
            (:data:`~regrasp.rollout.recording.options.FILE_BLOCK`, ``VIEWER_BLOCK``).

    Attributes:
        plant: The recorder's plant.
        options: Every option, checked (:class:`~regrasp.rollout.recording.options.RecorderOptions`).
        rrd_path: The ``.rrd`` file (a :class:`~pathlib.Path`), or None.
        connect: The gRPC URL streamed to, or None.
        decimation: Every how many steps one is logged.
        danger_fraction: The danger zones' width, a fraction of each interval.
        steps_logged: How many steps were logged.
        compute_seconds: Wall time spent making the logged steps' rows [s] (sending: the writer's).

    Raises:
        InvalidParameterError: no sink (none of ``rrd_path``, ``spawn``, ``connect``), a missing
            directory, ``spawn`` with ``connect``, a ``connect`` that is no rerun gRPC URL, or a
            parameter out of its domain.
        UnknownEdgeError: an edge in ``envelope_edges`` that the object does not have.
    """

    def __init__(
        self,
        plant: PlantLike,
        *,
        envelope_edges: Sequence[int | Sequence[int] | None] | None = None,
        rrd_path: str | Path | None = None,
        spawn: bool = False,
        connect: str | None = None,
        application_id: str = "regrasp",
        recording_name: str | None = None,
        danger_fraction: float = DANGER_FRACTION,
        decimation: int = 1,
        sliding: Sequence[int] | None = None,
        envelope_geometry: str = "ideal",
        force_scale: float = 10.0,
        cone_length: float = 15.0,
        plant_forces: bool = True,
        envelope_tolerance: float = 1e-5,
        flush_every: int | None = None,
    ):
        # ---- validation first: a bad argument leaves nothing behind (no stream, no file)
        options = checked_options(
            plant, envelope_edges=envelope_edges, rrd_path=rrd_path, spawn=spawn, connect=connect,
            application_id=application_id, recording_name=recording_name, danger_fraction=danger_fraction,
            decimation=decimation, sliding=sliding, envelope_geometry=envelope_geometry, force_scale=force_scale,
            cone_length=cone_length, plant_forces=plant_forces, envelope_tolerance=envelope_tolerance,
            flush_every=flush_every)
        self.plant = plant
        self.options = options
        self.rrd_path = options.rrd_path
        self.connect = options.connect
        self.decimation = options.decimation
        self.danger_fraction = options.danger_fraction
        hand = HandDrawing(plant.hand.fingers)
        self._layout = Layout(hand, tuple(options.sliding), options.danger_fraction)
        self._measure = PlantMeasure(  # (makes the envelopes now: a bad geometry raises here)
            self._layout, plant, envelope_edges=options.envelope_edges, geometry=options.envelope_geometry,
            tolerance=options.envelope_tolerance, plant_forces=options.plant_forces)
        polygon = plant.polygon
        self._object_closed = closed_outline(polygon)  # (a curve's: its outline within 0.05 mm)
        scene = Scene(self._object_closed, hand, polygon.edges, plant.friction, force_scale=options.force_scale,
                      cone_length=options.cone_length, danger_fraction=options.danger_fraction)

        # ---- the stream and its sinks
        self.steps_logged = 0
        self.compute_seconds = 0.0
        self._next_step = 0
        self._closed = False
        self._plant_events = PlantEventCursor()
        stream = rr.RecordingStream(options.application_id, recording_id=uuid.uuid4(), make_default=False,
                                    make_thread_default=False)
        self._writer = ColumnWriter(stream, options.flush_every, scene, hand.keys)
        self._finalizer = weakref.finalize(self, close_quietly, self._writer)
        try:
            stream.set_log_time_enabled(False)  # the simulation's own time is what matters
            connect_sinks(stream, options.rrd_path, options.spawn, options.connect, blueprint(plant, hand))
            stream.send_recording_name(options.recording_name)
            log_static(stream, plant, hand, options, self._object_closed)
        except BaseException:
            self.close()
            raise

    # ------------------------------------------------------------------ public API
    @property
    def closed(self) -> bool:
        """Whether :meth:`close` has run."""
        return self._closed

    @property
    def seconds_per_step(self) -> float:
        """Mean wall time [s] per logged step: geometry and buffering plus the amortised sending."""
        if self.steps_logged == 0:
            return float("nan")
        return (self.compute_seconds + self._writer.send_seconds) / self.steps_logged

    def log_step(
        self,
        plant: PlantLike,
        output: ControlOutput | None = None,
        *,
        step: int | None = None,
        time: float | None = None,
        desired_pose: ArrayLike | None = None,
        plant_step: PlantStep | None = None,
    ) -> bool:
        r"""Log the plant's current state (and the step's control output) at one step, measuring the
        plant (ξ from the tips, envelopes evaluated here): the path without a supervisor.

        Args:
            plant: The plant (the recorder's, or one with the same hand and object).
            output: The controller's output for the step that led here, or None (e.g. the
                initial state): then the predicted forces and margins are not plotted and the
                tracking error needs ``desired_pose``.
            step: The ``step`` timeline's value; default: one more than the previous call's
                (0 for the first call). Only the steps :func:`~regrasp.kernels.decimation.logged` at
                ``decimation`` (its multiples) are logged.
            time: The ``time`` timeline's value [s]; default ``plant.state.t``.
            desired_pose: The desired object pose (x, y, β), or the whole desired reduced state
                S_d = (x, y, β, ξ of each ``sliding`` contact): drawn as a ghost, and the
                tracking error is then measured at the logged state.
            plant_step: The :class:`~regrasp.plants.project.state.PlantStep` of the step, whose forces (at the
                step's start) are then drawn and plotted instead of recomputed ones.

        Returns:
            Whether the step was logged (False when ``decimation`` skips it).

        Raises:
            InvalidParameterError: the recorder is closed, the plant has no state or another
                hand, or an array has the wrong shape.
        """
        self._check_open()
        st = checked_plant_state(plant, self.plant)
        step = checked_step(step, self._next_step)
        self._next_step = step + 1
        t = checked_time(st.t if time is None else time)
        start = _time.perf_counter()
        for ev in self._plant_events.new(plant.events):
            self._writer.log_now("events", step, float(ev.time), event_line(ev))
        if not logged(step, self.decimation):
            return False
        desired = checked_desired(desired_pose)
        n_errors = self._layout.n_errors
        if output is not None and np.asarray(output.error).shape != (n_errors,):
            raise InvalidParameterError("output.error", np.shape(output.error),
                                        f"{n_errors} entries (3 + one per sliding contact {self.options.sliding}; "
                                        "pass sliding= to the recorder)")
        return self._row(step, t, start, lambda: self._measure.row(plant, output, desired, plant_step))

    def log_initial(self, plant: PlantLike, desired_pose: ArrayLike | None) -> bool:
        """Log the plant's state before the first step (step 0)."""
        return self.log_step(plant, None, step=0, desired_pose=desired_pose)

    def log_record(self, record: StepRecord, desired_pose: ArrayLike | None) -> bool:
        """Log one :class:`~regrasp.plants.simulation.StepRecord` of the simulation loop: the state after its
        step, as step ``record.index + 1``, against ``desired_pose`` (the desired pose then).

        A supervised record (``record.supervision`` not None) is logged from the record alone
        (:mod:`regrasp.rollout.recording`, "Two sources"); its events (the supervisor's decisions and the plant's
        events) go to ``events`` whatever the decimation. A record without a supervisor is logged
        like :meth:`log_step` with its ``PlantStep``.

        Returns:
            Whether the step was logged (False when ``decimation`` skips it).
        """
        if record.supervision is None:
            control = record.command.control
            # the recorder's error series are the object's (the sliding set changes with each slide)
            control = replace(control, error=self._layout.object_error(control.error))
            return self.log_step(self.plant, control, step=record.index + 1, desired_pose=desired_pose,
                                 plant_step=record.plant)
        return self._log_supervised(record.index + 1, record.plant.state.t, desired_pose,
                                    lambda: SupervisedStep.from_record(record), record.events)

    def log_stretch_step(self, step: int, t: float, X: np.ndarray, q: np.ndarray, desired_pose: ArrayLike,
                         surface: np.ndarray, predicted: np.ndarray,
                         predicted_surface: np.ndarray, feasible: Sequence[Sequence[tuple[float, float]]],
                         phases: Sequence[ContactPhase], xi: np.ndarray, error: np.ndarray,
                         plant_cone: np.ndarray, predicted_cone: np.ndarray, bounds: np.ndarray,
                         reference_xi: np.ndarray, planned_xi: np.ndarray) -> bool:
        """Log a supervised step that a compiled stretch (:mod:`regrasp.rollout.stretch`) took, as :meth:`log_record`
        logs its record (a stretch's steps have no events): the step ``step`` (``record.index + 1``), the plant's
        time ``t`` [s], pose ``X`` and joints ``q`` after it, and the record's fields
        (:class:`~regrasp.rollout.recording.rows.SupervisedStep`, the same names)."""
        return self._log_supervised(step, t, desired_pose, lambda: SupervisedStep(
            X, q, surface, predicted, predicted_surface, feasible, phases, xi, error, plant_cone, predicted_cone,
            bounds, reference_xi, planned_xi), ())

    def log_failure(self, failure: Failure, plant: PlantLike | None = None) -> None:
        """Log a rollout's :class:`~regrasp.core.events.Failure`: an ERROR line in ``events`` and the
        failure marked in the scene (``scene/failure``, :func:`~regrasp.rollout.recording.scene.failure_marker`)
        at the failure's time and the last step, drawn at ``plant``'s state (default: the recorder's plant)."""
        self._check_open()
        plant = self.plant if plant is None else plant
        step = max(self._next_step - 1, 0)
        t = checked_time(failure.time)
        self._writer.log_now("events", step, t, failure_line(failure))
        marker = failure_marker(failure, plant, self._layout.hand, self._object_closed)
        if marker is not None:
            self._writer.log_now("scene/failure", step, t, marker)

    def hook(self, plant: PlantLike, reference: Callable | None = None, *,
             log_initial: bool = True) -> Callable[[float, ControlOutput], None]:
        """An ``on_step`` callback for :func:`~regrasp.plants.closed_loop.run_closed_loop`.

        ``run_closed_loop`` calls it after ``plant.step``, so it logs ``plant.state`` (the state
        after the step) at ``time = plant.state.t``; the desired pose is ``reference(time)``'s
        first entry when ``reference`` is given. With ``log_initial`` the current state is
        logged now (step 0, no control output), so step k is the state after k control steps.
        """
        if plant.state is None:
            raise InvalidParameterError("plant.state", None, "a state: call plant.reset() first")

        def desired_at(t: float):
            if reference is None:
                return None
            value = reference(t)
            return value[0] if isinstance(value, tuple) else value

        if log_initial:
            self.log_step(plant, None, desired_pose=desired_at(plant.state.t))

        def on_step(t: float, output: ControlOutput) -> None:
            step = self._next_step
            desired = desired_at(plant.state.t) if logged(step, self.decimation) else None
            self.log_step(plant, output, step=step, desired_pose=desired)

        return on_step

    def flush(self) -> None:
        """Send the buffered rows and flush the stream (the file stays open)."""
        if not self._closed:
            self._writer.flush()

    def close(self) -> None:
        """Send what is buffered, flush, and finalise the file (footer) and viewer stream.

        Idempotent; after it, :meth:`log_step` raises.
        """
        if self._closed:
            return
        self._closed = True
        self._finalizer.detach()
        self._writer.close()

    def __enter__(self) -> RolloutRecorder:
        return self

    def __exit__(self, exc_type, exc, tb) -> bool:
        try:
            self.close()
        except Exception as close_exc:  # noqa: BLE001
            if exc_type is None:
                raise
            warnings.warn(f"RolloutRecorder.close() failed after {exc_type.__name__}: {close_exc!r}",
                          RuntimeWarning, stacklevel=2)  # (the rollout's exception is the one that propagates)
        return False

    def __repr__(self) -> str:
        state = "closed" if self._closed else "open"
        return f"RolloutRecorder({self.rrd_path or 'viewer'}, {self.steps_logged} steps logged, {state})"

    # ------------------------------------------------------------------ per step
    def _check_open(self) -> None:
        if self._closed:
            raise InvalidParameterError("recorder", "closed", "an open RolloutRecorder (log before close())")

    def _log_supervised(self, step: int, t: float, desired_pose: ArrayLike | None,
                        supervised: Callable[[], SupervisedStep], events: Sequence) -> bool:
        """Log a supervised step (:mod:`regrasp.rollout.recording`, "Two sources"): its events (decisions at the
        step's start, the previous state; the plant's after it) whatever the decimation, its row if logged."""
        self._check_open()
        step = checked_step(step, self._next_step)
        self._next_step = step + 1
        t = checked_time(t)
        start = _time.perf_counter()
        for ev in events:
            self._writer.log_now("events", max(step - 1, 0) if ev.source is EventSource.SUPERVISOR else step,
                                 float(ev.time), event_line(ev))
        self._plant_events.skip(self.plant.events)  # (the plant's are in the record, or there are none)
        if not logged(step, self.decimation):
            return False
        desired = checked_desired(desired_pose)
        return self._row(step, t, start, lambda: supervised_row(self._layout, self.plant.contacts, supervised(),
                                                                desired))

    def _row(self, step: int, t: float, start: float, make: Callable[[], StepRow]) -> bool:
        """Buffer the row ``make()`` builds (a step whose row raises leaves none: the steps before it stay)."""
        row = make()
        self.compute_seconds += _time.perf_counter() - start
        self.steps_logged += 1
        self._writer.append(row, step, t)  # may send a block (timed separately)
        return True


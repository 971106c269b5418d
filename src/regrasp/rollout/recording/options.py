"""A recorder's options, checked before anything is opened (:func:`checked_options`): a bad argument raises a typed
error and leaves nothing behind (no stream, no file); and the checks of what each logged step is given (its plant,
step number, time and desired pose)."""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from ...core.contact import ContactMode
from ...core.exceptions import InvalidParameterError
from ...core.validation import as_count, as_output_path
from ...plants.project.state import PlantState
from ...plants.simulation import PlantLike

__all__ = ["FILE_BLOCK", "VIEWER_BLOCK", "RecorderOptions", "as_viewer_url", "checked_desired", "checked_options",
           "checked_plant_state", "checked_step", "checked_time"]

#: Where ``connect`` may point: a rerun gRPC URL such as ``rerun+http://127.0.0.1:9876/proxy``.
#: Logged steps sent in one block (one chunk per entity) when the recording goes to a file alone: a whole rollout at
#: ``regrasp simulate --rrd``'s decimation in one chunk per entity (fewer, larger chunks: the viewer opens a file
#: sooner), and a bounded buffer for longer ones.
FILE_BLOCK = 5000
#: The same with a viewer, which sees the data in blocks of this many steps.
VIEWER_BLOCK = 500

_GRPC_URL = re.compile(r"^rerun(\+https?)?://[^/\s]+(/\S*)?$")


def as_viewer_url(name: str, value: object) -> str:
    """``value`` if it is a rerun viewer's gRPC URL (``rerun+http://127.0.0.1:9876/proxy``), else an
    :class:`~regrasp.core.exceptions.InvalidParameterError` naming ``name`` (a command line checks it before any
    work)."""
    if not isinstance(value, str) or not _GRPC_URL.match(value):
        raise InvalidParameterError(name, value, "a rerun gRPC URL such as 'rerun+http://127.0.0.1:9876/proxy'")
    return value


@dataclass(frozen=True)
class RecorderOptions:
    """A :class:`~regrasp.rollout.recording.recorder.RolloutRecorder`'s options, checked (its arguments' names,
    meanings and units).

    Attributes:
        rrd_path: The ``.rrd`` file, or None.
        spawn: Whether a viewer is spawned.
        connect: The gRPC URL streamed to, or None.
        application_id: Rerun application id.
        recording_name: The name shown in the viewer.
        danger_fraction: Width of each danger zone, a fraction of its interval, in [0, 0.5).
        decimation: Log every n-th step (1 <= n <= 10**6).
        flush_every: Send the buffered rows every this many logged steps (>= 1; :data:`FILE_BLOCK` for a file alone,
            :data:`VIEWER_BLOCK` with a viewer when not given).
        force_scale: Arrow length per newton [mm/N].
        cone_length: Length of the friction cones' rays [mm].
        plant_forces: Recompute the plant's forces without a ``PlantStep``.
        envelope_tolerance: Reuse an edge's envelope sample while the object moves less than this [m].
        envelope_geometry: ``"ideal"`` or ``"urdf"``.
        envelope_edges: Per finger the edges whose envelopes are drawn, or None (each contact's current edge).
        sliding: The contacts whose ξ are the tracking error's reduced coordinates.
    """

    rrd_path: Path | None
    spawn: bool
    connect: str | None
    application_id: str
    recording_name: str
    danger_fraction: float
    decimation: int
    flush_every: int
    force_scale: float
    cone_length: float
    plant_forces: bool
    envelope_tolerance: float
    envelope_geometry: str
    envelope_edges: list[tuple[int, ...]] | None
    sliding: list[int]


def checked_options(plant: PlantLike, *, envelope_edges: Sequence[int | Sequence[int] | None] | None,
                    rrd_path: str | Path | None, spawn: bool, connect: str | None, application_id: str,
                    recording_name: str | None, danger_fraction: float, decimation: int,
                    sliding: Sequence[int] | None, envelope_geometry: str, force_scale: float, cone_length: float,
                    plant_forces: bool, envelope_tolerance: float, flush_every: int | None) -> RecorderOptions:
    """A recorder's arguments (:class:`~regrasp.rollout.recording.recorder.RolloutRecorder`'s, the same names),
    checked and normalised. The envelope geometry is checked when the envelopes are made.

    Raises:
        InvalidParameterError: no plant, no sink, an ``rrd_path`` that cannot be written
            (:func:`~regrasp.core.validation.as_output_path`: a missing or read-only directory, a name too long or with
            a NUL byte, a directory), ``spawn`` with ``connect``, a ``connect``
            that is no rerun gRPC URL, or a parameter out of its domain.
        UnknownEdgeError: an edge in ``envelope_edges`` that the object does not have.
    """
    if not isinstance(plant, PlantLike):
        raise InvalidParameterError("plant", plant,
                                    "a plant (regrasp.Plant or regrasp.plants.mujoco.plant.MujocoPlant)")
    if connect is not None:
        as_viewer_url("connect", connect)
        if spawn:
            raise InvalidParameterError("connect", connect, "either spawn=True or connect, not both")
    if rrd_path is None and not spawn and connect is None:
        raise InvalidParameterError("rrd_path", None, "a sink: an .rrd path, spawn=True or connect, or both")
    path = None if rrd_path is None else as_output_path("rrd_path", rrd_path)  # (before any stream or file is made)
    if not (isinstance(danger_fraction, (int, float)) and 0.0 <= danger_fraction < 0.5):
        raise InvalidParameterError("danger_fraction", danger_fraction, "a fraction in [0, 0.5)")
    decimation = as_count("decimation", decimation, 1)
    if flush_every is None:  # a file alone: large blocks (few chunks: a viewer opens it sooner); a viewer: 500
        flush_every = FILE_BLOCK if not spawn and connect is None else VIEWER_BLOCK
    flush_every = as_count("flush_every", flush_every, 1)
    for name, value in (("force_scale", force_scale), ("cone_length", cone_length)):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise InvalidParameterError(name, value, "a length > 0 [mm per N, mm]")
    if not (isinstance(envelope_tolerance, (int, float)) and math.isfinite(envelope_tolerance)
            and envelope_tolerance >= 0):
        raise InvalidParameterError("envelope_tolerance", envelope_tolerance, "a distance >= 0 [m]")
    m = plant.hand.m
    edges = _parse_edges(envelope_edges, plant)
    if sliding is None:
        sliding = [i for i, c in enumerate(plant.contacts) if c.mode is ContactMode.SLIDING]
    sliding = list(sliding)
    if (len(set(sliding)) != len(sliding)
            or not all(isinstance(i, (int, np.integer)) and 0 <= i < m for i in sliding)):
        raise InvalidParameterError("sliding", sliding, f"distinct contact indices in 0..{m - 1}")
    name = recording_name if recording_name is not None else (path.stem if path is not None else "rollout")
    return RecorderOptions(
        rrd_path=path, spawn=spawn, connect=connect, application_id=application_id, recording_name=str(name),
        danger_fraction=float(danger_fraction), decimation=decimation, flush_every=flush_every,
        force_scale=float(force_scale), cone_length=float(cone_length), plant_forces=bool(plant_forces),
        envelope_tolerance=float(envelope_tolerance), envelope_geometry=envelope_geometry, envelope_edges=edges,
        sliding=[int(i) for i in sliding])


def _parse_edges(envelope_edges: object, plant: PlantLike) -> list[tuple[int, ...]] | None:
    """Per finger the edges to draw (an edge, a sequence of edges or None each), checked against the object."""
    if envelope_edges is None:
        return None
    m = plant.hand.m
    if isinstance(envelope_edges, (str, bytes)) or not isinstance(envelope_edges, Sequence) \
            or len(envelope_edges) != m:
        raise InvalidParameterError("envelope_edges", envelope_edges,
                                    f"one entry per finger ({m}): an edge, a list of edges or None")
    out = []
    for entry in envelope_edges:
        if entry is None:
            out.append(())
            continue
        edges = [entry] if isinstance(entry, (int, np.integer)) else list(entry)
        for e in edges:
            plant.polygon.edge(e)  # UnknownEdgeError
        out.append(tuple(int(e) for e in edges))
    return out


def checked_time(t: float) -> float:
    """A logged time [s], checked finite."""
    t = float(t)
    if not math.isfinite(t):
        raise InvalidParameterError("time", t, "a finite time [s]")
    return t


def checked_desired(desired_pose: ArrayLike | None) -> np.ndarray | None:
    """A desired pose (x, y, β) or reduced state S_d = (x, y, β, ξ...) as a flat float array, checked finite; or
    None."""
    desired = None if desired_pose is None else np.asarray(desired_pose, dtype=float).reshape(-1)
    if desired is not None and (desired.size < 3 or not np.isfinite(desired).all()):
        raise InvalidParameterError("desired_pose", desired_pose, "(x, y, beta) or S_d = (x, y, beta, xi...)")
    return desired


def checked_plant_state(plant: object, recorder_plant: PlantLike) -> PlantState:
    """The state of ``plant``: the recorder's plant, or one with as many fingers and an object of as many edges (a
    curved object: one face)."""
    m = recorder_plant.hand.m
    if plant is not recorder_plant and (not isinstance(plant, PlantLike) or plant.hand.m != m
                                        or len(plant.polygon.edges) != len(recorder_plant.polygon.edges)):
        raise InvalidParameterError("plant", plant, f"a plant with the recorder's {m} fingers and object")
    if plant.state is None:
        raise InvalidParameterError("plant.state", None, "a state: call plant.reset() first")
    return plant.state


def checked_step(step: object, default: int) -> int:
    """A logged step's number: ``step``, an integer >= 0, or ``default`` for None."""
    if step is None:
        return default
    if isinstance(step, bool) or not isinstance(step, (int, np.integer)) or step < 0:
        raise InvalidParameterError("step", step, "an integer >= 0")
    return int(step)

"""The recording's stream and its sinks, and the buffering of logged steps: :class:`ColumnWriter` keeps each logged
step's row and sends a block of them with one ``send_columns`` per entity (every ``flush_every`` rows and on
closing), so that a row costs numpy operations over the block rather than rerun calls of its own.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Sequence
from itertools import chain
from pathlib import Path

import numpy as np
import rerun as rr
import rerun.blueprint as rrb
from numpy.typing import ArrayLike

from .rows import StepRow, series_columns
from .scene import Scene

__all__ = ["ColumnWriter", "close_quietly", "connect_sinks", "nanoseconds"]


def nanoseconds(seconds: ArrayLike) -> np.ndarray:
    """Times [s] as timedelta64[ns], rounded (a float sum such as 1.0069999999 s reads 1.007 s)."""
    return np.round(np.asarray(seconds, dtype=float) * 1e9).astype(np.int64).astype("timedelta64[ns]")


def connect_sinks(stream: rr.RecordingStream, path: Path | None, spawn: bool, connect: str | None,
                  blueprint: rrb.Blueprint) -> None:
    """Point ``stream`` at its sinks, each sent ``blueprint``: the ``.rrd`` file ``path``, a viewer spawned
    (``spawn``) or the gRPC URL ``connect``, or the file and a viewer."""
    if not spawn and connect is None:
        stream.save(str(path), default_blueprint=blueprint)
    elif path is None and connect is not None:
        stream.connect_grpc(connect, default_blueprint=blueprint)
    elif path is None:
        stream.spawn(default_blueprint=blueprint)
    else:
        if spawn:
            rr.spawn(connect=False)
        stream.set_sinks(rr.GrpcSink(connect), rr.FileSink(str(path)), default_blueprint=blueprint)


class ColumnWriter:
    """Owns the recording stream; buffers the logged steps' rows and sends them with ``send_columns``.

    Kept apart from the recorder so that a ``weakref.finalize`` can close it (and send the last block) without
    keeping the recorder alive.

    Args:
        stream: The recording stream (its sinks set by the caller).
        flush_every: Send the buffered rows every this many rows.
        scene: How the rows are drawn.
        keys: The fingers' entity-path parts (the per-finger plots).
    """

    def __init__(self, stream: rr.RecordingStream, flush_every: int, scene: Scene, keys: Sequence[str]):
        self.stream = stream
        self.flush_every = flush_every
        self.scene = scene
        self.keys = list(keys)
        self.rows: list[StepRow] = []
        self.steps: list[int] = []
        self.times: list[float] = []
        self.closed = False
        self.send_seconds = 0.0  # wall time spent sending [s]

    def append(self, row: StepRow, step: int, t: float) -> None:
        """Buffer one logged step's row at ``step`` and time ``t`` [s]; send the block once it is full."""
        self.rows.append(row)
        self.steps.append(step)
        self.times.append(t)
        if len(self.rows) >= self.flush_every:
            self.send()

    def send(self) -> None:
        """Send every buffered row (one ``send_columns`` per entity)."""
        if not self.rows:
            return
        start = time.perf_counter()
        try:
            index = [rr.TimeColumn("step", sequence=np.asarray(self.steps, dtype=np.int64)),
                     rr.TimeColumn("time", duration=nanoseconds(self.times))]
            for path, columns in chain(self.scene.columns(self.rows), series_columns(self.rows, self.keys)):
                self.stream.send_columns(path, indexes=index, columns=columns)
        finally:
            self.rows.clear()
            self.steps.clear()
            self.times.clear()
            self.send_seconds += time.perf_counter() - start

    def log_now(self, path: str, step: int, t: float, archetype: rr.AsComponents) -> None:
        """Log one archetype immediately at (``step``, ``t`` [s]) (rare data: events, failures)."""
        self.stream.set_time("step", sequence=step)
        self.stream.set_time("time", duration=nanoseconds([t])[0])
        self.stream.log(path, archetype)

    def flush(self) -> None:
        """Send the buffered rows and flush the stream (the sinks stay open)."""
        self.send()
        self.stream.flush(timeout_sec=30.0)

    def close(self) -> None:
        """Send the buffer, flush, and finalise every sink (writes the .rrd footer). Idempotent."""
        if self.closed:
            return
        self.closed = True
        try:
            self.send()
        finally:
            try:
                self.stream.flush(timeout_sec=30.0)
            finally:
                self.stream.disconnect()


def close_quietly(writer: ColumnWriter) -> None:
    """The finalizer of a recorder that was never closed (garbage collection or interpreter exit)."""
    try:
        writer.close()
    except Exception as exc:  # noqa: BLE001 - nothing to raise to at that point
        warnings.warn(f"RolloutRecorder: closing the recording failed: {exc!r}", RuntimeWarning, stacklevel=1)

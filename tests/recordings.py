"""Reading a rerun recording back (the recorder's and the stretches' tests)."""

from pathlib import Path

import numpy as np
import pyarrow as pa
from rerun.chunk import RrdReader


def read(path: Path):
    """{entity: {column: values of the time-varying rows}}, the static entities, and the store counts."""
    reader = RrdReader(path)
    rows: dict[str, dict[str, list]] = {}
    static: set[str] = set()
    timelines: set[str] = set()
    for chunk in reader.stream().to_chunks():
        entity = chunk.entity_path.lstrip("/")
        if chunk.is_static:
            static.add(entity)
            continue
        timelines.update(chunk.timeline_names)
        batch = chunk.to_record_batch()
        cols = rows.setdefault(entity, {})
        for name in batch.schema.names:
            column = batch.column(name)
            if pa.types.is_duration(column.type):  # to_pylist() would make µs timedeltas
                column = column.cast(pa.int64())
            cols.setdefault(name, []).extend(column.to_pylist())
    for cols in rows.values():  # chunks may come in any order: sort rows by step
        order = np.argsort(cols["step"], kind="stable")
        for name in cols:
            cols[name] = [cols[name][k] for k in order]
    return rows, static, timelines, (len(reader.recordings()), len(reader.blueprints()))


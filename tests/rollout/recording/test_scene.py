"""The scene's line strips: built from numpy offsets with rerun's public line-strip type, they are the very Arrow
array rerun's own conversion makes."""

import numpy as np
import pyarrow as pa
import pytest
import rerun as rr
from rerun.components import LineStrip2D, LineStrip2DBatch

from regrasp.rollout.recording.scene import strips_array, strips_columns


@pytest.mark.parametrize("shape", [(5, 4, 2), (1, 3, 2), (7, 2, 2), (0, 5, 2), (0, 2, 2)])
def test_strips_are_rerun_own(shape):
    strips = np.random.default_rng(3).normal(size=shape) * 100.0
    array = strips_array(strips)
    assert array.equals(LineStrip2DBatch(strips.astype(np.float32)).as_arrow_array())
    assert array.type == rr.components.LineStrip2D.arrow_type()


def test_strip_columns_partition_the_strips_into_rows():
    strips = np.arange(24, dtype=float).reshape(4, 3, 2)
    (column, colour) = strips_columns(strips, [1, 0, 3], colours=[1, 2, 3, 4])
    assert column.as_arrow_array().value_lengths().to_pylist() == [1, 0, 3]
    assert colour.as_arrow_array().to_pylist() == [[1], [], [2, 3, 4]]


def test_strips_follow_a_rerun_whose_strip_type_is_another(monkeypatch):
    """A rerun whose line strips were no list of its points (a large list, say) converts them itself."""
    strips = np.random.default_rng(4).normal(size=(6, 3, 2))
    point = LineStrip2D.arrow_type().value_type
    monkeypatch.setattr(LineStrip2D, "arrow_type", classmethod(lambda cls: pa.large_list(point)))
    assert strips_array(strips).equals(LineStrip2DBatch(strips.astype(np.float32)).as_arrow_array())

"""A polygon's recording is what it was before curved objects were drawn: every logged value (each entity's
columns, time-varying and static, but the recording's start time and the row ids) equals the one stored in
``polygon_recording.json``, written by the recorder before the curve branches were added
(``python tests/rollout/recording/test_polygon_unchanged.py`` rewrites it: only when a polygon's drawing is meant to
change).

The recording: paper trajectory 2's two fingers (finger 1 slides up the left edge under Proposition 3, finger 2
holds the right edge), 20 steps through the hook with two envelopes per finger (slots 0 and 1 along edges 1 and 3,
edges 0 and 1), in blocks of 7 steps; then one supervised step (its row made from the step's values alone) and a
failure of the control law (the object's outline).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pyarrow as pa
import pytest
from rerun.chunk import RrdReader

from regrasp import Grasp, Hand, Plant, PlantContact, ReducedModel, load_scenario
from regrasp.core.events import Failure, FailureKind
from regrasp.dynamics.control import Gains
from regrasp.dynamics.laws import Proposition3Controller
from regrasp.plants.closed_loop import run_closed_loop
from regrasp.rollout.recording.recorder import RolloutRecorder
from regrasp.supervisor.types import ContactPhase

pytestmark = pytest.mark.filterwarnings("error::rerun.error_utils.RerunWarning")

ROOT = Path(__file__).resolve().parents[3]
FIXTURE = Path(__file__).with_name("polygon_recording.json")
MU = [0.05, 0.8]
X0 = np.array([0.0, 0.12, 0.0])
LO, HI, T_LEG, XI_HOLD = -0.007, 0.016, 1.5, 0.019


def reference(t):
    c, amp, w = 0.5 * (LO + HI), 0.5 * (HI - LO), np.pi / T_LEG
    xi, xi_d, xi_dd = c - amp * np.cos(w * t), amp * w * np.sin(w * t), amp * w * w * np.cos(w * t)
    return np.append(X0, xi), np.append(np.zeros(3), xi_d), np.append(np.zeros(3), xi_dd)


def record_polygon(path: Path) -> None:
    """The module docstring's recording, to ``path``."""
    sc = load_scenario(ROOT / "examples" / "scenarios" / "paper_trajectory_2.toml")
    hand = Hand([c.finger for c in sc.contacts], gravity_in_hand=sc.gravity_in_hand)
    model = ReducedModel(hand, Grasp(sc.polygon, [1, 3], ["sliding", "fixed"]), xi=[LO, XI_HOLD])
    S0, S0_dot, _ = reference(0.0)
    st = model.state(S0, S0_dot)
    plant = Plant(hand, sc.polygon, [PlantContact(1, "sliding", LO, 1.0), PlantContact(3, "fixed", XI_HOLD)],
                  friction=MU)
    plant.reset(st.q, st.q_dot, S0[:3], S0_dot[:3])
    controller = Proposition3Controller(model, Gains.critically_damped(40.0, 4), friction=MU)
    with RolloutRecorder(plant, rrd_path=path, envelope_edges=[[1, 0], [3, 1]], flush_every=7) as rec:
        run_closed_loop(plant, controller, reference, 0.02, on_step=rec.hook(plant, reference))
        s = plant.state
        rec.log_stretch_step(21, s.t + 1e-3, s.X, s.q, reference(s.t)[0], np.array([[1.0, 0.05], [1.2, -0.3]]),
                             np.array([[0.9, 0.1], [-1.1, 0.2]]), np.array([[0.95, 0.04], [1.1, -0.25]]),
                             [[(-0.02, -0.001), (0.002, 0.04)], [(0.0, 0.03)]],
                             [ContactPhase.SLIDING, ContactPhase.FIXED], np.array([LO + 1e-3, XI_HOLD]),
                             np.array([1e-4, -2e-4, 1e-3, 0.0]), np.array([0.0, 0.4]), np.array([0.01, 0.35]),
                             np.array([[-0.02, -0.001], [0.0, 0.03]]), np.array([LO + 2e-3, np.nan]),
                             np.array([np.nan, XI_HOLD]))
        rec.log_failure(Failure(s.t, FailureKind.CONTROL, "a singular grasp matrix", None))


def logged(path: Path) -> dict[str, dict[str, str]]:
    """Every logged value of a recording: {entity (static ones marked): {column: repr of its values}}, the rows of
    each entity in step order; not the recording's start time (``__properties``) nor the row ids."""
    out: dict[str, dict[str, list]] = {}
    for chunk in RrdReader(path).stream().to_chunks():
        entity = chunk.entity_path.lstrip("/")
        if entity == "__properties":
            continue
        key = f"{entity} (static)" if chunk.is_static else entity
        batch = chunk.to_record_batch()
        cols = out.setdefault(key, {})
        for name in batch.schema.names:
            if name.startswith("rerun.controls"):
                continue
            column = batch.column(name)
            if pa.types.is_duration(column.type):
                column = column.cast(pa.int64())
            cols.setdefault(name, []).extend(column.to_pylist())
    result = {}
    for key, cols in out.items():
        if "step" in cols:  # (chunks may come in any order)
            order = np.argsort(cols["step"], kind="stable")
            cols = {name: [values[k] for k in order] for name, values in cols.items()}
        result[key] = {name: repr(values) for name, values in sorted(cols.items())}
    return result


def test_a_polygons_recording_holds_the_values_it_held_before_curves(tmp_path):
    path = tmp_path / "polygon.rrd"
    record_polygon(path)
    now = logged(path)
    before = json.loads(FIXTURE.read_text())
    assert sorted(now) == sorted(before)
    for entity, cols in before.items():
        assert sorted(now[entity]) == sorted(cols), entity
        for name, values in cols.items():
            assert now[entity][name] == values, (entity, name)


if __name__ == "__main__":  # rewrite the fixture
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else FIXTURE
    rrd = out.with_suffix(".rrd")
    record_polygon(rrd)
    out.write_text(json.dumps(logged(rrd), indent=0, sort_keys=True) + "\n")
    rrd.unlink()

"""The rerun rollout recorder: complete, verifiable .rrd files, also when a rollout is interrupted.

The scenario is example 03's first leg (finger 1 slides up the left edge under Proposition 3 while
finger 2 holds the right edge), 0.05-0.15 s of it. Every file is checked with the rerun CLI
(``rerun rrd verify``) and read back with ``rerun.chunk.RrdReader``.
"""

import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import rerun as rr
from rerun.chunk import RrdReader

from factories import DANGER_START_THREE
from hang_guard import HANG_SECONDS
from recordings import read
from regrasp import Friction, Grasp, Hand, Plant, PlantContact, ReducedModel, RunSpec, load_scenario
from regrasp.core.events import Event, EventSource, Failure, FailureKind
from regrasp.core.exceptions import InvalidParameterError, RegraspError, UnknownEdgeError
from regrasp.core.intervals import DANGER_FRACTION, danger_zones
from regrasp.dynamics.control import Gains
from regrasp.dynamics.laws import Proposition3Controller
from regrasp.envelope.finger_envelope import FingerEnvelope
from regrasp.plants.closed_loop import run_closed_loop
from regrasp.rollout.recording.recorder import RolloutRecorder
from regrasp.rollout.recording.rows import BAND_LINES, PHASE_CODES, ZONE_LINES

pytestmark = pytest.mark.filterwarnings("error::rerun.error_utils.RerunWarning")

ROOT = Path(__file__).resolve().parents[3]
SC = load_scenario(ROOT / "examples" / "scenarios" / "paper_trajectory_2.toml")
MU = [0.05, 0.8]
XI_HOLD = 0.019
X0 = np.array([0.0, 0.12, 0.0])
LO, HI, T_LEG = -0.007, 0.016, 1.5  # example 03's slide range [m] and leg duration [s]

SCENE = ["scene/object", "scene/desired", "scene/fingers/finger1", "scene/fingers/finger2", "scene/joints",
         "scene/contacts/forces", "scene/contacts/forces_predicted", "scene/contacts/cones",
         "scene/envelope/safe", "scene/envelope/danger"]
PLOTS = ["plots/error/position", "plots/error/angle", "plots/xi/finger1", "plots/xi/finger2", "plots/xi/finger1/band",
         "plots/xi/finger2/band", "plots/force", "plots/cone_margin", "plots/mode", "plots/phase/finger1",
         "plots/phase/finger2"]
STATIC = ["model/object/outline", "model/object/edges", "model/setup"]


def reference(t):
    c, amp, w = 0.5 * (LO + HI), 0.5 * (HI - LO), np.pi / T_LEG
    xi, xi_d, xi_dd = c - amp * np.cos(w * t), amp * w * np.sin(w * t), amp * w * w * np.cos(w * t)
    return np.append(X0, xi), np.append(np.zeros(3), xi_d), np.append(np.zeros(3), xi_dd)


def setup(friction=MU):
    hand = Hand([c.finger for c in SC.contacts], gravity_in_hand=SC.gravity_in_hand)
    grasp = Grasp(SC.polygon, [1, 3], ["sliding", "fixed"])
    model = ReducedModel(hand, grasp, xi=[LO, XI_HOLD])
    S0, S0_dot, _ = reference(0.0)
    st = model.state(S0, S0_dot)
    plant = Plant(hand, SC.polygon, [PlantContact(1, "sliding", LO, 1.0), PlantContact(3, "fixed", XI_HOLD)],
                  friction=friction)
    plant.reset(st.q, st.q_dot, S0[:3], S0_dot[:3])
    return plant, Proposition3Controller(model, Gains.critically_damped(40.0, 4), friction=friction)


def rerun_cli() -> list[str]:
    exe = Path(sys.executable).with_name("rerun")
    if exe.exists():
        return [str(exe)]
    found = shutil.which("rerun")
    return [found] if found else [sys.executable, "-m", "rerun"]


def verify(path: Path) -> str:
    proc = subprocess.run([*rerun_cli(), "rrd", "verify", str(path)], capture_output=True, text=True,
                          timeout=HANG_SECONDS, check=False)
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, out
    assert "verified without error" in out, out
    return out



def test_recorded_rollout_verifies_and_reads_back(tmp_path):
    plant, controller = setup()
    path = tmp_path / "rollout.rrd"
    with RolloutRecorder(plant, rrd_path=path) as rec:
        log = run_closed_loop(plant, controller, reference, 0.15, on_step=rec.hook(plant, reference))
    n = len(log.times)
    assert n == 150 and not log.events and rec.closed
    assert rec.steps_logged == n + 1  # the initial state (step 0) and the state after each step
    assert 0.0 < rec.seconds_per_step < 0.05
    verify(path)

    rows, static, timelines, (n_rec, n_bp) = read(path)
    assert (n_rec, n_bp) == (1, 1)  # the recording and its blueprint
    assert {"time", "step"} <= timelines and "log_time" not in timelines
    assert set(SCENE + PLOTS) <= set(rows), sorted(rows)
    assert set(STATIC) <= static, sorted(static)
    for entity in SCENE + PLOTS:
        assert rows[entity]["step"] == list(range(n + 1)), entity
    assert rows["plots/error/position"]["time"] == [round(k * plant.dt * 1e9) for k in range(n + 1)]  # [ns]

    # the values are the rollout's: modes, ξ, forces and errors in the documented units
    last = {e: np.array(rows[e]["Scalars:scalars"][-1], dtype=float) for e in PLOTS}
    assert list(last["plots/mode"]) == [1.0, 0.0]  # finger 1 slides, finger 2 holds
    xi1 = last["plots/xi/finger1"]  # ξ, ξ desired, feasible lo, hi, danger lo, hi [mm]
    assert abs(xi1[0] - log.S[-1, 3] * 1e3) < 0.05 and abs(xi1[0] - xi1[1]) < 0.1
    assert xi1[2] <= xi1[4] < xi1[0] < xi1[5] <= xi1[3]
    assert np.isnan(last["plots/xi/finger2"][1])  # the holding finger has no desired ξ
    assert np.isnan(xi1[6]) and np.isnan(last["plots/phase/finger1"]).all()  # no schedule, no supervisor
    fn1, fn2, ft1, ft2 = last["plots/force"][:4]
    assert fn1 > 0 and fn2 > 0 and abs(abs(ft1) - MU[0] * fn1) < 1e-6  # Coulomb at the sliding contact
    assert np.abs(last["plots/error/position"]).max() < 0.5 and abs(last["plots/error/angle"][0]) < 0.5  # mm, deg
    assert len(last["plots/error/position"]) == 3 and len(last["plots/error/angle"]) == 1  # x, y, ξ [mm]; β [deg]
    # the band's fill lines: inside the safe part, then inside each danger zone (lo.. lo + f w, hi - f w.. hi)
    band = last["plots/xi/finger1/band"]
    assert len(band) == BAND_LINES + 2 * ZONE_LINES
    assert (xi1[4] < band[:BAND_LINES]).all() and (band[:BAND_LINES] < xi1[5]).all()
    zones = band[BAND_LINES:]
    assert ((xi1[2] < zones[:ZONE_LINES]) & (zones[:ZONE_LINES] < xi1[4])).all()
    assert ((xi1[5] < zones[ZONE_LINES:]) & (zones[ZONE_LINES:] < xi1[3])).all()
    assert len(rows["scene/object"]["LineStrips2D:strips"][-1][0]) == 5  # closed rectangle
    assert len(rows["scene/fingers/finger1"]["LineStrips2D:strips"][-1]) == 3  # two links and the chain
    safe = rows["scene/envelope/safe"]["LineStrips2D:strips"][-1]
    danger = rows["scene/envelope/danger"]["LineStrips2D:strips"][-1]
    assert len(safe) == 2 and len(danger) == 4  # one interval per contact edge, a danger zone at each end


def test_a_buffered_step_leaves_few_objects_for_the_garbage_collector(tmp_path):
    """A row waiting to be sent holds arrays (untracked by the collector), not lists: buffered lists once triggered a
    full collection (65-100 ms after a plan) inside a recorded rollout."""
    import gc

    plant, controller = setup()
    with RolloutRecorder(plant, rrd_path=tmp_path / "gc.rrd", flush_every=10**6, plant_forces=False) as rec:
        hook = rec.hook(plant, reference)
        run_closed_loop(plant, controller, reference, 0.01, on_step=hook)  # (warm)
        gc.collect()
        before = len(gc.get_objects())
        run_closed_loop(plant, controller, reference, 0.1, on_step=hook)  # 100 rows buffered
        gc.collect()
        kept = len(gc.get_objects()) - before
    assert rec.steps_logged > 100
    assert kept < 4 * 100, kept  # (a row and its series: 2; lists of lists: ~20)


def test_decimation_logs_every_nth_step(tmp_path):
    plant, controller = setup()
    path = tmp_path / "decimated.rrd"
    with RolloutRecorder(plant, rrd_path=path, decimation=10, plant_forces=False) as rec:
        run_closed_loop(plant, controller, reference, 0.05, on_step=rec.hook(plant, reference))
    verify(path)
    rows, *_ = read(path)
    assert rows["plots/error/position"]["step"] == [0, 10, 20, 30, 40, 50]
    assert np.isnan(rows["plots/force"]["Scalars:scalars"][-1][0])  # plant forces off: not plotted
    assert rec.steps_logged == 6


def test_interrupted_rollout_leaves_a_complete_file(tmp_path):
    plant, controller = setup()
    path = tmp_path / "interrupted.rrd"
    calls = []
    with pytest.raises(RuntimeError, match="operator pulled the plug"):
        with RolloutRecorder(plant, rrd_path=path, flush_every=1000) as rec:  # nothing sent before close()
            hook = rec.hook(plant, reference)

            def on_step(t, output):
                hook(t, output)
                calls.append(t)
                if len(calls) == 7:
                    raise RuntimeError("operator pulled the plug")

            run_closed_loop(plant, controller, reference, 0.1, on_step=on_step)
    assert rec.closed
    verify(path)
    rows, *_ = read(path)
    assert rows["plots/error/position"]["step"] == list(range(8))
    assert rows["scene/object"]["step"] == list(range(8))


def test_a_failure_inside_the_recorder_keeps_the_steps_before_it(tmp_path, monkeypatch):
    plant, controller = setup()
    path = tmp_path / "failed.rrd"
    at = FingerEnvelope.at
    with pytest.raises(ZeroDivisionError):
        with RolloutRecorder(plant, rrd_path=path, envelope_tolerance=0.0) as rec:
            hook = rec.hook(plant, reference)

            def failing(envelope, *args, **kwargs):  # fails half-way through step 4's row (after its forces)
                if rec.steps_logged == 4:
                    raise ZeroDivisionError("boom")
                return at(envelope, *args, **kwargs)

            monkeypatch.setattr(FingerEnvelope, "at", failing)  # (the recorder's envelopes, evaluated per row)
            run_closed_loop(plant, controller, reference, 0.01, on_step=hook)
    assert rec.closed and rec.steps_logged == 4
    verify(path)
    rows, *_ = read(path)
    for entity in SCENE + PLOTS:
        assert rows[entity]["step"] == [0, 1, 2, 3], entity


def test_log_step_with_plant_steps_and_close_is_idempotent(tmp_path):
    from regrasp.plants.closed_loop import measure_reduced_state

    plant, controller = setup()
    path = tmp_path / "manual.rrd"
    rec = RolloutRecorder(plant, rrd_path=path, recording_name="manual loop", envelope_edges=[[0, 1], None])
    forces = []
    for k in range(5):
        S, S_dot = measure_reduced_state(plant, controller.model)
        out = controller(S, S_dot, *reference(plant.state.t))
        step = plant.step(out.tau)
        forces.append(step.forces_surface.copy())
        if k == 2:  # a plant event is logged as text at its step
            plant.events.append(Event(plant.state.t, "finger2", "slip", "made up for the test", EventSource.PLANT))
        assert rec.log_step(plant, out, step=10 + k, desired_pose=reference(plant.state.t)[0][:3], plant_step=step)
    rec.close()
    rec.close()
    with pytest.raises(InvalidParameterError, match="closed"):
        rec.log_step(plant, None)
    verify(path)
    rows, *_ = read(path)
    assert rows["plots/force"]["step"] == list(range(10, 15))
    assert rows["events"]["step"] == [12] and "finger2: slip" in rows["events"]["TextLog:text"][0][0]
    logged = np.array(rows["plots/force"]["Scalars:scalars"])  # f_n..., f_t..., predicted...
    assert np.allclose(logged[:, :2], [f[:, 0] for f in forces])
    assert np.allclose(logged[:, 2:4], [f[:, 1] for f in forces])
    # finger 1's envelopes on edges 0 (empty: condition I) and 1 (the whole edge); none for finger 2
    assert len(rows["scene/envelope/safe"]["LineStrips2D:strips"][-1]) == 1
    err = np.array(rows["plots/error/position"]["Scalars:scalars"])  # x, y, ξ [mm]
    beta = np.array(rows["plots/error/angle"]["Scalars:scalars"])  # β [deg]
    assert np.isnan(err[:, 2]).all() and np.isfinite(err[:, :2]).all() and np.isfinite(beta).all()  # no ξ error


def test_recorders_are_independent_of_each_other_and_of_the_global_recording(tmp_path):
    plant, controller = setup()
    a, b = tmp_path / "a.rrd", tmp_path / "b.rrd"
    with RolloutRecorder(plant, rrd_path=a) as ra, RolloutRecorder(plant, rrd_path=b, decimation=5) as rb:
        hooks = [ra.hook(plant, reference), rb.hook(plant)]
        run_closed_loop(plant, controller, reference, 0.02, on_step=lambda t, out: [h(t, out) for h in hooks])
    assert rr.get_global_data_recording() is None and rr.get_thread_local_data_recording() is None
    for path in (a, b):
        verify(path)
    assert read(a)[0]["plots/mode"]["step"] == list(range(21))
    rows_b = read(b)[0]
    assert rows_b["plots/mode"]["step"] == [0, 5, 10, 15, 20]
    assert rows_b["scene/desired"]["LineStrips2D:strips"][-1] == []  # no reference given: no ghost


def test_bad_input_raises_typed_errors(tmp_path):
    plant, _ = setup()
    with pytest.raises(InvalidParameterError, match="sink") as info:
        RolloutRecorder(plant)
    assert isinstance(info.value, RegraspError) and info.value.name == "rrd_path"
    path = tmp_path / "x.rrd"
    bad = [dict(danger_fraction=0.5), dict(danger_fraction=-0.1), dict(decimation=0), dict(decimation=1.5),
           dict(envelope_edges=[1]), dict(sliding=[2]), dict(force_scale=0.0), dict(envelope_geometry="mesh"),
           dict(flush_every=0), dict(envelope_tolerance=-1.0), dict(connect="localhost:9876"), dict(connect=9876),
           dict(connect="rerun+http://127.0.0.1:9876/proxy", spawn=True)]
    for kwargs in bad:
        with pytest.raises(InvalidParameterError):
            RolloutRecorder(plant, rrd_path=path, **kwargs)
    with pytest.raises(UnknownEdgeError):
        RolloutRecorder(plant, rrd_path=path, envelope_edges=[7, None])
    with pytest.raises(InvalidParameterError, match="existing directory"):
        RolloutRecorder(plant, rrd_path=tmp_path / "missing" / "x.rrd")
    with pytest.raises(InvalidParameterError):
        RolloutRecorder("not a plant", rrd_path=path)
    assert not path.exists()  # rejected before any stream or file was made
    with RolloutRecorder(plant, rrd_path=path) as rec:
        with pytest.raises(InvalidParameterError, match="step"):
            rec.log_step(plant, None, step=-1)
        with pytest.raises(InvalidParameterError, match="desired_pose"):
            rec.log_step(plant, None, desired_pose=[0.0, 0.1])
    verify(path)


@pytest.mark.slow
def test_a_buffered_rollout_recording_holds_each_steps_values_at_its_time(tmp_path):
    """Blocks of steps sent with ``send_columns`` read back as the rollout's own numbers, step by
    step, and the same whether the steps go out one at a time or in blocks of any size."""
    from regrasp.rollout.build import build_rollout

    sc = load_scenario(ROOT / "examples" / "scenarios" / "paper_trajectory_2_three_fingers.toml")
    recorded = {}
    schedule = None  # planned once, for the three runs
    for flush_every in (1, 7, 500):  # one step per send (per-step logging), odd blocks, one block
        rollout = build_rollout(sc, RunSpec(duration=0.03), schedule=schedule)
        schedule = rollout.schedule
        path = tmp_path / f"flush_{flush_every}.rrd"
        with RolloutRecorder(rollout.plant, rrd_path=path, flush_every=flush_every) as rec:
            result = rollout.run(recorder=rec)
        verify(path)
        recorded[flush_every] = (read(path)[0], result)
    rows, result = recorded[1]
    n = result.steps
    assert n == 30 and result.success
    for flush_every in (7, 500):
        other, other_result = recorded[flush_every]
        assert np.array_equal(other_result.forces_surface, result.forces_surface)
        assert set(other) == set(rows)
        for entity, cols in rows.items():
            for name, values in cols.items():
                if name.startswith("rerun.controls"):  # row ids differ between recordings
                    continue
                assert repr(other[entity][name]) == repr(values), (flush_every, entity, name)

    # step k + 1 is the state after the rollout's k-th step, at the plant's time then
    assert rows["plots/force"]["step"] == list(range(n + 1))
    assert rows["plots/force"]["time"][1:n] == [round(t * 1e9) for t in result.times[1:]]
    force = np.array(rows["plots/force"]["Scalars:scalars"], dtype=float)  # f_n..., f_t..., predicted...
    m = len(result.names)
    assert np.isnan(force[0, :2 * m]).all()  # the initial state has no plant step
    assert np.array_equal(force[1:, :m], result.forces_surface[:, :, 0])  # the plant's, as they are
    assert np.array_equal(force[1:, m:2 * m], result.forces_surface[:, :, 1])
    mode = np.array(rows["plots/mode"]["Scalars:scalars"], dtype=float)
    assert set(np.unique(mode)) <= {0.0, 1.0} and (mode[:, 1:] == 0.0).all()  # finger 1 may start priming
    error = np.array(rows["plots/error/position"]["Scalars:scalars"], dtype=float)  # X_d - X [mm, mm]
    angle = np.array(rows["plots/error/angle"]["Scalars:scalars"], dtype=float)  # [deg]
    assert np.allclose(error[1:n, :2], result.object_error[1:, :2] * 1e3, rtol=0.0, atol=1e-9)
    assert np.allclose(angle[1:n, 0], np.degrees(result.object_error[1:, 2]), rtol=0.0, atol=1e-9)
    for i, key in enumerate(result.names):
        xi = np.array(rows[f"plots/xi/{key}"]["Scalars:scalars"], dtype=float)  # ξ, desired, bounds... [mm]
        assert np.allclose(xi[1:n, 0], result.xi[1:, i] * 1e3, rtol=0.0, atol=1e-4)  # held vs tip: drift
        assert np.isnan(xi[:, 1]).all()  # the recorder's error series are the object's only
        assert (xi[:, 2] <= xi[:, 0]).all() and (xi[:, 0] <= xi[:, 3]).all()  # inside its feasible interval


def test_cones_and_margins_use_each_contacts_coefficient_of_its_mode(tmp_path):
    """μ_s ≠ μ_k: the sliding finger's cone is drawn at ±atan μ_k and its plant cone margin is
    μ_k f_n - |f_t| (0: it slides on its kinetic edge), the holding finger's at ±atan μ_s with
    μ_s f_n - |f_t|; the set-up table shows each tip's friction as ``str(Friction)``."""
    friction = [Friction(0.3, 0.05), Friction(0.8, 0.6)]
    plant, controller = setup(friction)
    path = tmp_path / "cones.rrd"
    with RolloutRecorder(plant, rrd_path=path) as rec:
        log = run_closed_loop(plant, controller, reference, 0.02, on_step=rec.hook(plant, reference))
    assert not log.events
    verify(path)
    rows, *_ = read(path)
    for strips in rows["scene/contacts/cones"]["LineStrips2D:strips"][1:]:
        for (a, tip, b), mu in zip(strips, (0.05, 0.8)):  # (ray, tip, ray) per contact [mm]
            u, v = np.subtract(a, tip), np.subtract(b, tip)
            opening = np.arccos(u @ v / (np.linalg.norm(u) * np.linalg.norm(v)))
            assert opening == pytest.approx(2 * np.arctan(mu), abs=1e-5)  # (float32 points)
    forces = np.array(rows["plots/force"]["Scalars:scalars"][1:], dtype=float)  # f_n1, f_n2, f_t1, f_t2, ...
    margins = np.array(rows["plots/cone_margin"]["Scalars:scalars"][1:], dtype=float)[:, :2]
    np.testing.assert_allclose(margins[:, 0], 0.0, atol=1e-9)
    np.testing.assert_allclose(margins[:, 1], 0.8 * forces[:, 1] - np.abs(forces[:, 3]), rtol=1e-12)
    text = ""
    for chunk in RrdReader(path).stream().to_chunks():
        if chunk.is_static and chunk.entity_path.lstrip("/") == "model/setup":
            batch = chunk.to_record_batch()
            text = str(batch.column("TextDocument:text").to_pylist())
    assert "| sliding | mu_s = 0.3, mu_k = 0.05 |" in text and "| fixed | mu_s = 0.8, mu_k = 0.6 |" in text


# ------------------------------------------------------------------------- supervised rollouts
THREE = load_scenario(ROOT / "examples" / "scenarios" / "paper_trajectory_2_three_fingers.toml")
LOGGING: list = []  # the record being logged by record_rollout's recorder, while it is


def record_rollout(path: Path, *, policy="paper", duration=0.3, **kwargs):
    """A rollout of the three-finger scenario recorded to ``path``; returns it, its result and its records."""
    from regrasp.rollout.build import build_rollout

    start = DANGER_START_THREE if policy == "paper" else None  # (finger 1 slides at once)
    rollout = build_rollout(THREE, RunSpec(duration=duration, xi0=start), policy=policy)
    records = []
    with RolloutRecorder(rollout.plant, rrd_path=path, **kwargs) as rec:
        log_record = rec.log_record

        def keep(record, desired_pose):
            records.append(record)
            LOGGING.append(record)
            try:
                return log_record(record, desired_pose)
            finally:
                LOGGING.pop()

        rec.log_record = keep
        result = rollout.run(recorder=rec)
    verify(path)
    return rollout, result, records, rec


def per_step_entities(names):
    keys = list(names)
    return (["scene/object", "scene/desired", "scene/joints", "scene/contacts/forces",
             "scene/contacts/forces_predicted", "scene/contacts/cones", "scene/envelope/safe", "scene/envelope/danger",
             "plots/error/position", "plots/error/angle", "plots/force", "plots/cone_margin", "plots/mode"]
            + [f"scene/fingers/{k}" for k in keys] + [f"plots/xi/{k}" for k in keys]
            + [f"plots/xi/{k}/band" for k in keys]
            + [f"plots/phase/{k}" for k in keys])


def nan_equal(a, b, atol=1e-9):
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return a.shape == b.shape and bool((np.isnan(a) == np.isnan(b)).all()) and np.allclose(
        a[~np.isnan(a)], b[~np.isnan(b)], rtol=0.0, atol=atol)


def test_a_supervised_rollout_is_logged_from_its_records(tmp_path, monkeypatch):
    """Each step's row holds its record's values: the state after the step, the plant's forces and
    margins, the supervisor's phases, band, danger zones and ξ_d; the decisions and the plant's
    events are in ``events``; no envelope is evaluated by the recorder after the initial state."""
    path = tmp_path / "supervised.rrd"
    calls, evaluated = [], []
    at = FingerEnvelope.at

    def counted(envelope, *args, **kwargs):  # the record path evaluates no envelope of its own
        (calls if LOGGING else evaluated).append(args)
        return at(envelope, *args, **kwargs)

    monkeypatch.setattr(FingerEnvelope, "at", counted)
    rollout, result, records, rec = record_rollout(path)
    n = result.steps
    assert n == 300 and result.success and len(records) == n and not calls
    assert evaluated  # (the initial state's row, measured, and the supervisor's)
    rows, static, _, _ = read(path)
    names = rollout.names
    for entity in per_step_entities(names):
        assert rows[entity]["step"] == list(range(n + 1)), entity
    assert rows["plots/mode"]["time"][1:] == [round(r.plant.state.t * 1e9) for r in records]
    assert "scene/failure" not in rows

    # the per-finger panels (Figure 4.3): ξ, ξ_d of the law, band, danger zones, the schedule's ξ_d
    f = rec.danger_fraction
    assert f == DANGER_FRACTION  # (the one definition, as the PNG figures')
    for i, key in enumerate(names):
        xi = np.array(rows[f"plots/xi/{key}"]["Scalars:scalars"], dtype=float)[1:] / 1e3  # [m]
        sup = [r.supervision for r in records]
        bounds = np.array([s.bounds[i] for s in sup])
        assert nan_equal(xi[:, 0], [r.plant.xi[i] for r in records])
        assert nan_equal(xi[:, 1], [s.reference_xi[i] for s in sup])
        assert nan_equal(xi[:, 2:4], bounds)
        (_, lo_zone), (hi_zone, _) = danger_zones(bounds[:, 0], bounds[:, 1], DANGER_FRACTION)
        assert nan_equal(xi[:, 4], lo_zone) and nan_equal(xi[:, 5], hi_zone)
        assert np.isnan(xi[:, 6]).all()  # the paper's policy has no schedule
        phase = np.array(rows[f"plots/phase/{key}"]["Scalars:scalars"], dtype=float)[:, 0]
        assert np.isnan(phase[0])  # the initial state: no supervisor yet
        expected = [PHASE_CODES[s.phases[i]] for s in sup]
        assert list(phase[1:]) == expected  # so they change where the supervisor's phases change
    finger1 = np.array(rows["plots/phase/finger1"]["Scalars:scalars"], dtype=float)[1:, 0]
    assert {0.0, 1.0, 2.0, 3.0} <= set(finger1)  # finger 1 primes, slides, settles and holds again
    # priming from step 0 until the contact is sensed moving the slide's way faster than start_speed
    k = int(np.argmax(finger1 == 2.0))
    assert k >= 1 and (finger1[:k] == 1.0).all()
    start_speed = rollout.supervisor.settings.executor.start_speed
    direction = np.sign(records[int(np.argmax(finger1 == 3.0))].plant.xi[0] - records[0].plant.xi[0])
    speed = np.array([r.plant.xi_dot[0] for r in records[:k]]) * direction  # [m/s] after steps 0..k-1
    assert speed[-1] > start_speed and (speed[:-1] <= start_speed).all()

    # forces, margins and envelopes are the record's
    m = len(names)
    force = np.array(rows["plots/force"]["Scalars:scalars"], dtype=float)[1:]
    assert np.array_equal(force[:, :m], [r.plant.forces_surface[:, 0] for r in records])
    assert np.array_equal(force[:, 2 * m:3 * m], [r.command.control.contact_forces_surface[:, 0] for r in records])
    margin = np.array(rows["plots/cone_margin"]["Scalars:scalars"], dtype=float)[1:]
    assert np.array_equal(margin[:, :m], [r.cone_margins for r in records])
    safe = rows["scene/envelope/safe"]["LineStrips2D:strips"][1:]
    assert [len(s) for s in safe] == [sum(len(e.feasible) for e in r.supervision.envelopes) for r in records]

    # the events: every record's, with its source and level; decisions at the step they were taken at
    texts = [t[0] for t in rows["events"]["TextLog:text"]]
    levels = [v[0] for v in rows["events"]["TextLog:level"]]
    assert len(texts) == sum(len(r.events) for r in records)
    prime = texts.index(next(t for t in texts if "supervisor finger1: prime" in t))
    slide = texts.index(next(t for t in texts if "supervisor finger1: slide" in t))
    slip = texts.index(next(t for t in texts if "plant finger1: slip" in t))
    assert rows["events"]["step"][prime] == 0 and rows["events"]["step"][slide] == k  # where the phases change
    assert rows["events"]["step"][slip] == 1 and levels[slip] == "WARN" and levels[prime] == levels[slide] == "INFO"
    assert any("supervisor finger1: settled" in t for t in texts)
    assert any("supervisor finger2: prime" in t for t in texts)

    # each finger has its own ξ view in the blueprint, the phases one
    origins = blueprint_origins(path)
    assert {f"plots/xi/{k}" for k in names} | {"plots/phase", "events", "scene"} <= origins
    assert "plots/xi" not in origins


def blueprint_origins(path: Path) -> set[str]:
    reader = RrdReader(path)
    origins = set()
    for chunk in reader.stream(store=reader.blueprints()[0]).to_chunks():
        batch = chunk.to_record_batch()
        if "ViewBlueprint:space_origin" in batch.schema.names:
            origins.update(v[0] for v in batch.column("ViewBlueprint:space_origin").to_pylist())
    return origins


def blueprint_views(path: Path) -> tuple[dict[str, tuple[str, str]], list[bool]]:
    """Each view's entity (its id): (class, name), and every PlotLegend's visibility, from the stored blueprint."""
    reader = RrdReader(path)
    views: dict[str, dict] = {}
    legends = []
    for chunk in reader.stream(store=reader.blueprints()[0]).to_chunks():
        batch = chunk.to_record_batch()
        for column in ("ViewBlueprint:class_identifier", "ViewBlueprint:display_name"):
            if column in batch.schema.names:
                views.setdefault(chunk.entity_path, {})[column] = batch.column(column).to_pylist()[0][0]
        if "PlotLegend:visible" in batch.schema.names:
            legends += [v[0] for v in batch.column("PlotLegend:visible").to_pylist()]
    named = {k: (v["ViewBlueprint:class_identifier"], v["ViewBlueprint:display_name"]) for k, v in views.items()}
    return named, legends


def test_the_plots_have_one_unit_each_no_legend_and_a_file_one_chunk_per_entity(tmp_path):
    path = tmp_path / "layout.rrd"
    rollout, result, _, _ = record_rollout(path, duration=0.1, decimation=10)
    views, legends = blueprint_views(path)
    plots = [name for kind, name in views.values() if kind == "TimeSeries"]
    assert len(plots) == len(rollout.names) + 6 and len(legends) == len(plots) and not any(legends)
    for name in plots:  # one unit per view (codes: none)
        assert sum(unit in name for unit in ("[mm]", "[deg]", "[N]")) <= 1, name
    assert "tracking error x, y, ξ [mm]" in plots and "tracking error β [deg]" in plots
    # fewer, larger chunks: a file alone gets each entity's rows in one chunk (static styling apart)
    reader = RrdReader(path)
    per_entity: dict[str, int] = {}
    for chunk in reader.stream().to_chunks():
        if not chunk.is_static and chunk.entity_path.startswith(("/plots", "/scene")):
            per_entity[chunk.entity_path] = per_entity.get(chunk.entity_path, 0) + 1
    assert len(per_entity) >= 20 and set(per_entity.values()) == {1}, per_entity


def test_a_decimated_supervised_rollout_has_one_row_per_k_steps_and_every_event(tmp_path):
    path = tmp_path / "decimated.rrd"
    rollout, result, records, rec = record_rollout(path, duration=0.1, decimation=10)
    rows, *_ = read(path)
    for entity in per_step_entities(rollout.names):
        assert rows[entity]["step"] == list(range(0, result.steps + 1, 10)), entity
    assert rec.steps_logged == result.steps // 10 + 1
    assert len(rows["events"]["step"]) == sum(len(r.events) for r in records) > 0  # decimated away or not
    phase = np.array(rows["plots/phase/finger1"]["Scalars:scalars"], dtype=float)[1:, 0]
    assert list(phase) == [PHASE_CODES[records[k - 1].supervision.phases[0]] for k in range(10, result.steps + 1, 10)]


def test_a_schedules_xi_d_is_plotted(tmp_path):
    """The schedule's ξ_d (``planned_xi``) is the panel's seventh series (records made up from a real run's)."""
    from dataclasses import replace

    _, _, records, _ = record_rollout(tmp_path / "source.rrd", duration=0.005)
    from regrasp.rollout.build import build_rollout

    rollout = build_rollout(THREE, RunSpec(duration=0.005), policy="paper")
    path = tmp_path / "planned.rrd"
    planned = [np.array([-0.005 - 0.001 * k, np.nan, 0.002 * k]) for k in range(len(records))]
    with RolloutRecorder(rollout.plant, rrd_path=path) as rec:
        rec.log_initial(rollout.plant, rollout.supervisor.trajectory.pose(0.0))
        for record, xi_d in zip(records, planned):
            sup = replace(record.supervision, planned_xi=xi_d)
            record = replace(record, command=replace(record.command, supervision=sup))
            assert rec.log_record(record, record.command.desired.pose)
    verify(path)
    rows, *_ = read(path)
    for i, key in enumerate(rollout.names):
        logged = np.array(rows[f"plots/xi/{key}"]["Scalars:scalars"], dtype=float)[1:, 6] / 1e3
        assert nan_equal(logged, [p[i] for p in planned])


def test_a_collision_is_marked_on_the_colliding_link(tmp_path):
    """Without regrasps, finger 1's distal link hits the object (~1.29 s): the failure's ERROR
    line (with the reason) and the link's outline in red, labelled short (kind, finger, time: it stays in the
    scene), at the failure's time."""
    path = tmp_path / "collision.rrd"
    rollout, result, _, _ = record_rollout(path, policy="none", duration=1.5, decimation=50)
    failure = result.failure
    assert failure is not None and failure.kind is FailureKind.COLLISION and failure.contact == "finger1"
    link = next(e for e in reversed(rollout.plant.events) if e.kind == "collision").values["link"]
    assert link == 1  # the distal link
    rows, *_ = read(path)
    marks = rows["scene/failure"]
    assert marks["time"] == [round(failure.time * 1e9)] and marks["step"] == [result.steps]
    label = marks["LineStrips2D:labels"][0][0]
    assert label == f"collision (finger1) at t = {failure.time:.3f} s" and len(label) < 40
    (outline,) = marks["LineStrips2D:strips"][0]  # one link, one closed outline [mm, y flipped]
    pts = np.array(outline) * [1e-3, -1e-3]
    finger = rollout.plant.hand.fingers[0]
    _, elbow, tip = finger.joint_positions_in_hand(rollout.plant.state.q[:2])
    u = (tip - elbow) / np.linalg.norm(tip - elbow)
    along = (pts - elbow) @ u
    across = np.abs((pts - elbow) @ [-u[1], u[0]])
    assert along.min() > -0.01 and along.max() < np.linalg.norm(tip - elbow) + 0.01 and across.max() < 0.01
    error = [t[0] for t, lv in zip(rows["events"]["TextLog:text"], rows["events"]["TextLog:level"]) if lv == ["ERROR"]]
    assert error == [f"FAILURE (collision): {failure.reason}"]
    assert rows["plots/mode"]["step"][-1] == result.steps // 50 * 50


def test_a_contact_failure_is_a_circle_at_its_tip(tmp_path):
    from regrasp.rollout.build import build_rollout

    rollout = build_rollout(THREE, RunSpec(duration=0.005), policy="paper")
    path = tmp_path / "separation.rrd"
    with RolloutRecorder(rollout.plant, rrd_path=path) as rec:
        result = rollout.run(recorder=rec)
        t = rollout.plant.state.t
        rec.log_failure(Failure(t, FailureKind.SEPARATION, "separation of finger2: made up", "finger2"))
        rec.log_failure(Failure(t, FailureKind.INTERRUPTED, "interrupted (Ctrl-C)"))  # text only
    verify(path)
    rows, *_ = read(path)
    marks = rows["scene/failure"]
    assert marks["step"] == [result.steps] and marks["time"] == [round(t * 1e9)]
    (circle,) = marks["LineStrips2D:strips"][0]
    tip = rollout.plant.hand.fingers[1].joint_positions_in_hand(rollout.plant.state.q[2:4])[2]
    radius = np.linalg.norm(np.array(circle) * [1e-3, -1e-3] - tip, axis=1)
    assert np.allclose(radius, 0.004, atol=1e-6)
    errors = [t[0] for t, lv in zip(rows["events"]["TextLog:text"], rows["events"]["TextLog:level"]) if lv == ["ERROR"]]
    assert errors == ["FAILURE (separation): separation of finger2: made up",
                      "FAILURE (interrupted): interrupted (Ctrl-C)"]


def test_connect_streams_to_a_running_server(tmp_path):
    import socket

    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    server = rr.RecordingStream("regrasp_test_server", make_default=False, make_thread_default=False)
    url = server.serve_grpc(grpc_port=port)
    plant, controller = setup()
    path = tmp_path / "connected.rrd"
    with RolloutRecorder(plant, rrd_path=path, connect=url) as rec:  # the viewer and the file
        run_closed_loop(plant, controller, reference, 0.01, on_step=rec.hook(plant, reference))
    assert rec.connect == url
    verify(path)
    assert read(path)[0]["plots/mode"]["step"] == list(range(11))
    plant, controller = setup()
    with RolloutRecorder(plant, connect=url) as rec:  # the viewer only
        run_closed_loop(plant, controller, reference, 0.01, on_step=rec.hook(plant, reference))
    assert rec.steps_logged == 11 and rec.rrd_path is None


def test_the_recorders_module_constants_are_kept():
    from regrasp.rollout.recording import events, recorder, rows

    assert recorder.MODE_CODES is rows.MODE_CODES and recorder.PHASE_CODES is rows.PHASE_CODES
    assert recorder.WARN_KINDS is events.WARN_KINDS
    assert {"MODE_CODES", "PHASE_CODES", "WARN_KINDS", "RolloutRecorder"} <= set(recorder.__all__)

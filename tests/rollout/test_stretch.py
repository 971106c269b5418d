"""Compiled stretches (regrasp.rollout.stretch, regrasp.kernels.stretch): a rollout with them takes the same steps as
one without, and they serve most steps."""

from __future__ import annotations

import numpy as np
import pytest

from regrasp import RunSpec, build_rollout, load_scenario

pytestmark = pytest.mark.slow  # (rollouts, subprocesses: `pytest -m "not slow"` leaves them out)

THREE = "examples/scenarios/paper_trajectory_2_three_fingers.toml"
ROWS = ("times", "xi", "bounds", "planned_xi", "object_error", "poses", "joint_positions", "forces_surface")


@pytest.fixture(scope="module")
def scenario():
    return load_scenario(THREE)


@pytest.fixture(scope="module")
def both_ways(scenario):
    """1.8 s of the three-finger rollout (two rounds of slides: primes, slips, arrivals, settling) on the
    reference path and with stretches, from the same schedule."""
    first = build_rollout(scenario, RunSpec(duration=1.8))
    reference = first.run(compiled_stretches=False)
    fast = build_rollout(scenario, RunSpec(duration=1.8), schedule=first.schedule)
    return reference, fast.run(), fast


def _events(result):
    return [(e.time, e.contact, e.kind, e.source) for e in result.events]


def test_stretches_take_the_same_steps(both_ways):
    reference, fast, _ = both_ways
    assert reference.success and fast.success and fast.steps == reference.steps == 1800
    for name in ROWS:
        np.testing.assert_allclose(getattr(fast, name), getattr(reference, name), rtol=0, atol=1e-12, err_msg=name)
    assert np.array_equal(fast.phases, reference.phases)
    assert _events(fast) == _events(reference)
    assert len(reference.events) >= 15  # (the slides happened: the comparison covers them)
    assert fast.min_cone_margin == pytest.approx(reference.min_cone_margin, abs=1e-12)
    assert fast.min_envelope_margin == pytest.approx(reference.min_envelope_margin, abs=1e-12)
    assert fast.regrasps == reference.regrasps


def test_stretches_serve_most_steps(both_ways):
    _, fast, rollout = both_ways
    stretches = rollout.stretches
    assert stretches.steps >= 0.8 * fast.steps, stretches.steps  # (decisions every 10 ms, events: the rest)
    assert stretches.calls < stretches.steps / 4


def test_stretch_rows_time_their_steps(both_ways):
    _, fast, _ = both_ways
    assert np.all(fast.supervisor_seconds >= 0.0) and np.all(fast.control_seconds > 0.0)
    assert np.all(np.isfinite(fast.plant_seconds))


def test_a_recording_is_the_same_with_stretches(scenario, tmp_path):
    """Every 10th step logged from a stretch (RolloutRecorder.log_stretch_step) reads back as the reference path
    logs it from the step's record: the same entities, steps and values (1.8 s: slides included)."""
    from recordings import read
    from regrasp import RolloutRecorder

    first = build_rollout(scenario, RunSpec(duration=1.8))
    recordings = []
    for compiled in (False, True):
        rollout = build_rollout(scenario, RunSpec(duration=1.8), schedule=first.schedule)
        path = tmp_path / f"{compiled}.rrd"
        with RolloutRecorder(rollout.plant, rrd_path=path, decimation=10) as recorder:
            rollout.run(recorder=recorder, compiled_stretches=compiled)
        assert recorder.steps_logged == 181  # (the initial state and every 10th step)
        recordings.append(read(path))
    assert rollout.stretches.steps > 1500
    (reference, static, timelines, counts), (fast, static2, timelines2, counts2) = recordings
    assert (set(fast), static2, timelines2, counts2) == (set(reference), static, timelines, counts)
    compared = 0
    for entity, columns in reference.items():
        for name, values in columns.items():
            if name.endswith("RowId"):  # (a row's id is unique to its recording)
                continue
            other = fast[entity][name]
            assert len(other) == len(values), (entity, name)
            for a, b in zip(values, other):
                if isinstance(a, list) and a and isinstance(a[0], float):
                    np.testing.assert_allclose(np.array(b, float), np.array(a, float), rtol=0, atol=1e-9,
                                               err_msg=f"{entity} {name}")
                else:
                    assert a == b or (a != a and b != b), (entity, name, a, b)
            compared += 1
    assert compared > 40


def test_a_noisy_rollout_is_the_same_with_stretches(scenario):
    """With sensing noise, a slip sensor with a threshold and a delay, an actuation delay and torque noise, a
    stretch draws the run's noise from its generator in the same order and keeps the same deques: the same steps
    to 1e-12, the same events, and the generator where the reference path leaves it."""
    from regrasp import ActuatorNoise, SensorNoise

    first = build_rollout(scenario, RunSpec(duration=1.8))
    noisy = RunSpec(duration=1.8, sensor_noise=SensorNoise(position=1e-4, angle=1e-3, velocity=1e-3, xi=2e-4,
                                                           force=0.01, slip_threshold=0.002, slip_delay=1),
                    actuator_noise=ActuatorNoise(delay=1, torque=1e-4), seed=5)
    runs = []
    for compiled in (False, True):
        rollout = build_rollout(scenario, noisy, schedule=first.schedule)
        runs.append((rollout.run(compiled_stretches=compiled), rollout))
    (reference, ref_rollout), (fast, rollout) = runs
    assert reference.success and fast.steps == reference.steps == 1800
    for name in ROWS:
        np.testing.assert_allclose(getattr(fast, name), getattr(reference, name), rtol=0, atol=1e-12, err_msg=name)
    assert _events(fast) == _events(reference) and len(reference.events) >= 15
    # (fewer steps in stretches than without noise: a noisy held ξ, filtered, moves past hold_resolution and the
    # law is rebuilt on the reference path, and so does a friction estimate that rounds anew)
    assert rollout.stretches.steps >= 0.5 * fast.steps
    a, b = ref_rollout.disturbance, rollout.disturbance
    assert a.rng.bit_generator.state == b.rng.bit_generator.state
    for x, y in zip(a.stretch_deques(3), b.stretch_deques(3)):  # (the slip readings and commands in flight)
        assert np.array_equal(x, y)


def test_a_failure_is_the_same_with_stretches(scenario):
    """With no regrasp the fixed grasp fails (a finger's link reaches the object at 1.291 s: coal, in a step a
    stretch hands over): with stretches the rollout fails at the same step, for the same reason, as without."""
    runs = []
    for compiled in (False, True):
        rollout = build_rollout(scenario, policy="none")
        runs.append((rollout.run(compiled_stretches=compiled), rollout))
    (reference, _), (fast, rollout) = runs
    assert not reference.success and reference.failure.kind.value == "collision"
    assert fast.failure == reference.failure and fast.steps == reference.steps
    np.testing.assert_allclose(fast.poses, reference.poses, rtol=0, atol=1e-12)
    assert rollout.stretches.steps > 0.8 * fast.steps


def test_warm_up_compiles_the_signature_the_library_passes(both_ways):
    """warm_up() loads the stretch kernel with the library's argument types, so a rollout's first stretch does not
    compile (a second signature would mean it did)."""
    from regrasp.kernels import stretch_into, warm_up

    warm_up()
    assert len(stretch_into.signatures) == 1


def test_simulate_refuses_stretches_built_for_another_disturbance(scenario):
    from regrasp.core.exceptions import InvalidParameterError
    from regrasp.plants.disturbance import Disturbance
    from regrasp.plants.simulation import simulate

    rollout = build_rollout(scenario, RunSpec(duration=0.01))
    with pytest.raises(InvalidParameterError, match="stretches"):
        simulate(rollout.plant, None, 1, stretches=object(), disturbance=Disturbance())


def test_every_participant_follows_the_stretch_protocol(scenario):
    """The executor, the monitor, the scheduled policy, the plant's kernel and a disturbance each give a stretch its
    view and take its state back (regrasp.rollout.stretch.StretchParticipant)."""
    from regrasp import ActuatorNoise
    from regrasp.rollout.stretch import StretchParticipant

    rollout = build_rollout(scenario, RunSpec(duration=0.01, actuator_noise=ActuatorNoise(delay=1), seed=1))
    sup = rollout.supervisor
    for participant in (sup.executor, sup.monitor, sup.policy, rollout.plant.kernel, rollout.disturbance):
        assert isinstance(participant, StretchParticipant), type(participant).__name__
    assert not isinstance(sup, StretchParticipant)


def test_a_short_run_does_not_wait_for_a_stretch_kernel_still_compiling(scenario, monkeypatch):
    """On a machine's first run a worker may still be compiling the stretch kernel (regrasp.kernels.warm): a short
    run then takes its steps on the reference path (the same steps); with the kernel loaded it runs stretches."""
    import regrasp.rollout.build as build

    monkeypatch.setattr(build, "compiling", lambda group=None: group == "stretch")
    rollout = build_rollout(scenario, RunSpec(duration=0.05))
    rollout.run()
    assert rollout.stretches is None
    monkeypatch.undo()
    rollout = build_rollout(scenario, RunSpec(duration=0.05))
    rollout.run()
    assert rollout.stretches is not None and rollout.stretches.enabled

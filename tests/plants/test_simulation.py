"""The one simulation loop: its records, its stops and its failures."""

from pathlib import Path

import numpy as np
import pytest

from drivers import driver
from factories import DANGER_START_THREE
from regrasp import RunSpec, load_scenario
from regrasp.core.events import EventKind, EventSource, Failure, FailureKind
from regrasp.core.exceptions import RegraspError
from regrasp.plants.simulation import simulate
from regrasp.rollout.build import build_rollout

SCENARIOS = Path(__file__).resolve().parents[2] / "examples" / "scenarios"


@pytest.fixture()
def rollout():
    sc = load_scenario(SCENARIOS / "paper_trajectory_2_three_fingers.toml")
    return build_rollout(sc, RunSpec(duration=0.05, xi0=[-0.0125, 0.0125, 0.0]), policy="none")



def test_each_step_gives_one_record_in_order_with_the_plants_step(rollout):
    records = []
    outcome = simulate(rollout.plant, driver(rollout), 20, consumers=[records.append])
    assert outcome.steps == 20 and outcome.failure is None and len(records) == 20
    assert [r.index for r in records] == list(range(20))
    assert np.allclose([r.t for r in records], 1e-3 * np.arange(20), atol=1e-12)
    for a, b in zip(records, records[1:]):
        assert b.measurement.t == a.plant.state.t  # a step's measurement is the previous step's end state
        assert np.array_equal(b.measurement.X, a.plant.state.X)
    last = records[-1]
    assert np.array_equal(last.object_error, last.command.desired.pose - last.measurement.X)
    # the law's S_d is its E plus the measured S (all contacts fixed: S = X), and the desired pose up to
    # the integral action's shift of the reference
    assert np.allclose(last.command.S_desired - last.command.control.error, last.measurement.X, rtol=0, atol=1e-15)
    assert np.abs(last.command.S_desired - last.command.desired.pose).max() < 1e-6
    mu = [f.static for f in rollout.plant.friction]
    fn, ft = last.plant.forces_surface.T
    assert np.allclose(last.cone_margins, np.array(mu) * fn - np.abs(ft), rtol=0, atol=1e-12)


def test_a_failure_from_check_stops_the_loop_at_that_record(rollout):
    records = []
    stop = Failure(0.0, FailureKind.LEFT_ENVELOPE, "test")
    outcome = simulate(rollout.plant, driver(rollout), 20, consumers=[records.append],
                       check=lambda r: stop if r.index == 6 else None)
    assert outcome.failure is stop and outcome.steps == 7 and len(records) == 7


@pytest.mark.parametrize("error", [RegraspError("no torque"), np.linalg.LinAlgError("Singular matrix")])
def test_a_failing_control_law_is_a_control_failure_not_an_exception(rollout, error):
    outcome = simulate(rollout.plant, driver(rollout, fail_at=3, error=error), 20)
    assert outcome.steps == 3 and outcome.failure.kind is FailureKind.CONTROL and str(error) in outcome.failure.reason
    with pytest.raises(type(error)):
        simulate(rollout.plant, driver(rollout, fail_at=0, error=error), 5, control_failures=False)


def test_ctrl_c_ends_an_interruptible_run_with_its_records_intact(rollout):
    records = []

    def consumer(record):
        records.append(record)
        if record.index == 4:
            raise KeyboardInterrupt

    outcome = simulate(rollout.plant, driver(rollout), 20, consumers=[consumer], interruptible=True)
    assert outcome.failure.kind is FailureKind.INTERRUPTED and len(records) == 5
    with pytest.raises(KeyboardInterrupt):
        simulate(rollout.plant, driver(rollout), 20, consumers=[consumer])


@pytest.mark.parametrize("nested", [False, True])
def test_a_real_sigint_mid_step_ends_the_run_after_that_step_never_inside_a_consumer(rollout, nested):
    import contextlib
    import os
    import signal

    from regrasp.plants.simulation import InterruptAtStepEnd

    previous = signal.getsignal(signal.SIGINT)
    seen = []

    def first(record):
        if record.index == 4:
            os.kill(os.getpid(), signal.SIGINT)  # delivered here, in the middle of the step's consumers

    # nested: as in ``regrasp simulate``, which defers Ctrl-C from before it opens its recording
    with InterruptAtStepEnd() if nested else contextlib.nullcontext():
        outcome = simulate(rollout.plant, driver(rollout), 20, consumers=[first, seen.append], interruptible=True)
    # the step in progress is completed (its later consumers too); the next one never starts
    assert outcome.failure.kind is FailureKind.INTERRUPTED and outcome.steps == 5 and len(seen) == 5
    assert signal.getsignal(signal.SIGINT) is previous


def test_a_second_sigint_raises_at_once_and_a_nested_deferral_shares_the_outer_request():
    import os
    import signal

    from regrasp.plants.simulation import InterruptAtStepEnd

    previous = signal.getsignal(signal.SIGINT)
    with InterruptAtStepEnd() as outer:
        with InterruptAtStepEnd() as inner:
            assert not inner.requested
            os.kill(os.getpid(), signal.SIGINT)
            assert inner.requested and outer.requested
            with pytest.raises(KeyboardInterrupt):
                os.kill(os.getpid(), signal.SIGINT)
                for _ in range(1000):  # (the handler runs at the next bytecode boundary)
                    pass
        assert signal.getsignal(signal.SIGINT).__self__ is outer  # (the inner one left the outer's handler installed)
    assert signal.getsignal(signal.SIGINT) is previous
    with InterruptAtStepEnd(active=False) as off:
        assert signal.getsignal(signal.SIGINT) is previous and not off.requested


def test_plant_events_are_in_the_record_with_their_source():
    sc = load_scenario(SCENARIOS / "paper_trajectory_2_three_fingers.toml")
    rollout = build_rollout(sc, RunSpec(duration=0.01, xi0=DANGER_START_THREE), policy="paper")  # finger 1 slides
    result = rollout.run()
    slips = [e for e in result.events if e.kind is EventKind.SLIP]
    assert slips and all(e.source is EventSource.PLANT for e in slips)
    decisions = [e.kind for e in result.events if e.source is EventSource.SUPERVISOR and e.kind is not EventKind.DANGER]
    assert decisions[:2] == [EventKind.PRIME, EventKind.SLIDE]

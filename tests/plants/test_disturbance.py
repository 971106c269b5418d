"""The hand's sensing noise, slip sensor, torque noise and actuation delay: their statistics against the settings,
their delays step by step, and the simulation loop keeping the truth apart from what the controller sensed."""

import math
from pathlib import Path

import numpy as np
import pytest

from drivers import driver
from regrasp import ModelErrors, PlantSpec, RunSpec, load_scenario
from regrasp.core.exceptions import InvalidParameterError
from regrasp.core.measurement import Measurement
from regrasp.model.noise import ActuatorNoise, SensorNoise
from regrasp.plants.disturbance import Disturbance
from regrasp.plants.simulation import simulate
from regrasp.rollout.build import build_rollout

SCENARIOS = Path(__file__).resolve().parents[2] / "examples" / "scenarios"


def truth(t=0.0, xi_dot=(0.0, 0.0, 0.0), sliding=(False, False, False)):
    return Measurement(t, np.array([0.01, 0.12, 0.05]), np.array([0.1, -0.2, 0.3]), np.array([-0.01, 0.01, 0.0]),
                       np.array(xi_dot, dtype=float), np.array(sliding), np.array([0.1, -0.1, 0.0]),
                       np.array([1.0, 1.2, 0.8]))


@pytest.mark.parametrize("kind, bad", [
    (SensorNoise, dict(position=-1e-4)), (SensorNoise, dict(angle=math.nan)), (SensorNoise, dict(xi="0.1")),
    (SensorNoise, dict(force=1e9)), (SensorNoise, dict(slip_threshold=-0.1)), (SensorNoise, dict(slip_delay=1.5)),
    (SensorNoise, dict(slip_delay=True)), (SensorNoise, dict(slip_delay=11)), (ActuatorNoise, dict(torque=-1.0)),
    (ActuatorNoise, dict(delay=-1)), (ActuatorNoise, dict(delay=1e9)), (ActuatorNoise, dict(torque=math.inf))])
def test_bad_settings_are_typed_errors_naming_the_field(kind, bad):
    with pytest.raises(InvalidParameterError, match=next(iter(bad))):
        kind(**bad)


def test_noise_needs_a_seeded_generator_and_an_ideal_hand_reads_the_truth():
    with pytest.raises(InvalidParameterError, match="rng"):
        Disturbance(SensorNoise(xi=1e-4))
    ideal = Disturbance()
    reading = truth()
    assert ideal.measure(reading) is reading
    tau = np.array([0.1, 0.2])
    assert ideal.actuate(tau) is tau


def test_sensor_noise_has_the_standard_deviations_asked_for_and_no_bias():
    sigma = SensorNoise(position=1e-4, angle=1e-3, velocity=2e-3, angular_velocity=0.05, xi=2e-4, xi_dot=1e-3,
                        force=0.01)
    d = Disturbance(sigma, rng=np.random.default_rng(3))
    n = 20_000
    reading = truth()
    rows = []
    for _ in range(n):
        m = d.measure(reading)
        rows.append(np.concatenate([m.X - reading.X, m.V - reading.V, m.xi - reading.xi, m.xi_dot - reading.xi_dot,
                                    m.normal_force - reading.normal_force,
                                    m.tangential_force - reading.tangential_force]))
    rows = np.array(rows)
    want = np.array([1e-4, 1e-4, 1e-3, 2e-3, 2e-3, 0.05] + [2e-4] * 3 + [1e-3] * 3 + [0.01] * 6)
    # a sample standard deviation of n = 20 000 normal draws is within 3 % of sigma (about 6 of its own sigmas),
    # and a sample mean within 4 sigma / sqrt(n)
    np.testing.assert_allclose(rows.std(axis=0), want, rtol=0.03)
    assert (np.abs(rows.mean(axis=0)) < 4 * want / math.sqrt(n)).all()
    assert np.abs(np.corrcoef(rows.T) - np.eye(len(want))).max() < 0.05  # independent components


def test_the_slip_sensor_sees_speeds_above_its_threshold_its_delay_late():
    d = Disturbance(SensorNoise(slip_threshold=0.002, slip_delay=2))
    speeds = [(0.0, 0.0, 0.0), (0.001, -0.003, 0.0), (0.0025, 0.0, -0.0021), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)]
    seen = [d.measure(truth(k * 1e-3, v, sliding=(True, True, True))).sliding.tolist() for k, v in enumerate(speeds)]
    # the plant's mode is ignored; step k reports step k - 2's |xi_dot| > 2 mm/s (before the run: step 0's)
    assert seen == [[False, False, False], [False, False, False], [False, False, False], [False, True, False],
                    [True, False, True]]
    perfect = Disturbance(SensorNoise(slip_delay=1))
    seen = [perfect.measure(truth(sliding=s)).sliding.tolist() for s in ((False,) * 3, (True, False, False),
                                                                         (True, True, False))]
    assert seen == [[False] * 3, [False] * 3, [True, False, False]]


def test_the_actuator_applies_each_command_its_delay_late_with_its_noise():
    d = Disturbance(actuator=ActuatorNoise(delay=1))
    commands = [np.array([float(k), -float(k)]) for k in range(1, 5)]
    applied = [d.actuate(c) for c in commands]
    # before the run the hand held the first command, so step 0 applies it too
    for got, want in zip(applied, [commands[0]] + commands[:-1]):
        assert np.array_equal(got, want)
    noisy = Disturbance(actuator=ActuatorNoise(torque=0.01, delay=0), rng=np.random.default_rng(5))
    deviations = np.array([noisy.actuate(np.zeros(6)) for _ in range(5000)])
    np.testing.assert_allclose(deviations.std(axis=0), 0.01, rtol=0.06)


def test_the_loop_drives_the_controller_with_the_noisy_reading_and_the_plant_with_the_delayed_torque():
    sc = load_scenario(SCENARIOS / "paper_trajectory_2_three_fingers.toml")
    rollout = build_rollout(sc, RunSpec(duration=0.02, seed=7, xi0=[-0.0125, 0.0125, 0.0],
                                        sensor_noise=SensorNoise(position=1e-4, angle=1e-3, xi=2e-4),
                                        actuator_noise=ActuatorNoise(delay=1)), policy="none")
    records = []
    outcome = simulate(rollout.plant, driver(rollout), 20, consumers=[records.append],
                       disturbance=rollout.disturbance)
    assert outcome.failure is None and len(records) == 20
    for a, b in zip(records, records[1:]):
        assert np.array_equal(b.applied_tau, a.command.tau)  # one step late
        assert np.array_equal(b.truth.X, a.plant.state.X)  # the truth is the plant's state
    assert np.array_equal(records[0].applied_tau, records[0].command.tau)
    dx = np.array([r.measurement.X - r.truth.X for r in records])
    assert 2e-5 < np.abs(dx[:, :2]).max() < 6e-4 and 2e-4 < np.abs(dx[:, 2]).max() < 6e-3
    assert all(np.array_equal(r.object_error, r.command.desired.pose - r.truth.X) for r in records)
    with pytest.raises(InvalidParameterError, match="rng"):
        build_rollout(sc, RunSpec(duration=0.02, xi0=[-0.0125, 0.0125, 0.0], sensor_noise=SensorNoise(xi=1e-4)),
                      policy="none")


def test_a_placement_error_moves_the_plants_fingertips_and_not_the_supervisors_belief():
    sc = load_scenario(SCENARIOS / "paper_trajectory_2_three_fingers.toml")
    xi0 = np.array([-0.0125, 0.0125, 0.0])
    offset = np.array([2e-4, -1e-4, 0.0])
    rollout = build_rollout(sc, RunSpec(duration=0.01, xi0=xi0), policy="none",
                            plant=PlantSpec(errors=ModelErrors(xi_offset=offset)))
    np.testing.assert_allclose([c.xi for c in rollout.plant.contacts], xi0 + offset, rtol=0, atol=1e-15)
    # the plant's tips are on the object at the offset positions (its constraints hold at the start)
    assert rollout.plant.max_constraint_error < 1e-12
    assert rollout.run().success
    with pytest.raises(InvalidParameterError, match="xi_offset"):
        build_rollout(sc, RunSpec(duration=0.01, xi0=xi0), policy="none",
                      plant=PlantSpec(errors=ModelErrors(xi_offset=[0.0, math.nan, 0.0])))

"""What one rollout runs: :class:`RunSpec` (how long, the control step, where the contacts start, the hand's
sensing and actuation noise and the seed that draws it, and when a contact counts as lost). A robustness study
builds one per run from the run's seed and passes it through whole."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..core.exceptions import InvalidParameterError
from ..core.health import HealthCriteria
from ..core.trajectory import RepeatedTrajectory
from ..core.validation import (
    MAX_DURATION,
    MAX_SEED,
    as_count,
    as_duration,
    as_finite_array,
    as_positive_float,
    expect_type,
    step_count,
)
from ..model.noise import ActuatorNoise, SensorNoise
from ..model.scenario import Scenario
from ..plants.disturbance import Disturbance
from ..schedule.problem import trajectory_period

__all__ = ["RunSpec"]


@dataclass(frozen=True)
class RunSpec:
    """One rollout's run.

    Attributes:
        duration: Simulated time [s]; default: the trajectory's domain. A periodic trajectory repeats.
        periods: Instead of ``duration``: this many periods of a periodic trajectory (at most 10**6, and
            :data:`~regrasp.core.validation.MAX_DURATION`).
        dt: The control and plant step [s].
        seed: Seeds the noise (required when there is any): an int or a ``numpy.random.SeedSequence``.
        xi0: Where the supervisor believes the contacts start [m], one per finger (default: the schedule's start,
            else the planner's ``initial_xi``); the plant's are there plus the plant's placement errors.
        sensor_noise, actuator_noise: The hand's sensing noise, slip sensor, torque noise and actuation delay
            (:mod:`regrasp.model.noise`); default: none.
        health: When a contact is lost (:class:`~regrasp.core.health.HealthCriteria`): the run fails there, on
            every plant alike.
    """

    duration: float | None = None
    periods: int | None = None
    dt: float = 1e-3
    seed: int | np.random.SeedSequence | None = None
    xi0: tuple[float, ...] | None = None
    sensor_noise: SensorNoise = SensorNoise()
    actuator_noise: ActuatorNoise = ActuatorNoise()
    health: HealthCriteria = HealthCriteria()

    def __post_init__(self) -> None:
        if self.periods is not None:
            if self.duration is not None:
                raise InvalidParameterError("periods", self.periods, "either periods or duration, not both")
            object.__setattr__(self, "periods", as_count("periods", self.periods, 1))
        if self.duration is not None:
            object.__setattr__(self, "duration", as_duration("duration", self.duration))
        object.__setattr__(self, "dt", as_positive_float("dt", self.dt))
        if self.seed is not None and not isinstance(self.seed, np.random.SeedSequence):
            object.__setattr__(self, "seed", as_count("seed", self.seed, 0, MAX_SEED))
        if self.xi0 is not None:
            xi0 = as_finite_array("xi0", self.xi0)
            if xi0.ndim != 1:
                raise InvalidParameterError("xi0", self.xi0, "one initial contact position [m] per finger")
            object.__setattr__(self, "xi0", tuple(xi0.tolist()))
        expect_type("sensor_noise", self.sensor_noise, SensorNoise, "a SensorNoise (regrasp.model.noise)")
        expect_type("actuator_noise", self.actuator_noise, ActuatorNoise, "an ActuatorNoise (regrasp.model.noise)")
        expect_type("health", self.health, HealthCriteria, "a HealthCriteria (regrasp.core.health)")

    def resolve(self, scenario: Scenario) -> tuple[Scenario, float]:
        """The scenario with its trajectory repeated to cover the run, and the run's duration [s] (at least one step
        ``dt``: :func:`~regrasp.core.validation.step_count`)."""
        traj = scenario.trajectory
        domain = traj.t_end - traj.t_start
        period = trajectory_period(traj)
        duration = self.duration
        if self.periods is not None:
            if period is None:
                raise InvalidParameterError("periods", self.periods, f"a periodic trajectory (scenario "
                                            f"{scenario.name!r} is not; use duration)")
            duration = float(self.periods) * period
            if duration > MAX_DURATION:
                raise InvalidParameterError("periods", self.periods, f"at most {MAX_DURATION:g} s of simulated time "
                                            f"({int(MAX_DURATION // period)} periods of {period:.6g} s)")
        duration = domain if duration is None else duration
        step_count("periods" if self.periods is not None else "duration", duration, self.dt)  # (at least one step)
        if duration > domain + 1e-9:
            if period is None:
                raise InvalidParameterError("duration", duration, f"at most the trajectory's domain, {domain:.6g} s "
                                            "(it is not periodic, so it cannot be repeated)")
            scenario = replace(scenario, trajectory=RepeatedTrajectory(traj, traj.t_start + duration))
        return scenario, float(duration)

    def start(self, m: int) -> np.ndarray | None:
        """``xi0`` for ``m`` fingers [m], or None."""
        return None if self.xi0 is None else as_finite_array("xi0", self.xi0, (m,))

    def disturbance(self) -> Disturbance | None:
        """The run's seeded noise between the plant and the supervisor, or None (a perfect hand)."""
        if self.sensor_noise.ideal and self.actuator_noise.ideal:
            return None
        rng = None if self.seed is None else np.random.default_rng(self.seed)
        return Disturbance(self.sensor_noise, self.actuator_noise, rng)

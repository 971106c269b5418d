r"""What a real hand adds between a controller and the plant, as settings: :class:`SensorNoise` (white Gaussian
noise on each sensed quantity, a slip sensor with a threshold and a delay) and :class:`ActuatorNoise` (torque noise,
an actuation delay). A run's seeded realisation of both is :class:`~regrasp.plants.disturbance.Disturbance`."""

from __future__ import annotations

from dataclasses import dataclass

from ..core.exceptions import InvalidParameterError
from ..core.validation import as_finite_float, as_integer

__all__ = ["ActuatorNoise", "SensorNoise"]


#: The longest delay [steps] a sensor or an actuator may have (10 control periods: beyond that no law here is
#: stable, and a longer delay is a slower controller, not a delay).
MAX_DELAY_STEPS = 10


#: The largest standard deviation each noise may have, far beyond any usable sensor or actuator (it keeps the
#: arithmetic finite): [m], [rad], [m/s], [rad/s], [N], [N m].
NOISE_BOUNDS = {"position": 0.1, "angle": 3.2, "velocity": 10.0, "angular_velocity": 100.0, "xi": 0.1,
                "xi_dot": 10.0, "force": 100.0, "slip_threshold": 10.0, "torque": 10.0}


def _check_nonnegative(owner: object, names: tuple[str, ...]) -> None:
    for name in names:
        value = as_finite_float(name, getattr(owner, name))
        if not 0.0 <= value <= NOISE_BOUNDS[name]:
            raise InvalidParameterError(name, value, f"a value in [0, {NOISE_BOUNDS[name]:g}]")
        object.__setattr__(owner, name, value)


def _check_delay(owner: object, name: str) -> None:
    value = as_integer(name, getattr(owner, name))
    if value > MAX_DELAY_STEPS:
        raise InvalidParameterError(name, value, f"a delay of at most {MAX_DELAY_STEPS} steps")
    object.__setattr__(owner, name, value)


@dataclass(frozen=True)
class SensorNoise:
    """Standard deviations of the white Gaussian noise on each sensed quantity, and the slip sensor.

    Attributes:
        position: Object position (x, y) [m].
        angle: Object orientation β [rad].
        velocity: Object linear velocity [m/s].
        angular_velocity: Object angular velocity [rad/s].
        xi: Each contact's position ξ on its edge [m].
        xi_dot: Each contact's rate ξ̇ [m/s].
        force: Each sensed contact force component (normal, tangential) [N].
        slip_threshold: A contact is sensed as sliding when its true :math:`|\\dot\\xi|` exceeds this [m/s];
            None: the plant's own contact mode (a perfect slip sensor).
        slip_delay: The slip sensor reports what was true this many control steps ago.
    """

    position: float = 0.0
    angle: float = 0.0
    velocity: float = 0.0
    angular_velocity: float = 0.0
    xi: float = 0.0
    xi_dot: float = 0.0
    force: float = 0.0
    slip_threshold: float | None = None
    slip_delay: int = 0

    def __post_init__(self) -> None:
        _check_nonnegative(self, ("position", "angle", "velocity", "angular_velocity", "xi", "xi_dot", "force"))
        if self.slip_threshold is not None:
            _check_nonnegative(self, ("slip_threshold",))
        _check_delay(self, "slip_delay")

    @property
    def ideal(self) -> bool:
        """Whether this sensor reads the truth exactly."""
        return self == SensorNoise()


@dataclass(frozen=True)
class ActuatorNoise:
    """The joints' actuation: white Gaussian torque noise and a delay.

    Attributes:
        torque: Standard deviation of the noise added to every joint torque [N m].
        delay: The torque applied during a step is the one commanded this many steps before.
    """

    torque: float = 0.0
    delay: int = 0

    def __post_init__(self) -> None:
        _check_nonnegative(self, ("torque",))
        _check_delay(self, "delay")

    @property
    def ideal(self) -> bool:
        """Whether the commanded torque is applied exactly and at once."""
        return self == ActuatorNoise()

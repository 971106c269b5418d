r"""What a real hand adds between the controller and the plant: sensing noise, a slip sensor with a threshold
and a delay, torque noise and an actuation delay.

:class:`~regrasp.model.noise.SensorNoise` and :class:`~regrasp.model.noise.ActuatorNoise` are the settings (value
types); :class:`Disturbance` is one run's seeded realisation of both, which the simulation loop
(:func:`~regrasp.plants.simulation.simulate`) calls at every control step:

* :meth:`Disturbance.measure` turns the plant's noise-free reading (the *truth*,
  :func:`~regrasp.plants.simulation.sense`) into what the controller gets: white Gaussian noise of the given standard
  deviations on the object pose :math:`(x, y) [m]` and :math:`\beta [rad]`, its twist :math:`v [m/s]` and
  :math:`\omega [rad/s]`, each contact's :math:`\xi [m]` and :math:`\dot\xi [m/s]` and each sensed contact
  force [N]; a slip sensor that reports a contact as sliding when :math:`|\dot\xi|` (true) exceeds
  ``slip_threshold`` [m/s] (None: the plant's own contact mode, a perfect sensor), ``slip_delay`` steps late.
* :meth:`Disturbance.actuate` turns the commanded joint torques into the applied ones: the command of
  ``delay`` steps ago (before the first command, the first command: the hand held the grasp before the run
  started), plus white Gaussian noise of ``torque`` [N m] on every joint.

The noise is drawn from the generator the disturbance is given (one seeded stream per run, so that a study's
runs repeat exactly). The failure checks and the rollout's errors read the truth, never the noisy reading.
"""

from __future__ import annotations

from collections import deque
from dataclasses import fields, replace
from typing import TYPE_CHECKING

import numpy as np

from ..core.exceptions import InvalidParameterError
from ..core.validation import expect_type
from ..kernels.stretch_layout import StretchDisturbance
from ..model.noise import ActuatorNoise, SensorNoise

if TYPE_CHECKING:
    from ..core.measurement import Measurement

__all__ = ["Disturbance"]


class Disturbance:
    """One run's sensor and actuator (module docstring), seeded by ``rng``.

    Args:
        sensor: The sensing noise and the slip sensor.
        actuator: The torque noise and the actuation delay.
        rng: The run's generator (``numpy.random.default_rng(seed)``); it is the only source of the noise.
    """

    def __init__(self, sensor: SensorNoise = SensorNoise(), actuator: ActuatorNoise = ActuatorNoise(),
                 rng: np.random.Generator | None = None):
        self.sensor = expect_type("sensor", sensor, SensorNoise, "a SensorNoise")
        self.actuator = expect_type("actuator", actuator, ActuatorNoise, "an ActuatorNoise")
        noisy = any(getattr(sensor, f.name) for f in fields(SensorNoise)
                    if f.name not in ("slip_threshold", "slip_delay")) or actuator.torque > 0.0
        if rng is None and noisy:
            raise InvalidParameterError("rng", rng, "a numpy Generator (the noise must be seeded)")
        self.rng = expect_type("rng", rng, (np.random.Generator, type(None)), "a numpy Generator")
        self._slips: deque[np.ndarray] = deque(maxlen=sensor.slip_delay + 1)
        self._commands: deque[np.ndarray] = deque(maxlen=actuator.delay + 1)

    def _noise(self, sigma: float, shape: tuple[int, ...]) -> np.ndarray | float:
        return self.rng.normal(0.0, sigma, shape) if sigma > 0.0 else 0.0

    def measure(self, truth: Measurement) -> Measurement:
        """What the controller senses when ``truth`` is so (module docstring)."""
        s = self.sensor
        if s.ideal:
            return truth
        m = len(truth.xi)
        if s.slip_threshold is None:
            sliding = truth.sliding
        else:
            sliding = np.abs(truth.xi_dot) > s.slip_threshold
        self._slips.append(np.asarray(sliding, dtype=bool).copy())
        pose_sigma = np.array([s.position, s.position, s.angle])
        twist_sigma = np.array([s.velocity, s.velocity, s.angular_velocity])
        X = truth.X + (self.rng.normal(0.0, 1.0, 3) * pose_sigma if pose_sigma.any() else 0.0)
        V = truth.V + (self.rng.normal(0.0, 1.0, 3) * twist_sigma if twist_sigma.any() else 0.0)
        normal = truth.normal_force
        if normal is not None:
            normal = normal + self._noise(s.force, (m,))
        return replace(truth, X=X, V=V, xi=truth.xi + self._noise(s.xi, (m,)),
                       xi_dot=truth.xi_dot + self._noise(s.xi_dot, (m,)), sliding=self._slips[0],
                       tangential_force=truth.tangential_force + self._noise(s.force, (m,)), normal_force=normal)

    # stretches (regrasp.rollout.stretch): the same draws and deques, in compiled code
    def stretch_layout(self, m: int) -> dict[str, int]:
        """Where each noise term lies in one step's row of standard normals (-1: not drawn), in the order
        :meth:`measure` and :meth:`actuate` draw them, and the row's length (``"size"``), for m contacts."""
        s, a = self.sensor, self.actuator
        layout, k = {}, 0
        terms = (("pose", 3, not s.ideal and (s.position > 0.0 or s.angle > 0.0)),
                 ("twist", 3, not s.ideal and (s.velocity > 0.0 or s.angular_velocity > 0.0)),
                 ("normal", m, not s.ideal and s.force > 0.0), ("xi", m, not s.ideal and s.xi > 0.0),
                 ("xi_dot", m, not s.ideal and s.xi_dot > 0.0), ("friction", m, not s.ideal and s.force > 0.0),
                 ("torque", 2 * m, not a.ideal and a.torque > 0.0))
        for name, size, drawn in terms:
            layout[name] = k if drawn else -1
            k += size if drawn else 0
        layout["size"] = k
        return layout

    def stretch_view(self, m: int, steps: int) -> tuple[StretchDisturbance, object, int, int]:
        """What a compiled stretch of at most ``steps`` steps of m contacts needs: its draws and deques
        (:class:`~regrasp.kernels.stretch_layout.StretchDisturbance`), the generator's state before the draws and how
        many entries the slip sensor's and the actuation delay's deques hold (:meth:`take_stretch` takes them back)."""
        noise, state = self.stretch_noise(m, steps)
        slips, slip_count, commands, command_count = self.stretch_deques(m)
        return StretchDisturbance(noise, slips, commands), state, slip_count, command_count

    def stretch_noise(self, m: int, steps: int) -> tuple[np.ndarray, object]:
        """The standard normals ``steps`` steps would draw, one row a step (:meth:`stretch_layout`), and the
        generator's state before them (:meth:`take_stretch` rewinds to it)."""
        size = self.stretch_layout(m)["size"]
        if size == 0:
            return np.zeros((steps, 0)), None
        state = self.rng.bit_generator.state
        return self.rng.standard_normal((steps, size)), state

    def stretch_deques(self, m: int) -> tuple[np.ndarray, int, np.ndarray, int]:
        """The slip sensor's readings (d + 1, m) and the commanded torques (delay + 1, 2m), oldest first, with how
        many each deque holds."""
        slips = np.zeros((self.sensor.slip_delay + 1, m), np.bool_)
        for i, reading in enumerate(self._slips):
            slips[i] = reading
        commands = np.zeros((self.actuator.delay + 1, 2 * m))
        for i, command in enumerate(self._commands):
            commands[i] = command
        return slips, len(self._slips), commands, len(self._commands)

    def take_stretch(self, steps: int, state: object, size: int, slips: np.ndarray, slip_count: int,
                     commands: np.ndarray, command_count: int) -> None:
        """After a compiled stretch of ``steps`` steps: the generator as if it had drawn their noise (rewound to
        ``state`` and advanced by ``steps`` rows of ``size``), and the deques from the stretch's arrays."""
        if state is not None:
            self.rng.bit_generator.state = state
            self.rng.standard_normal(steps * size)
        self._slips = deque([row.copy() for row in slips[:slip_count]], maxlen=self._slips.maxlen)
        self._commands = deque([row.copy() for row in commands[:command_count]], maxlen=self._commands.maxlen)

    def actuate(self, tau: np.ndarray) -> np.ndarray:
        """The joint torques [N m] the plant gets during this step when ``tau`` is commanded now."""
        a = self.actuator
        if a.ideal:
            return tau
        if not self._commands:  # before the run the hand held the first command
            self._commands.extend([tau] * a.delay)
        self._commands.append(tau)
        applied = self._commands[0]
        return applied + self._noise(a.torque, applied.shape) if a.torque > 0.0 else applied

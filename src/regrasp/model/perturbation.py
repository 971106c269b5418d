r"""What a robustness study perturbs: the plant's model errors (drawn per run) and the hand's noise (per step).

:class:`Perturbation` holds the sizes. A study draws each run's model errors from its own seed
(:func:`draw_runs`, a :class:`RunDraw` per run); the noise is drawn at every control step by the run's
:class:`~regrasp.plants.disturbance.Disturbance`, seeded from the same run seed.

**Model errors**, drawn once per run. A relative half-width :math:`h` [-] multiplies the model's value by a
factor drawn uniformly from :math:`[1 - h, 1 + h]`; the controllers and the planner keep the model's value:

* ``mass``: the object's mass; ``inertia``: its rotational inertia (drawn on its own);
* ``mu``: every fingertip's :math:`\mu_s` and :math:`\mu_k` together; ``mu_kinetic``: :math:`\mu_k` alone
  on top of that (never above the plant's :math:`\mu_s`: a kinetic coefficient above the static one is not
  Coulomb friction);
* ``link_mass``: every finger link's mass and inertia (one factor for all links);
* ``contact_position`` [m]: each fingertip is placed :math:`\delta_i \sim U(-h, h)` off the planned
  :math:`\xi_0` along its edge, while the supervisor believes :math:`\xi_0` (a placement or calibration error).

**Noise**, white Gaussian, drawn at every control step (standard deviations; see
:class:`~regrasp.model.noise.SensorNoise` and :class:`~regrasp.model.noise.ActuatorNoise`): the object's
position [m], angle [rad], velocity [m/s], angular velocity [rad/s], each :math:`\xi` [m] and :math:`\dot\xi`
[m/s], the contact force sensor [N]; a slip sensor's threshold [m/s] and delay [steps]; torque noise [N m] and
an actuation delay [steps].
"""

from __future__ import annotations

from dataclasses import dataclass, fields

from ..core.exceptions import InvalidParameterError
from ..core.validation import as_finite_float
from .noise import ActuatorNoise, SensorNoise

__all__ = ["Perturbation"]


#: The relative model errors (half-widths in [0, 1)), in the order a run draws them.
RELATIVE = ("mass", "mu", "inertia", "link_mass", "mu_kinetic")


#: The largest contact placement error [m] (a fingertip this far off its plan is another grasp).
MAX_CONTACT_POSITION = 0.01

#: Perturbation's noise fields and the SensorNoise / ActuatorNoise fields they set.
SENSOR_FIELDS = {"position_noise": "position", "angle_noise": "angle", "velocity_noise": "velocity",
                 "angular_velocity_noise": "angular_velocity", "xi_noise": "xi", "xi_dot_noise": "xi_dot",
                 "force_noise": "force", "slip_threshold": "slip_threshold", "slip_delay": "slip_delay"}
ACTUATOR_FIELDS = {"torque_noise": "torque", "delay": "delay"}


@dataclass(frozen=True)
class Perturbation:
    """The sizes of a study's perturbations (module docstring); every default is "none".

    Attributes:
        mass, mu, inertia, link_mass, mu_kinetic: Relative half-widths [-] in [0, 1).
        contact_position: Half-width of each fingertip's placement error [m], at most 1 cm.
        position_noise, angle_noise: Object pose noise [m], [rad].
        velocity_noise, angular_velocity_noise: Object twist noise [m/s], [rad/s].
        xi_noise, xi_dot_noise: Contact position and rate noise [m], [m/s].
        force_noise: Contact force sensor noise [N].
        slip_threshold: The slip sensor's threshold [m/s] (None: a perfect slip sensor).
        slip_delay: The slip sensor's delay [control steps].
        torque_noise: Joint torque noise [N m].
        delay: Actuation delay [control steps].
    """

    mass: float = 0.0
    mu: float = 0.0
    inertia: float = 0.0
    link_mass: float = 0.0
    mu_kinetic: float = 0.0
    contact_position: float = 0.0
    position_noise: float = 0.0
    angle_noise: float = 0.0
    velocity_noise: float = 0.0
    angular_velocity_noise: float = 0.0
    xi_noise: float = 0.0
    xi_dot_noise: float = 0.0
    force_noise: float = 0.0
    slip_threshold: float | None = None
    slip_delay: int = 0
    torque_noise: float = 0.0
    delay: int = 0

    def __post_init__(self) -> None:
        for name in RELATIVE:
            value = as_finite_float(name, getattr(self, name))
            if not 0.0 <= value < 1.0:
                raise InvalidParameterError(name, value, "a relative half-width in [0, 1)")
            object.__setattr__(self, name, value)
        h = as_finite_float("contact_position", self.contact_position)
        if not 0.0 <= h <= MAX_CONTACT_POSITION:
            raise InvalidParameterError("contact_position", h, f"a half-width in [0, {MAX_CONTACT_POSITION}] m")
        object.__setattr__(self, "contact_position", h)
        # the noise fields are checked (and normalised) by the value types they build, under this class's names
        try:
            sensor, actuator = self.sensor_noise(), self.actuator_noise()
        except InvalidParameterError as exc:
            mine = {theirs: mine for mine, theirs in {**SENSOR_FIELDS, **ACTUATOR_FIELDS}.items()}
            raise InvalidParameterError(mine.get(exc.name, exc.name), exc.value, exc.expected) from None
        for mine, theirs in SENSOR_FIELDS.items():
            object.__setattr__(self, mine, getattr(sensor, theirs))
        for mine, theirs in ACTUATOR_FIELDS.items():
            object.__setattr__(self, mine, getattr(actuator, theirs))

    def sensor_noise(self) -> SensorNoise:
        """The hand's sensing noise and slip sensor."""
        return SensorNoise(**{theirs: getattr(self, mine) for mine, theirs in SENSOR_FIELDS.items()})

    def actuator_noise(self) -> ActuatorNoise:
        """The hand's torque noise and actuation delay."""
        return ActuatorNoise(**{theirs: getattr(self, mine) for mine, theirs in ACTUATOR_FIELDS.items()})

    def nonzero(self) -> dict[str, float | int]:
        """The perturbations this one sets (name: size), in field order."""
        return {f.name: getattr(self, f.name) for f in fields(self)
                if getattr(self, f.name) not in (0, 0.0, None)
                or (f.name == "slip_threshold" and self.slip_threshold == 0.0)}

    def describe(self) -> str:
        """One line, e.g. ``mass ±20%, contact_position ±0.2 mm, angle_noise 1 mrad, delay 1 step``."""
        parts = []
        for name, value in self.nonzero().items():
            if name in RELATIVE:
                parts.append(f"{name} ±{value:.0%}")
            elif name in ("delay", "slip_delay"):
                parts.append(f"{name} {value} step{'s' if value != 1 else ''}")
            else:
                scale, unit = _UNITS[name]
                parts.append(f"{name} {'±' if name == 'contact_position' else ''}{value * scale:g} {unit}")
        return ", ".join(parts) or "no perturbation"


#: How :meth:`Perturbation.describe` shows each size: (scale, unit).
_UNITS = {"contact_position": (1e3, "mm"), "position_noise": (1e3, "mm"), "angle_noise": (1e3, "mrad"),
          "velocity_noise": (1e3, "mm/s"), "angular_velocity_noise": (1.0, "rad/s"), "xi_noise": (1e3, "mm"),
          "xi_dot_noise": (1e3, "mm/s"), "force_noise": (1.0, "N"), "slip_threshold": (1e3, "mm/s"),
          "torque_noise": (1e3, "mN m")}



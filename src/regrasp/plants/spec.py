r"""Which plant a rollout runs on, and how it differs from the model: :class:`PlantSpec` (its kind, the kind's
settings, its :class:`ModelErrors`) builds the plant for a scenario (:meth:`PlantSpec.build`).

The controllers and the planners keep the scenario's model (object mass and inertia, the URDFs' links, μ_s and
μ_k, the planned fingertip placement); :class:`ModelErrors` says what the plant has instead, as factors on the
model's values and placement offsets. A robustness study draws one per run
(:func:`~regrasp.study.draws.draw_runs`) and passes it through whole.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ..core.contact import ContactMode, Friction, FrictionLike, as_frictions
from ..core.exceptions import InvalidParameterError
from ..core.pad import Pad
from ..core.validation import as_finite_array, as_positive_float, expect_type
from ..model.hand import Hand
from .project.plant import Plant
from .project.state import PlantContact

if TYPE_CHECKING:
    from ..model.scenario import Scenario
    from .drake.model import DrakeSettings
    from .mujoco.mjcf import MujocoSettings
    from .simulation import PlantLike

__all__ = ["PLANTS", "ROLLOUT_STOPS", "ModelErrors", "PlantSpec"]

#: The plants a :class:`PlantSpec` knows by name: the project's (:class:`~regrasp.plants.project.plant.Plant`),
#: MuJoCo (:class:`~regrasp.plants.mujoco.plant.MujocoPlant`, the ``mujoco`` extra) and Drake
#: (:class:`~regrasp.plants.drake.plant.DrakePlant`, the ``drake`` extra).
PLANTS = ("project", "mujoco", "drake")

#: Each optional plant's settings class: (module under regrasp.plants, class name).
_SETTINGS = {"mujoco": ("mujoco.mjcf", "MujocoSettings"), "drake": ("drake.model", "DrakeSettings")}

#: The plant events that stop a rollout's plant: a contact off its edge, a link in the object, a singular finger.
ROLLOUT_STOPS = ("left_edge", "collision", "singular")


@dataclass(frozen=True)
class ModelErrors:
    """How the plant differs from the model; every default is "not at all".

    Attributes:
        mass_scale: The plant's object mass over the model's [-].
        inertia_scale: The plant's object inertia over the model's [-] (None: ``mass_scale``).
        link_mass_scale: The plant's finger links' masses and inertias over the URDFs' [-].
        mu_scale: The plant's μ_s and μ_k over the model's [-].
        mu_kinetic_scale: The plant's μ_k over ``mu_scale`` × the model's, at most the plant's μ_s [-].
        xi_offset: Where the plant's fingertips are placed relative to where the supervisor believes [m], one per
            finger (empty: none): a placement or calibration error of the initial grasp.
    """

    mass_scale: float = 1.0
    inertia_scale: float | None = None
    link_mass_scale: float = 1.0
    mu_scale: float = 1.0
    mu_kinetic_scale: float = 1.0
    xi_offset: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        for name in ("mass_scale", "link_mass_scale", "mu_scale", "mu_kinetic_scale"):
            object.__setattr__(self, name, as_positive_float(name, getattr(self, name)))
        if self.inertia_scale is not None:
            object.__setattr__(self, "inertia_scale", as_positive_float("inertia_scale", self.inertia_scale))
        offsets = as_finite_array("xi_offset", self.xi_offset)
        if offsets.ndim != 1:
            raise InvalidParameterError("xi_offset", self.xi_offset, "one placement offset [m] per finger")
        object.__setattr__(self, "xi_offset", tuple(offsets.tolist()))

    @property
    def object_inertia_scale(self) -> float:
        """The plant's object inertia over the model's [-]."""
        return self.mass_scale if self.inertia_scale is None else self.inertia_scale

    def friction(self, model: Sequence[Friction]) -> tuple[Friction, ...]:
        """The plant's friction for the model's, one per contact: μ_s × ``mu_scale``, μ_k × ``mu_scale`` ×
        ``mu_kinetic_scale`` capped at the (model's) μ_s × ``mu_scale``."""
        mu, kinetic = self.mu_scale, self.mu_kinetic_scale
        return tuple(Friction(f.static * mu, min(f.static, f.kinetic * kinetic) * mu) for f in model)

    def placement(self, xi: np.ndarray) -> np.ndarray:
        """Where the plant's fingertips are [m] when the supervisor believes ``xi`` [m], (m,)."""
        if not self.xi_offset:
            return xi
        if len(self.xi_offset) != len(xi):
            raise InvalidParameterError("xi_offset", self.xi_offset, f"one placement offset per finger ({len(xi)})")
        return xi + np.array(self.xi_offset)


@dataclass(frozen=True)
class PlantSpec:
    """The plant a rollout runs on.

    Attributes:
        kind: ``"project"`` (:class:`~regrasp.plants.project.plant.Plant`), ``"mujoco"``
            (:class:`~regrasp.plants.mujoco.plant.MujocoPlant`: sphere tips, soft contacts; the ``mujoco`` extra) or
            ``"drake"`` (:class:`~regrasp.plants.drake.plant.DrakePlant`: sphere tips, compliant point contacts; the
            ``drake`` extra).
        settings: The MuJoCo plant's :class:`~regrasp.plants.mujoco.mjcf.MujocoSettings` or the Drake plant's
            :class:`~regrasp.plants.drake.model.DrakeSettings` (tip radius, contact parameters, the engine's step;
            None: the defaults), of the kind's class.
        errors: How the plant differs from the model (:class:`ModelErrors`).
        friction: The plant's friction outright, anything :class:`~regrasp.plants.project.plant.Plant` takes
            (None: the scenario's, with ``errors``' scales).
        pad: ``"project"`` only: a compliant pad on every fingertip (:class:`~regrasp.core.pad.Pad`: the project's
            plant with soft normal contacts, on its reference path). None (default): the scenario's ``[pad]``, and
            rigid contacts when it has none. The MuJoCo and Drake plants have their own contact laws and ignore a
            scenario's pad.
    """

    kind: str = "project"
    settings: MujocoSettings | DrakeSettings | None = None
    errors: ModelErrors = field(default_factory=ModelErrors)
    friction: FrictionLike | None = None
    pad: Pad | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.kind, str) or self.kind not in PLANTS:
            raise InvalidParameterError("kind", self.kind, f"one of {', '.join(PLANTS)}")
        if self.kind == "mujoco":  # (before any planning: a missing extra is a bad input)
            from .mujoco.mjcf import require_mujoco

            require_mujoco()
        elif self.kind == "drake":
            from .drake.model import require_drake

            require_drake()
        if self.settings is not None:
            if self.kind not in _SETTINGS:
                raise InvalidParameterError("settings", self.settings, "None unless kind='mujoco' or 'drake'")
            where, name = _SETTINGS[self.kind]
            expect_type("settings", self.settings, self.settings_class(), f"a {name} (regrasp.plants.{where})")
        expect_type("errors", self.errors, ModelErrors, "a ModelErrors")
        if self.pad is not None:
            expect_type("pad", self.pad, Pad, "a Pad (regrasp.core.pad) or None")
            if self.kind != "project":
                raise InvalidParameterError("pad", self.pad, "None unless kind='project' (MuJoCo and Drake have "
                                            "their own contact laws)")
        if self.friction is not None:  # (checked now, whatever the scenario: one value for all, or one per finger)
            f = self.friction
            per_finger = (isinstance(f, Sequence) and not isinstance(f, (str, bytes))) or (isinstance(f, np.ndarray)
                                                                                      and f.ndim > 0)
            as_frictions(f, len(f) if per_finger else 1)

    def settings_class(self) -> type:
        """The kind's settings class (:class:`~regrasp.plants.mujoco.mjcf.MujocoSettings` or
        :class:`~regrasp.plants.drake.model.DrakeSettings`); the project's plant has none."""
        if self.kind == "mujoco":
            from .mujoco.mjcf import MujocoSettings

            return MujocoSettings
        if self.kind == "drake":
            from .drake.model import DrakeSettings

            return DrakeSettings
        raise InvalidParameterError("kind", self.kind, "a plant with settings ('mujoco' or 'drake')")

    @property
    def resolved_settings(self) -> MujocoSettings | DrakeSettings | None:
        """The settings the plant is built with: ``settings``, or the kind's defaults (None for the project's)."""
        if self.settings is not None or self.kind not in _SETTINGS:
            return self.settings
        return self.settings_class()()

    @classmethod
    def of(cls, plant: PlantSpec | str) -> PlantSpec:
        """``plant`` as a spec: a :class:`PlantSpec`, or a kind's name (``"project"``, ``"mujoco"``, ``"drake"``)."""
        if isinstance(plant, PlantSpec):
            return plant
        if isinstance(plant, str) and plant in PLANTS:
            return cls(plant)
        raise InvalidParameterError("plant", plant, f"a PlantSpec or one of {', '.join(PLANTS)}")

    @property
    def tip_radius(self) -> float:
        """The plant's fingertip radius [m] (0: point contacts)."""
        settings = self.resolved_settings
        return 0.0 if settings is None else settings.tip_radius

    def build(self, scenario: Scenario, hand: Hand, xi: ArrayLike, X: ArrayLike, V: ArrayLike, t: float,
              dt: float) -> PlantLike:
        """The plant of ``scenario`` for the model's ``hand``, every contact fixed where the supervisor believes
        ``xi`` [m] (the plant's where ``errors`` puts it), reset to the object's pose ``X`` and twist ``V`` at
        ``t`` [s]; control step ``dt`` [s]."""
        from ..dynamics.grasp import Grasp
        from ..dynamics.reduced import ReducedModel

        errors = self.errors
        m = len(scenario.contacts)
        edges = [c.edge for c in scenario.contacts]
        xi_plant = errors.placement(as_finite_array("xi", xi, (m,)))
        state = ReducedModel(hand, Grasp(scenario.polygon, edges, [ContactMode.FIXED] * m), xi_plant).state(X, V)
        friction = errors.friction(scenario.friction) if self.friction is None else as_frictions(self.friction, m)
        plant_hand = hand if errors.link_mass_scale == 1.0 else Hand(
            list(hand.fingers), gravity_in_hand=scenario.gravity_in_hand, link_mass_scale=errors.link_mass_scale)
        contacts = [PlantContact(e, ContactMode.FIXED, x) for e, x in zip(edges, xi_plant.tolist())]
        # (a contact's loss is the rollout's health criteria's to judge, alike on every plant: a plant's separation is
        # an event, not a stop)
        physics = dict(friction=friction, object_mass=scenario.polygon.mass * errors.mass_scale,
                       object_inertia=scenario.polygon.inertia * errors.object_inertia_scale, dt=dt,
                       stop_on=ROLLOUT_STOPS)
        clearance = [c.tip_clearance for c in scenario.contacts]
        if self.kind == "mujoco":
            from .mujoco.plant import MujocoPlant

            plant: PlantLike = MujocoPlant(plant_hand, scenario.polygon, contacts, **physics,
                                           settings=self.resolved_settings, tip_clearance=clearance)
        elif self.kind == "drake":
            from .drake.plant import DrakePlant

            plant = DrakePlant(plant_hand, scenario.polygon, contacts, **physics, settings=self.resolved_settings,
                               tip_clearance=clearance)
        else:
            pad = self.pad if self.pad is not None else scenario.pad
            plant = Plant(plant_hand, scenario.polygon, contacts, **physics, pad=pad)
        plant.reset(state.q, state.q_dot, X, V, t=t)
        return plant

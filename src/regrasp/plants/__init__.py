"""``regrasp.plants``: The plants a controller is checked on, and the loop that drives them: the project's
full-coordinate plant (:mod:`regrasp.plants.project`), MuJoCo (:mod:`regrasp.plants.mujoco`), Drake
(:mod:`regrasp.plants.drake`), which one a rollout runs on and how it differs from the model (:class:`PlantSpec`,
:class:`ModelErrors`), the simulation loop and its records (:func:`simulate`), a single law's closed loop
(:func:`run_closed_loop`) and the noise between a plant and its controller (:class:`Disturbance`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..core.lazy import lazy_exports

if TYPE_CHECKING:
    from .closed_loop import ClosedLoopLog, measure_reduced_state, run_closed_loop  # noqa: F401
    from .disturbance import Disturbance  # noqa: F401
    from .drake.model import DrakeSettings  # noqa: F401
    from .drake.plant import DrakePlant  # noqa: F401
    from .mujoco.mjcf import MujocoSettings, scenario_to_mjcf  # noqa: F401
    from .mujoco.plant import MujocoPlant  # noqa: F401
    from .project.plant import Plant
    from .project.state import PlantContact, PlantState, PlantStep
    from .simulation import Command, PlantLike, StepRecord, sense, sense_projected, simulate  # noqa: F401
    from .spec import PLANTS, ModelErrors, PlantSpec  # noqa: F401

__getattr__, __dir__, __all__ = lazy_exports(__name__)

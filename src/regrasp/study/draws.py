"""A study's runs, drawn: each run's seed and the model errors drawn from it (:func:`draw_runs`, a :class:`RunDraw`
per run), from the sizes a :class:`~regrasp.model.perturbation.Perturbation` gives."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.validation import MAX_RUNS, MAX_SEED, as_count, expect_type
from ..model.perturbation import Perturbation
from ..model.softness import ContactSoftness, SoftnessRanges
from ..plants.spec import ModelErrors

__all__ = ["MAX_RUNS", "MAX_SEED", "RunDraw", "draw_runs"]



#: The most fingers a study draws placement errors for.
MAX_CONTACTS = 64


@dataclass(frozen=True)
class RunDraw:
    """One run's seed and the model errors drawn from it.

    Attributes:
        index: The run's number in the study (0-based).
        entropy: The run's seed, as the spawned ``SeedSequence``'s words (to repeat the run alone; its noise is
            seeded by ``SeedSequence(entropy)``).
        errors: How the run's plant differs from the model (:class:`~regrasp.plants.spec.ModelErrors`), passed to
            the rollout whole.
        softness: How soft the run's compliant contacts are (:class:`~regrasp.model.softness.ContactSoftness`), or
            None (the plant's own).
    """

    index: int
    entropy: tuple[int, ...]
    errors: ModelErrors = ModelErrors()
    softness: ContactSoftness | None = None

    @property
    def seed(self) -> np.random.SeedSequence:
        """The run's noise seed."""
        return np.random.SeedSequence(list(self.entropy))

    def to_json_dict(self) -> dict:
        """The draw as plain JSON types: its index, seed words and model errors, flat."""
        e = self.errors
        return {"index": self.index, "entropy": list(self.entropy), "mass_scale": e.mass_scale,
                "mu_scale": e.mu_scale, "inertia_scale": e.object_inertia_scale,
                "link_mass_scale": e.link_mass_scale, "mu_kinetic_scale": e.mu_kinetic_scale,
                "xi_offset": list(e.xi_offset),
                "softness": None if self.softness is None else self.softness.to_json_dict()}


def draw_runs(runs: int, seed: int, perturbation: Perturbation, contacts: int = 0,
              softness: SoftnessRanges | None = None) -> tuple[RunDraw, ...]:
    """The ``runs`` draws of a study: run :math:`i` draws from ``SeedSequence(seed).spawn(runs)[i]``, so a run's
    draw does not depend on how many runs there are or who runs them. ``contacts``: the fingers to draw a
    placement error for; ``softness``: the ranges to draw the contacts' softness from (None: none drawn; drawn
    after the rest, so that the model errors are the same with and without)."""
    runs = as_count("runs", runs, 1, MAX_RUNS)
    seed = as_count("seed", seed, 0, MAX_SEED)
    expect_type("perturbation", perturbation, Perturbation, "a Perturbation")
    contacts = as_count("contacts", contacts, 0, MAX_CONTACTS)
    if softness is not None:
        expect_type("softness", softness, SoftnessRanges, "a SoftnessRanges (regrasp.model.softness)")
    p = perturbation
    out = []
    for i, child in enumerate(np.random.SeedSequence(seed).spawn(runs)):
        rng = np.random.default_rng(child)
        mass, mu, inertia, links = rng.uniform(-1.0, 1.0, 4).tolist()  # (the order of the first studies)
        kinetic = float(rng.uniform(-1.0, 1.0))
        offsets = rng.uniform(-1.0, 1.0, contacts) * p.contact_position
        errors = ModelErrors(mass_scale=1.0 + p.mass * mass, mu_scale=1.0 + p.mu * mu,
                             inertia_scale=1.0 + p.inertia * inertia, link_mass_scale=1.0 + p.link_mass * links,
                             mu_kinetic_scale=1.0 + p.mu_kinetic * kinetic, xi_offset=tuple(offsets.tolist()))
        soft = None if softness is None else softness.draw(rng)
        out.append(RunDraw(i, tuple(int(w) for w in child.generate_state(4)), errors, soft))
    return tuple(out)

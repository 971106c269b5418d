"""A suite's variants, drawn: variant i's values from ``SeedSequence(seed).spawn(variants)[i]``
(:func:`draw_variant`), set on a copy of the base scenario's TOML document
(:func:`~regrasp.suite.document.apply_values`) and built by the scenario's own validation (:func:`variant_scenario`,
:func:`~regrasp.model.scenario.scenario_from_document`).

A variant depends only on the spec and its index: not on how many variants there are beyond it, nor on who draws it,
in what order (its generator is ``SeedSequence(seed, spawn_key=(i,))``, the i-th child ``spawn`` gives).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..core.validation import as_count
from .document import apply_values
from .spec import SuiteSpec

if TYPE_CHECKING:
    from ..model.scenario import Scenario

__all__ = ["Variant", "draw_variant", "variant_scenario"]


@dataclass(frozen=True)
class Variant:
    """One variant of a suite, drawn.

    Attributes:
        index: Its number in the suite (0-based).
        entropy: Its seed, as its ``SeedSequence``'s words (``SeedSequence(list(entropy))`` seeds its rollout).
        values: Each varied key's drawn value, in the spec's order: (key, value) pairs.
        document: The scenario's TOML document with those values (a dict, as :mod:`tomllib` gives it).
    """

    index: int
    entropy: tuple[int, ...]
    values: tuple[tuple[str, object], ...]
    document: dict

    @property
    def parameters(self) -> dict[str, object]:
        """The drawn values by key."""
        return dict(self.values)


def draw_variant(spec: SuiteSpec, index: int) -> Variant:
    """Variant ``index`` of ``spec`` (module docstring): its values drawn in the spec's order, set on the base's
    document, named ``<base name> variant <index>``."""
    index = as_count("index", index, 0, spec.variants - 1)
    child = np.random.SeedSequence(spec.seed, spawn_key=(index,))
    rng = np.random.default_rng(child)
    drawn = [(v, v.draw(rng)) for v in spec.varied]
    document = apply_values(spec.base, [(v.key, v.path, x) for v, x in drawn], spec.where)
    base_name = document.get("name", spec.scenario.stem)
    document["name"] = f"{base_name} variant {index}"
    return Variant(index, tuple(int(w) for w in child.generate_state(4)), tuple((v.key, x) for v, x in drawn),
                   document)


def variant_scenario(spec: SuiteSpec, variant: Variant) -> Scenario:
    """The variant's scenario, built and validated by :func:`~regrasp.model.scenario.scenario_from_document` as a
    file next to the base scenario (its relative URDF paths are the base's)."""
    from ..model.scenario import scenario_from_document

    return scenario_from_document(copy.deepcopy(variant.document), spec.scenario)

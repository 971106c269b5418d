r"""A suite's spec (TOML): a base scenario, and the ranges and choices its variants are drawn from.

.. code-block:: toml

    name = "default"                                   # (default: the file's stem)
    description = "..."
    scenario = "../scenarios/paper_trajectory_2_three_fingers.toml"   # the base, relative to this file
    variants = 120                                     # how many variants
    seed = 1                                           # variant i draws from SeedSequence(seed).spawn(variants)[i]

    [vary]                                             # scenario key -> how it is drawn
    "object.width" = [0.08, 0.11]                      # uniform in [lo, hi]
    "trajectory.omega" = {uniform = [1.5, 3.0]}        # the same, spelled out
    "fingers.palm.base.0" = [0.02, 0.04]               # an array's component: its index (the palm's base x)
    "fingers.finger1.edge" = {choices = [1]}           # one of a list, each as likely
    "hand.gravity_angle" = [-0.2, 0.2]                 # gravity turned by this angle [rad], counter-clockwise

    [[vary.trajectory.choices]]                        # a whole table to choose (an inline table stays on one line)
    type = "ellipse"
    cx = 0.0
    cy = 0.12
    a = 0.09
    b = 0.05
    omega = {uniform = [1.5, 3.0]}                     # a range inside a chosen table is drawn too

A key of ``[vary]`` is a path into the scenario's TOML document (:mod:`regrasp.model.scenario`, every key in
``docs/scenario.md``): its tables and keys joined by dots, a finger by its name or index (``fingers.palm``,
``fingers.2``), an array's entry by its index (``hand.gravity.1``); ``fingers`` alone replaces the whole list (a
choice of lists of finger tables: the number of fingers). ``hand.gravity_angle`` is the one key that is no
scenario key: it turns the base scenario's gravity. A finger's ``urdf`` given here is relative to the spec's file.

Whole tables are set before the keys inside them, whatever the spec's order. Every value a key can take (both ends of
a range, every choice) is checked when the spec is read, through the scenario's own validation: a bad key, a bad
value, a missing URDF is a :class:`~regrasp.core.exceptions.ScenarioError` naming the spec's file and key.
"""

from __future__ import annotations

import copy
import datetime
import difflib
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core.exceptions import InvalidParameterError, ScenarioError, short_repr
from ..core.validation import MAX_RUNS, MAX_SEED, as_count, expect_type, file_problem, read_toml
from .document import GRAVITY_ANGLE, apply_values

__all__ = ["GRAVITY_ANGLE", "ROOTS", "SuiteSpec", "Varied", "load_suite_spec"]

#: The scenario's tables a ``[vary]`` key may start with.
ROOTS = ("object", "trajectory", "hand", "fingers", "planner", "pad", "study")
#: A spec's top-level keys.
_TOP = ("name", "description", "scenario", "variants", "seed", "vary")
#: The keys of a drawn value's table: ``{uniform = [lo, hi]}`` or ``{choices = [...]}``.
_NODES = ("uniform", "choices")
_FORMS = "a range [lo, hi] (two numbers), {uniform = [lo, hi]} or {choices = [value, ...]}"


def _is_node(value: object) -> bool:
    return isinstance(value, dict) and any(k in value for k in _NODES)


def _finite_number(value: object) -> bool:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:
        return False


@dataclass(frozen=True)
class Varied:
    """One varied key: uniform in [``low``, ``high``], or one of ``choices`` (each as likely).

    Attributes:
        key: The key, as the spec names it (``"object.width"``).
        path: The key's parts: table and key names, and indices (ints) into arrays and the fingers.
        low: The range's lower end (None: a choice).
        high: Its upper end (None: a choice).
        choices: The values to choose from (None: a range); a value may hold ranges and choices of its own.
    """

    key: str
    path: tuple[str | int, ...]
    low: float | None = None
    high: float | None = None
    choices: tuple | None = None

    def draw(self, rng: np.random.Generator) -> object:
        """A value drawn with ``rng``: a float of the range, or a choice (its own ranges and choices drawn)."""
        if self.choices is None:
            return float(rng.uniform(self.low, self.high))
        return settle(self.choices[int(rng.integers(len(self.choices)))], rng)

    def ends(self) -> list:
        """The values to check the key with: both ends of the range, or every choice (its own ranges at both ends)."""
        if self.choices is None:
            return [self.low, self.high]
        return [settle(c, end) for c in self.choices for end in ("low", "high")]

    def describe(self) -> str:
        """``U(lo, hi)`` or ``one of N``."""
        if self.choices is None:
            return f"U({self.low:g}, {self.high:g})"
        return f"one of {len(self.choices)}"

    @property
    def numeric(self) -> bool:
        """Whether every value it takes is a number (a range, or choices of numbers)."""
        return self.choices is None or all(_finite_number(c) for c in self.choices)


def settle(value: object, pick: np.random.Generator | str) -> object:
    """``value`` with the ranges and choices inside it drawn with ``pick`` (a generator), or set to their ``"low"``
    or ``"high"`` end (a choice: its first value)."""
    if _is_node(value):
        if "uniform" in value:
            lo, hi = value["uniform"]
            if isinstance(pick, str):
                return float(lo if pick == "low" else hi)
            return float(pick.uniform(lo, hi))
        options = value["choices"]
        chosen = options[0] if isinstance(pick, str) else options[int(pick.integers(len(options)))]
        return settle(chosen, pick)
    if isinstance(value, dict):
        return {k: settle(v, pick) for k, v in value.items()}
    if isinstance(value, list):
        return [settle(v, pick) for v in value]
    return value


@dataclass(frozen=True)
class SuiteSpec:
    """A suite: a base scenario and how its variants are drawn (:func:`load_suite_spec` reads one from TOML).

    Attributes:
        name: The suite's name.
        scenario: The base scenario's file.
        base: The base scenario's TOML document (a dict; each variant is a copy with its drawn values).
        varied: The varied keys, in the spec's order (the order they are drawn in).
        variants: How many variants (1 to ``MAX_RUNS``).
        seed: The suite's seed: variant i draws from ``SeedSequence(seed).spawn(variants)[i]``.
        path: The spec's file (None: built in code).
        description: Free text.
    """

    name: str
    scenario: Path
    base: dict = field(repr=False)
    varied: tuple[Varied, ...]
    variants: int
    seed: int = 0
    path: Path | None = None
    description: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise InvalidParameterError("name", self.name, "a non-empty string")
        object.__setattr__(self, "scenario", Path(expect_type("scenario", self.scenario, (str, Path),
                                                              "the base scenario's path")))
        expect_type("base", self.base, dict, "the base scenario's TOML document (a dict)")
        varied = tuple(expect_type("varied", self.varied, (tuple, list), "a sequence of Varied"))
        for v in varied:
            expect_type("varied", v, Varied, "a sequence of Varied")
        object.__setattr__(self, "varied", varied)
        object.__setattr__(self, "variants", as_count("variants", self.variants, 1, MAX_RUNS))
        object.__setattr__(self, "seed", as_count("seed", self.seed, 0, MAX_SEED))
        if self.path is not None:
            object.__setattr__(self, "path", Path(expect_type("path", self.path, (str, Path), "a path or None")))
        expect_type("description", self.description, str, "a string")

    @property
    def where(self) -> str:
        """The spec's file (or its name) for messages."""
        return str(self.path) if self.path is not None else f"<suite {self.name}>"


def _fail(path: Path, key: str | None, expected: str) -> ScenarioError:
    return ScenarioError(path, key, expected)


def _parts(path: Path, key: str) -> tuple[str | int, ...]:
    """A ``[vary]`` key's parts (indices as ints); its first part must be one of :data:`ROOTS`."""
    parts = key.split(".")
    if any(not p for p in parts):
        raise _fail(path, f"vary.{key}", "expected a dotted scenario key such as 'object.width' (an empty part)")
    if parts[0] not in ROOTS:
        near = difflib.get_close_matches(parts[0], ROOTS, n=1)
        raise _fail(path, f"vary.{key}", f"expected a key in one of the scenario's tables ({', '.join(ROOTS)})"
                    + (f" ({near[0]!r}: a typo?)" if near else ""))
    return tuple(int(p) if p.isdigit() else p for p in parts)


def _flatten(table: dict, prefix: str = "") -> list[tuple[str, object]]:
    """``[vary]``'s keys as dotted paths: a nested table (``[vary.object]``) is a path, a drawn value a leaf."""
    out = []
    for k, v in table.items():
        if isinstance(v, dict) and not _is_node(v):
            out += _flatten(v, f"{prefix}{k}.")
        else:
            out.append((f"{prefix}{k}", v))
    return out


def _range(path: Path, key: str, value: object) -> tuple[float, float]:
    if not isinstance(value, list) or len(value) != 2 or not all(_finite_number(v) for v in value):
        raise _fail(path, key, f"expected a range [lo, hi] of two finite numbers, got {short_repr(value)}")
    lo, hi = float(value[0]), float(value[1])
    if lo > hi:
        raise _fail(path, key, f"expected lo <= hi in [lo, hi], got [{value[0]!r}, {value[1]!r}] (an empty range)")
    return lo, hi


def _checked(path: Path, key: str, value: object, urdf: bool) -> object:
    """A choice's value: plain TOML (no dates), its ranges and choices checked, its URDF paths (``urdf``: the value
    is one; or under a key ``urdf``) made absolute from the spec's folder and checked to exist."""
    if isinstance(value, (datetime.date, datetime.time)):
        raise _fail(path, key, f"expected numbers, strings, booleans, arrays or tables, got {short_repr(value)}")
    if _is_node(value):
        extra = sorted(set(value) - {"uniform"}) if "uniform" in value else sorted(set(value) - {"choices"})
        if extra:
            raise _fail(path, f"{key}.{extra[0]}", f"unknown key: expected {_FORMS}")
        if "uniform" in value:
            return {"uniform": list(_range(path, f"{key}.uniform", value["uniform"]))}
        return {"choices": list(_choices(path, f"{key}.choices", value["choices"], urdf))}
    if isinstance(value, dict):
        return {k: _checked(path, f"{key}.{k}", v, k == "urdf") for k, v in value.items()}
    if isinstance(value, list):
        return [_checked(path, f"{key}[{i}]", v, urdf) for i, v in enumerate(value)]
    if urdf:
        if not isinstance(value, str):
            raise _fail(path, key, f"expected a URDF file's path, got {short_repr(value)}")
        file = Path(value) if Path(value).is_absolute() else path.parent / value
        problem = file_problem(file, "URDF file")
        if problem is not None:
            raise _fail(path, key, f"{problem}: {file}")
        return str(file.resolve())
    return value


def _choices(path: Path, key: str, value: object, urdf: bool) -> tuple:
    if not isinstance(value, list) or not value:
        raise _fail(path, key, f"expected a non-empty list of values to choose from, got {short_repr(value)}")
    return tuple(_checked(path, f"{key}[{i}]", v, urdf) for i, v in enumerate(value))


def _varied(path: Path, key: str, value: object) -> Varied:
    """One ``[vary]`` entry, checked (not yet against the scenario: :func:`load_suite_spec` does that)."""
    parts = _parts(path, key)
    where = f"vary.{key}"
    if key == GRAVITY_ANGLE and not (isinstance(value, list) or (isinstance(value, dict) and "uniform" in value)):
        raise _fail(path, where, f"expected a range of angles [lo, hi] [rad], got {short_repr(value)}")
    if isinstance(value, list):
        return Varied(key, parts, *_range(path, where, value))
    if not _is_node(value):
        raise _fail(path, where, f"expected {_FORMS}, got {short_repr(value)}")
    value = _checked(path, where, value, parts[-1] == "urdf")
    if "uniform" in value:
        return Varied(key, parts, *value["uniform"])
    return Varied(key, parts, choices=tuple(value["choices"]))


def _integer(path: Path, data: dict, key: str, least: int, most: int) -> int:
    value = data[key]
    if isinstance(value, bool) or not isinstance(value, int) or not least <= value <= most:
        raise _fail(path, key, f"expected an integer in [{least}, {most}], got {short_repr(value)}")
    return value


def load_suite_spec(path: str | Path) -> SuiteSpec:
    """Read and check a suite's spec (module docstring); a :class:`~regrasp.core.exceptions.ScenarioError` naming the
    file and key for anything wrong, the values of every varied key checked through the scenario's validation."""
    path, data = read_toml(path, "suite spec")
    for key in data:
        if key not in _TOP:
            near = difflib.get_close_matches(key, _TOP, n=1)
            raise _fail(path, key, "unknown key (a spec has " + ", ".join(_TOP) + ")"
                        + (f"; {near[0]!r}: a typo?" if near else ""))
    for key in ("name", "description"):
        if key in data and not (isinstance(data[key], str) and (data[key] or key == "description")):
            raise _fail(path, key, f"expected a {'non-empty ' if key == 'name' else ''}string, "
                                   f"got {short_repr(data[key])}")
    if "scenario" not in data:
        raise _fail(path, "scenario", "this key is required: the base scenario's file, relative to the spec")
    if not isinstance(data["scenario"], str):
        raise _fail(path, "scenario", f"expected a scenario file's path, got {short_repr(data['scenario'])}")
    scenario = Path(data["scenario"])
    scenario = (scenario if scenario.is_absolute() else path.parent / scenario).resolve()
    problem = file_problem(scenario, "scenario file")
    if problem is not None:
        raise _fail(path, "scenario", f"{problem}: {scenario}")
    try:
        base = tomllib.loads(scenario.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise _fail(path, "scenario", f"{scenario} is not valid TOML: {exc}") from exc
    if "variants" not in data:
        raise _fail(path, "variants", "this key is required: how many variants to draw")
    variants = _integer(path, data, "variants", 1, MAX_RUNS)
    seed = _integer(path, data, "seed", 0, MAX_SEED) if "seed" in data else 0
    vary = data.get("vary", {})
    if not isinstance(vary, dict):
        raise _fail(path, "vary", f"expected a table [vary] of scenario keys, got {short_repr(vary)}")
    varied = tuple(_varied(path, key, value) for key, value in _flatten(vary))
    spec = SuiteSpec(data.get("name", path.stem), scenario, base, varied, variants, seed, path,
                     data.get("description", ""))
    _check_against_scenario(spec)
    return spec


def _check_against_scenario(spec: SuiteSpec) -> None:
    """Every value each varied key can take (:meth:`Varied.ends`), set alone on the base scenario, makes a valid
    scenario; else a ScenarioError naming the spec's file and the key."""
    from ..model.scenario import scenario_from_document

    scenario_from_document(copy.deepcopy(spec.base), spec.scenario)  # (the base itself first)
    for v in spec.varied:
        for value in v.ends():
            document = apply_values(spec.base, [(v.key, v.path, value)], spec.where)
            try:
                scenario_from_document(document, spec.scenario)
            except ScenarioError as exc:
                raise ScenarioError(spec.where, f"vary.{v.key}", f"with {v.key} = {short_repr(value)} the scenario is "
                                    f"not valid: {exc.key or 'the document'}: {exc.expected}") from exc

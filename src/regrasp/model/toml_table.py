"""Typed access to one TOML table of a scenario file, with errors that name the file and the key
(:class:`TableReader`), and :func:`wrap_errors`, which turns a library error raised while building from a table
into such an error."""

from __future__ import annotations

import difflib
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from ..core.exceptions import InvalidParameterError, RegraspError, ScenarioError, TrajectoryError, short_repr
from ..core.validation import as_finite_array

__all__ = ["TableReader", "wrap_errors"]

_T = TypeVar("_T")


def _finite(value: int | float) -> bool:
    """Whether a TOML number is a finite float (an integer too large for a float is not)."""
    try:
        return math.isfinite(value)
    except OverflowError:
        return False


class TableReader:
    """Typed access to one TOML table with error messages that name the key."""

    def __init__(self, path: Path, table: dict, prefix: str):
        self.path, self.table, self.prefix = path, table, prefix
        self.used: set[str] = set()

    def key(self, name: str) -> str:
        return f"{self.prefix}{name}"

    def fail(self, name: str | None, expected: str) -> ScenarioError:
        return ScenarioError(self.path, self.key(name) if name else self.prefix.rstrip(".") or None, expected)

    def has(self, name: str) -> bool:
        return name in self.table

    def get(self, name: str, default: Any = ...) -> Any:
        self.used.add(name)
        if name not in self.table:
            if default is ...:
                near = difflib.get_close_matches(name, [k for k in self.table if isinstance(k, str)], n=1)
                raise self.fail(name, "this key is required"
                                + (f" (the table has {near[0]!r}: a typo?)" if near else ""))
            return default
        return self.table[name]

    def number(self, name: str, default: Any = ...) -> float:
        value = self.get(name, default)
        if value is None:
            return value
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not _finite(value):
            raise self.fail(name, f"expected a finite number, got {short_repr(value)}")
        return float(value)

    def integer(self, name: str, default: Any = ...) -> int:
        value = self.get(name, default)
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.fail(name, f"expected an integer, got {value!r}")
        return value

    def string(self, name: str, default: Any = ..., choices: tuple[str, ...] | None = None) -> str:
        value = self.get(name, default)
        if not isinstance(value, str):
            raise self.fail(name, f"expected a string, got {value!r}")
        if choices is not None and value not in choices:
            raise self.fail(name, f"expected one of {', '.join(repr(c) for c in choices)}, got {value!r}")
        return value

    def array(self, name: str, shape: tuple[int, ...], default: Any = ...) -> np.ndarray:
        value = self.get(name, default)
        want = "x".join("n" if s == -1 else str(s) for s in shape)
        try:
            arr = as_finite_array(self.key(name), value)
        except InvalidParameterError as exc:
            raise self.fail(name, f"expected an array of finite numbers of shape ({want}), got {short_repr(value)} "
                                  f"({exc.expected})") from None
        if arr.ndim != len(shape) or any(s not in (-1, a) for s, a in zip(shape, arr.shape)):
            raise self.fail(name, f"expected an array of numbers of shape ({want}), got {short_repr(value)}")
        return arr

    def finish(self) -> None:
        extra = sorted(set(self.table) - self.used)
        if extra:
            raise ScenarioError(self.path, self.key(extra[0]), "unknown key (check its spelling and section)")


def wrap_errors(reader: TableReader, name: str | None, build: Callable[[], _T]) -> _T:
    """Run ``build()`` and turn a library error into a ScenarioError naming the key."""
    try:
        return build()
    except ScenarioError:
        raise
    except RegraspError as exc:
        param = getattr(exc, "name", None)
        if isinstance(exc, (InvalidParameterError, TrajectoryError)) and param in reader.table:
            name = param  # e.g. a negative mass is reported at object.mass, waypoints too close at trajectory.times
        raise reader.fail(name, str(exc)) from exc



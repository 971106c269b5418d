"""Argument checks that raise typed errors (never ``assert``): the one validation layer of the library.

A *number* is an int or a float (Python's or numpy's), never a bool, a string, bytes or a complex
number: ``float(True)``, ``float("2")`` and ``float(1 + 0j)``-style conversions that would silently
accept them are refused, and so is an integer too large for a float (``10**400``).
"""

from __future__ import annotations

import math
import os
import tempfile
import tomllib
from collections.abc import Callable, Iterable, Mapping
from collections.abc import Set as AbstractSet
from pathlib import Path
from typing import TypeVar

import numpy as np

from .exceptions import InvalidParameterError, ScenarioError

_NOT_NUMBERS = (bool, np.bool_, str, bytes, complex, np.complexfloating)
_NUMBER_KINDS = frozenset("iuf")

_T = TypeVar("_T")


def _has_non_numbers(value) -> bool:
    """Whether ``value`` (a scalar, a nested list/tuple or an array) holds a bool, a string, bytes, a
    complex number or None anywhere."""
    if isinstance(value, np.ndarray):
        if value.dtype.kind in _NUMBER_KINDS:
            return False
        if value.dtype.kind != "O":
            return True
        return any(_has_non_numbers(v) for v in value.reshape(-1).tolist())
    if isinstance(value, (list, tuple)):
        return any(_has_non_numbers(v) for v in value)
    return value is None or isinstance(value, _NOT_NUMBERS)


def as_number_array(name: str, value: object, shape: tuple[int, ...] | None = None) -> np.ndarray:
    """``value`` as a float array of the given shape (-1: any length) of numbers (no bool, string or complex
    entries; NaN and inf are numbers here: :func:`as_finite_array` refuses them)."""
    if _has_non_numbers(value):
        raise InvalidParameterError(name, value, "an array of numbers (no booleans, strings or complex numbers)")
    try:
        arr = np.array(value, dtype=float)
    except OverflowError as exc:
        raise InvalidParameterError(name, value, "finite numbers (an integer too large for a float)") from exc
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError(name, value, "an array of numbers") from exc
    if shape is not None:
        if len(shape) != arr.ndim or any(s != -1 and s != a for s, a in zip(shape, arr.shape)):
            want = "x".join("n" if s == -1 else str(s) for s in shape)
            raise InvalidParameterError(name, value, f"an array of shape ({want})")
    return arr


def as_finite_array(name: str, value: object, shape: tuple[int, ...] | None = None) -> np.ndarray:
    """``value`` as a float array of the given shape with only finite entries (numbers only: no bool,
    string or complex entries)."""
    arr = as_number_array(name, value, shape)
    if not np.all(np.isfinite(arr)):
        raise InvalidParameterError(name, value, "finite numbers (no NaN or inf)")
    return arr


def as_finite_float(name: str, value: object) -> float:
    """``value`` as a finite float (a number: not a bool, a string or a complex number)."""
    if type(value) is float and value - value == 0.0:  # the common case first (NaN and inf fail the test)
        return value
    if isinstance(value, _NOT_NUMBERS) or value is None or (isinstance(value, np.ndarray) and value.ndim > 0):
        raise InvalidParameterError(name, value, "a number")
    try:
        out = float(value)
    except OverflowError as exc:
        raise InvalidParameterError(name, value, "a finite number (an integer too large for a float)") from exc
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError(name, value, "a number") from exc
    if not np.isfinite(out):
        raise InvalidParameterError(name, value, "a finite number")
    return out


def as_positive_float(name: str, value: object, *, allow_zero: bool = False) -> float:
    """``value`` as a finite float > 0 (or >= 0 with ``allow_zero``)."""
    out = as_finite_float(name, value)
    if out < 0.0 or (out == 0.0 and not allow_zero):
        raise InvalidParameterError(name, value, ">= 0" if allow_zero else "> 0")
    return out


def as_finite_vectors(names: tuple[str, ...], values: tuple, n: int) -> np.ndarray:
    """The ``values`` as the rows of one (len(values), n) float array, all checked at once (hot paths).

    Raises the error :func:`as_finite_array` raises for the first bad value, in order.
    """
    try:
        arr = np.array(values, dtype=float)
    except (TypeError, ValueError):
        arr = None
    # a sum is finite when every entry is (a finite sum that overflows only takes the slow path)
    if arr is None or arr.shape != (len(values), n) or not math.isfinite(sum(arr.reshape(-1).tolist())):
        arr = np.array([as_finite_array(name, value, (n,)) for name, value in zip(names, values)])
    return arr


#: The most time samples a plan may ask for: 100 000 samples of 2 fingers at about 70 µs (``urdf``)
#: is about 4 min and 0.3 GB of envelopes; more is a mistake, not a plan.
MAX_SAMPLES = 100_000


def as_sample_count(name: str, value: object) -> int:
    """``value`` as a number of time samples: an integer in [2, :data:`MAX_SAMPLES`]."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise InvalidParameterError(name, value, f"an integer number of samples in [2, {MAX_SAMPLES}]")
    if not 2 <= value <= MAX_SAMPLES:
        raise InvalidParameterError(name, value, f"an integer number of samples in [2, {MAX_SAMPLES}]")
    return int(value)


#: The longest simulated run [s]: an hour is 3.6 million 1 ms steps (about 3 h of wall time today).
MAX_DURATION = 3600.0


def _positive_at_most(name: str, value: object, limit: float, expected: str) -> float:
    """``value`` as a float in (0, ``limit``], else an error saying ``expected``."""
    out = as_positive_float(name, value)
    if out > limit:
        raise InvalidParameterError(name, value, expected)
    return out


def as_duration(name: str, value: object) -> float:
    """``value`` as a simulated duration [s]: a number in (0, :data:`MAX_DURATION`]."""
    return _positive_at_most(name, value, MAX_DURATION, f"a duration of at most {MAX_DURATION:g} s")


def step_count(name: str, duration: float, dt: float) -> int:
    """The control steps a run of ``duration`` [s] takes at the step ``dt`` [s] (``round(duration / dt)``), or an
    :class:`InvalidParameterError` naming ``name`` for a run shorter than one step (it would run none, and report
    nothing): the one check every run makes of its length."""
    if not duration >= dt * (1.0 - 1e-9):
        raise InvalidParameterError(name, duration, f"a run of at least one control step ({dt:g} s)")
    return int(round(duration / dt))


def expect_type(name: str, value: _T, kind: type | tuple[type, ...], what: str) -> _T:
    """``value`` if it is an instance of ``kind``, else an :class:`InvalidParameterError` saying ``what``
    was expected (the check every public entry point makes of its structured arguments)."""
    if not isinstance(value, kind):
        raise InvalidParameterError(name, value, what)
    return value


def check_fields(instance: object, check: Callable[..., object], names: Iterable[str], *args: object,
                 optional: bool = False, **options: object) -> None:
    """Set each field ``name`` of the frozen dataclass ``instance`` to ``check(name, value, *args, **options)``
    (a None left as it is when ``optional``): how a settings type checks, and normalises, its fields on
    construction (``check_fields(self, as_count, ("every",), 1)``)."""
    for name in names:
        value = getattr(instance, name)
        if not (optional and value is None):
            object.__setattr__(instance, name, check(name, value, *args, **options))


def expect_sequence_of(name: str, values: object, kind: type, what: str) -> tuple:
    """``values`` as a tuple whose items are all instances of ``kind`` (a list, a tuple...; not a string, nor a
    mapping or a set, whose order is not the caller's)."""
    if isinstance(values, (str, bytes, Mapping, AbstractSet)) or not hasattr(values, "__iter__"):
        raise InvalidParameterError(name, values, f"a sequence of {what}")
    out = tuple(values)
    for v in out:
        if not isinstance(v, kind):
            raise InvalidParameterError(name, values, f"a sequence of {what} (got a {type(v).__name__})")
    return out


def expect_choices(name: str, values: object, choices: frozenset[str], what: str) -> tuple[str, ...]:
    """``values`` as a tuple of strings, each one of ``choices`` (a list, a tuple, a set...; not a string, None or
    another object): a plant's ``stop_on`` kinds, for example."""
    expected = f"a sequence of {what} ({', '.join(sorted(choices))})"
    if isinstance(values, (str, bytes)) or not hasattr(values, "__iter__"):
        raise InvalidParameterError(name, values, expected)
    out = tuple(values)
    if not all(isinstance(v, str) and v in choices for v in out):
        raise InvalidParameterError(name, values, expected)
    return out


def file_problem(path: Path, what: str = "file") -> str | None:
    """Why ``path`` cannot be read as a file (``"<what> not found"``, ``"not a usable file name (...)"`` for a
    name too long for the file system or with a NUL byte), or None when it is a file."""
    try:
        found = Path(path).is_file()
    except (OSError, ValueError) as exc:
        reason = getattr(exc, "strerror", None) or str(exc)
        return f"not a usable file name ({type(exc).__name__}: {reason})"
    return None if found else f"{what} not found"


def read_toml(path: str | Path, what: str = "file") -> tuple[Path, dict]:
    """(``path``, its TOML document), or a :class:`~regrasp.core.exceptions.ScenarioError` naming the file: not a path
    (``InvalidParameterError``), not a file (:func:`file_problem`, ``what`` naming it), or not valid TOML."""
    if not isinstance(path, (str, Path)):
        raise InvalidParameterError("path", path, f"a {what}'s path (str or pathlib.Path)")
    path = Path(path)
    problem = file_problem(path, what)
    if problem is not None:
        raise ScenarioError(path, None, problem)
    try:
        return path, tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ScenarioError(path, None, f"not valid TOML: {exc}") from exc


#: The longest name of one path component [bytes] where the file system does not say (NAME_MAX on Linux and macOS),
#: and the longest path [bytes] (Linux's PATH_MAX).
NAME_MAX = 255
PATH_MAX = 4096


def _existing_ancestor(path: Path) -> Path:
    """``path`` or its nearest ancestor that exists (an absolute path: the root at worst)."""
    for candidate in (path, *path.parents):
        try:
            if candidate.exists():
                return candidate
        except (OSError, ValueError):  # (a component too long, a loop: look higher)
            continue
    return Path(path.anchor)


def _name_max(directory: Path) -> int:
    try:
        return int(os.pathconf(directory, "PC_NAME_MAX"))
    except (OSError, ValueError, AttributeError, TypeError):  # (no pathconf on Windows, or no such limit)
        return NAME_MAX


def _unwritable(directory: Path) -> str | None:
    """Why no file can be made in ``directory``, or None: a file is made there and removed (permissions alone do not
    say: root may write anywhere but on a read-only file system or /proc)."""
    if not directory.is_dir():
        return f"{directory} is not a directory"
    try:
        fd, probe = tempfile.mkstemp(prefix=".regrasp-write-check-", dir=directory)
    except OSError as exc:
        return f"no file can be made in {directory} ({exc.strerror or exc})"
    os.close(fd)
    try:
        os.unlink(probe)
    except OSError:  # pragma: no cover (made a moment ago)
        pass
    return None


def output_path_problem(path: object, *, directory: bool = False) -> str | None:
    """Why ``path`` cannot be written, or None: a file (its directory exists and takes a new file; it is not a
    directory itself) or, with ``directory``, a directory to write files into (a directory, or a path that can be
    made one: its nearest existing ancestor takes a new entry). Checked: a str or ``os.PathLike``, not empty, no NUL
    byte, each name at most the file system's ``NAME_MAX`` bytes and the whole at most :data:`PATH_MAX`. The
    output-side twin of :func:`file_problem`."""
    try:
        text = os.fspath(path) if isinstance(path, (str, os.PathLike)) else None
    except TypeError:
        text = None
    if not isinstance(text, str):
        return "not a path (a str or an os.PathLike)"
    if not text:
        return "an empty path"
    if "\0" in text:
        return "a NUL byte in the name"
    try:
        target = Path(os.path.abspath(text))
        if len(os.fsencode(str(target))) > PATH_MAX:
            return f"a path longer than {PATH_MAX} bytes"
        existing = _existing_ancestor(target)
        limit = _name_max(existing)
        for part in target.parts:
            if len(os.fsencode(part)) > limit:
                return f"a name of {len(os.fsencode(part))} bytes (the file system takes at most {limit})"
        if directory:
            if existing == target and not target.is_dir():
                return "it is a file"
            return _unwritable(existing)
        if target.is_dir():
            return "it is a directory"
        if existing != target and existing != target.parent:
            return f"its directory {target.parent} does not exist"
        if target.exists() and not os.access(target, os.W_OK):
            return "an existing file that cannot be written"
        return _unwritable(target.parent)
    except (OSError, ValueError) as exc:
        return f"not a usable path ({type(exc).__name__}: {getattr(exc, 'strerror', None) or exc})"


def _path_text(value: object) -> object:
    """A path as text for an error message (a Path's repr is longer), anything else as it is."""
    return os.fspath(value) if isinstance(value, os.PathLike) else value


def as_output_path(name: str, value: object) -> Path:
    """``value`` as the path of a file to write (:func:`output_path_problem`), checked before any work, else an
    :class:`InvalidParameterError` naming ``name`` and saying why."""
    problem = output_path_problem(value)
    if problem is not None:
        raise InvalidParameterError(name, _path_text(value), f"a writable file path in an existing directory "
                                    f"({problem})")
    return Path(os.fspath(value))


def as_output_directory(name: str, value: object) -> Path:
    """``value`` as a directory to write files into, existing or to be made (:func:`output_path_problem`), else an
    :class:`InvalidParameterError` naming ``name``."""
    problem = output_path_problem(value, directory=True)
    if problem is not None:
        raise InvalidParameterError(name, _path_text(value), f"a directory that can be written ({problem})")
    return Path(os.fspath(value))


def as_integer(name: str, value: object, least: int = 0) -> int:
    """``value`` as an int >= ``least`` (an integer, Python's or numpy's; not a bool, a float or a string)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or value < least:
        raise InvalidParameterError(name, value, f"an integer >= {least}")
    return int(value)


#: The largest count (of periods, substeps, candidates, re-plans, steps between samples...) a setting takes: far
#: above any useful value, and low enough that a product of two counts stays an exact float.
MAX_COUNT = 10**6


#: The most runs one study takes, and the most worker processes (or a local Ray cluster's CPUs) it runs them on (far
#: more than any machine's cores).
MAX_RUNS = 100_000
MAX_WORKERS = 1024

#: The largest seed a run or a study takes: 128 bits, as much as a ``numpy.random.SeedSequence``'s entropy holds.
MAX_SEED = 2**128 - 1


def as_count(name: str, value: object, least: int = 0, most: int = MAX_COUNT) -> int:
    """``value`` as an int in [``least``, ``most``] (Python's or numpy's integer; not a bool, a float, a NaN or
    a string): the one check of every count a setting or a command line takes."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) \
            or not least <= value <= most:
        raise InvalidParameterError(name, value, f"an integer in [{least}, {most}]")
    return int(value)


def as_flag(name: str, value: object) -> bool:
    """``value`` if it is True or False (Python's or numpy's), else an error (no truthiness of other values)."""
    if not isinstance(value, (bool, np.bool_)):
        raise InvalidParameterError(name, value, "True or False")
    return bool(value)


def as_name(name: str, value: object) -> str:
    """``value`` as a non-empty string (a finger's, a frame's name)."""
    if not isinstance(value, str) or not value:
        raise InvalidParameterError(name, value, "a non-empty string")
    return value


#: The heaviest object or link [kg], and the largest rotational inertia [kg m^2], a hand model takes: far above any
#: hand's (a test models an immovable wall as 1e9 kg), and low enough that forces (mass times gravity or
#: acceleration) stay far from overflow.
MAX_MASS = 1e12
MAX_INERTIA = 1e12


def as_mass(name: str, value: object) -> float:
    """``value`` as a mass [kg] in (0, :data:`MAX_MASS`]."""
    return _positive_at_most(name, value, MAX_MASS, f"a mass of at most {MAX_MASS:g} kg")


def as_inertia(name: str, value: object) -> float:
    """``value`` as a rotational inertia [kg m^2] in (0, :data:`MAX_INERTIA`]."""
    return _positive_at_most(name, value, MAX_INERTIA, f"an inertia of at most {MAX_INERTIA:g} kg m^2")


#: The largest position [m], angle [rad] and speed [m/s or rad/s] a mechanical state takes (a hand's joints, an
#: object's pose and twist): far beyond any hand's (a workspace of a kilometre, a thousand turns, a motor at 100 000
#: rpm is 1e4 rad/s), and low enough that an angle's sine stays precise (q1 + q2 finite) and squares of speeds
#: (kinetic energies, Coriolis terms) stay far from overflow.
MAX_POSITION = 1e3
MAX_ANGLE = 1e4
MAX_SPEED = 1e4


def as_bounded_array(name: str, value: object, shape: tuple[int, ...], limit: float | tuple[float, ...],
                     unit: str) -> np.ndarray:
    """:func:`as_finite_array` with every entry's magnitude at most ``limit`` (one for all entries, or one per entry
    of the last axis), else an error saying the limit and its ``unit``."""
    arr = as_finite_array(name, value, shape)
    if not np.all(np.abs(arr) <= np.asarray(limit)):
        bound = f"{limit:g}" if isinstance(limit, (int, float)) else "(" + ", ".join(f"{v:g}" for v in limit) + ")"
        raise InvalidParameterError(name, value, f"entries of magnitude at most {bound} [{unit}]")
    return arr


def as_sign(name: str, value: object) -> float:
    """``value`` as a direction +1.0 or -1.0 (an int or a float equal to ±1; not a bool or an array)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)) \
            or value not in (-1, 1):
        raise InvalidParameterError(name, value, "+1 or -1")
    return float(value)


#: The largest fingertip sphere radius [m] a plant takes: a 5 cm ball is far larger than any fingertip, and small
#: enough that the erosion of an object by it stays meaningful.
MAX_TIP_RADIUS = 0.05


def as_tip_radius(name: str, value: object, *, allow_zero: bool = False) -> float:
    """``value`` as a fingertip sphere's radius [m] in (0, :data:`MAX_TIP_RADIUS`] ([0, ...] with ``allow_zero``: a
    point)."""
    out = as_positive_float(name, value, allow_zero=allow_zero)
    if out > MAX_TIP_RADIUS:
        raise InvalidParameterError(name, value, f"a radius of at most {MAX_TIP_RADIUS:g} m")
    return out

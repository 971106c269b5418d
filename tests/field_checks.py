"""Generated bad values for the fields of a value type (a settings type, a schedule, a friction): each field, given a
value of the wrong type, a non-finite one, a bool where a number is expected, an integer too large for a float
(10**400), a complex number, None, an object or a list or array of the wrong shape, raises an
:class:`~regrasp.core.exceptions.InvalidParameterError` naming that field, unless the value is one the field documents
as valid (None for an optional field, inf for an unbounded force...); a good value, also as a numpy scalar, is
accepted and stored as a plain float, int or bool.

A type's table is a list of :class:`Field` (:func:`fields_of` builds it from the kinds, and checks that it names
every field of the type). Used by the settings' tests (tests/supervisor/test_settings.py, tests/schedule/...).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from regrasp.core.exceptions import InvalidParameterError, short_repr
from regrasp.core.validation import MAX_COUNT
from regrasp.model.geometry import Geometry

#: Fast and the same on every run.
FIELD_SETTINGS = settings(derandomize=True, database=None, max_examples=12, deadline=None,
                          suppress_health_check=[HealthCheck.too_slow])

#: Values no numeric field takes (and that only a few kinds take at all: see :func:`valid_alone`).
FIXED_BAD = [math.nan, math.inf, -math.inf, None, "", "1.0", "abc", b"1", True, False, np.bool_(True), 10**400,
             -(10**400), 1 + 2j, np.complex128(1.0), np.float32("nan"), np.float64("inf"), object(), {}, {"a": 1},
             [math.nan], [None, 1.0], [[1.0], [1.0, 2.0]], ["1", "2"], np.full(2, math.nan), np.array([[1.0, 2.0]]),
             np.array(["a", "b"]), np.array([True, False])]

_bad_scalars = st.one_of(
    st.none(), st.booleans(), st.sampled_from([np.bool_(True), np.bool_(False), np.float32("inf"), object()]),
    st.text(max_size=4), st.binary(max_size=2), st.complex_numbers(allow_nan=True, allow_infinity=True),
    st.sampled_from([math.nan, math.inf, -math.inf]),
    st.integers(min_value=10**309, max_value=10**400), st.integers(min_value=-(10**400), max_value=-(10**309)),
    st.dictionaries(st.text(max_size=2), st.integers(0, 3), max_size=2))
#: Generated bad values: a bad scalar, or a list of them.
BAD_VALUES = st.one_of(_bad_scalars, st.lists(_bad_scalars, min_size=1, max_size=3))


@dataclass(frozen=True)
class Field:
    """One field of a value type: its kind (what it takes, below), a good value, the name its errors carry.

    Kinds: ``pos`` (a finite number > 0), ``nonneg`` (>= 0), ``real`` (finite), ``count0``/``count1`` (an integer
    >= 0 / >= 1), ``flag``, ``geometry``, ``choice`` (one of ``choices``), ``name`` (a non-empty string),
    ``type`` (an instance of a value type), ``array`` (finite numbers of ``shape``), ``pos+inf`` (> 0 or inf),
    ``real+inf`` (a number, ±inf allowed, not NaN), ``sign`` (±1), ``names`` (a sequence of non-empty strings),
    ``at`` (a schedule's (time or NaN, name or '')), ``other`` (a structure no bad value matches but an empty
    iterable when ``empty_ok``). ``optional``: None is valid too.
    """

    owner: object
    field: str
    kind: str
    good: object
    name: str
    optional: bool = False
    choices: tuple = ()
    shape: tuple = ()
    empty_ok: bool = False

    def __str__(self) -> str:
        return f"{type(self.owner).__name__}.{self.field}"


def fields_of(owner: object, kinds: dict[str, tuple[str, ...]], *, optional: tuple[str, ...] = (),
              good: dict | None = None, names: dict | None = None, choices: dict | None = None,
              shapes: dict | None = None, empty_ok: tuple[str, ...] = ()) -> list[Field]:
    """The table of ``owner``'s fields (``owner``: a valid instance; ``kinds``: kind -> field names), checked to name
    each of its fields once."""
    good, names, choices, shapes = good or {}, names or {}, choices or {}, shapes or {}
    out = [Field(owner, f, kind, good.get(f, getattr(owner, f)), names.get(f, f), f in optional, choices.get(f, ()),
                 shapes.get(f, ()), f in empty_ok)
           for kind, fs in kinds.items() for f in fs]
    listed = sorted(c.field for c in out)
    assert listed == sorted(f.name for f in dataclasses.fields(owner)), (type(owner).__name__, listed)
    return out


def is_number(v: object) -> bool:
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, (bool, np.bool_))


def number(v: object) -> float | None:
    """``v`` as a float if it is a number a float can hold (NaN and inf included), else None."""
    if not is_number(v):
        return None
    try:
        return float(v)
    except OverflowError:
        return None


def valid_alone(case: Field, value: object) -> bool:
    """Whether ``value`` is valid for the field on its own (the kinds' documented values; a value valid alone may
    still conflict with another field: an error then may name either)."""
    if value is None:
        return case.optional
    kind = case.kind
    if kind == "flag":
        return isinstance(value, (bool, np.bool_))
    if kind == "geometry":
        return isinstance(value, Geometry) or (isinstance(value, str) and value in ("ideal", "urdf"))
    if kind == "choice":
        return isinstance(value, str) and value in case.choices
    if kind == "name":
        return isinstance(value, str) and value != ""
    if kind == "pos+inf":
        return isinstance(value, float) and value == math.inf
    if kind == "real+inf":
        return number(value) is not None and not math.isnan(number(value))
    if kind == "names":
        return isinstance(value, (list, tuple, np.ndarray)) and len(value) > 0 \
            and all(isinstance(v, str) and v for v in value)
    if kind == "at":  # (time or NaN, one of the owner's names or "")
        return isinstance(value, (list, tuple)) and len(value) == 2 and isinstance(value[1], str) \
            and value[1] in (*case.owner.names, "") and number(value[0]) is not None \
            and not math.isinf(number(value[0]))
    if kind in ("array", "other"):
        empty = not isinstance(value, (str, bytes)) and hasattr(value, "__len__") and len(value) == 0
        return empty and (case.empty_ok or (kind == "array" and 0 in case.shape))
    return False  # numbers and counts: no bad value is one


def check_bad(case: Field, value: object) -> None:
    """``value`` in ``case``'s field: an error naming it, or a value the field documents as valid."""
    try:
        made = dataclasses.replace(case.owner, **{case.field: value})
    except InvalidParameterError as exc:
        assert exc.name == case.name or valid_alone(case, value), (str(case), value, str(exc))
        assert "\n" not in str(exc) and len(str(exc)) < 600
        return
    assert valid_alone(case, value), (str(case), value, getattr(made, case.field))


def check_signs(case: Field) -> None:
    """The numbers a numeric field refuses by its sign or size (a count: also a float, and more than MAX_COUNT)."""
    refused = {"pos": [-1.0, 0.0, -5e-324], "nonneg": [-1.0, -5e-324], "count0": [-1, 2.5, 1.0, MAX_COUNT + 1],
               "count1": [0, -1, 2.5, MAX_COUNT + 1], "pos+inf": [-1.0, -math.inf],
               "sign": [0, 2, 0.5, -1.5]}.get(case.kind, [])
    for value in refused:
        with pytest.raises(InvalidParameterError) as info:
            dataclasses.replace(case.owner, **{case.field: value})
        assert info.value.name == case.name, (str(case), value, str(info.value))


def numpy_twin(value: object) -> object:
    """``value`` as numpy's scalar (a float as np.float64, an int as np.int64, a bool as np.bool_)."""
    if isinstance(value, bool):
        return np.bool_(value)
    if isinstance(value, int):
        return np.int64(value)
    if isinstance(value, float):
        return np.float64(value)
    return value


def check_good(case: Field) -> None:
    """The good value, and its numpy twin, are accepted; a number is stored as a plain float or int, a flag as a
    bool."""
    for value in (case.good, numpy_twin(case.good)):
        made = dataclasses.replace(case.owner, **{case.field: value})
        stored = getattr(made, case.field)
        if isinstance(case.good, bool):
            assert type(stored) is bool and stored == case.good, (str(case), stored)
        elif is_number(case.good):
            assert type(stored) is type(case.good) and stored == case.good, (str(case), stored)
        elif case.kind == "array":
            assert isinstance(stored, np.ndarray) and np.array_equal(stored, np.asarray(case.good)), str(case)


def field_tests(table: list[Field]) -> tuple:
    """The two tests of a table, for a test module to name (``test_fields, test_generated = field_tests(TABLE)``):
    every field refuses :data:`FIXED_BAD` and its sign's bad numbers and takes its good value; and refuses
    :data:`BAD_VALUES`."""

    @pytest.mark.parametrize("case", table, ids=str)
    def test_each_field_refuses_bad_values_and_takes_good_ones(case):
        for value in FIXED_BAD:
            check_bad(case, value)
        check_signs(case)
        check_good(case)

    @pytest.mark.parametrize("case", table, ids=str)
    @FIELD_SETTINGS
    @given(value=BAD_VALUES)
    def test_each_field_refuses_generated_bad_values(case, value):
        check_bad(case, value)

    return test_each_field_refuses_bad_values_and_takes_good_ones, test_each_field_refuses_generated_bad_values


def short_id(value: object) -> str:
    """A short test id for a parameter value (10**400 is 401 characters)."""
    return short_repr(value, 24)

"""The contact's value types (``regrasp.core.contact``): ContactMode, Friction, as_frictions, as_modes,
coefficients and cone_margin."""

import math
from dataclasses import FrozenInstanceError

import numpy as np
import pytest

import regrasp
from field_checks import field_tests, fields_of
from regrasp.core.contact import ContactMode, Friction, as_frictions, as_modes, coefficients, cone_margin
from regrasp.core.exceptions import InvalidParameterError, RegraspError


def test_contact_mode_members_equal_their_strings():
    assert [m.value for m in ContactMode] == ["fixed", "sliding", "separated"]
    assert ContactMode("sliding") is ContactMode.SLIDING
    assert ContactMode.FIXED == "fixed" and hash(ContactMode.FIXED) == hash("fixed")
    assert {"fixed": 0}[ContactMode.FIXED] == 0  # dictionaries keyed by the strings still look up
    assert (regrasp.ContactMode is ContactMode and regrasp.Friction is Friction
            and regrasp.core.cone_margin is cone_margin)


def test_as_modes_converts_strings_and_rejects_anything_else():
    assert as_modes(["fixed", ContactMode.SLIDING, "separated"]) == (ContactMode.FIXED, ContactMode.SLIDING,
                                                                     ContactMode.SEPARATED)
    assert all(type(m) is ContactMode for m in as_modes(("fixed", "sliding"), 2))
    for bad in ("fixed", ["glued"], [True, False], [0, 1], None, [["fixed"]]):
        with pytest.raises(InvalidParameterError):
            as_modes(bad)
    with pytest.raises(InvalidParameterError, match=r"\(3\)"):
        as_modes(["fixed", "fixed"], 3)


def test_friction_defaults_kinetic_to_static_and_is_frozen():
    f = Friction(0.5)
    assert (f.static, f.kinetic) == (0.5, 0.5) and f == Friction(0.5, 0.5)
    g = Friction(0.8, 0.4)
    assert (g.static, g.kinetic) == (0.8, 0.4)
    assert type(Friction(1).static) is float and type(Friction(np.float64(0.3), 0).kinetic) is float
    assert Friction(0.0) == Friction(0.0, 0.0)  # frictionless
    with pytest.raises(FrozenInstanceError):
        g.static = 0.9
    assert {g: 1}[Friction(0.8, 0.4)] == 1  # hashable: usable in cache keys
    assert str(f) == "mu = 0.5" and str(g) == "mu_s = 0.8, mu_k = 0.4"
    assert g.scaled(0.5) == Friction(0.4, 0.2)


@pytest.mark.parametrize("static,kinetic,name", [
    (-0.1, None, "mu_static"), (math.nan, None, "mu_static"), (math.inf, None, "mu_static"),
    ("0.5x", None, "mu_static"), (True, None, "mu_static"), (None, None, "mu_static"), (0.5, -0.1, "mu_kinetic"),
    (0.5, math.nan, "mu_kinetic"), (0.5, False, "mu_kinetic"), (0.4, 0.5, "mu_kinetic"),  # kinetic above static
])
def test_friction_rejects_bad_coefficients_with_typed_errors(static, kinetic, name):
    with pytest.raises(InvalidParameterError) as err:
        Friction(static, kinetic)
    assert err.value.name == name and isinstance(err.value, RegraspError)


FRICTION_TABLE = fields_of(Friction(0.5, 0.4), {"nonneg": ("static", "kinetic")}, optional=("kinetic",),
                           names={"static": "mu_static", "kinetic": "mu_kinetic"})

test_each_coefficient_refuses_bad_values, test_each_coefficient_refuses_generated_bad_values = \
    field_tests(FRICTION_TABLE)


@pytest.mark.parametrize("static,kinetic,name", [
    ("0.5", None, "mu_static"), (0.5, "0.4", "mu_kinetic"), (np.bool_(True), None, "mu_static"),
    (1 + 0j, None, "mu_static"), (10**400, None, "mu_static"), (np.array([0.5]), None, "mu_static")])
def test_a_coefficient_is_a_number_not_a_string_or_a_bool(static, kinetic, name):
    """Issue 25: ``Friction('0.5')``, ``Friction(0.5, '0.4')`` and ``Friction(np.bool_(True))`` were accepted."""
    with pytest.raises(InvalidParameterError) as err:
        Friction(static, kinetic)
    assert err.value.name == name


@pytest.mark.parametrize("factor", ["2", None, math.nan, math.inf, 0.0, -1.0, True, 1e308])
def test_scaled_takes_a_positive_number_that_keeps_the_coefficients_finite(factor):
    """Issue 25: ``Friction(0.5).scaled('2')`` was a TypeError."""
    with pytest.raises(InvalidParameterError, match="factor"):
        Friction(5.0).scaled(factor)
    assert Friction(0.5, 0.25).scaled(np.int64(2)) == Friction(1.0, 0.5)


def test_coefficient_is_static_when_fixed_and_kinetic_when_sliding():
    f = Friction(0.8, 0.4)
    assert f.coefficient(ContactMode.FIXED) == 0.8
    assert f.coefficient(ContactMode.SLIDING) == 0.4
    assert f.coefficient(ContactMode.SEPARATED) == 0.0
    modes = (ContactMode.SLIDING, ContactMode.FIXED, ContactMode.SEPARATED)
    assert coefficients([f, Friction(0.6, 0.1), f], modes) == (0.4, 0.6, 0.0)
    with pytest.raises(InvalidParameterError):
        coefficients([f], modes)


def test_as_frictions_forms():
    f = Friction(0.8, 0.4)
    assert as_frictions(f, 3) == (f, f, f)
    assert as_frictions(0.5, 2) == (Friction(0.5), Friction(0.5))
    assert as_frictions(np.float64(0.3), 2) == (Friction(0.3),) * 2
    assert as_frictions(np.array(0.3), 1) == (Friction(0.3),)  # a 0-d array is a number
    assert as_frictions([0.5, f], 2) == (Friction(0.5), f)
    assert as_frictions(np.array([0.2, 0.7]), 2) == (Friction(0.2), Friction(0.7))
    assert as_frictions((f, Friction(0.1)), 2) == (f, Friction(0.1))
    for bad in ("0.5", None, [0.5], [0.5, 0.5, 0.5], [0.5, -1.0], -0.5, [f, "x"],
                [False, []], [0.5, [1, [2]]], {0.5: 1, 0.4: 2}, {0.5, 0.4}):  # (ragged: numpy's ndim raises on them)
        with pytest.raises(InvalidParameterError):
            as_frictions(bad, 2)


def test_cone_margin_is_mu_fn_minus_abs_ft_for_floats_and_arrays():
    assert cone_margin(0.5, 2.0, 0.4) == pytest.approx(0.6)
    assert cone_margin(0.5, 2.0, -0.4) == pytest.approx(0.6)  # either tangential direction
    assert cone_margin(0.5, 2.0, 1.0) == 0.0  # on the cone's edge
    assert cone_margin(0.5, 2.0, -1.5) == pytest.approx(-0.5)  # outside
    assert isinstance(cone_margin(0.5, 2.0, 1.0), float)
    mu, fn, ft = np.array([0.8, 0.4]), np.array([1.0, 2.0]), np.array([-0.5, 1.0])
    np.testing.assert_array_equal(cone_margin(mu, fn, ft), [0.8 - 0.5, 0.8 - 1.0])
    np.testing.assert_array_equal(cone_margin(0.5, fn, ft), [0.0, 0.0])

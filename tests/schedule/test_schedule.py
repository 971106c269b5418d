"""The schedule value types (regrasp.schedule.schedule): slide profiles and schedule evaluation."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

from field_checks import field_tests, fields_of, short_id
from regrasp.core.exceptions import InvalidParameterError
from regrasp.schedule.schedule import NoScheduleError, RegraspSchedule, ScheduleLimit, Slide, slides_at


def _slide(**kw):
    args = dict(contact=0, name="f", direction=1, start=0.2, end=0.7, start_xi=-0.01, end_xi=0.012, ramp=0.01)
    args.update(kw)
    return Slide(**args)


@pytest.mark.parametrize("direction", [1, -1])
def test_slide_profile_is_smooth_and_within_its_limits(direction):
    s = _slide(direction=direction, start_xi=0.01 * -direction, end_xi=0.012 * direction)
    t = np.linspace(0.1, 0.8, 70001)
    x, v, a = s.profile(t)
    dt = t[1] - t[0]
    # rates are the finite differences of the position and speed (central, away from the ramp corners)
    np.testing.assert_allclose(np.gradient(x, dt)[1:-1], v[1:-1], atol=s.speed * 2e-3)
    corners = np.array([s.start, s.start + s.ramp, s.end - s.ramp, s.end])
    away = np.min(np.abs(t[:, None] - corners[None]), axis=1) > 3 * dt
    np.testing.assert_allclose(np.gradient(v, dt)[away], a[away], atol=1e-6)
    # at rest at both ends, where it should be, never faster than v nor harder than v / r
    assert x[0] == s.start_xi and x[-1] == pytest.approx(s.end_xi, abs=1e-15)
    assert v[0] == 0.0 and v[-1] == 0.0
    assert np.abs(v).max() <= s.speed * (1 + 1e-12)
    assert np.abs(a).max() <= s.acceleration * (1 + 1e-12)
    assert s.speed == pytest.approx(0.022 / (0.5 - 0.01))
    # monotone in its direction, and continuous
    assert np.all(np.diff(x) * direction >= -1e-15)
    assert np.abs(np.diff(x)).max() < 2 * s.speed * dt


def test_schedule_sample_follows_each_contacts_latest_slide_and_repeats_when_periodic():
    slides = (_slide(contact=0, start=0.1, end=0.3, start_xi=0.0, end_xi=0.01),
              _slide(contact=1, direction=-1, start=0.2, end=0.5, start_xi=0.005, end_xi=-0.005),
              _slide(contact=0, direction=-1, start=0.6, end=0.8, start_xi=0.01, end_xi=0.0))
    xi0 = np.array([0.0, 0.005])
    t = np.array([0.0, 0.15, 0.35, 0.55, 0.7, 0.95])
    out = slides_at(xi0, slides, t)
    assert out.xi[0].tolist() == [0.0, 0.005]
    assert out.direction[1].tolist() == [1, 0] and out.direction[3].tolist() == [0, 0]
    assert out.xi[3, 0] == pytest.approx(0.01) and out.xi[3, 1] == pytest.approx(-0.005)
    assert out.direction[4].tolist() == [-1, 0]
    assert out.xi[5].tolist() == pytest.approx([0.0, -0.005])
    sched = _schedule(slides, xi0, periodic=True, t_end=1.0)
    np.testing.assert_allclose(sched.at(t + 3.0).xi, out.xi, atol=1e-12)
    np.testing.assert_allclose(sched.at(0.35).xi, out.xi[2])
    held = _schedule(slides, xi0, periodic=False, t_end=1.0)
    np.testing.assert_allclose(held.at(7.0).xi, out.xi[5])
    with pytest.raises(InvalidParameterError):
        sched.at(math.nan)


@pytest.mark.parametrize("periodic", [True, False])
def test_one_time_is_the_array_path_at_that_time(periodic):
    """``at(t)`` for one float (the supervisor's path, in floats) equals ``at`` of an array holding t, at
    random times and at every slide's corners (start, ramp ends, end)."""
    slides = (_slide(contact=0, start=0.1, end=0.3, start_xi=0.0, end_xi=0.01),
              _slide(contact=1, direction=-1, start=0.2, end=0.5, start_xi=0.005, end_xi=-0.005),
              _slide(contact=0, direction=-1, start=0.6, end=0.8, start_xi=0.01, end_xi=0.0))
    sched = _schedule(slides, np.array([0.0, 0.005]), periodic=periodic, t_end=1.0)
    corners = [c + k for s in slides for c in (s.start, s.start + s.ramp, s.end - s.ramp, s.end) for k in (0.0, 2.0)]
    times = np.concatenate([np.random.default_rng(3).uniform(-0.5, 3.5, 400), corners])
    many = sched.at(times)
    for j, t in enumerate(times.tolist()):
        one = sched.at(t)
        for name in ("xi", "xi_dot", "xi_ddot"):
            np.testing.assert_allclose(getattr(one, name), getattr(many, name)[j], rtol=1e-15, atol=1e-17)
        assert one.direction.tolist() == many.direction[j].tolist()
        assert one.direction.dtype == many.direction.dtype
    assert sched.at(np.float64(0.35)).xi.tolist() == sched.at(0.35).xi.tolist()


def _schedule(slides, xi0, *, periodic, t_end):
    times = np.linspace(0, t_end, 11)
    sample = slides_at(xi0, slides, times)
    z = np.zeros((11, 2))
    return RegraspSchedule(("a", "b"), (1, 3), 0.0, t_end, periodic, xi0, slides, times, sample.xi, sample.xi_dot,
                           sample.xi_ddot, sample.direction, z + 0.002, z + 0.3, z + 1.0, 1e-3, 0.1, 0.002, (0.0, "a"),
                           0.3, (0.0, "a"), 1.5, 3)


def test_schedule_json_has_the_documented_keys():
    slides = (_slide(contact=0, name="a", start=0.1, end=0.3, start_xi=0.0, end_xi=0.01),)
    doc = _schedule(slides, np.array([0.0, 0.005]), periodic=True, t_end=1.0).to_json_dict()
    for key in ("found", "reason", "periodic", "times", "xi", "sliding", "slides", "min_envelope_margin",
                "min_cone_margin", "planning_seconds"):
        assert key in doc
    assert doc["found"] is True and doc["reason"] is None
    assert doc["slides"][0] == {"contact": "a", "direction": 1, "start": 0.1, "end": 0.3, "from": 0.0, "to": 0.01}
    assert len(doc["times"]) == len(doc["xi"]) == len(doc["sliding"]) == 11
    assert isinstance(doc["sliding"][2][0], bool)
    json.dumps(doc)


def test_no_schedule_error_carries_its_diagnosis():
    err = NoScheduleError(1.3, ScheduleLimit.FORCES, ("finger1",), "finger1 cannot slide", rule="the rule")
    assert err.limit is ScheduleLimit.FORCES and err.latest_time == 1.3 and err.contacts == ("finger1",)
    assert "finger1 cannot slide" in str(err) and "the rule" in str(err)
    doc = err.to_json_dict()
    assert doc["found"] is False and doc["limit"] == "forces" and doc["rule"] == "the rule"
    json.dumps(doc)


BASE = _schedule((_slide(contact=0, name="a", start=0.1, end=0.3, start_xi=0.0, end_xi=0.01),),
                 np.array([0.0, 0.005]), periodic=True, t_end=1.0)
SHAPE = (len(BASE.times), BASE.m)
TABLE = [
    *fields_of(BASE, {
        "names": ("names",), "other": ("edges", "slides"), "real": ("t_start", "t_end"), "flag": ("periodic",),
        "array": ("xi_start", "times", "xi", "xi_dot", "xi_ddot", "sliding", "envelope_margin", "cone_margin",
                  "normal_force"),
        "nonneg": ("required_envelope_margin", "required_cone_margin", "planning_seconds"),
        "real+inf": ("min_envelope_margin", "min_cone_margin"), "at": ("min_envelope_margin_at", "min_cone_margin_at"),
        "count0": ("slides_lower_bound",)},
        optional=("slides_lower_bound",), empty_ok=("slides",),
        shapes={"xi_start": (BASE.m,), "times": SHAPE[:1], **{name: SHAPE for name in (
            "xi", "xi_dot", "xi_ddot", "sliding", "envelope_margin", "cone_margin", "normal_force")}}),
    *fields_of(_slide(), {"count0": ("contact",), "name": ("name",), "sign": ("direction",),
                          "real": ("start", "end", "start_xi", "end_xi"), "pos": ("ramp",)}),
]

test_each_field_refuses_bad_values, test_each_field_refuses_generated_bad_values = field_tests(TABLE)


@pytest.mark.parametrize("xi_start", [[0.0, 0.0, 0.0], None, {}, [0.0, math.nan], ["0", "1"]], ids=short_id)
def test_a_schedule_refuses_a_bad_start_on_construction(xi_start):
    """Issue 25: ``replace(schedule, xi_start=[0.0, 0.0, 0.0])`` (or None, {}) was accepted, and its rollout an
    AttributeError ('list' object has no attribute 'tolist')."""
    with pytest.raises(InvalidParameterError, match="xi_start"):
        dataclasses.replace(BASE, xi_start=xi_start)
    made = dataclasses.replace(BASE, xi_start=[0.0, 0.005])  # a list of the right length: an array
    assert isinstance(made.xi_start, np.ndarray) and made.at(0.05).xi.tolist() == [0.0, 0.005]


@pytest.mark.parametrize("field,value", [
    ("times", np.linspace(1.0, 0.0, 11)), ("times", np.linspace(0.0, 2.0, 11)), ("t_end", 0.0),
    ("sliding", np.full(SHAPE, 2)), ("sliding", np.full(SHAPE, 0.5)), ("envelope_margin", np.full(SHAPE, math.nan)),
    ("cone_margin", np.full(SHAPE, math.inf)), ("edges", (1,)), ("names", ("a",)), ("names", "ab"),
    ("slides", (_slide(contact=2),)), ("slides", (_slide(start=0.5, end=0.7), _slide(start=0.2, end=0.4))),
    ("min_cone_margin", math.nan), ("min_cone_margin_at", (0.0, "c")), ("min_cone_margin_at", (math.inf, "a"))],
    ids=str)
def test_a_schedule_refuses_inconsistent_fields(field, value):
    with pytest.raises(InvalidParameterError):
        dataclasses.replace(BASE, **{field: value})


def test_the_documented_non_finite_values_are_accepted():
    """NaN cone margins and forces (sliding contacts, drafts), a -inf envelope margin (no feasible interval), no
    minimum (inf at (NaN, ''))."""
    made = dataclasses.replace(BASE, cone_margin=np.full(SHAPE, math.nan), normal_force=np.full(SHAPE, math.nan),
                               envelope_margin=np.full(SHAPE, -math.inf), min_cone_margin=math.inf,
                               min_cone_margin_at=(math.nan, ""), sliding=np.zeros(SHAPE, dtype=np.int8))
    assert made.sliding.dtype == int and made.min_cone_margin_at[1] == ""


@pytest.mark.parametrize("t", ["abc", object(), 1 + 2j, [[0.1], [0.1, 0.2]], "1.0", True, np.bool_(False), None,
                               math.inf, [0.1, math.nan], np.array([[0.1, 0.2]]), ["0.1"]], ids=short_id)
def test_at_takes_finite_times_only(t):
    """Issue 25: ``at('abc' | object() | 1+2j | ragged)`` were ValueError/TypeError, ``at('1.0')`` and ``at(True)``
    accepted."""
    with pytest.raises(InvalidParameterError) as err:
        BASE.at(t)
    assert err.value.name == "t"


@pytest.mark.parametrize("t", [np.full(2, math.inf), math.nan, "1.0", True, [0.1, None]], ids=short_id)
def test_local_time_takes_finite_times_only(t):
    """Issue 25: ``local_time(np.full(2, inf))`` returned t_end."""
    with pytest.raises(InvalidParameterError):
        BASE.local_time(t)
    if np.ndim(t) == 0:
        with pytest.raises(InvalidParameterError):
            BASE.local_time_at(t)


def test_numbers_of_any_kind_are_times():
    for t in (0.25, 1, np.int64(1), np.float32(0.25), np.array(0.25)):
        assert BASE.at(t).xi.tolist() == BASE.at(float(t)).xi.tolist()
        assert float(BASE.local_time(t)) == BASE.local_time_at(t if np.ndim(t) == 0 else float(t))
    assert BASE.at([0.25, 1.25]).xi.shape == (2, 2) and BASE.local_time([0.25, 1.25]).tolist() == [0.25, 0.25]

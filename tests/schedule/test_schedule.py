"""The schedule value types (regrasp.schedule.schedule): slide profiles and schedule evaluation."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

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

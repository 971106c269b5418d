"""The runtime envelope monitor: margins, bounds and rates at the measured pose."""

from pathlib import Path

import numpy as np
import pytest

from regrasp import FingerEnvelope, load_scenario
from regrasp.core.exceptions import InvalidParameterError
from regrasp.envelope.planner import plan_scenario
from regrasp.supervisor.monitor import EnvelopeMonitor, bound_speeds

SCENARIOS = Path(__file__).resolve().parents[2] / "examples" / "scenarios"


SC = load_scenario(SCENARIOS / "paper_trajectory_2_three_fingers.toml")
ENVELOPES = [FingerEnvelope(c.finger, SC.polygon, c.edge, geometry="ideal") for c in SC.contacts]
XI = np.array([-0.0125, 0.0125, 0.0])


def test_a_reading_is_the_envelopes_at_the_measured_pose_with_finite_difference_rates():
    monitor = EnvelopeMonitor(ENVELOPES)
    t0, t1 = 0.5, 0.501
    a = monitor.read(t0, SC.trajectory.pose(t0), XI)
    b = monitor.read(t1, SC.trajectory.pose(t1), XI)
    for i, env in enumerate(ENVELOPES):  # independent: FingerEnvelope.at at the same pose
        sample = env.at(SC.trajectory.pose(t1), t1)
        assert b.margins[i] == sample.margin(XI[i])
        lo, hi = b.bounds[i]
        assert any(lo == p and hi == q for p, q in sample.feasible)
    assert b.fresh and np.allclose(b.rates, (b.bounds - a.bounds) / (t1 - t0), rtol=0, atol=1e-9)


def test_every_k_reuses_the_samples_but_takes_the_margin_at_the_current_xi():
    monitor = EnvelopeMonitor(ENVELOPES, every=3)
    first = monitor.read(0.5, SC.trajectory.pose(0.5), XI)
    moved = XI + np.array([0.001, 0.0, 0.0])
    second = monitor.read(0.501, SC.trajectory.pose(0.501), moved)
    assert not second.fresh and second.samples == first.samples
    assert second.margins[0] == first.samples[0].margin(moved[0])
    assert monitor.read(0.502, SC.trajectory.pose(0.502), XI).fresh is False
    assert monitor.read(0.503, SC.trajectory.pose(0.503), XI).fresh is True


def test_a_bound_that_jumps_gets_no_rate():
    monitor = EnvelopeMonitor(ENVELOPES, max_bound_step=1e-9)
    monitor.read(0.5, SC.trajectory.pose(0.5), XI)
    assert np.all(monitor.read(0.501, SC.trajectory.pose(0.501), XI).rates == 0.0)


@pytest.mark.parametrize("kwargs", [dict(envelopes=[]), dict(envelopes=["x"]), dict(envelopes=ENVELOPES, every=0),
                                    dict(envelopes=ENVELOPES, every=True)])
def test_bad_monitors_are_refused(kwargs):
    with pytest.raises(InvalidParameterError):
        EnvelopeMonitor(**kwargs)


def _shape_changed(a: np.ndarray, b: np.ndarray, step) -> np.ndarray:
    """Per contact: whether the interval (lo, hi) changed by more than ``step`` [m] (per contact: (m, 1)), or
    to or from NaN."""
    with np.errstate(invalid="ignore"):
        return ~(np.abs(b - a) <= step).all(axis=1)


@pytest.mark.parametrize("geometry", ["ideal", "urdf"])
def test_a_stale_reading_misses_at_most_its_bound(geometry):
    """Every 10th step against every step, along 1.5 s of the three-finger trajectory at 1 kHz with the
    contacts moving across their edges at up to 20 mm/s: while no bound changed shape or moved faster than the
    monitor's ``speed_factor`` x its known speed since the stale samples, each margin is within ``miss_bound``
    of the fresh one; such windows are the exception; and the bound is not vacuous (some stale margin differs
    from the fresh one by more than a quarter of its bound)."""
    plan = plan_scenario(SC, geometry=geometry, samples=401)
    envelopes = [FingerEnvelope(c.finger, SC.polygon, c.edge, geometry=geometry, tip_clearance=c.tip_clearance)
                 for c in SC.contacts]
    k = 10
    fresh = EnvelopeMonitor(envelopes)
    stale = EnvelopeMonitor(envelopes, every=k, bound_speed=bound_speeds([f.samples for f in plan.fingers]))
    assert np.all(stale.bound_speed > 0.0)
    changed_since = np.zeros(3, dtype=bool)
    previous, checked, differing, tightest, excluded = None, 0, 0, 0.0, 0
    for j in range(1500):
        t = 0.001 * j
        xi = XI + 0.003 * np.sin(np.array([7.0, 5.0, 3.0]) * t)
        a, b = fresh.read(t, SC.trajectory.pose(t), xi), stale.read(t, SC.trajectory.pose(t), xi)
        if b.fresh:
            changed_since[:] = False
            assert np.array_equal(a.margins, b.margins) and b.age == 0.0 and np.all(b.miss_bound == 0.0)
        elif previous is not None:  # a change of shape, or a bound faster than the stale monitor assumes
            limit = np.minimum(fresh.max_bound_step, stale.speed_factor * stale.bound_speed * 0.001)
            changed_since |= _shape_changed(previous, a.bounds, limit[:, None])
            excluded += int(changed_since.sum())
        previous = a.bounds
        assert j % k != 0 or b.fresh  # a change of shape is seen at most k - 1 steps late
        for i in np.flatnonzero(~changed_since & np.isfinite(a.margins)):
            assert abs(b.margins[i] - a.margins[i]) <= b.miss_bound[i] + 1e-12, (t, i)
            checked += 1
            differing += b.margins[i] != a.margins[i]
            if b.miss_bound[i] > 0.0:
                tightest = max(tightest, abs(b.margins[i] - a.margins[i]) / b.miss_bound[i])
    assert checked > 3000 and differing > 500 and excluded < 0.1 * checked
    assert tightest > 0.25


def test_bound_speeds_skip_changes_of_shape():
    from regrasp.envelope.finger_envelope import EnvelopeSample

    def sample(t, feasible):
        base = ENVELOPES[0].at(SC.trajectory.pose(0.5), 0.5)
        return EnvelopeSample(t, base.d, base.lam, base.condition, base.reachable, base.edge_range, feasible, None,
                              0.0)

    samples = [sample(0.0, ((0.0, 0.01),)), sample(0.1, ((0.001, 0.01),)), sample(0.2, ((0.001, 0.03),)),
               sample(0.3, ((0.0, 0.001), (0.002, 0.03)))]
    assert bound_speeds([samples])[0] == pytest.approx(0.01)  # 1 mm in 0.1 s; the 20 mm jump and the split skipped


@pytest.mark.parametrize("kwargs", [dict(bound_speed=-1.0), dict(bound_speed=[0.1, 0.2]), dict(speed_factor=0.5),
                                    dict(bound_speed=np.nan), dict(max_bound_step=0.0)])
def test_bad_bound_settings_are_refused(kwargs):
    with pytest.raises(InvalidParameterError):
        EnvelopeMonitor(ENVELOPES, **kwargs)


def test_a_fresh_read_on_request_restarts_the_count():
    """read(fresh=True) evaluates now (the supervisor asks at each decision) and the k reads start again there;
    held_reads says how many reads the held samples still serve."""
    monitor = EnvelopeMonitor(ENVELOPES, every=3)
    assert monitor.held_reads() == 0
    assert monitor.read(0.5, SC.trajectory.pose(0.5), XI).fresh
    assert monitor.held_reads() == 2
    assert not monitor.read(0.501, SC.trajectory.pose(0.501), XI).fresh
    forced = monitor.read(0.502, SC.trajectory.pose(0.502), XI, fresh=True)
    assert forced.fresh and forced.age == 0.0
    assert forced.samples[0].feasible == ENVELOPES[0].at(SC.trajectory.pose(0.502), 0.502).feasible
    assert monitor.held_reads() == 2
    assert [monitor.read(t, SC.trajectory.pose(t), XI).fresh for t in (0.503, 0.504, 0.505)] == [False, False, True]


def test_the_held_intervals_are_the_samples_feasible_sets():
    monitor = EnvelopeMonitor(ENVELOPES, every=10)
    reading = monitor.read(0.5, SC.trajectory.pose(0.5), XI)
    intervals, counts = monitor.held_intervals()
    for i, sample in enumerate(reading.samples):
        assert counts[i] == len(sample.feasible)
        assert [tuple(r) for r in intervals[i, :counts[i]].tolist()] == list(sample.feasible)
    with pytest.raises(InvalidParameterError):
        EnvelopeMonitor(ENVELOPES).held_intervals()  # (nothing read yet)

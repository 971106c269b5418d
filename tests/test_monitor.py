"""The runtime envelope monitor: margins, bounds and rates at the measured pose."""

import numpy as np
import pytest

from regrasp import FingerEnvelope, load_scenario
from regrasp.exceptions import InvalidParameterError
from regrasp.monitor import EnvelopeMonitor

from test_rollout import SCENARIOS

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

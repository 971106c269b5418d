"""The handover hold (regrasp.supervisor.handover): a phase change holds each contact's last predicted load and
releases it linearly; a change within a hold starts a new one."""

import numpy as np
import pytest

from regrasp.supervisor.handover import HandoverHold

FIXED, PRIMING, SLIDING = ("fixed",) * 3, ("priming", "fixed", "fixed"), ("sliding", "fixed", "fixed")


def test_a_phase_change_holds_the_last_loads_and_releases_them_linearly():
    hold = HandoverHold(3, time=0.03, load_max=2.0)
    hold.see(FIXED, 0.0)
    hold.note(np.array([0.5, 0.76, 3.0]))
    assert not hold.changed(FIXED) and hold.changed(PRIMING)
    hold.see(PRIMING, 0.001)
    assert hold.active(0.001) and not hold.changed(PRIMING)
    np.testing.assert_allclose(hold.floors(0.001), [0.5, 0.76, 2.0])  # (capped at load_max)
    np.testing.assert_allclose(hold.floors(0.016), [0.25, 0.38, 1.0])
    assert not hold.active(0.031) and not hold.floors(0.031).any()


def test_no_hold_without_a_previous_step_or_a_time():
    hold = HandoverHold(3, time=0.03, load_max=2.0)
    hold.note(np.ones(3))
    hold.see(PRIMING, 0.0)  # (the first step: nothing to compare with)
    assert not hold.active(0.0) and not hold.floors(0.0).any()
    off = HandoverHold(3, time=0.0, load_max=2.0)
    off.see(FIXED, 0.0)
    off.note(np.ones(3))
    assert not off.changed(PRIMING)  # (no hold: nothing for a compiled stretch to stop for)
    off.see(PRIMING, 0.001)
    assert not off.active(0.001) and not off.floors(0.001).any()


def test_a_change_within_a_hold_starts_a_new_one_from_the_loads_of_the_step_before():
    hold = HandoverHold(3, time=0.03, load_max=2.0)
    hold.see(FIXED, 0.0)
    hold.note(np.array([0.5, 0.76, 0.4]))
    hold.see(PRIMING, 0.001)
    hold.note(np.array([1.17, 0.7, 0.45]))  # (primed past its cone, contact 0 pushes harder)
    hold.see(SLIDING, 0.010)
    np.testing.assert_allclose(hold.floors(0.010), [1.17, 0.7, 0.45])  # (what it pushes with as it starts to slide)
    np.testing.assert_allclose(hold.floors(0.025), [0.585, 0.35, 0.225])


@pytest.mark.parametrize("bad", [np.nan, -1.0])
def test_an_unknown_or_negative_load_holds_nothing(bad):
    hold = HandoverHold(2, time=0.03, load_max=2.0)
    hold.see(("fixed", "fixed"), 0.0)
    hold.note(np.array([bad, 0.5]))
    hold.see(("priming", "fixed"), 0.001)
    np.testing.assert_allclose(hold.floors(0.001), [0.0, 0.5])

"""The rollout figures (Figs. 4.2–4.4): bands from the monitor's samples, danger zones, titles, frames."""

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from matplotlib.collections import PolyCollection

from regrasp import load_scenario
from regrasp.core.events import Failure, FailureKind
from regrasp.core.figures import FAILURE_COLOURS, gravity_words
from regrasp.core.intervals import DANGER_FRACTION, danger_zones
from regrasp.model.hand import Hand
from regrasp.rollout import plots
from regrasp.rollout.plots import band_samples, plot_frames, plot_rollout, rollout_title
from regrasp.rollout.result import RolloutResult

SCENARIOS = Path(__file__).resolve().parents[2] / "examples" / "scenarios"
XI = 0.017  # finger2's ξ [m]: inside the band until the last sample, which excludes it (as in paper Fig. 4.2)


def result(*, fail: bool = True, phases=("fixed", "fixed")) -> RolloutResult:
    """91 steps of 1 ms, the envelope sampled every 10 steps: finger2's lower bound climbs 1.4 mm a sample, from
    5 mm to 16.2 mm at 0.080 s and 17.75 mm at the last step (0.090 s), past ξ = 17 mm."""
    n = 91
    t = np.arange(n) * 1e-3
    sample = np.minimum(np.arange(n) // 10, 9)
    lo = 0.005 + 0.0014 * sample
    lo[-1] = 0.01775
    bounds = np.zeros((n, 2, 2))
    bounds[:, 0] = [-0.02, -0.005]
    bounds[:, 1, 0], bounds[:, 1, 1] = lo, 0.02
    xi = np.tile([-0.015, XI], (n, 1))
    failure = Failure(float(t[-1]), FailureKind.LEFT_ENVELOPE, "finger2 left", "finger2") if fail else None
    z = np.zeros(n)
    return RolloutResult(
        success=not fail, failure=failure, duration=0.1, steps=n, object_width=0.1,
        max_object_error_after_transient=np.nan, max_orientation_error_after_transient=np.nan, regrasps={},
        events=(), min_cone_margin=0.3, min_cone_margin_at=(0.0, "finger1"), min_envelope_margin=-7.5e-4,
        min_envelope_margin_at=(0.09, "finger2"), times=t, xi=xi, bounds=bounds, planned_xi=xi.copy(),
        phases=np.array([list(phases)] * n, dtype=object), object_error=np.zeros((n, 3)),
        poses=np.tile([0.0, 0.17, 0.0], (n, 1)), joint_positions=np.tile([1.2, 0.8, 1.9, -0.8], (n, 1)),
        forces_surface=np.zeros((n, 2, 2)), supervisor_seconds=z, control_seconds=z, plant_seconds=z,
        wall_seconds=1.0, names=("finger1", "finger2"), policy="scheduled")


@pytest.fixture()
def figures(monkeypatch):
    """The figures the plots make, kept open (their saving skipped)."""
    made = []

    def keep(fig, path, layout=True):
        made.append(fig)
        return Path(path)

    monkeypatch.setattr(plots, "save_figure", keep)
    return made


def test_band_samples_are_the_monitor_samples_at_their_own_times():
    r = result()
    ts, lo, hi, sampled = band_samples(r.times, r.bounds[:, 1])
    assert ts[sampled].tolist() == pytest.approx([0.0, 0.01, 0.02, 0.03, 0.04, 0.05, 0.06, 0.07, 0.08, 0.09])
    assert lo[-1] == pytest.approx(0.01775) and ts[-1] == pytest.approx(0.09)  # (the failing step's reading)
    assert lo[-1] > XI  # the band at the failure time excludes ξ
    # no staircase: between two samples the bound moves in a straight line (no vertical jump 1 step before one)
    assert np.interp(0.0895, ts, lo) > np.interp(0.085, ts, lo) > np.interp(0.08, ts, lo)
    assert np.all(np.diff(ts) > 0)


def test_band_samples_keep_a_constant_bound_flat_and_gaps_nan():
    t = np.arange(30) * 1e-3
    b = np.tile([0.0, 0.01], (30, 1))
    b[10:20] = np.nan
    ts, lo, hi, _ = band_samples(t, b)
    assert np.isnan(np.interp(0.015, ts, lo))
    assert np.nanmax(hi) == np.nanmin(hi) == 0.01


def test_rollout_band_excludes_the_failing_xi_at_the_failure_time(figures):
    r = result()
    plot_rollout(r, "unused.png")
    ax = figures[0].axes[1]
    fills = [c for c in ax.collections if isinstance(c, PolyCollection)]
    assert len(fills) == 3  # the feasible band and its two danger zones

    def covered(t, xi_mm):
        return any(p.contains_point((t, xi_mm)) for c in fills for p in c.get_paths())

    assert covered(0.05, XI * 1e3)
    assert not covered(0.0899, XI * 1e3)  # just before the failure line, ξ is already out of the drawn band
    assert covered(0.0899, 18.5)


def test_rollout_danger_zones_are_the_core_ones(figures):
    r = result(fail=False)
    plot_rollout(r, "unused.png")
    band, low, high = [c for c in figures[0].axes[1].collections if isinstance(c, PolyCollection)]
    ts, lo, hi, _ = band_samples(r.times, r.bounds[:, 1])
    (lo_end, lo_zone), (hi_zone, hi_end) = danger_zones(lo * 1e3, hi * 1e3, DANGER_FRACTION)

    def edges(collection):
        return set(np.round(collection.get_paths()[0].vertices[:, 1], 9))

    assert edges(low) == set(np.round(lo_end, 9)) | set(np.round(lo_zone, 9))
    assert edges(high) == set(np.round(hi_zone, 9)) | set(np.round(hi_end, 9))
    assert edges(band) == set(np.round(lo_zone, 9)) | set(np.round(hi_zone, 9))
    assert np.all(lo_zone - lo_end == pytest.approx(DANGER_FRACTION * (hi - lo) * 1e3))


def test_titles_name_scenario_plant_gravity_and_policy(figures):
    up = SimpleNamespace(name="paper_trajectory_2_gravity_up", gravity_in_hand=np.array([0.0, 9.81]), polygon=None)
    title = rollout_title(result(), up, "project")
    for word in ("paper_trajectory_2_gravity_up", "project plant", "gravity up", "scheduled policy", "left_envelope",
                 "0.090 s"):
        assert word in title
    plot_rollout(result(), "unused.png", scenario=up, plant="mujoco")
    assert "mujoco plant, gravity up" in figures[0].get_suptitle()
    assert gravity_words([0.0, -9.81]) == "gravity down" and gravity_words([0.0, 0.0]) == "no gravity"
    assert gravity_words([1.0, -1.0]).startswith("gravity (1, -1)")


def test_frames_legend_lists_only_the_phases_drawn_and_names_the_fingers(figures):
    sc = load_scenario(SCENARIOS / "paper_trajectory_1.toml")
    hand = Hand([c.finger for c in sc.contacts], gravity_in_hand=sc.gravity_in_hand)
    r = result(phases=("fixed", "sliding"))
    plot_frames(r, hand, sc.polygon, "unused.png", scenario=sc, plant="project", frames=3)
    fig = figures[0]
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert labels == ["contact fixed", "contact sliding"]  # (no priming, no settling: they never occur)
    texts = [t.get_text() for t in fig.axes[0].texts]
    assert "finger1" in texts and "finger2" in texts and "g" in texts  # fingers named, gravity drawn
    assert "gravity down" in fig.get_suptitle()
    assert "left_envelope" in fig.axes[2].get_title()
    rings = [line for line in fig.axes[2].lines if line.get_markersize() == 14]  # the failing contact, ringed
    assert len(rings) == 1 and rings[0].get_markeredgecolor() == FAILURE_COLOURS["left_envelope"]
    assert not any(line.get_markersize() == 14 for line in fig.axes[1].lines)

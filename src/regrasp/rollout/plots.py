"""PNG figures of a rollout, after the paper's Figures 4.2–4.4 (matplotlib, headless).

* :func:`plot_rollout` (Fig. 4.3, as run): per finger, the feasible band around the contact at the measured pose
  (:func:`band_samples`: the monitor's samples at their own times, joined by straight lines, filled), its danger
  zones (:func:`~regrasp.core.intervals.danger_zones`, :data:`~regrasp.core.intervals.DANGER_FRACTION` of the band's
  width at both ends: the same zones the rerun recording draws), the schedule's planned ξ_d and the actual ξ against
  time, the slides shaded, the failure marked where it happened; with the scenario, a rounded polygon's arcs shaded.
* :func:`plot_frames` (Figs. 4.2 and 4.4): the hand and the object at a few times of the rollout (fingers as their
  joint chains, named, contacts coloured by phase; gravity as an arrow), the failure's frame last. A curved object
  is its outline (:func:`~regrasp.rollout.recording.outline.outline_in`: within 0.05 mm of the curve).

:func:`write_rollout_figures` writes both. Both titles say what was run (:func:`rollout_title`): the scenario, the
plant, the gravity, the policy and the outcome.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..core.figures import ARC_STYLE, FAILURE_COLOURS, gravity_words, pyplot, save_figure, shade_arcs
from ..core.intervals import DANGER_FRACTION, danger_zones
from .recording.outline import outline_in

if TYPE_CHECKING:
    from ..core.curves import CurvedObject
    from ..core.polygon import ConvexPolygon
    from ..model.hand import Hand
    from ..model.scenario import Scenario
    from .build import Rollout
    from .result import RolloutResult

__all__ = ["band_samples", "plot_frames", "plot_rollout", "rollout_title", "write_rollout_figures"]

_MM = 1000.0
_PHASE_COLOURS = {"fixed": "#2ca02c", "priming": "#9467bd", "sliding": "#ff7f0e", "settling": "#8c564b"}
_BAND, _DANGER, _SLIDE = "#cfe8cf", "#f4b6b6", "#ffd8a8"


def rollout_title(result: RolloutResult, scenario: Scenario | None = None, plant: str | None = None) -> str:
    """What a rollout figure shows: ``<scenario>, <plant> plant, <gravity>, <policy> policy: <outcome>`` (the parts
    not known left out)."""
    parts = [] if scenario is None else [scenario.name]
    if plant is not None:
        parts.append(f"{plant} plant")
    if scenario is not None:
        parts.append(gravity_words(scenario.gravity_in_hand))
    parts.append(f"{result.policy} policy")
    if result.success:
        outcome = f"success over {result.simulated_seconds:.2f} s"
    else:
        f = result.failure
        outcome = f"{f.kind.value} at t = {f.time:.3f} s" + (f" ({f.contact})" if f.contact else "")
    return ", ".join(parts) + ": " + outcome


def band_samples(times: np.ndarray, bounds: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """One contact's feasible band as the envelope monitor sampled it: (times [s], lo, hi, whether each point is a
    sample), to be joined by straight lines.

    The per-step ``bounds`` (k, 2) hold each sample until the next one (a staircase); a sample shows where a bound
    changes, at that step's time. Each sample is kept at its own time, preceded by the previous sample's value one
    evaluation period earlier (the period: the most common time between changes; that evaluation saw the same value
    and its row did not change), so that a bound moves only between two evaluations, as the monitor saw it. The first
    and last steps are kept (the last: the failing step's reading, when the rollout failed). NaN bounds (no interval)
    stay NaN: a gap in the band.
    """
    t = np.asarray(times, dtype=float)
    b = np.asarray(bounds, dtype=float)
    n = len(t)
    if n == 0:
        return t, b[:, 0], b[:, 1], np.zeros(0, dtype=bool)
    same = np.all((b[1:] == b[:-1]) | (np.isnan(b[1:]) & np.isnan(b[:-1])), axis=1)
    changes = np.flatnonzero(~same) + 1
    gaps = np.diff(t[changes])
    if gaps.size:
        values, counts = np.unique(np.round(gaps, 9), return_counts=True)
        period = float(values[np.argmax(counts)])
    else:
        period = np.inf
    half_step = 0.5 * float(np.min(np.diff(t))) if n > 1 else 0.0
    keep_t, keep_b, sampled = [t[0]], [b[0]], [True]
    for k in changes:
        held = t[k] - period
        if held > keep_t[-1] + half_step:
            keep_t.append(held)
            keep_b.append(b[k - 1])
            sampled.append(False)
        keep_t.append(t[k])
        keep_b.append(b[k])
        sampled.append(True)
    if t[-1] > keep_t[-1]:
        keep_t.append(t[-1])
        keep_b.append(b[-1])
        sampled.append(False)
    kb = np.array(keep_b)
    return np.array(keep_t), kb[:, 0], kb[:, 1], np.array(sampled)


def plot_rollout(result: RolloutResult, path: str | Path, *, scenario: Scenario | None = None,
                 plant: str | None = None, danger_fraction: float = DANGER_FRACTION) -> Path:
    """Per finger: feasible band, danger zones, planned and actual contact versus time (module docstring); the title
    :func:`rollout_title` of ``scenario`` and ``plant`` (the plant's name, e.g. ``"project"``)."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    m = len(result.names)
    fig, axes = pyplot().subplots(m, 1, figsize=(9, 2.3 * m + 0.6), sharex=True, squeeze=False)
    t = result.times
    failure = result.failure
    colour = "#d62728" if failure is None else FAILURE_COLOURS.get(failure.kind.value, "#d62728")
    handles = {}
    for i, (ax, name) in enumerate(zip(axes[:, 0], result.names)):
        ts, lo, hi, _ = band_samples(t, result.bounds[:, i])
        lo, hi = lo * _MM, hi * _MM
        (lo_end, lo_zone), (hi_zone, hi_end) = danger_zones(lo, hi, danger_fraction)
        ax.fill_between(ts, lo_zone, hi_zone, color=_BAND, linewidth=0)
        ax.fill_between(ts, lo_end, lo_zone, color=_DANGER, linewidth=0)
        ax.fill_between(ts, hi_zone, hi_end, color=_DANGER, linewidth=0)
        handles["band"] = Patch(color=_BAND, label="feasible band at the measured pose (the monitor's samples, "
                                                   "joined)")
        handles["danger"] = Patch(color=_DANGER, label=f"danger zone ({100 * danger_fraction:g} % of the band at "
                                                       "each end)")
        sliding = np.array([p in ("priming", "sliding", "settling") for p in result.phases[:, i]])
        if sliding.any():
            ax.fill_between(t, 0, 1, where=sliding, transform=ax.get_xaxis_transform(), color=_SLIDE,
                            alpha=0.5, linewidth=0)
            handles["slide"] = Patch(color=_SLIDE, alpha=0.5, label="sliding (priming, sliding, settling)")
        if np.isfinite(result.planned_xi[:, i]).any():
            ax.plot(t, result.planned_xi[:, i] * _MM, "--", color="#1f77b4", lw=1.2)
            handles["planned"] = Line2D([], [], ls="--", color="#1f77b4", lw=1.2, label="planned ξ_d")
        ax.plot(t, result.xi[:, i] * _MM, color="black", lw=1.0)
        handles["xi"] = Line2D([], [], color="black", lw=1.0, label="actual ξ")
        if failure is not None:
            ax.axvline(failure.time, color=colour, lw=1.2)
            if failure.contact == name and len(t):
                ax.plot([t[-1]], [result.xi[-1, i] * _MM], "x", color=colour, ms=9, mew=2)
            handles["failure"] = Line2D([], [], color=colour, lw=1.2, marker="x",
                                        label=f"failure ({failure.kind.value})")
        ax.set_ylabel(f"{name}\nξ [mm]")
        ax.grid(alpha=0.3)
        ylim = ax.get_ylim()
        if scenario is not None and shade_arcs(ax, scenario.polygon, ylim[0] / _MM, ylim[1] / _MM):
            handles["arc"] = Patch(**ARC_STYLE, label="a corner's arc")
        ax.set_ylim(*ylim)
    axes[-1, 0].set_xlabel("t [s]")
    fig.suptitle(rollout_title(result, scenario, plant), fontsize=10)
    fig.tight_layout(rect=(0, 0.5 / (2.3 * m + 0.6), 1, 1))
    fig.legend(handles=list(handles.values()), loc="lower center", ncol=3, fontsize=7, frameon=False)
    return save_figure(fig, path, layout=False)


def plot_frames(result: RolloutResult, hand: Hand, polygon: ConvexPolygon | CurvedObject, path: str | Path, *,
                scenario: Scenario | None = None, plant: str | None = None, frames: int = 6) -> Path:
    """The hand and the object at ``frames`` times of the rollout (module docstring); the gravity arrow is
    ``scenario``'s (none without one), the title :func:`rollout_title`."""
    n = result.steps
    picks = list(np.linspace(0, n - 1, frames).round().astype(int)) if n else []
    cols = min(len(picks), 3) or 1
    rows = max(1, -(-len(picks) // cols))
    plt = pyplot()
    fig, axes = plt.subplots(rows, cols, figsize=(3.6 * cols, 3.4 * rows + 0.6), squeeze=False)
    everything = []
    seen = set()
    for ax, k in zip(axes.flat, picks):
        X = result.poses[k]
        verts = outline_in(polygon, X) * _MM  # (a curve's outline: within 0.05 mm of it)
        ax.fill(*np.vstack([verts, verts[:1]]).T, color="#bbbbbb", ec="#333333", lw=1.2)
        for i, finger in enumerate(hand.fingers):
            chain = finger.joint_positions_in_hand(result.joint_positions[k, 2 * i:2 * i + 2]) * _MM
            everything.append(chain)
            ax.plot(chain[:, 0], chain[:, 1], "-o", color="#1f77b4", lw=3, ms=3)
            phase = result.phases[k, i]
            seen.add(phase)
            ax.plot(*chain[-1], "o", color=_PHASE_COLOURS.get(phase, "black"), ms=7)
            ax.annotate(finger.name, chain[0], xytext=(0, -4), textcoords="offset points", ha="center", va="top",
                        fontsize=7, color="#1f4e79")
        everything.append(verts)
        failed = result.failure is not None and k == n - 1
        if failed and result.failure.contact in result.names:  # the failing contact ringed in its kind's colour
            i = result.names.index(result.failure.contact)
            tip = hand.fingers[i].joint_positions_in_hand(result.joint_positions[k, 2 * i:2 * i + 2])[-1] * _MM
            ax.plot(*tip, "o", mfc="none", mec=FAILURE_COLOURS.get(result.failure.kind.value, "#d62728"), ms=14,
                    mew=2)
        ax.set_title(f"t = {result.times[k]:.3f} s" + (f" - {result.failure.kind.value}" if failed else ""),
                     fontsize=9, color=FAILURE_COLOURS.get(result.failure.kind.value, "#d62728") if failed else "black")
        ax.set_aspect("equal")
        ax.grid(alpha=0.3)
    for ax in list(axes.flat)[len(picks):]:
        ax.axis("off")
    if everything:
        pts = np.vstack(everything)
        lo, hi = pts.min(axis=0) - 12, pts.max(axis=0) + 12
        for ax in list(axes.flat)[:len(picks)]:
            ax.set_xlim(lo[0], hi[0])
            ax.set_ylim(lo[1], hi[1])
            if scenario is not None:
                _gravity_arrow(ax, scenario.gravity_in_hand)
    handles = [plt.Line2D([], [], marker="o", ls="", color=c, label=f"contact {p}") for p, c in _PHASE_COLOURS.items()
               if p in seen]
    fig.suptitle(f"{rollout_title(result, scenario, plant)}\nhand frame [mm]", fontsize=10)
    fig.tight_layout(rect=(0, 0.06, 1, 0.97))
    fig.legend(handles=handles, loc="lower center", ncol=len(handles) or 1, fontsize=8, frameon=False)
    return save_figure(fig, path, layout=False)


def write_rollout_figures(rollout: Rollout, result: RolloutResult, directory: str | Path, *,
                          plant: str | None = None) -> list[Path]:
    """Write ``rollout.png`` (:func:`plot_rollout`) and ``frames.png`` (:func:`plot_frames`) of ``result``, a run of
    ``rollout`` on the plant named ``plant``, into ``directory``; their paths."""
    directory = Path(directory)
    named = dict(scenario=rollout.scenario, plant=plant)
    return [plot_rollout(result, directory / "rollout.png", **named),
            plot_frames(result, rollout.supervisor.hand, rollout.plant.polygon, directory / "frames.png", **named)]


def _gravity_arrow(ax, gravity) -> None:
    """Gravity's direction as an arrow in the axes' upper left corner ("g")."""
    g = np.asarray(gravity, dtype=float)
    size = float(np.hypot(*g))
    if size == 0.0:
        return
    u = 0.08 * g / size
    tail = np.array([0.08, 0.86]) - 0.5 * u
    ax.annotate("", xy=tuple(tail + u), xytext=tuple(tail), xycoords="axes fraction",
                arrowprops=dict(arrowstyle="-|>", color="#444444", lw=1.5))
    ax.text(*(tail + np.array([0.04, 0.0])), "g", transform=ax.transAxes, fontsize=8, color="#444444",
            va="center")

"""PNG figures of a rollout, after the paper's Figures 4.2–4.4 (matplotlib, headless).

* :func:`plot_rollout` (Fig. 4.3, as run): per finger, the feasible band around the contact at
  the measured pose, its danger zones (``danger_fraction`` of the band's width at both ends), the
  schedule's planned ξ_d and the actual ξ against time, the slides shaded, the failure marked.
* :func:`plot_frames` (Figs. 4.2 and 4.4): the hand and the object at a few times of the rollout
  (fingers as their joint chains, contacts coloured by phase), the failure's frame last.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..core.figures import pyplot, save_figure

if TYPE_CHECKING:
    from ..core.polygon import ConvexPolygon
    from ..model.hand import Hand
    from .result import RolloutResult

__all__ = ["plot_frames", "plot_rollout"]

_MM = 1000.0
_PHASE_COLOURS = {"fixed": "#2ca02c", "priming": "#9467bd", "sliding": "#ff7f0e", "settling": "#8c564b"}


def _failure_title(result) -> str:
    if result.success:
        return f"success over {result.simulated_seconds:.2f} s"
    f = result.failure
    return f"failure at t = {f.time:.3f} s ({f.kind.value})"


def plot_rollout(result: RolloutResult, path: str | Path, *, danger_fraction: float = 0.1) -> Path:
    """Per finger: feasible band, danger zones, planned and actual contact versus time (module docstring)."""
    m = len(result.names)
    fig, axes = pyplot().subplots(m, 1, figsize=(9, 2.4 * m), sharex=True, squeeze=False)
    t = result.times
    for i, (ax, name) in enumerate(zip(axes[:, 0], result.names)):
        lo, hi = result.bounds[:, i, 0] * _MM, result.bounds[:, i, 1] * _MM
        keep = danger_fraction * (hi - lo)
        ax.fill_between(t, lo, hi, color="#cfe8cf", label="feasible (at the measured pose)", linewidth=0)
        ax.fill_between(t, lo, lo + keep, color="#f4b6b6", label="danger zone", linewidth=0)
        ax.fill_between(t, hi - keep, hi, color="#f4b6b6", linewidth=0)
        sliding = np.array([p in ("priming", "sliding", "settling") for p in result.phases[:, i]])
        if sliding.any():
            ax.fill_between(t, 0, 1, where=sliding, transform=ax.get_xaxis_transform(), color="#ffd8a8",
                            alpha=0.5, linewidth=0, label="sliding")
        if np.isfinite(result.planned_xi[:, i]).any():
            ax.plot(t, result.planned_xi[:, i] * _MM, "--", color="#1f77b4", lw=1.2, label="planned ξ_d")
        ax.plot(t, result.xi[:, i] * _MM, color="black", lw=1.0, label="actual ξ")
        if result.failure is not None:
            ax.axvline(result.failure.time, color="#d62728", lw=1.2, label="failure")
        ax.set_ylabel(f"{name}\nξ [mm]")
        ax.grid(alpha=0.3)
    axes[0, 0].legend(loc="upper right", fontsize=7, ncol=3)
    axes[-1, 0].set_xlabel("t [s]")
    fig.suptitle(f"{result.policy} policy: contacts in their feasible bands - {_failure_title(result)}", fontsize=10)
    return save_figure(fig, path)


def plot_frames(result: RolloutResult, hand: Hand, polygon: ConvexPolygon, path: str | Path, *,
                frames: int = 6) -> Path:
    """The hand and the object at ``frames`` times of the rollout (module docstring)."""
    n = result.steps
    picks = list(np.linspace(0, n - 1, frames).round().astype(int)) if n else []
    cols = min(len(picks), 3) or 1
    rows = max(1, -(-len(picks) // cols))
    plt = pyplot()
    fig, axes = plt.subplots(rows, cols, figsize=(3.6 * cols, 3.4 * rows), squeeze=False)
    everything = []
    for ax, k in zip(axes.flat, picks):
        X = result.poses[k]
        verts = polygon.vertices_in(X) * _MM
        ax.fill(*np.vstack([verts, verts[:1]]).T, color="#bbbbbb", ec="#333333", lw=1.2)
        for i, finger in enumerate(hand.fingers):
            chain = finger.joint_positions_in_hand(result.joint_positions[k, 2 * i:2 * i + 2]) * _MM
            everything.append(chain)
            ax.plot(chain[:, 0], chain[:, 1], "-o", color="#1f77b4", lw=3, ms=3)
            phase = result.phases[k, i]
            ax.plot(*chain[-1], "o", color=_PHASE_COLOURS.get(phase, "black"), ms=7)
        everything.append(verts)
        failed = result.failure is not None and k == n - 1
        ax.set_title(f"t = {result.times[k]:.3f} s" + (f" - {result.failure.kind.value}" if failed else ""),
                     fontsize=9, color="#d62728" if failed else "black")
        ax.set_aspect("equal")
        ax.grid(alpha=0.3)
    for ax in list(axes.flat)[len(picks):]:
        ax.axis("off")
    if everything:
        pts = np.vstack(everything)
        lo, hi = pts.min(axis=0) - 10, pts.max(axis=0) + 10
        for ax in list(axes.flat)[:len(picks)]:
            ax.set_xlim(lo[0], hi[0])
            ax.set_ylim(lo[1], hi[1])
    handles = [plt.Line2D([], [], marker="o", ls="", color=c, label=p) for p, c in _PHASE_COLOURS.items()]
    fig.legend(handles=handles, loc="lower center", ncol=4, fontsize=8)
    fig.suptitle(f"{result.policy} policy, hand frame [mm] - {_failure_title(result)}", fontsize=10)
    fig.tight_layout(rect=(0, 0.05, 1, 0.95))
    return save_figure(fig, path, layout=False)

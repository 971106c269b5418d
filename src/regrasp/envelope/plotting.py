"""PNG figures of a plan, after the paper's Figures 2.9, 2.10 and 2.14 (matplotlib, headless).

* ``d.png`` (Fig. 2.9): d(t) of each finger, the bands ±l1, and the condition I–IV
  intervals shaded.
* ``reachable.png`` (Fig. 2.10): the reachable set on the edge's line (a curve's boundary) versus time.
* ``feasible.png`` (Fig. 2.14): the feasible set inside the reachable set versus time,
  with the edge's ends (ξ_lower, ξ_upper) and the suggested initial contact. On a rounded polygon both shade its
  corners' arcs.

The regrasp schedule's figure (Fig. 4.3) is :func:`regrasp.schedule.plotting.plot_schedule`. matplotlib is
imported on first use (:mod:`regrasp.core.figures`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..core.figures import ARC_STYLE, MM, membership, save_figure, shade_arcs, stacked_axes
from .planner import FingerPlan, PlanResult

__all__ = ["plot_conditions", "plot_feasible", "plot_reachable", "write_plan_figures"]

_CONDITION_COLORS = {"I": "#e41a1c", "II": "#ff7f00", "III": "#4daf4a", "IV": "#377eb8"}


def _runs(values):
    """(start index, end index, value) of maximal runs of equal consecutive values."""
    out, start = [], 0
    for k in range(1, len(values) + 1):
        if k == len(values) or values[k] != values[start]:
            out.append((start, k - 1, values[start]))
            start = k
    return out


def _shade_conditions(ax, times, finger: FingerPlan, alpha=0.15):
    conds = [s.condition.value for s in finger.samples]
    half = 0.5 * (times[1] - times[0]) if len(times) > 1 else 0.0
    for i, j, c in _runs(conds):
        ax.axvspan(times[i] - half, times[j] + half, color=_CONDITION_COLORS[c], alpha=alpha, lw=0)


def _condition_legend(present):
    from matplotlib.patches import Patch

    return [Patch(color=_CONDITION_COLORS[c], alpha=0.35, label=f"condition {c}") for c in ("I", "II", "III", "IV")
            if c in present]


def plot_conditions(plan: PlanResult, path: str | Path) -> Path:
    """Figure 2.9: d(t) with ±l1 and the condition intervals shaded."""
    times = plan.times
    fig, axes = stacked_axes(len(plan.fingers))
    for ax, finger in zip(axes, plan.fingers):
        d = np.array([s.d for s in finger.samples]) * MM
        l1 = finger.link_lengths[0] * MM
        _shade_conditions(ax, times, finger)
        ax.plot(times, d, color="k", lw=1.6, label="d(t)")
        for y, style in ((l1, "--"), (-l1, "--"), (0.0, ":")):
            ax.axhline(y, color="0.3", ls=style, lw=1)
        ax.text(times[0], l1, "+l1", va="bottom", ha="left", fontsize=8)
        ax.text(times[0], -l1, "-l1", va="top", ha="left", fontsize=8)
        for k, iv in enumerate(finger.infeasible_intervals):
            ax.plot([iv.start, iv.end], [-l1 * 1.12] * 2, color=_CONDITION_COLORS["I"], lw=3, solid_capstyle="butt")
            ax.annotate(f"infeasible: {iv.reason}", xy=(0.5 * (iv.start + iv.end), -l1 * 1.12),
                        xytext=(0, -10 - 11 * (k % 2)), textcoords="offset points", ha="center", fontsize=8,
                        color=_CONDITION_COLORS["I"])
        ax.set_ylabel("d [mm]")
        ax.set_title(f"{finger.name}: edge {finger.edge}, {finger.configuration} configuration")
        present = {s.condition.value for s in finger.samples}
        ax.legend(handles=[*ax.get_legend_handles_labels()[0], *_condition_legend(present)], loc="upper left",
                  bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)  # (beside the plot: it hid d(t))
        ax.set_ylim(min(d.min(), -l1) - 0.45 * l1, max(d.max(), l1) + 0.35 * l1)
    axes[-1].set_xlabel("t [s]")
    fig.suptitle(f"{plan.scenario or 'plan'}: line distance d(t) and conditions I-IV (paper Fig. 2.9)")
    return save_figure(fig, path)


def _envelope_axes(ax, plan: PlanResult, finger: FingerPlan, feasible: bool):
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    times = plan.times
    reach = [s.reachable for s in finger.samples]
    edge_lo, edge_hi = finger.samples[0].edge_range
    curved = finger.samples[0].xi_foot is not None  # (a curve: each sample's window of one perimeter)
    if curved:
        lo = min(s.edge_range[0] for s in finger.samples)
        hi = max(s.edge_range[1] for s in finger.samples)
    elif feasible:  # zoom on the actual edge: that is where contacts can be
        pad = 0.6 * (edge_hi - edge_lo)
        lo, hi = edge_lo - pad, edge_hi + pad
    else:
        ends = [x for r in reach for iv in r for x in iv] + [edge_lo, edge_hi]
        span = max(ends) - min(ends)
        lo, hi = min(ends) - 0.03 * span, max(ends) + 0.03 * span
    grid = np.linspace(lo, hi, 700)
    extent = (times[0], times[-1], lo * MM, hi * MM)
    img = membership(times, reach, grid).astype(float)
    if feasible:
        img += membership(times, [s.feasible for s in finger.samples], grid)
    cmap = ListedColormap(["white", "#c6dbef", "#08519c"])
    ax.imshow(img, origin="lower", aspect="auto", extent=extent, cmap=cmap, vmin=0, vmax=2,
              interpolation="nearest")
    _shade_conditions(ax, times, finger, alpha=0.08)
    handles = [Patch(color="#c6dbef", label="reachable")]
    if curved and shade_arcs(ax, plan.polygon, lo, hi):
        handles.append(Patch(**ARC_STYLE, label="a corner's arc"))
    if feasible:
        handles.append(Patch(color="#08519c", label="feasible"))
        for y, name in () if curved else ((edge_hi, "upper"), (edge_lo, "lower")):
            ax.axhline(y * MM, color="#d95f02", ls="--", lw=1.2)
            ax.text(times[0], y * MM, f" ξ_{name} (edge end)", va="bottom", ha="left", fontsize=8, color="#d95f02")
        if finger.initial_xi is not None:
            until = finger.initial_xi_feasible_until
            ax.plot([times[0], until], [finger.initial_xi * MM] * 2, color="#e7298a", lw=2,
                    label=f"initial ξ = {finger.initial_xi * MM:.1f} mm,\nfeasible until t = {until:.2f} s")
            handles.append(ax.get_legend_handles_labels()[0][-1])
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8,
              frameon=False)  # (beside the plot: it hid the sets)
    ax.set_ylabel("ξ [mm]")
    ax.set_title(f"{finger.name}: {'the boundary' if curved else f'edge {finger.edge}'}, {finger.configuration} "
                 "configuration")


def plot_reachable(plan: PlanResult, path: str | Path) -> Path:
    """Figure 2.10: the set of reachable points versus time."""
    fig, axes = stacked_axes(len(plan.fingers))
    for ax, finger in zip(axes, plan.fingers):
        _envelope_axes(ax, plan, finger, feasible=False)
    axes[-1].set_xlabel("t [s]")
    where = "boundary" if plan.fingers[0].samples[0].xi_foot is not None else "edge's line"
    fig.suptitle(f"{plan.scenario or 'plan'}: reachable contacts on the {where} (paper Fig. 2.10)")
    return save_figure(fig, path)


def plot_feasible(plan: PlanResult, path: str | Path) -> Path:
    """Figure 2.14: the feasible set inside the reachable set versus time."""
    fig, axes = stacked_axes(len(plan.fingers))
    for ax, finger in zip(axes, plan.fingers):
        _envelope_axes(ax, plan, finger, feasible=True)
    axes[-1].set_xlabel("t [s]")
    fig.suptitle(f"{plan.scenario or 'plan'}: feasible contacts inside the reachable set "
                 f"({plan.geometry.value} geometry, paper Fig. 2.14)")
    return save_figure(fig, path)


def write_plan_figures(plan: PlanResult, directory: str | Path) -> list[Path]:
    """Write ``d.png``, ``reachable.png`` and ``feasible.png`` into ``directory``."""
    directory = Path(directory)
    return [
        plot_conditions(plan, directory / "d.png"),
        plot_reachable(plan, directory / "reachable.png"),
        plot_feasible(plan, directory / "feasible.png"),
    ]

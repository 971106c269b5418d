"""PNG figure of a regrasp schedule, after the paper's Figure 4.3 (matplotlib, headless).

* ``regrasp.png`` (Fig. 4.3, :func:`plot_schedule`): per finger its feasible band, its danger zones
  (:func:`~regrasp.core.intervals.danger_zones`: the same zones the rollout figures and the rerun recording draw),
  the part within the schedule's required margin of its bounds, the scheduled contact and its slides; on a rounded
  polygon its corners' arcs (a slide from an edge onto an arc crosses into one).

matplotlib is imported on first use (:mod:`regrasp.core.figures`).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..core.figures import ARC_STYLE, MM, membership, save_figure, shade_arcs, stacked_axes
from ..core.intervals import DANGER_FRACTION, without_danger_zones

if TYPE_CHECKING:
    from ..envelope.planner import PlanResult
    from .schedule import NoScheduleError, RegraspSchedule

__all__ = ["plot_schedule"]


def plot_schedule(plan: PlanResult, schedule: RegraspSchedule, path: str | Path, *,
                  failure: NoScheduleError | None = None) -> Path:
    """Paper Figure 4.3 for a planned schedule: per finger its feasible band over time, its danger zones
    (:data:`~regrasp.core.intervals.DANGER_FRACTION` of each interval at both ends), the parts within the required
    envelope margin of its bounds (which the schedule keeps ξ_d out of),
    the scheduled contact ξ_d(t) and its slides (shaded, with their direction). With ``failure``
    (a :class:`~regrasp.schedule.schedule.NoScheduleError` whose ``partial`` is ``schedule``), the schedule
    is drawn up to the latest time any admissible state survives, which is marked with the reason."""
    from matplotlib.colors import ListedColormap
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    times = plan.times
    fig, axes = stacked_axes(len(plan.fingers))
    t_grid = np.linspace(times[0], times[-1], 2000)
    xi_d = schedule.at(t_grid).xi
    if schedule.period is None:  # a schedule that does not repeat says nothing past its horizon
        xi_d[(t_grid < schedule.t_start) | (t_grid > schedule.t_end)] = np.nan
    margin = schedule.required_envelope_margin
    period = schedule.period
    repeats = [0.0] if period is None else period * np.arange(int(np.ceil((times[-1] - schedule.t_start) / period)) + 1)
    curved = getattr(plan.polygon.edge(plan.fingers[0].edge), "curved", False)
    arcs = False
    for i, (ax, finger) in enumerate(zip(axes, plan.fingers)):
        edge_lo, edge_hi = finger.samples[0].edge_range
        if curved:  # (no edge ends: the span of the feasible sets, ξ unwrapped along the trajectory)
            ends = [x for s in finger.samples for iv in s.feasible for x in iv] or [edge_lo, edge_hi]
            edge_lo, edge_hi = min(ends), max(ends)
        pad = 0.08 * (edge_hi - edge_lo)
        grid = np.linspace(edge_lo - pad, edge_hi + pad, 600)
        feasible = [s.feasible for s in finger.samples]
        kept = [tuple((lo + margin, hi - margin) for lo, hi in f if hi - lo > 2 * margin) for f in feasible]
        inside = membership(times, feasible, grid)
        kept_in = membership(times, kept, grid)
        safe = kept_in & membership(times, [without_danger_zones(f) for f in feasible], grid)
        img = inside.astype(float) + kept_in + safe  # 0 out, 1 within the margin, 2 danger zone, 3 safe
        cmap = ListedColormap(["white", "#cb181d", "#fc9272", "#c6dbef"])
        ax.imshow(img, origin="lower", aspect="auto", cmap=cmap, vmin=0, vmax=3, interpolation="nearest",
                  extent=(times[0], times[-1], grid[0] * MM, grid[-1] * MM))
        for y in () if curved else (edge_lo, edge_hi):
            ax.axhline(y * MM, color="#d95f02", ls="--", lw=1)
        arcs = (curved and shade_arcs(ax, plan.polygon, grid[0], grid[-1])) or arcs
        ours = [s for s in schedule.slides if s.contact == i]
        for offset in repeats:
            for s in ours:
                start, end = s.start + offset, s.end + offset
                if start > times[-1]:
                    continue
                ax.axvspan(start, end, color="#969696", alpha=0.25, lw=0)
                ax.annotate("", xy=(end, s.end_xi * MM), xytext=(start, s.start_xi * MM),
                            arrowprops=dict(arrowstyle="->", color="#a63603", lw=1.2))
        ax.plot(t_grid, xi_d[:, i] * MM, color="k", lw=1.8)
        if failure is not None:
            ax.axvline(failure.latest_time, color="#cb181d", lw=1.5)
            if failure.contacts == (finger.name,) or finger.name in failure.contacts:
                ax.text(failure.latest_time, grid[-1] * MM, f" no schedule after t = {failure.latest_time:.2f} s "
                        f"({failure.limit.value})", va="top", ha="left", fontsize=8, color="#cb181d")
        per = f"{len(ours)} slide{'s' if len(ours) != 1 else ''}" + (" per period" if period else "")
        ax.set_title(f"{finger.name}: {'the boundary' if curved else f'edge {finger.edge}'}, {per}")
        ax.set_ylabel("ξ [mm]")
        ax.set_ylim(grid[0] * MM, grid[-1] * MM)
    handles = [Patch(color="#c6dbef", label="feasible"),
               Patch(color="#fc9272", label=f"danger zone ({100 * DANGER_FRACTION:g} % of the band at each end)"),
               Patch(color="#cb181d", label=f"within the required margin ({margin * MM:g} mm) of a bound"),
               Patch(color="#969696", alpha=0.25, label="slide (arrow: from, to)"),
               Line2D([], [], color="k", lw=1.8, label="scheduled contact ξ_d(t)"),
               *([] if curved else [Line2D([], [], color="#d95f02", ls="--", lw=1, label="edge ends")]),
               *([Patch(**ARC_STYLE, label="a corner's arc")] if arcs else [])]
    axes[-1].set_xlabel("t [s]")
    if failure is None:
        title = (f"{plan.scenario or 'plan'}: regrasp schedule, {len(schedule.slides)} slides"
                 + (f" per period of {period:.3g} s" if period else "") + " (paper Fig. 4.3)")
    else:
        title = (f"{plan.scenario or 'plan'}: no regrasp schedule ({failure.limit.value}); the best one "
                 f"up to t = {failure.latest_time:.2f} s")
    fig.suptitle(title)
    fig.tight_layout(rect=(0, 0.045, 1, 1))
    fig.legend(handles=handles, loc="lower center", fontsize=8, ncol=3, frameon=False)
    return save_figure(fig, path, layout=False)

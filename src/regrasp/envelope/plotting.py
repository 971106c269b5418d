"""PNG figures of a plan, after the paper's Figures 2.9, 2.10 and 2.14 (matplotlib, headless).

* ``d.png`` (Fig. 2.9): d(t) of each finger, the bands ±l1, and the condition I–IV
  intervals shaded.
* ``reachable.png`` (Fig. 2.10): the reachable set on the edge's line versus time.
* ``feasible.png`` (Fig. 2.14): the feasible set inside the reachable set versus time,
  with the edge's ends (ξ_lower, ξ_upper) and the suggested initial contact.
* ``regrasp.png`` (Fig. 4.3, :func:`plot_schedule`): per finger its feasible band, the danger
  zones within the required margin of its bounds, the scheduled contact and its slides.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402
from numpy.typing import ArrayLike  # noqa: E402

from .planner import FingerPlan, PlanResult  # noqa: E402

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ..core.contact import FrictionLike
    from ..core.polygon import ConvexPolygon
    from ..dynamics.sliding import SlideFeasibility
    from ..model.finger import Finger
    from ..schedule.schedule import NoScheduleError, RegraspSchedule

__all__ = ["plot_conditions", "plot_feasible", "plot_reachable", "plot_schedule", "plot_slide_feasibility",
           "write_plan_figures"]

_CONDITION_COLORS = {"I": "#e41a1c", "II": "#ff7f00", "III": "#4daf4a", "IV": "#377eb8"}
_MM = 1000.0  # plot lengths in millimetres


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
    return [Patch(color=_CONDITION_COLORS[c], alpha=0.35, label=f"condition {c}") for c in ("I", "II", "III", "IV")
            if c in present]


def _membership(times, sets_per_sample, grid):
    """(len(grid), len(times)) boolean image: grid value inside the sample's interval set."""
    img = np.zeros((len(grid), len(times)), dtype=bool)
    for k, intervals in enumerate(sets_per_sample):
        for lo, hi in intervals:
            img[:, k] |= (grid >= lo) & (grid <= hi)
    return img


def _figure(n):
    fig, axes = plt.subplots(n, 1, figsize=(9, 3.4 * n), sharex=True, squeeze=False)
    return fig, axes[:, 0]


def plot_conditions(plan: PlanResult, path: str | Path) -> Path:
    """Figure 2.9: d(t) with ±l1 and the condition intervals shaded."""
    times = plan.times
    fig, axes = _figure(len(plan.fingers))
    for ax, finger in zip(axes, plan.fingers):
        d = np.array([s.d for s in finger.samples]) * _MM
        l1 = finger.link_lengths[0] * _MM
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
        ax.legend(handles=[*ax.get_legend_handles_labels()[0], *_condition_legend(present)], loc="upper right",
                  fontsize=8, ncol=5)
        ax.set_ylim(min(d.min(), -l1) - 0.45 * l1, max(d.max(), l1) + 0.35 * l1)
    axes[-1].set_xlabel("t [s]")
    fig.suptitle(f"{plan.scenario or 'plan'}: line distance d(t) and conditions I-IV (paper Fig. 2.9)")
    return save_figure(fig, path)


def _envelope_axes(ax, plan: PlanResult, finger: FingerPlan, feasible: bool):
    times = plan.times
    reach = [s.reachable for s in finger.samples]
    edge_lo, edge_hi = finger.samples[0].edge_range
    if feasible:  # zoom on the actual edge: that is where contacts can be
        pad = 0.6 * (edge_hi - edge_lo)
        lo, hi = edge_lo - pad, edge_hi + pad
    else:
        ends = [x for r in reach for iv in r for x in iv] + [edge_lo, edge_hi]
        span = max(ends) - min(ends)
        lo, hi = min(ends) - 0.03 * span, max(ends) + 0.03 * span
    grid = np.linspace(lo, hi, 700)
    extent = (times[0], times[-1], lo * _MM, hi * _MM)
    img = _membership(times, reach, grid).astype(float)
    if feasible:
        img += _membership(times, [s.feasible for s in finger.samples], grid)
    cmap = matplotlib.colors.ListedColormap(["white", "#c6dbef", "#08519c"])
    ax.imshow(img, origin="lower", aspect="auto", extent=extent, cmap=cmap, vmin=0, vmax=2,
              interpolation="nearest")
    _shade_conditions(ax, times, finger, alpha=0.08)
    handles = [Patch(color="#c6dbef", label="reachable")]
    if feasible:
        handles.append(Patch(color="#08519c", label="feasible"))
        for y, name in ((edge_hi, "upper"), (edge_lo, "lower")):
            ax.axhline(y * _MM, color="#d95f02", ls="--", lw=1.2)
            ax.text(times[0], y * _MM, f" ξ_{name} (edge end)", va="bottom", ha="left", fontsize=8, color="#d95f02")
        if finger.initial_xi is not None:
            until = finger.initial_xi_feasible_until
            ax.plot([times[0], until], [finger.initial_xi * _MM] * 2, color="#e7298a", lw=2,
                    label=f"initial ξ = {finger.initial_xi * _MM:.1f} mm, feasible until t = {until:.2f} s")
            handles.append(ax.get_legend_handles_labels()[0][-1])
    ax.legend(handles=handles, loc="upper right", fontsize=8, framealpha=0.9)
    ax.set_ylabel("ξ [mm]")
    ax.set_title(f"{finger.name}: edge {finger.edge}, {finger.configuration} configuration")


def plot_reachable(plan: PlanResult, path: str | Path) -> Path:
    """Figure 2.10: the set of reachable points versus time."""
    fig, axes = _figure(len(plan.fingers))
    for ax, finger in zip(axes, plan.fingers):
        _envelope_axes(ax, plan, finger, feasible=False)
    axes[-1].set_xlabel("t [s]")
    fig.suptitle(f"{plan.scenario or 'plan'}: reachable contacts on the edge's line (paper Fig. 2.10)")
    return save_figure(fig, path)


def plot_feasible(plan: PlanResult, path: str | Path) -> Path:
    """Figure 2.14: the feasible set inside the reachable set versus time."""
    fig, axes = _figure(len(plan.fingers))
    for ax, finger in zip(axes, plan.fingers):
        _envelope_axes(ax, plan, finger, feasible=True)
    axes[-1].set_xlabel("t [s]")
    fig.suptitle(f"{plan.scenario or 'plan'}: feasible contacts inside the reachable set "
                 f"({plan.geometry.value} geometry, paper Fig. 2.14)")
    return save_figure(fig, path)


def save_figure(fig: Figure, path: str | Path, layout: bool = True) -> Path:
    """Write ``fig`` to ``path`` (its directory made if missing) and close it."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if layout:
        fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def write_plan_figures(plan: PlanResult, directory: str | Path) -> list[Path]:
    """Write ``d.png``, ``reachable.png`` and ``feasible.png`` into ``directory``."""
    directory = Path(directory)
    return [
        plot_conditions(plan, directory / "d.png"),
        plot_reachable(plan, directory / "reachable.png"),
        plot_feasible(plan, directory / "feasible.png"),
    ]


def plot_slide_feasibility(polygon: ConvexPolygon, pose: ArrayLike, fingers: Sequence[Finger],
                           points_in_hand: np.ndarray | Sequence[ArrayLike], edges: Sequence[int],
                           friction: FrictionLike, results: Sequence[SlideFeasibility], path: str | Path, *,
                           gravity_in_hand: ArrayLike = (0.0, -9.81), title: str = "") -> Path:
    """Figure 3.4: the object, the fingers and, per slide direction, the predicted contact forces
    inside their friction cones, and whether the slide is possible.

    Args:
        polygon: The object; ``pose`` its pose (x, y, β) in the hand frame.
        fingers: The fingers (drawn through their inverse kinematics to ``points_in_hand``).
        points_in_hand: Contact points (m, 2) [m], on edges ``edges``.
        friction: The contacts' :class:`~regrasp.core.contact.Friction` (one for all, a coefficient, or one
            per contact): cone half-angle atan μ_k at each panel's sliding contact, atan μ_s elsewhere.
        results: One :class:`~regrasp.dynamics.sliding.SlideFeasibility` per panel.
        path: Output PNG.
    """
    from matplotlib.patches import Polygon as PolygonPatch  # noqa: PLC0415

    from ..core.contact import ContactMode, as_frictions  # noqa: PLC0415
    from ..core.planar import rotation  # noqa: PLC0415

    friction = as_frictions(friction, len(edges))
    pose = np.asarray(pose, dtype=float)
    verts = polygon.vertices_in(pose) * _MM
    rot = rotation(pose[2])
    chains = [finger.joint_positions_in_hand(finger.inverse_kinematics(point)) * _MM
              for finger, point in zip(fingers, points_in_hand)]
    everything = np.vstack([verts, *chains])
    fig, axes = plt.subplots(1, len(results), figsize=(5.2 * len(results), 5.6), squeeze=False)
    for ax, res in zip(axes[0], results):
        ax.add_patch(PolygonPatch(verts, closed=True, facecolor="#d9d9d9", edgecolor="k", lw=1.5))
        for joints in chains:
            ax.plot(joints[:, 0], joints[:, 1], "-o", color="#4d4d4d", lw=4, ms=5, solid_capstyle="round")
        scale = 25.0 / max(1e-9, np.abs(res.forces_surface).max())  # [mm per N]
        for i, (point, k) in enumerate(zip(points_in_hand, edges)):
            n = rot @ polygon.edge(k).inward_normal
            t = rot @ polygon.edge(k).xi_direction
            p = np.asarray(point) * _MM
            half = np.arctan(friction[i].coefficient(ContactMode.SLIDING if i == res.contact else ContactMode.FIXED))
            for side in (1.0, -1.0):  # the cone of forces the finger can push with, around n
                d = np.cos(half) * n + side * np.sin(half) * t
                ax.plot([p[0], p[0] + 30 * d[0]], [p[1], p[1] + 30 * d[1]], color="#66a61e", lw=1, ls=":")
            force = res.forces_surface[i, 0] * n + res.forces_surface[i, 1] * t
            color = "#1b9e77" if res.forces_surface[i, 0] >= 0 else "#d95f02"
            ax.annotate("", xy=p + scale * force, xytext=p, arrowprops=dict(arrowstyle="-|>", color=color, lw=2.2))
            ax.text(*(p + scale * force + 4 * n), f"{res.forces_surface[i, 0]:.2f} N", fontsize=8, color=color,
                    ha="center")
            if i == res.contact:
                ax.annotate("", xy=p + 14 * res.direction * t - 6 * n, xytext=p - 6 * n,
                            arrowprops=dict(arrowstyle="->", color="#7570b3", lw=1.8))
        g = np.asarray(gravity_in_hand, dtype=float)
        c = pose[:2] * _MM
        unit = g / max(np.linalg.norm(g), 1e-9)
        ax.annotate("", xy=c + 12 * unit, xytext=c, arrowprops=dict(arrowstyle="-|>", color="k", lw=1.2))
        ax.text(*(c + 15 * unit), "g", ha="center", va="center")
        verdict = "possible" if res.possible else "impossible"
        ax.set_title(f"slide {'up' if res.direction > 0 else 'down'}: {verdict}"
                     + ("" if res.possible else f"\n{res.reason}"), fontsize=9)
        ax.set_aspect("equal")
        ax.set_xlabel("x [mm]")
        ax.set_ylabel("y [mm]")
        lo, hi = np.min(everything, axis=0) - 15, np.max(everything, axis=0) + 35
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
    if title:
        fig.suptitle(title, fontsize=10)
    return save_figure(fig, path)


def plot_schedule(plan: PlanResult, schedule: RegraspSchedule, path: str | Path, *,
                  failure: NoScheduleError | None = None) -> Path:
    """Paper Figure 4.3 for a planned schedule: per finger its feasible band over time, the zones
    within the required envelope margin of its bounds (the danger zones the schedule keeps out of),
    the scheduled contact ξ_d(t) and its slides (shaded, with their direction). With ``failure``
    (a :class:`~regrasp.schedule.schedule.NoScheduleError` whose ``partial`` is ``schedule``), the schedule
    is drawn up to the latest time any admissible state survives, which is marked with the reason."""
    times = plan.times
    fig, axes = _figure(len(plan.fingers))
    t_grid = np.linspace(times[0], times[-1], 2000)
    xi_d = schedule.at(t_grid).xi
    if schedule.period is None:  # a schedule that does not repeat says nothing past its horizon
        xi_d[(t_grid < schedule.t_start) | (t_grid > schedule.t_end)] = np.nan
    margin = schedule.required_envelope_margin
    period = schedule.period
    repeats = [0.0] if period is None else period * np.arange(int(np.ceil((times[-1] - schedule.t_start) / period)) + 1)
    for i, (ax, finger) in enumerate(zip(axes, plan.fingers)):
        edge_lo, edge_hi = finger.samples[0].edge_range
        pad = 0.08 * (edge_hi - edge_lo)
        grid = np.linspace(edge_lo - pad, edge_hi + pad, 600)
        feasible = [s.feasible for s in finger.samples]
        safe = [tuple((lo + margin, hi - margin) for lo, hi in f if hi - lo > 2 * margin) for f in feasible]
        img = _membership(times, feasible, grid).astype(float) + _membership(times, safe, grid)
        cmap = matplotlib.colors.ListedColormap(["white", "#fc9272", "#c6dbef"])
        ax.imshow(img, origin="lower", aspect="auto", cmap=cmap, vmin=0, vmax=2, interpolation="nearest",
                  extent=(times[0], times[-1], grid[0] * _MM, grid[-1] * _MM))
        for y in (edge_lo, edge_hi):
            ax.axhline(y * _MM, color="#d95f02", ls="--", lw=1)
        ours = [s for s in schedule.slides if s.contact == i]
        for offset in repeats:
            for s in ours:
                start, end = s.start + offset, s.end + offset
                if start > times[-1]:
                    continue
                ax.axvspan(start, end, color="#969696", alpha=0.25, lw=0)
                ax.annotate("", xy=(end, s.end_xi * _MM), xytext=(start, s.start_xi * _MM),
                            arrowprops=dict(arrowstyle="->", color="#a63603", lw=1.2))
        ax.plot(t_grid, xi_d[:, i] * _MM, color="k", lw=1.8)
        if failure is not None:
            ax.axvline(failure.latest_time, color="#cb181d", lw=1.5)
            if failure.contacts == (finger.name,) or finger.name in failure.contacts:
                ax.text(failure.latest_time, grid[-1] * _MM, f" no schedule after t = {failure.latest_time:.2f} s "
                        f"({failure.limit.value})", va="top", ha="left", fontsize=8, color="#cb181d")
        per = f"{len(ours)} slide{'s' if len(ours) != 1 else ''}" + (" per period" if period else "")
        ax.set_title(f"{finger.name}: edge {finger.edge}, {per}")
        ax.set_ylabel("ξ [mm]")
        ax.set_ylim(grid[0] * _MM, grid[-1] * _MM)
    handles = [Patch(color="#c6dbef", label="feasible, with the margin"),
               Patch(color="#fc9272", label=f"danger zone (within {margin * _MM:g} mm of a bound)"),
               Patch(color="#969696", alpha=0.25, label="slide (arrow: from, to)"),
               matplotlib.lines.Line2D([], [], color="k", lw=1.8, label="scheduled contact ξ_d(t)"),
               matplotlib.lines.Line2D([], [], color="#d95f02", ls="--", lw=1, label="edge ends")]
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

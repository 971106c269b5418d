"""The viewer's layout stored in a recording (its default blueprint): the hand and the object with the events log
on the left, each finger's ξ panel and the phases in the middle, the other time series on the right; one unit per
plot axis, the plots' legends hidden (each view's name says what its lines are)."""

from __future__ import annotations

import numpy as np
import rerun.blueprint as rrb

from ...plants.simulation import PlantLike
from .hand import HandDrawing
from .outline import outline_in
from .style import MM

__all__ = ["blueprint", "scene_bounds"]


def scene_bounds(plant: PlantLike) -> rrb.VisualBounds2D:
    """The scene view's bounds [mm]: the fingers' joints 1, the object and the fingers at ``plant``'s state (or
    the fingers' reach without one), 25 mm around."""
    fingers = plant.hand.fingers
    pts = [f.joint1_in_hand for f in fingers]
    st = plant.state
    if st is not None:
        pts += list(outline_in(plant.polygon, st.X))
        pts += [p for i, f in enumerate(fingers) for p in f.joint_positions_in_hand(st.q[2 * i:2 * i + 2])]
    else:
        pts += [f.joint1_in_hand + s * f.reach[1] for f in fingers for s in (-1.0, 1.0)]
    mm = np.asarray(pts) * MM
    lo, hi = mm.min(axis=0) - 25.0, mm.max(axis=0) + 25.0
    return rrb.VisualBounds2D(x_range=(float(lo[0]), float(hi[0])), y_range=(float(lo[1]), float(hi[1])))


def _plot(origin: str, name: str, **kwargs) -> rrb.TimeSeriesView:
    """A time-series view of ``origin`` (and its children) with its legend hidden: the view's name says what its
    lines are, and hovering a line names it (a legend covered ~40 % of a panel)."""
    return rrb.TimeSeriesView(origin=origin, name=name, plot_legend=rrb.PlotLegend(visible=False), **kwargs)


def blueprint(plant: PlantLike, hand: HandDrawing) -> rrb.Blueprint:
    """The recording's default blueprint for ``plant`` drawn as ``hand``: one unit per plot axis."""
    scene = rrb.Spatial2DView(origin="scene", name="hand frame [mm] (y up)", visual_bounds=scene_bounds(plant))
    left = rrb.Vertical(
        rrb.Tabs(scene, rrb.Spatial2DView(origin="model/object", name="object frame [mm]"),
                 rrb.TextDocumentView(origin="model/setup", name="set-up")),
        rrb.TextLogView(origin="events", name="events: supervisor decisions and plant events"),
        row_shares=[3, 1],
    )
    middle = rrb.Vertical(
        *[_plot(f"plots/xi/{f.key}", f"{f.name} ξ [mm], ξ_d, band, danger zones") for f in hand.fingers],
        _plot("plots/phase", "phase: 0 fixed, 1 priming, 2 sliding, 3 settling",
              axis_y=rrb.ScalarAxis(range=(-0.2, 3.2))),
    )
    right = rrb.Vertical(
        _plot("plots/error/position", "tracking error x, y, ξ [mm]"),
        _plot("plots/error/angle", "tracking error β [deg]"),
        _plot("plots/force", "contact forces [N]: f_n, f_t darker, predicted faint"),
        _plot("plots/cone_margin", "friction-cone margin μ f_n − |f_t| [N]"),
        _plot("plots/mode", "contact mode: 0 fixed, 1 sliding, 2 separated", axis_y=rrb.ScalarAxis(range=(-0.2, 2.2))),
        row_shares=[3, 2, 3, 3, 2],
    )
    return rrb.Blueprint(
        rrb.Horizontal(left, middle, right, column_shares=[3, 2, 2]),
        rrb.BlueprintPanel(state="collapsed"),
        rrb.SelectionPanel(state="collapsed"),
        rrb.TimePanel(state="expanded", timeline="time"),
    )

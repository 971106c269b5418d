"""What a recording logs once (static): the object in its own frame (``model/object``), the set-up table
(``model/setup``), the styling of every scene entity (the rows carry geometry only) and the plots' series names
and colours (``rr.SeriesLines``)."""

from __future__ import annotations

import math

import numpy as np
import rerun as rr

from ...core.curves import CurvedObject
from ...plants.simulation import PlantLike
from .hand import HandDrawing
from .options import RecorderOptions
from .rows import BAND_LINES, ZONE_LINES
from .style import BAND, BAND_EDGE, DANGER, DANGER_FILL, FORCE, GHOST, MM, OBJECT, PREDICTED, colours, darker, rgba

__all__ = ["log_static"]


def log_static(stream: rr.RecordingStream, plant: PlantLike, hand: HandDrawing, options: RecorderOptions,
               object_closed: np.ndarray) -> None:
    """Log the static data of a recording of ``plant`` (``object_closed``: its outline, closed, [m]: a curve's as
    :func:`~regrasp.rollout.recording.outline.closed_outline` samples it)."""
    _log_model(stream, plant, hand, options, object_closed)
    _log_scene_styles(stream, hand)
    _log_series_styles(stream, hand, options)


def _log_model(stream: rr.RecordingStream, plant: PlantLike, hand: HandDrawing, options: RecorderOptions,
               object_closed: np.ndarray) -> None:
    """The object in its own frame (outline, edge numbers, centre of mass; a curved object's one face marked at
    ξ = 0) and the set-up table."""
    log = stream.log
    polygon = plant.polygon
    log("model/object/outline", rr.LineStrips2D([object_closed * MM], radii=0.6,
                                                colors=colours([rgba(OBJECT)]), labels=["object"]), static=True)
    if isinstance(polygon, CurvedObject):
        marks, labels = polygon.points(np.zeros(1)) * MM, ["edge 0 (the boundary): ξ = 0, ξ grows clockwise"]
        shape = f"{type(polygon).__name__} (perimeter {polygon.perimeter * 1e3:.1f} mm)"
    else:
        marks = np.array([0.5 * (e.start + e.end) for e in polygon.edges]) * MM
        labels = [f"edge {k}" for k in range(polygon.n_vertices)]
        shape = f"{polygon.n_vertices}-gon"
    log("model/object/edges", rr.Points2D(marks, radii=1.0, colors=colours([rgba(OBJECT)]), labels=labels,
                                          show_labels=True), static=True)
    log("model/object/centre_of_mass", rr.Points2D([[0.0, 0.0]], radii=1.5, labels=["centre of mass"]),
        static=True)
    rows = ["| finger | entity | l1, l2 [mm] | base [mm, deg] | configuration | edge | mode | friction |",
            "|---|---|---|---|---|---|---|---|"]
    for i, f in enumerate(plant.hand.fingers):
        c = plant.contacts[i]
        b = f.base_in_hand
        rows.append(f"| {f.name} | `{hand.fingers[i].key}` | {f.link_lengths[0] * 1e3:.1f}, "
                    f"{f.link_lengths[1] * 1e3:.1f} | ({b[0] * 1e3:.1f}, {b[1] * 1e3:.1f}, {math.degrees(b[2]):.1f}) "
                    f"| {f.configuration.value} | {c.edge} | {c.mode.value} | {plant.friction[i]} |")
    text = "\n".join([
        "# Rollout set-up", "",
        f"Object: {shape}, mass {polygon.mass:g} kg, inertia {polygon.inertia:.3g} kg m², "
        f"plant step {plant.dt * 1e3:g} ms.", "",
        *rows, "",
        f"Scene in mm with y flipped (rerun draws y down). Force arrows {options.force_scale:g} mm/N; "
        f"cone rays {options.cone_length:g} mm; danger zones {100 * options.danger_fraction:g} % of each "
        f"feasible interval at both ends; envelope geometry '{options.envelope_geometry}'; "
        f"decimation {options.decimation}.",
    ])
    log("model/setup", rr.TextDocument(text, media_type=rr.MediaType.MARKDOWN), static=True)


def _log_scene_styles(stream: rr.RecordingStream, hand: HandDrawing) -> None:
    """The styling of the time-varying scene: radii, colours, labels and draw order of each entity."""
    log = stream.log
    names = [f.name for f in hand.fingers]
    log("scene/object", rr.LineStrips2D.from_fields(radii=[0.7], colors=colours([rgba(OBJECT)]), labels=["object"],
                                                    show_labels=False, draw_order=10.0), static=True)
    log("scene/desired", rr.LineStrips2D.from_fields(radii=[0.4], colors=colours([rgba(GHOST)]), labels=["desired"],
                                                     show_labels=False, draw_order=5.0), static=True)
    for f in hand.fingers:
        n_links = len(f.shapes)
        log(f.path, rr.LineStrips2D.from_fields(
            radii=[0.3] * n_links + [0.9],
            colors=colours([rgba(f.colour, 200)] * n_links + [rgba(darker(f.colour))]),
            labels=list(f.labels), show_labels=False, draw_order=20.0), static=True)
    log("scene/joints", rr.Points2D.from_fields(
        radii=[1.3] * (3 * len(names)),
        colors=colours([rgba(darker(f.colour)) for f in hand.fingers for _ in range(3)]),
        labels=[f"{n} {j}" for n in names for j in ("joint 1", "elbow", "tip")], show_labels=False,
        draw_order=21.0), static=True)
    log("scene/contacts/forces", rr.Arrows2D.from_fields(radii=[0.6], colors=colours([rgba(FORCE)]),
                                                         labels=[f"{n}: force on the object" for n in names],
                                                         show_labels=False, draw_order=30.0), static=True)
    log("scene/contacts/forces_predicted", rr.Arrows2D.from_fields(
        radii=[0.3], colors=colours([rgba(PREDICTED, 220)]), labels=[f"{n}: predicted force" for n in names],
        show_labels=False, draw_order=29.0), static=True)
    log("scene/contacts/cones", rr.LineStrips2D.from_fields(
        radii=[0.3], labels=[f"{n}: friction cone" for n in names], show_labels=False, draw_order=25.0),
        static=True)
    log("scene/envelope/safe", rr.LineStrips2D.from_fields(radii=[1.4], draw_order=15.0), static=True)
    log("scene/envelope/danger", rr.LineStrips2D.from_fields(radii=[1.4], colors=colours([rgba(DANGER)]),
                                                             draw_order=16.0), static=True)


def _log_series_styles(stream: rr.RecordingStream, hand: HandDrawing, options: RecorderOptions) -> None:
    """Each plot's series names and colours."""
    log = stream.log
    fingers = hand.fingers
    names = [f.name for f in fingers]
    finger_colours = [f.colour for f in fingers]
    err_names = ["x [mm]", "y [mm]"] + [f"ξ {fingers[i].name} [mm]" for i in options.sliding]
    err_colours = [(31, 119, 180), (44, 160, 44)] + [finger_colours[i] for i in options.sliding]
    log("plots/error/position", rr.SeriesLines(names=err_names, colors=colours([rgba(c) for c in err_colours])),
        static=True)
    log("plots/error/angle", rr.SeriesLines(names=["β [deg]"], colors=colours([rgba((214, 39, 40))])), static=True)
    pct = 100.0 * options.danger_fraction
    for f in fingers:
        c = f.colour
        log(f"plots/xi/{f.key}", rr.SeriesLines(
            names=[f"ξ {f.name}", f"ξ_d control law {f.name}", f"feasible lo {f.name}", f"feasible hi {f.name}",
                   f"danger zone ({pct:g} %) ends {f.name}", f"danger zone ({pct:g} %) starts {f.name}",
                   f"ξ_d schedule {f.name}"],
            colors=colours([rgba(c), rgba(darker(c, 0.5), 200), rgba(BAND_EDGE), rgba(BAND_EDGE),
                            rgba(DANGER, 160), rgba(DANGER, 160), rgba(c, 110)]),
            widths=[2.0, 1.0, 1.0, 1.0, 0.5, 0.5, 3.0]), static=True)
        log(f"plots/xi/{f.key}/band", rr.SeriesLines(  # (the band's fill: rows.band_fill)
            names=[f"feasible band {f.name}"] * BAND_LINES + [f"danger zone {f.name}"] * (2 * ZONE_LINES),
            colors=colours([rgba(BAND, 70)] * BAND_LINES + [rgba(DANGER_FILL, 110)] * (2 * ZONE_LINES)),
            widths=[8.0] * BAND_LINES + [4.0] * (2 * ZONE_LINES)), static=True)
        log(f"plots/phase/{f.key}", rr.SeriesLines(names=[f.name], colors=colours([rgba(c)])), static=True)
    force_names = ([f"f_n {n}" for n in names] + [f"f_t {n}" for n in names]
                   + [f"f_n {n} (predicted)" for n in names] + [f"f_t {n} (predicted)" for n in names])
    force_colours = ([rgba(c) for c in finger_colours] + [rgba(darker(c, 0.5)) for c in finger_colours]
                     + [rgba(c, 90) for c in finger_colours] + [rgba(darker(c, 0.5), 90) for c in finger_colours])
    log("plots/force", rr.SeriesLines(names=force_names, colors=colours(force_colours)), static=True)
    log("plots/cone_margin", rr.SeriesLines(
        names=list(names) + [f"{n} (predicted)" for n in names],
        colors=colours([rgba(c) for c in finger_colours] + [rgba(c, 90) for c in finger_colours])), static=True)
    log("plots/mode", rr.SeriesLines(names=names, colors=colours([rgba(c) for c in finger_colours])), static=True)

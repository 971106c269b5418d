"""The drawn scene (entities under ``scene/``, hand frame, millimetres with y flipped: module docstring of
:mod:`regrasp.rollout.recording`): :class:`Scene` turns a block of logged steps' rows into each scene entity's
columns with whole-block numpy operations (outlines, arrows, cones, envelope segments), and
:func:`failure_marker` draws a failure.

On a curved object (:mod:`regrasp.core.curves`) the outline is the curve's (:mod:`~regrasp.rollout.recording.outline`),
each contact's cone and forces are drawn in the surface frame at its ξ of the step, and each feasible interval is a
polyline along the curve, its slot's distance outside it (:func:`~regrasp.rollout.recording.outline.curve_path`).
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from typing import TYPE_CHECKING

import numpy as np
import pyarrow as pa
import rerun as rr
from numpy.typing import ArrayLike
from rerun.components import LineStrip2D, LineStrip2DBatch
from rerun.encodings import Vec2DBatch

from ...core.contact import ContactMode, Friction
from ...core.curves import CurvedObject, CurveFace
from ...core.events import EventKind, Failure, FailureKind
from ...core.intervals import danger_zones
from ...core.polygon import Edge
from .hand import HandDrawing, circle
from .outline import curve_path
from .rows import MODE_CODES, StepRow
from .style import DANGER, MM, MODE_RGBA, colours, rgba

if TYPE_CHECKING:
    from ...plants.simulation import PlantLike

__all__ = ["ENVELOPE_GAP", "Scene", "arrows_columns", "failure_label", "failure_marker", "ragged_strips_array",
           "strips_array", "strips_columns"]

#: How far outside the edge [m] the first envelope drawn along it is, and each next one further.
ENVELOPE_GAP = 0.003
#: The most arcs a scene keeps drawn (object frame) for the next steps that draw the same intervals.
_ARC_CACHE = 4096

_SIGN = np.sign(MM)  # a vector [m] -> scene [mm]: MM with the force scale instead of 1000
_CODE_RGBA = np.zeros(max(MODE_CODES.values()) + 1, dtype=np.uint32)  # a mode code's cone colour
for _mode, _code in MODE_CODES.items():
    _CODE_RGBA[_code] = MODE_RGBA[_mode]


def strips_array(strips: np.ndarray) -> pa.Array:
    """Line strips of equal length (count, points, 2) as rerun's line-strip component array: its list type
    (:meth:`rerun.components.LineStrip2D.arrow_type`) built from numpy offsets, as rerun's numpy path builds it
    with a Python loop per strip; rerun's own conversion when its type is another than a list of its points."""
    strips = np.ascontiguousarray(strips, dtype=np.float32)
    count, width = strips.shape[:2]
    points = Vec2DBatch(strips.reshape(-1, 2)).as_arrow_array()
    strip_type = LineStrip2D.arrow_type()
    if not (pa.types.is_list(strip_type) and strip_type.value_type == points.type):
        return LineStrip2DBatch(strips).as_arrow_array()
    offsets = np.arange(0, count * width + 1, width, dtype=np.int32) if width else np.zeros(count + 1, np.int32)
    return pa.ListArray.from_arrays(offsets, points, type=strip_type)


def ragged_strips_array(points: np.ndarray, sizes: Sequence[int]) -> pa.Array:
    """Line strips of any lengths, their points one after the other (sum(sizes), 2), ``sizes[k]`` points in strip k,
    as rerun's line-strip component array (as :func:`strips_array` builds it)."""
    points = np.ascontiguousarray(points, dtype=np.float32).reshape(-1, 2)
    sizes = np.asarray(sizes, dtype=np.int64)
    strip_type = LineStrip2D.arrow_type()
    values = Vec2DBatch(points).as_arrow_array()
    if not (pa.types.is_list(strip_type) and strip_type.value_type == values.type):
        return LineStrip2DBatch(np.split(points, np.cumsum(sizes)[:-1]) if sizes.size else []).as_arrow_array()
    offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int32)
    return pa.ListArray.from_arrays(offsets, values, type=strip_type)


def strips_columns(strips: np.ndarray | pa.Array, lengths: Sequence[int], colours: ArrayLike | None = None
                   ) -> rr.ComponentColumnList:
    """``LineStrips2D`` columns of equal-length strips (count, points, 2) [mm] (or strips already as rerun's array,
    :func:`ragged_strips_array`), ``lengths[k]`` strips in row k, with a packed colour per strip if given."""
    batch = strips if isinstance(strips, pa.Array) else strips_array(strips)
    if colours is None:
        return rr.LineStrips2D.columns(strips=batch).partition(lengths)
    return rr.LineStrips2D.columns(strips=batch, colors=np.asarray(colours, dtype=np.uint32)).partition(lengths)


def arrows_columns(origins: np.ndarray, vectors: np.ndarray, lengths: Sequence[int]) -> rr.ComponentColumnList:
    """``Arrows2D`` columns: origins and vectors (..., 2) [mm], ``lengths[k]`` arrows in row k."""
    return rr.Arrows2D.columns(origins=origins.reshape(-1, 2).astype(np.float32),
                               vectors=vectors.reshape(-1, 2).astype(np.float32)).partition(lengths)


def _rotate(c: np.ndarray, s: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Vectors ``v`` (..., 2) rotated by the angles whose cosines and sines are ``c``, ``s`` (broadcast)."""
    return np.stack([c * v[..., 0] - s * v[..., 1], s * v[..., 0] + c * v[..., 1]], axis=-1)


class Scene:
    """How a block of logged steps is drawn.

    Args:
        object_closed: The object's outline, closed (nv + 1, 2) [m], object frame
            (:func:`~regrasp.rollout.recording.outline.closed_outline`).
        hand: The fingers as drawn.
        edges: The object's edges (their inward normals and ξ axes, object frame), or a curved object's one face
            (its frames at each contact's ξ).
        frictions: Each contact's friction (a fixed contact's cone at μ_s, a sliding one's at μ_k).
        force_scale: Arrow length per newton [mm/N].
        cone_length: Length of the friction cones' rays [mm].
        danger_fraction: Width of each danger zone, a fraction of its interval.
    """

    def __init__(self, object_closed: np.ndarray, hand: HandDrawing, edges: Sequence[Edge],
                 frictions: Sequence[Friction], *, force_scale: float, cone_length: float, danger_fraction: float):
        self.object_closed = object_closed
        self.hand = hand
        self.curve: CurvedObject | None = None
        if isinstance(edges[0], CurveFace):
            self.curve = edges[0].curve
        else:
            self.normals = np.array([e.inward_normal for e in edges])
            self.xi_directions = np.array([e.xi_direction for e in edges])
            self.xi_origins = np.array([e.xi_origin for e in edges])
        self._arcs: dict[tuple[float, float, float], np.ndarray] = {}  # a curve's arcs drawn (object frame)
        self.static = np.array([f.static for f in frictions])  # (m,): a fixed contact's cone
        self.kinetic = np.array([f.kinetic for f in frictions])  # a sliding one's
        self.finger_colours = np.array([rgba(f.colour, 200) for f in hand.fingers], dtype=np.uint32)
        self.force_scale = force_scale
        self.cone_length = cone_length
        self.danger_fraction = danger_fraction

    def columns(self, rows: Sequence[StepRow]) -> Iterator[tuple[str, rr.ComponentColumnList]]:
        """``(entity path, columns)`` of the scene for a block of rows (one row per step), in a fixed order."""
        n = len(rows)
        pose = np.array([r.pose for r in rows])  # (n, 4): cos β, sin β, x, y
        c, s = pose[:, 0], pose[:, 1]
        RT = np.empty((n, 2, 2))  # R(β)ᵀ per step
        RT[:, 0, 0], RT[:, 0, 1], RT[:, 1, 0], RT[:, 1, 1] = c, s, -s, c
        origin = pose[:, 2:4]
        yield from self._object(rows, RT, origin)
        chains = np.stack([r.chains for r in rows])  # (n, m, 3, 2): joint 1, elbow, tip [m]
        yield from self._fingers(rows, chains)
        yield from self._contacts(rows, c, s, chains[:, :, 2])
        yield from self._envelopes(rows, c, s, RT, origin)

    def _object(self, rows, RT, origin):
        """The object and its desired pose's ghost (none in a row without one)."""
        n = len(rows)
        yield "scene/object", strips_columns((self.object_closed @ RT + origin[:, None]) * MM, [1] * n)
        ghost = [r.desired for r in rows if r.desired is not None]
        if ghost:
            g = np.array(ghost)  # cos, sin, x, y
            RdT = np.empty((len(g), 2, 2))
            RdT[:, 0, 0], RdT[:, 0, 1], RdT[:, 1, 0], RdT[:, 1, 1] = g[:, 0], g[:, 1], -g[:, 1], g[:, 0]
            strips = (self.object_closed @ RdT + g[:, None, 2:4]) * MM
        else:
            strips = np.zeros((0, len(self.object_closed), 2))
        yield "scene/desired", strips_columns(strips, [0 if r.desired is None else 1 for r in rows])

    def _fingers(self, rows, chains):
        """Each link's outline placed by its joint frame and the joint chain, per finger; the joints as dots."""
        n, m = chains.shape[:2]
        frames = np.stack([r.frames for r in rows]).reshape(n, m, 2, 4, 4)  # joints 1, 2 per finger
        for i, finger in enumerate(self.hand.fingers):
            width = finger.width
            strips = []
            for joint, points in finger.shapes:
                H = frames[:, i, joint]
                placed = points @ H[:, :3, :3].transpose(0, 2, 1) + H[:, None, :3, 3]
                strips.append(_pad_last(placed[:, :, :2], width))
            strips.append(_pad_last(chains[:, i], width))
            yield finger.path, strips_columns(np.stack(strips, axis=1).reshape(-1, width, 2) * MM,
                                              [len(strips)] * n)
        yield "scene/joints", rr.Points2D.columns(
            positions=(chains.reshape(-1, 2) * MM).astype(np.float32)).partition([3 * m] * n)

    def _contacts(self, rows, c, s, tips):
        """Each contact's force (the plant's and the predicted) as an arrow from its tip, and its friction cone."""
        n, m = tips.shape[:2]
        cc, ss = c[:, None], s[:, None]
        if self.curve is not None:  # the inward normal at each contact's ξ of the step (none at a ξ not finite)
            frame = self.curve.local_floats
            local = np.array([frame(x)[2:4] if math.isfinite(x) else (math.nan, math.nan)
                              for r in rows for x in r.xi.tolist()]).reshape(n, m, 2)
            normals = _rotate(cc, ss, local)
            tangents = np.stack([-normals[..., 1], normals[..., 0]], axis=-1)
        else:
            edges = np.array([r.edges for r in rows], dtype=np.intp).reshape(n, m)
            normals = _rotate(cc, ss, self.normals[edges])  # (n, m, 2), hand frame
            tangents = _rotate(cc, ss, self.xi_directions[edges])
        have = [k for k, r in enumerate(rows) if r.surface is not None]
        if have:
            f = np.array([rows[k].surface for k in have])  # (h, m, 2)
            vectors = f[..., :1] * normals[have] + f[..., 1:2] * tangents[have]
            origins, vectors = tips[have] * MM, vectors * self.force_scale * _SIGN
        else:
            origins = vectors = np.zeros((0, m, 2))
        yield "scene/contacts/forces", arrows_columns(origins, vectors, [0 if r.surface is None else m for r in rows])
        have = [k for k, r in enumerate(rows) if r.predicted is not None]
        if have:
            origins = tips[have] * MM
            vectors = np.array([rows[k].predicted for k in have]) * self.force_scale * _SIGN
        else:
            origins = vectors = np.zeros((0, m, 2))
        yield "scene/contacts/forces_predicted", arrows_columns(
            origins, vectors, [0 if r.predicted is None else m for r in rows])
        codes = np.array([r.modes for r in rows], dtype=np.intp).reshape(n, m)
        sliding = codes == MODE_CODES[ContactMode.SLIDING]
        half = np.arctan(np.where(sliding, self.kinetic, self.static))  # (n, m): μ_k sliding, else μ_s
        ch, sh = np.cos(half)[..., None], np.sin(half)[..., None]
        perp_n = np.stack([-normals[..., 1], normals[..., 0]], axis=-1)
        ray_a = ch * normals + sh * perp_n
        ray_b = ch * normals - sh * perp_n
        L = self.cone_length / 1000.0
        cones = np.stack([tips + L * ray_a, tips, tips + L * ray_b], axis=2) * MM  # (n, m, 3, 2)
        cone_colours = _CODE_RGBA[codes.reshape(-1)]
        yield "scene/contacts/cones", strips_columns(cones.reshape(-1, 3, 2), [m] * n, cone_colours)

    def _envelopes(self, rows, c, s, RT, origin):
        """Each drawn interval as safe and danger segments just outside its edge (3 mm further per slot)."""
        n = len(rows)
        counts = [len(r.segments) for r in rows]
        if self.curve is not None:
            yield from self._curve_envelopes(rows, counts, RT, origin)
            return
        if sum(counts):
            finger, edge, slot, lo, hi = np.concatenate([r.segments for r in rows]).T
            step = np.repeat(np.arange(n), counts)
            edge = edge.astype(np.intp)
            RTs = RT[step.astype(np.intp)]
            nrm = np.stack([c[step] * self.normals[edge, 0] - s[step] * self.normals[edge, 1],
                            s[step] * self.normals[edge, 0] + c[step] * self.normals[edge, 1]], axis=-1)
            offset = -(ENVELOPE_GAP + ENVELOPE_GAP * slot)[:, None] * nrm
            (_, lo_zone), (hi_zone, _) = danger_zones(lo, hi, self.danger_fraction)
            wdt = lo_zone - lo
            u = np.stack([lo, lo_zone, hi_zone, hi], axis=1)  # (S, 4)
            in_object = self.xi_origins[edge][:, None] + u[..., None] * self.xi_directions[edge][:, None]
            ends = in_object @ RTs + (origin[step.astype(np.intp)] + offset)[:, None]  # (S, 4, 2)
            safe = ends[:, 1:3] * MM
            zoned = wdt > 0.0
            danger = np.stack([ends[zoned, 0:2], ends[zoned, 2:4]], axis=1).reshape(-1, 2, 2) * MM
            safe_colours = self.finger_colours[finger.astype(np.intp)]
            per_step = np.bincount(step.astype(np.intp), weights=zoned, minlength=n).astype(int)
            danger_counts = (2 * per_step).tolist()
        else:
            safe = danger = np.zeros((0, 2, 2))
            safe_colours = np.zeros(0, dtype=np.uint32)
            danger_counts = [0] * n
        yield "scene/envelope/safe", strips_columns(safe, counts, safe_colours)
        yield "scene/envelope/danger", strips_columns(danger, danger_counts)

    def _curve_envelopes(self, rows, counts, RT, origin):
        """:meth:`_envelopes` on a curve: each interval's safe part and danger zones as polylines along the curve,
        :data:`ENVELOPE_GAP` × (1 + slot) outside it (:func:`~regrasp.rollout.recording.outline.curve_path`)."""
        n = len(rows)
        safe, danger, safe_colours, danger_counts = [], [], [], [0] * n
        if sum(counts):
            finger, _, slot, lo, hi = np.concatenate([r.segments for r in rows]).T
            step = np.repeat(np.arange(n), counts)
            offset = ENVELOPE_GAP + ENVELOPE_GAP * slot
            (_, lo_zone), (hi_zone, _) = danger_zones(lo, hi, self.danger_fraction)
            for k, (a, b, c, d, o) in enumerate(zip(lo.tolist(), lo_zone.tolist(), hi_zone.tolist(), hi.tolist(),
                                                    offset.tolist())):
                safe.append((step[k], self._arc(b, c, o)))
                if b > a:
                    danger += [(step[k], self._arc(a, b, o)), (step[k], self._arc(c, d, o))]
                    danger_counts[step[k]] += 2
            safe_colours = self.finger_colours[finger.astype(np.intp)]
        yield "scene/envelope/safe", strips_columns(_placed(safe, RT, origin), counts, safe_colours)
        yield "scene/envelope/danger", strips_columns(_placed(danger, RT, origin), danger_counts)

    def _arc(self, lo: float, hi: float, offset: float) -> np.ndarray:
        """The curve's arc ξ in [lo, hi] [m], ``offset`` [m] outside it, object frame (kept for the next steps)."""
        key = (lo, hi, offset)
        arc = self._arcs.get(key)
        if arc is None:
            if len(self._arcs) >= _ARC_CACHE:
                self._arcs.clear()
            arc = self._arcs[key] = curve_path(self.curve, lo, hi, offset)
        return arc


def _placed(arcs: list[tuple[int, np.ndarray]], RT: np.ndarray, origin: np.ndarray) -> pa.Array:
    """Polylines (step, points (k, 2) [m], object frame) placed at their step's pose (``RT`` its R(β)ᵀ, ``origin``)
    as rerun's strips in the scene's millimetres (:func:`ragged_strips_array`)."""
    if not arcs:
        return ragged_strips_array(np.zeros((0, 2)), [])
    sizes = [len(a) for _, a in arcs]
    at = np.repeat(np.array([k for k, _ in arcs], dtype=np.intp), sizes)
    points = np.concatenate([a for _, a in arcs])
    placed = np.einsum("pi,pij->pj", points, RT[at]) + origin[at]
    return ragged_strips_array(placed * MM, sizes)


def _pad_last(points: np.ndarray, n: int) -> np.ndarray:
    """Repeat the last point of each polyline in a block (steps, k, 2) so that each has ``n`` points."""
    k = points.shape[1]
    if k >= n:
        return points
    return np.concatenate([points, np.repeat(points[:, -1:], n - k, axis=1)], axis=1)


def failure_marker(failure: Failure, plant: PlantLike, hand: HandDrawing,
                   object_closed: np.ndarray) -> rr.LineStrips2D | None:
    """The red outline marking ``failure`` at ``plant``'s state (``scene/failure``), labelled with its kind, contact and
    time (:func:`failure_label`; its reason is the ``events`` log's ERROR line): a
    collision's link outline (the colliding link of the plant's last ``collision`` event of that finger, both
    links if unknown), a circle around the tip of the contact any other contact failure names, the object's
    outline (``object_closed`` (nv + 1, 2) [m], object frame) for a failure of no one contact; None for an
    interruption or a plant without a state."""
    kind = FailureKind(failure.kind)
    if kind is FailureKind.INTERRUPTED or plant.state is None:
        return None
    st = plant.state
    names = [f.name for f in hand.fingers]
    i = names.index(failure.contact) if failure.contact in names else None
    if i is None:  # no one contact: the object
        X = st.X
        c_, s_ = math.cos(X[2]), math.sin(X[2])
        strips = [object_closed @ np.array([[c_, s_], [-s_, c_]]) + X[:2]]
    else:
        frames, chains = hand.kinematics(st.q)
        if kind is FailureKind.COLLISION:
            link = None
            for ev in reversed(plant.events):
                if ev.contact == failure.contact and ev.kind == EventKind.COLLISION and "link" in ev.values:
                    link = int(ev.values["link"])
                    break
            shapes = [(j, pts) for j, pts in hand.fingers[i].shapes if link is None or j == link]
            strips = [(pts @ frames[2 * i + j][:3, :3].T + frames[2 * i + j][:3, 3])[:, :2] for j, pts in shapes]
            if not strips:  # a finger without collision shapes: its chain
                strips = [chains[i]]
        else:
            strips = [chains[i, 2] + np.vstack([circle(0.004), circle(0.004)[:1]])]
    return rr.LineStrips2D([s * MM for s in strips], radii=1.2, colors=colours([rgba(DANGER)]),
                           labels=[failure_label(failure)], show_labels=True, draw_order=40.0)


def failure_label(failure: Failure) -> str:
    """The failure marker's label, short enough to stay inside the scene: ``<kind> (<contact>) at t = … s`` (the
    reason is the ``events`` log's ERROR line)."""
    who = f" ({failure.contact})" if failure.contact else ""
    return f"{FailureKind(failure.kind).value}{who} at t = {failure.time:.3f} s"

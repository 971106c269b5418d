r"""Record rollouts to rerun: an ``.rrd`` file, a live viewer (spawned or connected to), or both.

A :class:`RolloutRecorder` turns each control step of a supervised rollout
(:meth:`Rollout.run(recorder=...) <regrasp.rollout.build.Rollout.run>`, one
:class:`~regrasp.plants.simulation.StepRecord` per step) or of :func:`~regrasp.plants.closed_loop.run_closed_loop`
into a rerun recording a reviewer can scrub through: the hand and the object with the events
log on the left, each finger's ξ panel (the paper's Figure 4.3, live) and the phases in the
middle, the other time series on the right (the blueprint is stored in the file). It uses its own
``rerun.RecordingStream`` (never rerun's global or thread-local recording), so several recorders
can run side by side, and it needs no viewer: ``rrd_path`` alone writes a file headless.

::

    with RolloutRecorder(rollout.plant, rrd_path="rollout.rrd", decimation=10) as rec:
        rollout.run(recorder=rec)
    # or, a bare control law:
    with RolloutRecorder(plant, rrd_path="rollout.rrd") as rec:
        run_closed_loop(plant, controller, reference, 1.0, on_step=rec.hook(plant, reference))
    # then: rerun rollout.rrd

**Timelines.** ``time`` (a duration: the plant's time [s] of the logged state) and ``step``
(a sequence). Step 0 is the state before the first control step (:meth:`~RolloutRecorder.log_initial`,
or when the hook was made) and step k the state after the k-th control step (record k - 1);
``decimation = n`` logs only the steps that are multiples of n, one row of every per-step entity
each (events and the failure are logged whatever the decimation).

**Two sources.** :meth:`~RolloutRecorder.log_record` with a supervised record logs from the record
alone: the state after the step (``record.plant.state``, ξ = ``record.plant.xi``), the plant's
forces at the step's start (``record.plant.forces_surface``) and their cone margins
(``record.cone_margins``), the controller's prediction (``record.command.control``) and the
supervisor's view at the step's start (``record.supervision``: phases, envelopes, the interval
holding each ξ, ξ_d): each row is "the step that led here", what the supervisor saw and did at
its start and where the plant ended. Nothing is recomputed (no envelope evaluation, no KKT
solve); only the drawing needs the fingers' forward kinematics and the contacts' modes now
(``plant.contacts``). Without a supervisor (:meth:`~RolloutRecorder.hook`,
:meth:`~RolloutRecorder.log_step`, a record with ``supervision`` None) the recorder measures
the plant as before: ξ from the tips, envelopes with :class:`~regrasp.envelope.finger_envelope.FingerEnvelope`,
forces from the ``PlantStep`` or one KKT solve; the phase series are then NaN.

**Scene** (entities under ``scene/``, the hand frame, in **millimetres**). Rerun's 2-D view draws
y *downwards* (image convention), so the recorder logs every point as (1000 x, -1000 y): the
picture is upright (gravity points down the screen) and values read off the viewer are mm with
the sign of y flipped.

* ``scene/object``: the polygon at the plant's pose (``polygon.vertices`` through X).
* ``scene/desired``: the desired pose (``reference(t)``'s first three entries), a faint ghost.
* ``scene/fingers/<finger>``: each link's URDF collision shape as its outline in the plane
  (cylinders and boxes are rectangles, capsules stadiums): the shape's points, placed by Pinocchio
  (``data.oMi[joint] * placement``), are the 2-D convex hull computed once in the joint frame;
  the last strip is the joint chain (joint 1, elbow, tip) as a thick polyline.
  ``scene/joints``: the joints and tips as dots.
* ``scene/contacts/forces``: each contact's force on the object, an arrow from the fingertip,
  ``force_scale`` mm per N (default 10 mm/N). It is the plant's force: the ``PlantStep``'s
  (at the step's start) when one is passed, otherwise recomputed at the logged state under the
  step's torque (``plant.accelerations``, one KKT solve; ``plant_forces=False`` skips it).
  ``scene/contacts/forces_predicted``: the controller's predicted force
  (``ControlOutput.contact_forces``), thinner.
* ``scene/contacts/cones``: each friction cone as two rays of ``cone_length`` mm around the inward
  normal, at :math:`\pm\arctan\mu_s` and green while the contact is fixed, at
  :math:`\pm\arctan\mu_k` and orange while it slides, grey (at :math:`\mu_s`) once separated.
* ``scene/envelope/safe`` and ``scene/envelope/danger``: each drawn edge's feasible set as thick
  segments drawn just outside the edge, in the finger's colour, with the last ``danger_fraction``
  of each interval's width at both ends in red: the supervisor's samples (``SupervisorOutput.envelopes``,
  each contact's own edge) for a supervised record, else :class:`~regrasp.envelope.finger_envelope.FingerEnvelope`
  ``.at`` the plant's current pose (the ``envelope_edges``).
* ``scene/failure`` (logged once, by :meth:`~RolloutRecorder.log_failure`, at the failure's time
  and the last step): the failure marked in red, labelled with its reason: a collision's link
  outline (the colliding link of the plant's last ``collision`` event of that finger, both links
  if unknown), a circle around the tip of the contact any other contact failure names
  (separation, unplanned slip, left envelope or edge, singular), the object's outline for a
  failure of no one contact (the control law's); nothing for an interruption.

**Plots** (under ``plots/``; each entity holds several series, named by static
``rr.SeriesLines``; NaN where a value is absent): ``plots/error`` the tracking error (x, y [mm],
β [deg], each reduced ξ [mm]), measured at the logged state against the desired S_d when the
reference is known, otherwise the controller's ``ControlOutput.error``;
``plots/xi/<finger>`` (one view per finger, Figure 4.3) seven series [mm]: 0 the actual ξ,
1 the control law's ξ_d (the sliding law's ``reference_xi``, or the closed loop's S_d), 2-3 the
feasible interval holding ξ (lo, hi; the supervisor's ``bounds``), 4-5 where the danger zones
start (lo + f w, hi − f w with f = ``danger_fraction``, w = hi − lo), 6 the schedule's ξ_d
(``planned_xi``); a separated contact's are all NaN; ``plots/force`` normal and tangential
forces (plant and predicted); ``plots/cone_margin`` μ f_n − |f_t| (plant and predicted; μ_s at a
fixed contact, μ_k at a sliding one); ``plots/mode`` 0 fixed, 1 sliding, 2 separated;
``plots/phase/<finger>`` the supervisor's phase of the contact during the step (:data:`PHASE_CODES`:
0 fixed, 1 priming, 2 sliding, 3 settling; NaN without a supervisor).

**Events** (``events``, a text log, at each event's own time; the supervisor's decisions at the
step whose state they were taken at, the plant's at the step after which they were detected):
``t = … s  <source> <finger>: <kind> (<detail>)``, level WARN for the kinds in
:data:`WARN_KINDS` (slip, separation, collision, a contact off its edge or singular, left envelope,
slide rejected or aborted, re-plan failed), INFO otherwise; a failure is one ERROR line
``FAILURE (<kind>) <finger>: <reason>``.

**Static data** (logged once): ``model/object`` (the polygon in its own frame, mm, with its edge
numbers and centre of mass), ``model/setup`` (a Markdown table of the fingers, their edges, modes
and friction), and the styling of every entity above.

**Cost.** Per logged step the recorder keeps what the step needs: Pinocchio forward kinematics
(the joint frames and the chain), without a supervisor one ``FingerEnvelope.at`` per drawn edge
(~20 µs each in the ``ideal`` geometry; a supervised record brings its own), and the plotted
numbers. Every ``flush_every`` logged steps (default 500) and
on :meth:`~RolloutRecorder.close` it turns the buffered steps into each entity's rows with numpy
operations over the whole block (outlines, arrows, cones, envelope segments) and sends them with
one ``send_columns`` per entity, so a live viewer sees the data in blocks of that many steps. The
recorded values are the same whatever ``flush_every`` is. :attr:`RolloutRecorder.seconds_per_step`
reports the measured mean cost (about 0.1-0.2 ms on the three-finger rollout). **Size.** A 1 s
three-finger rollout (``policy="paper"``, 1000 steps) writes 1.7 MB at decimation 1, 0.39 MB at
10 and 0.27 MB at 100: about 1.4 kB per logged step on top of about 0.25 MB per file (each
entity's chunk schemas, static and per block sent).

**Robustness.** :meth:`~RolloutRecorder.close` sends what is buffered, flushes and finalises the
file (footer included), and is idempotent; the context manager calls it also when the block
raises, so an interrupted rollout leaves a complete, readable file with the steps logged so far.
A recorder that is never closed is closed when it is garbage-collected or at interpreter exit
(a ``weakref.finalize`` tied to the recorder; nothing else is registered). A process killed
outright (SIGKILL, ``os._exit``) cannot finalise its file.
"""

from __future__ import annotations

import math
import re
import time as _time
import uuid
import warnings
import weakref
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin
import pyarrow as pa
import rerun as rr
import rerun.blueprint as rrb
from numpy.typing import ArrayLike
from rerun.components import LineStrip2DBatch
from rerun.encodings import Vec2DBatch

from ...core.contact import ContactMode, coefficients, cone_margin
from ...core.events import EventKind, EventSource, FailureKind
from ...core.exceptions import InvalidParameterError, RegraspError
from ...core.planar import wrap_angle
from ...dynamics.control import ControlOutput
from ...envelope.finger_envelope import EnvelopeSample, FingerEnvelope
from ...plants.project.plant import PlantStep
from ...plants.simulation import PlantLike
from ...supervisor.types import ContactPhase

if TYPE_CHECKING:
    from ...core.events import Failure
    from ...plants.simulation import StepRecord

__all__ = ["MODE_CODES", "PHASE_CODES", "WARN_KINDS", "RolloutRecorder"]

#: Contact mode → the value plotted under ``plots/mode`` (a ContactMode equals its string, so either looks up).
MODE_CODES = {ContactMode.FIXED: 0, ContactMode.SLIDING: 1, ContactMode.SEPARATED: 2}
#: Supervisor phase → the value plotted under ``plots/phase/<finger>``.
PHASE_CODES = {ContactPhase.FIXED: 0, ContactPhase.PRIMING: 1, ContactPhase.SLIDING: 2, ContactPhase.SETTLING: 3}
#: The event kinds logged at level WARN (the others at INFO).
WARN_KINDS = frozenset({EventKind.SLIP, EventKind.SEPARATION, EventKind.COLLISION, EventKind.LEFT_EDGE,
                        EventKind.SINGULAR, EventKind.LEFT_ENVELOPE, EventKind.SLIDE_REJECTED,
                        EventKind.SLIDE_ABORTED, EventKind.REPLAN_FAILED})
#: Where ``connect`` may point: a rerun gRPC URL such as ``rerun+http://127.0.0.1:9876/proxy``.
_GRPC_URL = re.compile(r"^rerun(\+https?)?://[^/\s]+(/\S*)?$")

_MM = np.array([1000.0, -1000.0])  # metres (hand frame, y up) -> scene millimetres (y down)
_FINGER_COLOURS = [(31, 119, 180), (148, 103, 189), (23, 190, 207), (140, 86, 75), (227, 119, 194),
                   (188, 189, 34), (127, 127, 127)]
_MODE_COLOURS = {ContactMode.FIXED: (44, 160, 44), ContactMode.SLIDING: (255, 127, 14),
                 ContactMode.SEPARATED: (160, 160, 160)}
_DANGER = (214, 39, 40)
_FORCE = (200, 30, 30)
_PREDICTED = (255, 152, 150)
_OBJECT = (60, 60, 60)
_GHOST = (140, 140, 140, 110)


def _rgba(colour, alpha: int = 255) -> int:
    """0xRRGGBBAA of an (r, g, b[, a]) tuple."""
    r, g, b = colour[:3]
    a = colour[3] if len(colour) > 3 else alpha
    return (int(r) << 24) | (int(g) << 16) | (int(b) << 8) | int(a)


_MODE_RGBA = {mode: _rgba(colour) for mode, colour in _MODE_COLOURS.items()}


def _colours(values) -> np.ndarray:
    """Packed 0xRRGGBBAA colours as the uint32 array rerun reads unambiguously."""
    return np.asarray(values, dtype=np.uint32)


def _darker(colour, factor: float = 0.6):
    return tuple(int(c * factor) for c in colour[:3])


def _entity_name(name: str, taken: set[str]) -> str:
    """A path-safe, unique entity-path part for a finger name."""
    base = re.sub(r"[^A-Za-z0-9_\-]", "_", str(name)) or "finger"
    key, k = base, 1
    while key in taken:
        k += 1
        key = f"{base}_{k}"
    taken.add(key)
    return key


# ---------------------------------------------------------------------------------------- shapes
def _circle(radius: float, n: int = 24) -> np.ndarray:
    a = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return radius * np.stack([np.cos(a), np.sin(a)], axis=1)


def _sphere_samples(centre: np.ndarray, radius: float) -> np.ndarray:
    """Points on a sphere's three great circles (enough for the hull of its projection)."""
    c = _circle(radius)
    z = np.zeros(len(c))
    rings = [np.column_stack([c[:, 0], c[:, 1], z]), np.column_stack([c[:, 0], z, c[:, 1]]),
             np.column_stack([z, c[:, 0], c[:, 1]])]
    return np.concatenate(rings) + centre


def _shape_samples(geometry) -> np.ndarray:
    """Points (n, 3) of a coal shape, in the shape's frame, whose hull is the shape's."""
    kind = type(geometry).__name__
    if kind == "Box":
        h = np.asarray(geometry.halfSide, dtype=float)
        signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=float)
        return signs * h
    if kind == "Cylinder":
        c = _circle(float(geometry.radius))
        h = float(geometry.halfLength)
        return np.concatenate([np.column_stack([c, np.full(len(c), s * h)]) for s in (-1, 1)])
    if kind == "Capsule":
        r, h = float(geometry.radius), float(geometry.halfLength)
        return np.concatenate([_sphere_samples(np.array([0.0, 0.0, s * h]), r) for s in (-1, 1)])
    if kind == "Sphere":
        return _sphere_samples(np.zeros(3), float(geometry.radius))
    geometry.computeLocalAABB()  # meshes, convexes, ...: their bounding box
    lo, hi = np.asarray(geometry.aabb_local.min_), np.asarray(geometry.aabb_local.max_)
    return np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])


def _hull_2d(points: np.ndarray) -> np.ndarray:
    """Convex hull (k, 2) of 2-D points, counter-clockwise, collinear points dropped (monotone chain)."""
    pts = sorted(set(map(tuple, np.round(points, 12))))
    if len(pts) <= 2:
        return np.array(pts, dtype=float)

    def half(seq):
        out = []
        for p in seq:
            while len(out) >= 2 and ((out[-1][0] - out[-2][0]) * (p[1] - out[-2][1])
                                     - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0])) <= 0.0:
                out.pop()
            out.append(p)
        return out

    lower, upper = half(pts), half(reversed(pts))
    return np.array(lower[:-1] + upper[:-1], dtype=float)


def _outline_in_shape_frame(geometry, placement: pin.SE3) -> np.ndarray:
    """The shape's outline in the plane of its joint, as closed-polyline points (k, 3) in the
    shape's own frame (so that ``(oMi[joint] * placement).act`` puts it in the hand frame)."""
    samples = _shape_samples(geometry)
    in_joint = samples @ placement.rotation.T + placement.translation
    hull = _hull_2d(in_joint[:, :2])
    hull = np.vstack([hull, hull[:1]])
    in_plane = np.column_stack([hull, np.zeros(len(hull))])
    return (in_plane - placement.translation) @ placement.rotation


def _nanoseconds(seconds) -> np.ndarray:
    """Times [s] as timedelta64[ns], rounded (a float sum such as 1.0069999999 s reads 1.007 s)."""
    return np.round(np.asarray(seconds, dtype=float) * 1e9).astype(np.int64).astype("timedelta64[ns]")


def _pad_last(points: np.ndarray, n: int) -> np.ndarray:
    """Repeat the last point of each polyline in a block (steps, k, 2) so that each has ``n`` points."""
    k = points.shape[1]
    if k >= n:
        return points
    return np.concatenate([points, np.repeat(points[:, -1:], n - k, axis=1)], axis=1)


# ---------------------------------------------------------------------------------------- writer
class _Scene:
    """The recorder's per-step raw data and how to draw it, for a block of logged steps at once.

    :meth:`RolloutRecorder.log_step` appends one entry per list (the object's pose, the fingers'
    joint frames, the contacts, the envelope intervals, the plotted numbers); :meth:`columns`
    turns a block of steps into each entity's rows with whole-block numpy operations. Kept apart
    from the recorder so that the writer's ``weakref.finalize`` can send the last block without
    keeping the recorder alive.
    """

    _LISTS = ("pose", "desired", "frames", "chains", "edges", "modes", "surface", "predicted", "segments")

    def __init__(self, *, object_closed, fingers, keys, edges, frictions, colours, force_scale, cone_length,
                 danger_fraction):
        self.object_closed = object_closed  # (nv, 2) [m], object frame
        self.fingers = fingers  # per finger: (entity path, [(joint frame 0|1, points in the joint frame (k, 3))], width)
        self.keys = keys
        self.normals = np.array([e.inward_normal for e in edges])
        self.xi_directions = np.array([e.xi_direction for e in edges])
        self.xi_origins = np.array([e.xi_origin for e in edges])
        self.static = np.array([f.static for f in frictions])  # (m,): a fixed contact's cone
        self.kinetic = np.array([f.kinetic for f in frictions])  # a sliding one's
        self.finger_colours = np.array([_rgba(c, 200) for c in colours], dtype=np.uint32)
        self.force_scale = force_scale
        self.cone_length = cone_length
        self.danger_fraction = danger_fraction
        self.scalar_paths = (["plots/error"] + [f"plots/xi/{k}" for k in keys]
                             + ["plots/force", "plots/cone_margin", "plots/mode"]
                             + [f"plots/phase/{k}" for k in keys])
        self.rows: dict[str, list] = {name: [] for name in self._LISTS + tuple(self.scalar_paths)}

    def truncate(self, n: int) -> None:
        for rows in self.rows.values():
            del rows[n:]

    def clear(self) -> None:
        for rows in self.rows.values():
            rows.clear()

    def columns(self, n: int):
        """``(entity path, component columns)`` of the ``n`` buffered steps, in a fixed order."""
        r = self.rows
        for path, rows in r.items():
            if len(rows) != n:
                raise RuntimeError(f"recorder bug: {path} has {len(rows)} rows for {n} steps")
        sign = np.sign(_MM)
        pose = np.array(r["pose"])  # (n, 5): cos β, sin β, x, y, β
        c, s = pose[:, 0], pose[:, 1]
        RT = np.empty((n, 2, 2))  # R(β)ᵀ per step
        RT[:, 0, 0], RT[:, 0, 1], RT[:, 1, 0], RT[:, 1, 1] = c, s, -s, c
        origin = pose[:, 2:4]

        # object and ghost
        yield "scene/object", self._strips((self.object_closed @ RT + origin[:, None]) * _MM, [1] * n)
        ghost = [d for d in r["desired"] if d is not None]
        nv = len(self.object_closed)
        if ghost:
            g = np.array(ghost)  # cos, sin, x, y
            RdT = np.empty((len(g), 2, 2))
            RdT[:, 0, 0], RdT[:, 0, 1], RdT[:, 1, 0], RdT[:, 1, 1] = g[:, 0], g[:, 1], -g[:, 1], g[:, 0]
            strips = (self.object_closed @ RdT + g[:, None, 2:4]) * _MM
        else:
            strips = np.zeros((0, nv, 2))
        yield "scene/desired", self._strips(strips, [0 if d is None else 1 for d in r["desired"]])

        # fingers: each link's outline placed by its joint frame, and the joint chain
        chains = np.stack(r["chains"])  # (n, m, 3, 2): joint 1, elbow, tip [m]
        m = chains.shape[1]
        frames = np.stack([H for step in r["frames"] for H in step]).reshape(n, m, 2, 4, 4)  # joints 1 and 2 of each finger, hand frame
        for i, (path, shapes, width) in enumerate(self.fingers):
            strips = []
            for joint, points in shapes:
                H = frames[:, i, joint]
                placed = points @ H[:, :3, :3].transpose(0, 2, 1) + H[:, None, :3, 3]
                strips.append(_pad_last(placed[:, :, :2], width))
            strips.append(_pad_last(chains[:, i], width))
            yield path, self._strips(np.stack(strips, axis=1).reshape(-1, width, 2) * _MM, [len(strips)] * n)
        yield "scene/joints", rr.Points2D.columns(
            positions=(chains.reshape(-1, 2) * _MM).astype(np.float32)).partition([3 * m] * n)
        tips = chains[:, :, 2]

        # contacts: frames, forces, cones
        edges = np.array(r["edges"], dtype=np.intp).reshape(n, m)
        n0, t0 = self.normals[edges], self.xi_directions[edges]  # (n, m, 2), object frame
        cc, ss = c[:, None], s[:, None]
        normals = np.stack([cc * n0[..., 0] - ss * n0[..., 1], ss * n0[..., 0] + cc * n0[..., 1]], axis=-1)
        tangents = np.stack([cc * t0[..., 0] - ss * t0[..., 1], ss * t0[..., 0] + cc * t0[..., 1]], axis=-1)
        have = [k for k, f in enumerate(r["surface"]) if f is not None]
        if have:
            f = np.array([r["surface"][k] for k in have])  # (h, m, 2)
            vectors = f[..., :1] * normals[have] + f[..., 1:2] * tangents[have]
            origins, vectors = tips[have] * _MM, vectors * self.force_scale * sign
        else:
            origins = vectors = np.zeros((0, m, 2))
        yield "scene/contacts/forces", self._arrows(origins, vectors, [0 if f is None else m for f in r["surface"]])
        have = [k for k, f in enumerate(r["predicted"]) if f is not None]
        if have:
            origins = tips[have] * _MM
            vectors = np.array([r["predicted"][k] for k in have]) * self.force_scale * sign
        else:
            origins = vectors = np.zeros((0, m, 2))
        yield "scene/contacts/forces_predicted", self._arrows(origins, vectors,
                                                             [0 if f is None else m for f in r["predicted"]])
        sliding = np.array([[mo is ContactMode.SLIDING for mo in modes] for modes in r["modes"]], dtype=bool)
        half = np.arctan(np.where(sliding.reshape(n, m), self.kinetic, self.static))  # (n, m): μ_k sliding, else μ_s
        ch, sh = np.cos(half)[..., None], np.sin(half)[..., None]
        perp_n = np.stack([-normals[..., 1], normals[..., 0]], axis=-1)
        ray_a = ch * normals + sh * perp_n
        ray_b = ch * normals - sh * perp_n
        L = self.cone_length / 1000.0
        cones = np.stack([tips + L * ray_a, tips, tips + L * ray_b], axis=2) * _MM  # (n, m, 3, 2)
        colours = [_MODE_RGBA.get(mo, _MODE_RGBA[ContactMode.SEPARATED]) for modes in r["modes"] for mo in modes]
        yield "scene/contacts/cones", self._strips(cones.reshape(-1, 3, 2), [m] * n, colours)

        # envelopes: safe and danger segments just outside each drawn edge
        segments = [(k, *seg) for k, segs in enumerate(r["segments"]) for seg in segs]
        counts = [len(segs) for segs in r["segments"]]
        if segments:
            step, finger, edge, slot, lo, hi = (np.array(col) for col in zip(*segments))
            edge = edge.astype(np.intp)
            RTs = RT[step.astype(np.intp)]
            nrm = np.stack([c[step] * self.normals[edge, 0] - s[step] * self.normals[edge, 1],
                            s[step] * self.normals[edge, 0] + c[step] * self.normals[edge, 1]], axis=-1)
            offset = -(0.003 + 0.003 * slot)[:, None] * nrm
            wdt = self.danger_fraction * (hi - lo)
            u = np.stack([lo, lo + wdt, hi - wdt, hi], axis=1)  # (S, 4)
            in_object = self.xi_origins[edge][:, None] + u[..., None] * self.xi_directions[edge][:, None]
            ends = in_object @ RTs + (origin[step.astype(np.intp)] + offset)[:, None]  # (S, 4, 2)
            safe = ends[:, 1:3] * _MM
            zoned = wdt > 0.0
            danger = np.stack([ends[zoned, 0:2], ends[zoned, 2:4]], axis=1).reshape(-1, 2, 2) * _MM
            safe_colours = self.finger_colours[finger.astype(np.intp)]
            per_step = np.bincount(step.astype(np.intp), weights=zoned, minlength=n).astype(int)
            danger_counts = (2 * per_step).tolist()
        else:
            safe = danger = np.zeros((0, 2, 2))
            safe_colours = np.zeros(0, dtype=np.uint32)
            danger_counts = [0] * n
        yield "scene/envelope/safe", self._strips(safe, counts, safe_colours)
        yield "scene/envelope/danger", self._strips(danger, danger_counts)

        for path in self.scalar_paths:
            yield path, rr.Scalars.columns(scalars=np.array(r[path], dtype=float))

    @staticmethod
    def _strips(strips: np.ndarray, lengths, colours=None):
        """Line strips of equal length (count, points, 2), as rerun's own numpy path makes them (the
        Arrow list array is built here with numpy offsets instead of a Python loop per strip)."""
        strips = np.ascontiguousarray(strips, dtype=np.float32)
        count, width = strips.shape[:2]
        points = Vec2DBatch(strips.reshape(-1, 2)).as_arrow_array()
        offsets = np.arange(0, count * width + 1, width, dtype=np.int32) if width else np.zeros(count + 1, np.int32)
        batch = pa.ListArray.from_arrays(offsets, points, type=LineStrip2DBatch._ARROW_DATATYPE)
        if colours is None:
            return rr.LineStrips2D.columns(strips=batch).partition(lengths)
        return rr.LineStrips2D.columns(strips=batch, colors=np.asarray(colours, dtype=np.uint32)).partition(lengths)

    @staticmethod
    def _arrows(origins: np.ndarray, vectors: np.ndarray, lengths):
        return rr.Arrows2D.columns(origins=origins.reshape(-1, 2).astype(np.float32),
                                   vectors=vectors.reshape(-1, 2).astype(np.float32)).partition(lengths)


class _ColumnWriter:
    """Owns the recording stream; sends the scene's buffered steps with ``send_columns``.

    Kept apart from the recorder so that a ``weakref.finalize`` can close it without keeping
    the recorder alive.
    """

    def __init__(self, stream: rr.RecordingStream, flush_every: int, scene: _Scene):
        self.stream = stream
        self.flush_every = flush_every
        self.scene = scene
        self.steps: list[int] = []
        self.times: list[float] = []
        self.closed = False
        self.send_seconds = 0.0

    def rollback(self) -> None:
        """Drop a partly written row (a step whose logging raised), keeping the columns aligned."""
        self.scene.truncate(len(self.steps))

    def end_row(self, step: int, t: float) -> None:
        self.steps.append(step)
        self.times.append(t)
        if len(self.steps) >= self.flush_every:
            self.send()

    def send(self) -> None:
        """Send every buffered row (one ``send_columns`` per entity)."""
        n = len(self.steps)
        if n == 0:
            return
        start = _time.perf_counter()
        try:
            index = [rr.TimeColumn("step", sequence=np.asarray(self.steps, dtype=np.int64)),
                     rr.TimeColumn("time", duration=_nanoseconds(self.times))]
            for path, columns in self.scene.columns(n):
                self.stream.send_columns(path, indexes=index, columns=columns)
        finally:
            self.scene.clear()
            self.steps.clear()
            self.times.clear()
            self.send_seconds += _time.perf_counter() - start

    def log_now(self, path: str, step: int, t: float, archetype) -> None:
        """Log one archetype immediately at (step, t) (rare data: events)."""
        self.stream.set_time("step", sequence=step)
        self.stream.set_time("time", duration=_nanoseconds([t])[0])
        self.stream.log(path, archetype)

    def close(self) -> None:
        """Send the buffer, flush, and finalise every sink (writes the .rrd footer). Idempotent."""
        if self.closed:
            return
        self.closed = True
        try:
            self.send()
        finally:
            try:
                self.stream.flush(timeout_sec=30.0)
            finally:
                self.stream.disconnect()


def _close_quietly(writer: _ColumnWriter) -> None:
    """The finalizer of a recorder that was never closed (garbage collection or interpreter exit)."""
    try:
        writer.close()
    except Exception as exc:  # noqa: BLE001 - nothing to raise to at that point
        warnings.warn(f"RolloutRecorder: closing the recording failed: {exc!r}", RuntimeWarning, stacklevel=1)


# -------------------------------------------------------------------------------------- recorder
class RolloutRecorder:
    r"""Stream and/or save a closed-loop rollout to rerun (see the module docstring for the scene,
    the plots and the units).

    Args:
        plant: The plant being simulated (its hand, object, contacts and friction set up the recording).
        envelope_edges: Which feasible envelopes to draw: one entry per finger, each an edge
            index, a sequence of edge indices or None (none for that finger). Default: each
            finger's current contact edge (``plant.contacts[i].edge``, followed if it changes).
        rrd_path: Write the recording to this ``.rrd`` file (its directory must exist).
        spawn: Start a rerun viewer and stream to it (with ``rrd_path``: both).
        connect: Stream to a running viewer (or ``rerun --serve-grpc`` server) at this gRPC URL,
            e.g. ``"rerun+http://127.0.0.1:9876/proxy"`` (with ``rrd_path``: both; not with ``spawn``).
        application_id: Rerun application id.
        recording_name: Name shown in the viewer (default: the file's stem, or "rollout").
        danger_fraction: Width of each danger zone as a fraction of its feasible interval, in
            [0, 0.5).
        decimation: Log every n-th step only (n >= 1).
        sliding: Contacts whose ξ are the reduced coordinates S[3:] (the controller's
            ``grasp.sliding``), for naming the error series. Default: the contacts in mode
            ``ContactMode.SLIDING`` now.
        envelope_geometry: ``"ideal"`` (segments, ~60 µs per envelope) or ``"urdf"`` (coal,
            ~1 ms), see :class:`~regrasp.envelope.finger_envelope.FingerEnvelope`.
        force_scale: Arrow length per newton [mm/N].
        cone_length: Length of the friction-cone rays [mm].
        plant_forces: Without a ``PlantStep``, recompute the plant's contact forces at the
            logged state (one KKT solve per logged step, ~150 µs); False: draw and plot the
            controller's predicted forces only.
        envelope_tolerance: Reuse an edge's envelope while the object has moved less than this
            [m] (each coordinate, and β times the object's diameter) since it was computed;
            0 recomputes it at every logged step.
        flush_every: Send the buffered rows every this many logged steps (the cost of a send is
            mostly per entity, so larger blocks are cheaper per step; a live viewer sees the
            data in blocks of this many steps).

    Raises:
        InvalidParameterError: no sink (none of ``rrd_path``, ``spawn``, ``connect``), a missing
            directory, ``spawn`` with ``connect``, a ``connect`` that is no rerun gRPC URL, or a
            parameter out of its domain.
        UnknownEdgeError: an edge in ``envelope_edges`` that the object does not have.
    """

    def __init__(
        self,
        plant: PlantLike,
        *,
        envelope_edges: Sequence[int | Sequence[int] | None] | None = None,
        rrd_path: str | Path | None = None,
        spawn: bool = False,
        connect: str | None = None,
        application_id: str = "regrasp",
        recording_name: str | None = None,
        danger_fraction: float = 0.1,
        decimation: int = 1,
        sliding: Sequence[int] | None = None,
        envelope_geometry: str = "ideal",
        force_scale: float = 10.0,
        cone_length: float = 15.0,
        plant_forces: bool = True,
        envelope_tolerance: float = 1e-5,
        flush_every: int = 500,
    ):
        # ---- validation first: a bad argument leaves nothing behind (no stream, no file)
        if not isinstance(plant, PlantLike):
            raise InvalidParameterError("plant", plant, "a plant (regrasp.Plant or regrasp.plants.mujoco.plant.MujocoPlant)")
        if connect is not None:
            if not isinstance(connect, str) or not _GRPC_URL.match(connect):
                raise InvalidParameterError("connect", connect,
                                            "a rerun gRPC URL such as 'rerun+http://127.0.0.1:9876/proxy'")
            if spawn:
                raise InvalidParameterError("connect", connect, "either spawn=True or connect, not both")
        if rrd_path is None and not spawn and connect is None:
            raise InvalidParameterError("rrd_path", None, "a sink: an .rrd path, spawn=True or connect, or both")
        path = None
        if rrd_path is not None:
            path = Path(rrd_path)
            if path.is_dir() or not path.parent.is_dir():
                raise InvalidParameterError("rrd_path", rrd_path, "a file path in an existing directory")
        if not (isinstance(danger_fraction, (int, float)) and 0.0 <= danger_fraction < 0.5):
            raise InvalidParameterError("danger_fraction", danger_fraction, "a fraction in [0, 0.5)")
        self.decimation = self._positive_int("decimation", decimation)
        flush_every = self._positive_int("flush_every", flush_every)
        for name, value in (("force_scale", force_scale), ("cone_length", cone_length)):
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise InvalidParameterError(name, value, "a length > 0 [mm per N, mm]")
        if not (isinstance(envelope_tolerance, (int, float)) and math.isfinite(envelope_tolerance)
                and envelope_tolerance >= 0):
            raise InvalidParameterError("envelope_tolerance", envelope_tolerance, "a distance >= 0 [m]")
        self.envelope_tolerance = float(envelope_tolerance)
        self.plant = plant
        hand = plant.hand
        self.m = hand.m
        self.fingers = hand.fingers
        self.polygon = plant.polygon
        self.friction = plant.friction
        self.danger_fraction = float(danger_fraction)
        self.force_scale = float(force_scale)
        self.cone_length = float(cone_length)
        self.plant_forces = bool(plant_forces)
        self.envelope_edges = self._parse_edges(envelope_edges)
        if sliding is None:
            sliding = [i for i, c in enumerate(plant.contacts) if c.mode is ContactMode.SLIDING]
        sliding = list(sliding)
        if (len(set(sliding)) != len(sliding)
                or not all(isinstance(i, (int, np.integer)) and 0 <= i < self.m for i in sliding)):
            raise InvalidParameterError("sliding", sliding, f"distinct contact indices in 0..{self.m - 1}")
        self.sliding = [int(i) for i in sliding]
        self._envelopes: dict[tuple[int, int], FingerEnvelope] = {}
        self._samples: dict[tuple[int, int], tuple[np.ndarray, EnvelopeSample]] = {}
        self._envelope_geometry = envelope_geometry
        for i, c in enumerate(plant.contacts):  # build now, so that a bad geometry raises here
            self._envelope(i, c.edge)
            for e in (self.envelope_edges[i] if self.envelope_edges is not None else ()):
                self._envelope(i, e)

        # ---- geometry caches
        taken: set[str] = set()
        self.keys = [_entity_name(f.name, taken) for f in self.fingers]
        self.colours = [_FINGER_COLOURS[i % len(_FINGER_COLOURS)] for i in range(self.m)]
        self._edges = self.polygon.edges
        self._object_closed = np.vstack([self.polygon.vertices, self.polygon.vertices[:1]])
        self._kin = []  # per finger: (model, data, tip placement)
        drawn = []  # per finger: (entity, [(joint 0|1, outline points in the joint frame)], points per strip)
        for f, key in zip(self.fingers, self.keys):
            shapes = []
            for sh in f.link_shapes():
                placement = sh.placement_in_joint
                outline = _outline_in_shape_frame(sh.geometry, placement)
                shapes.append((sh.link, outline @ placement.rotation.T + placement.translation))
            width = max([3] + [len(p) for _, p in shapes])
            self._kin.append((f.model, f.model.createData(), f.model.frames[f.tip_frame_id].placement))
            drawn.append((f"scene/fingers/{key}", shapes, width))
        self._n_links = [len(shapes) for _, shapes, _ in drawn]
        scene = _Scene(object_closed=self._object_closed, fingers=drawn, keys=self.keys, edges=self._edges,
                       frictions=self.friction, colours=self.colours, force_scale=self.force_scale,
                       cone_length=self.cone_length, danger_fraction=self.danger_fraction)

        # ---- the stream and its sinks
        self.rrd_path = path
        self.connect = connect
        self.steps_logged = 0
        self.compute_seconds = 0.0
        self._next_step = 0
        self._closed = False
        self._events_seen = (None, 0)
        stream = rr.RecordingStream(application_id, recording_id=uuid.uuid4(), make_default=False,
                                    make_thread_default=False)
        self._writer = _ColumnWriter(stream, flush_every, scene)
        self._finalizer = weakref.finalize(self, _close_quietly, self._writer)
        try:
            stream.set_log_time_enabled(False)  # the simulation's own time is what matters
            blueprint = self._blueprint()
            if not spawn and connect is None:
                stream.save(str(path), default_blueprint=blueprint)
            elif path is None and connect is not None:
                stream.connect_grpc(connect, default_blueprint=blueprint)
            elif path is None:
                stream.spawn(default_blueprint=blueprint)
            else:
                if spawn:
                    rr.spawn(connect=False)
                stream.set_sinks(rr.GrpcSink(connect), rr.FileSink(str(path)), default_blueprint=blueprint)
            name = recording_name if recording_name is not None else (path.stem if path is not None else "rollout")
            stream.send_recording_name(str(name))
            self._log_static()
        except BaseException:
            self.close()
            raise

    # ------------------------------------------------------------------ construction helpers
    @staticmethod
    def _positive_int(name: str, value) -> int:
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
            raise InvalidParameterError(name, value, "an integer >= 1")
        return int(value)

    def _parse_edges(self, envelope_edges):
        if envelope_edges is None:
            return None
        if isinstance(envelope_edges, (str, bytes)) or not isinstance(envelope_edges, Sequence) \
                or len(envelope_edges) != self.m:
            raise InvalidParameterError("envelope_edges", envelope_edges,
                                        f"one entry per finger ({self.m}): an edge, a list of edges or None")
        out = []
        for entry in envelope_edges:
            if entry is None:
                out.append(())
                continue
            edges = [entry] if isinstance(entry, (int, np.integer)) else list(entry)
            for e in edges:
                self.polygon.edge(e)  # UnknownEdgeError
            out.append(tuple(int(e) for e in edges))
        return out

    def _envelope(self, i: int, edge: int) -> FingerEnvelope:
        env = self._envelopes.get((i, edge))
        if env is None:
            env = FingerEnvelope(self.fingers[i], self.polygon, edge, geometry=self._envelope_geometry)
            self._envelopes[(i, edge)] = env
        return env

    def _scene_bounds(self):
        pts = [f.joint1_in_hand for f in self.fingers]
        st = self.plant.state
        if st is not None:
            pts += list(self.polygon.vertices_in(st.X))
            pts += [p for i, f in enumerate(self.fingers) for p in f.joint_positions_in_hand(st.q[2 * i:2 * i + 2])]
        else:
            pts += [f.joint1_in_hand + s * f.reach[1] for f in self.fingers for s in (-1.0, 1.0)]
        mm = np.asarray(pts) * _MM
        lo, hi = mm.min(axis=0) - 25.0, mm.max(axis=0) + 25.0
        return rrb.VisualBounds2D(x_range=(float(lo[0]), float(hi[0])), y_range=(float(lo[1]), float(hi[1])))

    def _blueprint(self) -> rrb.Blueprint:
        scene = rrb.Spatial2DView(origin="scene", name="hand frame [mm] (y up)", visual_bounds=self._scene_bounds())
        left = rrb.Vertical(
            rrb.Tabs(scene, rrb.Spatial2DView(origin="model/object", name="object frame [mm]"),
                     rrb.TextDocumentView(origin="model/setup", name="set-up")),
            rrb.TextLogView(origin="events", name="events: supervisor decisions and plant events"),
            row_shares=[3, 1],
        )
        middle = rrb.Vertical(
            *[rrb.TimeSeriesView(origin=f"plots/xi/{key}", name=f"{f.name}: ξ, feasible band, danger zones, ξ_d [mm]")
              for f, key in zip(self.fingers, self.keys)],
            rrb.TimeSeriesView(origin="plots/phase", name="phase: 0 fixed, 1 priming, 2 sliding, 3 settling",
                               axis_y=rrb.ScalarAxis(range=(-0.2, 3.2))),
        )
        right = rrb.Vertical(
            rrb.TimeSeriesView(origin="plots/error", name="tracking error: x, y, ξ [mm], β [deg]"),
            rrb.TimeSeriesView(origin="plots/force", name="contact forces [N]"),
            rrb.TimeSeriesView(origin="plots/cone_margin", name="friction-cone margin μ f_n − |f_t| [N]"),
            rrb.TimeSeriesView(origin="plots/mode", name="contact mode: 0 fixed, 1 sliding, 2 separated",
                               axis_y=rrb.ScalarAxis(range=(-0.2, 2.2))),
        )
        return rrb.Blueprint(
            rrb.Horizontal(left, middle, right, column_shares=[3, 2, 2]),
            rrb.BlueprintPanel(state="collapsed"),
            rrb.SelectionPanel(state="collapsed"),
            rrb.TimePanel(state="expanded", timeline="time"),
        )

    def _log_static(self) -> None:
        log = self._writer.stream.log
        n_edges = self.polygon.n_vertices
        # the object in its own frame
        log("model/object/outline", rr.LineStrips2D([self._object_closed * _MM], radii=0.6,
                                                    colors=_colours([_rgba(_OBJECT)]), labels=["object"]), static=True)
        mids = np.array([0.5 * (e.start + e.end) for e in self.polygon.edges]) * _MM
        log("model/object/edges", rr.Points2D(mids, radii=1.0, colors=_colours([_rgba(_OBJECT)]),
                                              labels=[f"edge {k}" for k in range(n_edges)], show_labels=True),
            static=True)
        log("model/object/centre_of_mass", rr.Points2D([[0.0, 0.0]], radii=1.5, labels=["centre of mass"]),
            static=True)
        rows = ["| finger | entity | l1, l2 [mm] | base [mm, deg] | configuration | edge | mode | friction |",
                "|---|---|---|---|---|---|---|---|"]
        for i, f in enumerate(self.fingers):
            c = self.plant.contacts[i]
            b = f.base_in_hand
            rows.append(f"| {f.name} | `{self.keys[i]}` | {f.link_lengths[0] * 1e3:.1f}, {f.link_lengths[1] * 1e3:.1f} "
                        f"| ({b[0] * 1e3:.1f}, {b[1] * 1e3:.1f}, {math.degrees(b[2]):.1f}) | {f.configuration.value} "
                        f"| {c.edge} | {c.mode.value} | {self.friction[i]} |")
        text = "\n".join([
            "# Rollout set-up", "",
            f"Object: {n_edges}-gon, mass {self.polygon.mass:g} kg, inertia {self.polygon.inertia:.3g} kg m², "
            f"plant step {self.plant.dt * 1e3:g} ms.", "",
            *rows, "",
            f"Scene in mm with y flipped (rerun draws y down). Force arrows {self.force_scale:g} mm/N; "
            f"cone rays {self.cone_length:g} mm; danger zones {100 * self.danger_fraction:g} % of each "
            f"feasible interval at both ends; envelope geometry '{self._envelope_geometry}'; "
            f"decimation {self.decimation}.",
        ])
        log("model/setup", rr.TextDocument(text, media_type=rr.MediaType.MARKDOWN), static=True)

        # styling of the time-varying scene (the rows carry geometry only)
        names = [f.name for f in self.fingers]
        log("scene/object", rr.LineStrips2D.from_fields(radii=[0.7], colors=_colours([_rgba(_OBJECT)]),
                                                        labels=["object"],
                                                        show_labels=False, draw_order=10.0), static=True)
        log("scene/desired", rr.LineStrips2D.from_fields(radii=[0.4], colors=_colours([_rgba(_GHOST)]),
                                                         labels=["desired"],
                                                         show_labels=False, draw_order=5.0), static=True)
        for i, f in enumerate(self.fingers):
            n_links = self._n_links[i]
            log(f"scene/fingers/{self.keys[i]}", rr.LineStrips2D.from_fields(
                radii=[0.3] * n_links + [0.9],
                colors=_colours([_rgba(self.colours[i], 200)] * n_links + [_rgba(_darker(self.colours[i]))]),
                labels=[f"{f.name} {s.name}" for s in f.link_shapes()] + [f.name], show_labels=False,
                draw_order=20.0), static=True)
        log("scene/joints", rr.Points2D.from_fields(
            radii=[1.3] * (3 * self.m), colors=_colours([_rgba(_darker(c)) for c in self.colours for _ in range(3)]),
            labels=[f"{n} {j}" for n in names for j in ("joint 1", "elbow", "tip")], show_labels=False,
            draw_order=21.0), static=True)
        log("scene/contacts/forces", rr.Arrows2D.from_fields(radii=[0.6], colors=_colours([_rgba(_FORCE)]),
                                                             labels=[f"{n}: force on the object" for n in names],
                                                             show_labels=False, draw_order=30.0), static=True)
        log("scene/contacts/forces_predicted", rr.Arrows2D.from_fields(
            radii=[0.3], colors=_colours([_rgba(_PREDICTED, 220)]), labels=[f"{n}: predicted force" for n in names],
            show_labels=False, draw_order=29.0), static=True)
        log("scene/contacts/cones", rr.LineStrips2D.from_fields(
            radii=[0.3], labels=[f"{n}: friction cone" for n in names], show_labels=False, draw_order=25.0),
            static=True)
        log("scene/envelope/safe", rr.LineStrips2D.from_fields(radii=[1.4], draw_order=15.0), static=True)
        log("scene/envelope/danger", rr.LineStrips2D.from_fields(radii=[1.4], colors=_colours([_rgba(_DANGER)]),
                                                                 draw_order=16.0), static=True)

        # time series
        p = len(self.sliding)
        err_names = ["x [mm]", "y [mm]", "β [deg]"] + [f"ξ {self.fingers[i].name} [mm]" for i in self.sliding]
        err_colours = [(31, 119, 180), (44, 160, 44), (214, 39, 40)] + \
                      [self.colours[i] for i in self.sliding]
        log("plots/error", rr.SeriesLines(names=err_names, colors=_colours([_rgba(c) for c in err_colours])),
            static=True)
        pct = 100.0 * self.danger_fraction
        for i, f in enumerate(self.fingers):
            c = self.colours[i]
            log(f"plots/xi/{self.keys[i]}", rr.SeriesLines(
                names=[f"ξ {f.name}", f"ξ_d control law {f.name}", f"feasible lo {f.name}", f"feasible hi {f.name}",
                       f"lo + {pct:g} % (danger) {f.name}", f"hi − {pct:g} % (danger) {f.name}",
                       f"ξ_d schedule {f.name}"],
                colors=_colours([_rgba(c), _rgba(_darker(c, 0.5), 200), _rgba(_OBJECT), _rgba(_OBJECT),
                                 _rgba(_DANGER, 160), _rgba(_DANGER, 160), _rgba(c, 110)]),
                widths=[2.0, 1.0, 1.5, 1.5, 1.0, 1.0, 3.0]), static=True)
            log(f"plots/phase/{self.keys[i]}", rr.SeriesLines(names=[f.name], colors=_colours([_rgba(c)])),
                static=True)
        force_names = ([f"f_n {n}" for n in names] + [f"f_t {n}" for n in names]
                       + [f"f_n {n} (predicted)" for n in names] + [f"f_t {n} (predicted)" for n in names])
        force_colours = ([_rgba(c) for c in self.colours] + [_rgba(_darker(c, 0.5)) for c in self.colours]
                         + [_rgba(c, 90) for c in self.colours] + [_rgba(_darker(c, 0.5), 90) for c in self.colours])
        log("plots/force", rr.SeriesLines(names=force_names, colors=_colours(force_colours)), static=True)
        log("plots/cone_margin", rr.SeriesLines(
            names=[n for n in names] + [f"{n} (predicted)" for n in names],
            colors=_colours([_rgba(c) for c in self.colours] + [_rgba(c, 90) for c in self.colours])), static=True)
        log("plots/mode", rr.SeriesLines(names=names, colors=_colours([_rgba(c) for c in self.colours])), static=True)
        self._n_errors = 3 + p

    # ------------------------------------------------------------------ public API
    @property
    def closed(self) -> bool:
        """Whether :meth:`close` has run."""
        return self._closed

    @property
    def seconds_per_step(self) -> float:
        """Mean wall time [s] per logged step: geometry and buffering plus the amortised sending."""
        if self.steps_logged == 0:
            return float("nan")
        return (self.compute_seconds + self._writer.send_seconds) / self.steps_logged

    def log_step(
        self,
        plant: PlantLike,
        output: ControlOutput | None = None,
        *,
        step: int | None = None,
        time: float | None = None,
        desired_pose: ArrayLike | None = None,
        plant_step: PlantStep | None = None,
    ) -> bool:
        r"""Log the plant's current state (and the step's control output) at one step, measuring the
        plant (ξ from the tips, envelopes evaluated here): the path without a supervisor.

        Args:
            plant: The plant (the recorder's, or one with the same hand and object).
            output: The controller's output for the step that led here, or None (e.g. the
                initial state): then the predicted forces and margins are not plotted and the
                tracking error needs ``desired_pose``.
            step: The ``step`` timeline's value; default: one more than the previous call's
                (0 for the first call). Only multiples of ``decimation`` are logged.
            time: The ``time`` timeline's value [s]; default ``plant.state.t``.
            desired_pose: The desired object pose (x, y, β), or the whole desired reduced state
                S_d = (x, y, β, ξ of each ``sliding`` contact): drawn as a ghost, and the
                tracking error is then measured at the logged state.
            plant_step: The :class:`~regrasp.plants.project.plant.PlantStep` of the step, whose forces (at the
                step's start) are then drawn and plotted instead of recomputed ones.

        Returns:
            Whether the step was logged (False when ``decimation`` skips it).

        Raises:
            InvalidParameterError: the recorder is closed, the plant has no state or another
                hand, or an array has the wrong shape.
        """
        self._check_open()
        if plant is not self.plant and (not isinstance(plant, PlantLike) or plant.hand.m != self.m
                                        or plant.polygon.n_vertices != self.polygon.n_vertices):
            raise InvalidParameterError("plant", plant, f"a plant with the recorder's {self.m} fingers and object")
        st = plant.state
        if st is None:
            raise InvalidParameterError("plant.state", None, "a state: call plant.reset() first")
        step = self._step(step)
        t = self._time(st.t if time is None else time)
        start = _time.perf_counter()
        self._log_plant_events(plant, step)
        if step % self.decimation:
            return False
        desired = self._desired(desired_pose)
        if output is not None and np.asarray(output.error).shape != (self._n_errors,):
            raise InvalidParameterError("output.error", np.shape(output.error),
                                        f"{self._n_errors} entries (3 + one per sliding contact {self.sliding}; "
                                        "pass sliding= to the recorder)")
        return self._row(step, t, start, lambda: self._log_rows(plant, output, desired, plant_step))

    def log_initial(self, plant: PlantLike, desired_pose: ArrayLike | None) -> bool:
        """Log the plant's state before the first step (step 0)."""
        return self.log_step(plant, None, step=0, desired_pose=desired_pose)

    def log_record(self, record: StepRecord, desired_pose: ArrayLike | None) -> bool:
        """Log one :class:`~regrasp.plants.simulation.StepRecord` of the simulation loop: the state after its
        step, as step ``record.index + 1``, against ``desired_pose`` (the desired pose then).

        A supervised record (``record.supervision`` not None) is logged from the record alone
        (module docstring, "Two sources"); its events (the supervisor's decisions and the plant's
        events) go to ``events`` whatever the decimation. A record without a supervisor is logged
        like :meth:`log_step` with its ``PlantStep``.

        Returns:
            Whether the step was logged (False when ``decimation`` skips it).
        """
        sup = record.supervision
        if sup is None:
            control = record.command.control
            # the recorder's error series are the object's (the sliding set changes with each slide)
            control = replace(control, error=self._object_error(control.error))
            return self.log_step(self.plant, control, step=record.index + 1, desired_pose=desired_pose,
                                 plant_step=record.plant)
        self._check_open()
        step = self._step(record.index + 1)
        t = self._time(record.plant.state.t)
        start = _time.perf_counter()
        for ev in record.events:  # decisions at the step's start (the previous state), plant events after it
            self._log_event(ev, max(step - 1, 0) if ev.source is EventSource.SUPERVISOR else step)
        self._events_seen = (self.plant.events, len(self.plant.events))  # the plant's are in the record
        if step % self.decimation:
            return False
        desired = self._desired(desired_pose)
        return self._row(step, t, start, lambda: self._record_rows(record, desired))

    def log_failure(self, failure: Failure, plant: PlantLike | None = None) -> None:
        """Log a rollout's :class:`~regrasp.core.events.Failure`: an ERROR line in ``events`` and the
        failure marked in the scene (``scene/failure``, module docstring) at the failure's time and
        the last step, drawn at ``plant``'s state (default: the recorder's plant)."""
        self._check_open()
        plant = self.plant if plant is None else plant
        step = max(self._next_step - 1, 0)
        t = self._time(failure.time)
        kind = FailureKind(failure.kind)
        self._writer.log_now("events", step, t,
                             rr.TextLog(f"FAILURE ({kind.value}): {failure.reason}", level="ERROR"))
        marker = self._failure_marker(kind, failure, plant)
        if marker is not None:
            self._writer.log_now("scene/failure", step, t, marker)

    def hook(self, plant: PlantLike, reference: Callable | None = None, *,
             log_initial: bool = True) -> Callable[[float, ControlOutput], None]:
        """An ``on_step`` callback for :func:`~regrasp.plants.closed_loop.run_closed_loop`.

        ``run_closed_loop`` calls it after ``plant.step``, so it logs ``plant.state`` (the state
        after the step) at ``time = plant.state.t``; the desired pose is ``reference(time)``'s
        first entry when ``reference`` is given. With ``log_initial`` the current state is
        logged now (step 0, no control output), so step k is the state after k control steps.
        """
        if plant.state is None:
            raise InvalidParameterError("plant.state", None, "a state: call plant.reset() first")

        def desired_at(t: float):
            if reference is None:
                return None
            value = reference(t)
            return value[0] if isinstance(value, tuple) else value

        if log_initial:
            self.log_step(plant, None, desired_pose=desired_at(plant.state.t))

        def on_step(t: float, output: ControlOutput) -> None:
            step = self._next_step
            desired = desired_at(plant.state.t) if step % self.decimation == 0 else None
            self.log_step(plant, output, step=step, desired_pose=desired)

        return on_step

    def flush(self) -> None:
        """Send the buffered rows and flush the stream (the file stays open)."""
        if not self._closed:
            self._writer.send()
            self._writer.stream.flush(timeout_sec=30.0)

    def close(self) -> None:
        """Send what is buffered, flush, and finalise the file (footer) and viewer stream.

        Idempotent; after it, :meth:`log_step` raises.
        """
        if self._closed:
            return
        self._closed = True
        self._finalizer.detach()
        self._writer.close()

    def __enter__(self) -> "RolloutRecorder":
        return self

    def __exit__(self, exc_type, exc, tb) -> bool:
        if exc_type is None:
            self.close()
        else:  # keep the rollout's exception the one that propagates
            try:
                self.close()
            except Exception as close_exc:  # noqa: BLE001
                warnings.warn(f"RolloutRecorder.close() failed after {exc_type.__name__}: {close_exc!r}",
                              RuntimeWarning, stacklevel=2)
        return False

    def __repr__(self) -> str:
        state = "closed" if self._closed else "open"
        return f"RolloutRecorder({self.rrd_path or 'viewer'}, {self.steps_logged} steps logged, {state})"

    # ------------------------------------------------------------------ per step
    def _check_open(self) -> None:
        if self._closed:
            raise InvalidParameterError("recorder", "closed", "an open RolloutRecorder (log before close())")

    def _step(self, step) -> int:
        if step is None:
            step = self._next_step
        elif isinstance(step, bool) or not isinstance(step, (int, np.integer)) or step < 0:
            raise InvalidParameterError("step", step, "an integer >= 0")
        step = int(step)
        self._next_step = step + 1
        return step

    @staticmethod
    def _time(t) -> float:
        t = float(t)
        if not math.isfinite(t):
            raise InvalidParameterError("time", t, "a finite time [s]")
        return t

    @staticmethod
    def _desired(desired_pose):
        desired = None if desired_pose is None else np.asarray(desired_pose, dtype=float).reshape(-1)
        if desired is not None and (desired.size < 3 or not np.isfinite(desired).all()):
            raise InvalidParameterError("desired_pose", desired_pose, "(x, y, beta) or S_d = (x, y, beta, xi...)")
        return desired

    def _object_error(self, error) -> np.ndarray:
        """A control law's error cut to the object's entries and padded to the recorder's series."""
        out = np.full(self._n_errors, np.nan)
        out[:3] = np.asarray(error, dtype=float)[:3]
        return out

    def _row(self, step: int, t: float, start: float, fill: Callable[[], None]) -> bool:
        try:
            fill()
        except BaseException:
            self._writer.rollback()  # the steps logged so far stay intact
            raise
        self.compute_seconds += _time.perf_counter() - start
        self.steps_logged += 1
        self._writer.end_row(step, t)  # may send a block (timed separately)
        return True

    def _log_event(self, ev, step: int) -> None:
        """One event (an :class:`~regrasp.core.events.Event`, the plant's or the supervisor's) as a text line."""
        level = "WARN" if ev.kind in WARN_KINDS else "INFO"
        self._writer.log_now("events", step, float(ev.time), rr.TextLog(
            f"t = {ev.time:.4f} s  {ev.source.value} {ev.contact or '-'}: {ev.kind.value} ({ev.detail})", level=level))

    def _log_plant_events(self, plant: PlantLike, step: int) -> None:
        events = plant.events
        seen_list, seen = self._events_seen
        if seen_list is not events:  # plant.reset() starts a new list
            seen = 0
        for ev in events[seen:]:
            self._log_event(ev, step)
        self._events_seen = (events, len(events))

    def _edges_drawn(self, plant: PlantLike, i: int):
        if self.envelope_edges is None:
            return (plant.contacts[i].edge,)
        return self.envelope_edges[i]

    def _kinematics(self, q) -> tuple[list[np.ndarray], np.ndarray]:
        """The fingers' joint frames (joints 1 and 2 of each, 4x4, hand frame) and chains (m, 3, 2) at ``q``."""
        chains = np.empty((self.m, 3, 2))
        frames = []
        for i, (model, data, tip_placement) in enumerate(self._kin):
            pin.forwardKinematics(model, data, q[2 * i:2 * i + 2])
            oMi = data.oMi
            H1, H2 = oMi[1].homogeneous, oMi[2].homogeneous
            frames.append(H1)
            frames.append(H2)
            chains[i, 0] = H1[:2, 3]
            chains[i, 1] = H2[:2, 3]
            chains[i, 2] = (oMi[2] * tip_placement).translation[:2]
        return frames, chains

    def _append_pose(self, rows, X, q, desired) -> np.ndarray:
        """The object's and the desired pose's rows and the fingers'; returns the tips (m, 2) [m]."""
        x, y, beta = np.asarray(X, dtype=float).tolist()
        rows["pose"].append((math.cos(beta), math.sin(beta), x, y))
        if desired is not None:
            rows["desired"].append((math.cos(desired[2]), math.sin(desired[2]), desired[0], desired[1]))
        else:
            rows["desired"].append(None)
        frames, chains = self._kinematics(q)
        rows["frames"].append(frames)
        rows["chains"].append(chains)
        return chains[:, 2]

    @staticmethod
    def _segments(edges, feasible_of) -> list:
        """(finger, edge, slot, lo, hi) of each drawn interval: the slot-th envelope along its edge."""
        segments = []
        slot: dict[int, int] = {}
        for i, edge in edges:
            k = slot.get(edge, 0)
            slot[edge] = k + 1
            for lo, hi in feasible_of(i, edge):
                segments.append((i, edge, k, lo, hi))
        return segments

    def _append_series(self, rows, X, xi, modes, desired, output_error, forces, predicted, bands, law_xi,
                       planned_xi, phases) -> None:
        """The plotted rows (x, y, ξ in mm, β in degrees). ``bands`` (m, 2) is the feasible interval
        holding each ξ [m] (NaN: none); ``law_xi``, ``planned_xi`` per contact [m] (NaN: none);
        ``phases`` the phase codes (NaN: no supervisor)."""
        nan = math.nan
        x, y, beta = np.asarray(X, dtype=float).tolist()
        if desired is not None:
            d = desired.tolist()
            err = [d[0] - x, d[1] - y, wrap_angle(d[2] - beta)] + [nan] * (self._n_errors - 3)
            for j, i in enumerate(self.sliding):
                if 3 + j < len(d):
                    err[3 + j] = d[3 + j] - xi[i]
        elif output_error is not None:
            err = np.asarray(output_error, dtype=float).tolist()
        else:
            err = [nan] * self._n_errors
        err[0] *= 1000.0
        err[1] *= 1000.0
        err[2] = math.degrees(err[2])
        rows["plots/error"].append(err[:3] + [v * 1000.0 for v in err[3:]])
        f = self.danger_fraction
        for i in range(self.m):
            row = [nan] * 7
            if modes[i] is not ContactMode.SEPARATED:
                lo, hi = bands[i]
                w = f * (hi - lo)
                row = [xi[i], law_xi[i], lo, hi, lo + w, hi - w, planned_xi[i]]
            rows[f"plots/xi/{self.keys[i]}"].append([v * 1000.0 for v in row])
            rows[f"plots/phase/{self.keys[i]}"].append([phases[i]])
        rows["plots/force"].append(forces)
        rows["plots/cone_margin"].append(predicted)
        rows["plots/mode"].append([float(MODE_CODES.get(mo, 2)) for mo in modes])

    def _record_rows(self, record, desired) -> None:
        """A supervised record's rows, from the record alone (module docstring)."""
        ps, sup, control = record.plant, record.supervision, record.command.control
        self._supervised_rows(ps.state.X, ps.state.q, desired, ps.forces_surface, control.contact_forces,
                              control.contact_forces_surface, [e.feasible for e in sup.envelopes], sup.phases, ps.xi,
                              control.error, record.cone_margins, control.cone_margins, sup.bounds, sup.reference_xi,
                              sup.planned_xi)

    def _supervised_rows(self, X, q, desired, surface, predicted, predicted_surface, feasible, phases, xi, error,
                         plant_cone, predicted_cone, bounds, reference_xi, planned_xi) -> None:
        """A supervised step's rows: the plant's pose X and joints q after it, its forces (at its start), the law's predicted
        forces (hand and surface frames), error and cone margins, the envelopes' feasible sets, the phases, ξ after
        it, the plant's cone margins, the bounds, the law's and the plan's ξ."""
        rows = self._writer.scene.rows
        self._append_pose(rows, X, q, desired)
        contacts = self.plant.contacts
        modes = [c.mode for c in contacts]
        edges = [c.edge for c in contacts]
        rows["edges"].append(edges)
        rows["modes"].append(modes)
        surface = np.array(surface, dtype=float)
        rows["surface"].append(surface)
        rows["predicted"].append(np.array(predicted, dtype=float))
        pred = np.asarray(predicted_surface, dtype=float)
        rows["segments"].append(self._segments(enumerate(edges), lambda i, _edge: feasible[i]))
        phases = [float(PHASE_CODES.get(ph, math.nan)) for ph in phases]
        self._append_series(
            rows, X, np.asarray(xi, dtype=float).tolist(), modes, desired, self._object_error(error),
            surface[:, 0].tolist() + surface[:, 1].tolist() + pred[:, 0].tolist() + pred[:, 1].tolist(),
            np.asarray(plant_cone, dtype=float).tolist() + np.asarray(predicted_cone, dtype=float).tolist(),
            np.asarray(bounds, dtype=float).tolist(), np.asarray(reference_xi, dtype=float).tolist(),
            np.asarray(planned_xi, dtype=float).tolist(), phases)

    def log_stretch_step(self, step: int, t: float, X: np.ndarray, q: np.ndarray, desired_pose: ArrayLike,
                         surface: np.ndarray, predicted: np.ndarray,
                         predicted_surface: np.ndarray, feasible: Sequence[Sequence[tuple[float, float]]],
                         phases: Sequence[ContactPhase], xi: np.ndarray, error: np.ndarray,
                         plant_cone: np.ndarray, predicted_cone: np.ndarray, bounds: np.ndarray,
                         reference_xi: np.ndarray, planned_xi: np.ndarray) -> bool:
        """Log a supervised step that a compiled stretch (:mod:`regrasp.rollout.stretch`) took, as :meth:`log_record` logs
        its record (a stretch's steps have no events): the step ``step`` (``record.index + 1``), the plant's time
        ``t`` [s], pose ``X`` and joints ``q`` after it, and the record's fields (:meth:`_supervised_rows`)."""
        self._check_open()
        step = self._step(step)
        t = self._time(t)
        start = _time.perf_counter()
        self._events_seen = (self.plant.events, len(self.plant.events))
        if step % self.decimation:
            return False
        desired = self._desired(desired_pose)
        return self._row(step, t, start, lambda: self._supervised_rows(
            X, q, desired, surface, predicted, predicted_surface, feasible, phases, xi, error, plant_cone,
            predicted_cone, bounds, reference_xi, planned_xi))

    def _log_rows(self, plant: PlantLike, output: ControlOutput | None, desired, plant_step: PlantStep | None) -> None:
        # the step's numbers are computed here; the drawn geometry per block of steps in _Scene.columns
        rows = self._writer.scene.rows
        st = plant.state
        X = st.X
        x, y, beta = X.tolist()
        c_, s_ = math.cos(beta), math.sin(beta)
        R = np.array([[c_, -s_], [s_, c_]])
        origin = X[:2]
        tips = self._append_pose(rows, X, st.q, desired)

        # contacts: ξ, forces
        contacts = plant.contacts
        xi = []
        edges = []
        RT = R.T
        for i, c in enumerate(contacts):
            e = self._edges[c.edge]
            edges.append(c.edge)
            xi.append(float(e.xi_direction @ (RT @ (tips[i] - origin) - e.xi_origin)))
        modes = [c.mode for c in contacts]
        rows["edges"].append(edges)
        rows["modes"].append(modes)
        surface = None
        if plant_step is not None:
            surface = np.array(plant_step.forces_surface, dtype=float)
        elif self.plant_forces and output is not None:
            try:
                forces = plant.accelerations(st, output.tau)[2]
                surface = plant.surface_forces(st, forces)
            except (np.linalg.LinAlgError, RegraspError):
                surface = None
        rows["surface"].append(surface)
        nan = math.nan
        nan_m = [nan] * self.m
        if surface is not None:
            fn, ft = surface[:, 0].tolist(), surface[:, 1].tolist()
            # the coefficient of each contact's mode while these forces acted (μ_s fixed, μ_k sliding)
            during = plant_step.modes if plant_step is not None else modes
            margin = [cone_margin(mu, a, b) for mu, a, b in zip(coefficients(self.friction, during), fn, ft)]
        else:
            fn = ft = margin = nan_m
        if output is not None:
            rows["predicted"].append(np.array(output.contact_forces, dtype=float))
            pred = np.asarray(output.contact_forces_surface, dtype=float)
            pfn, pft = pred[:, 0].tolist(), pred[:, 1].tolist()
            pmargin = np.asarray(output.cone_margins, dtype=float).tolist()
        else:
            rows["predicted"].append(None)
            pfn = pft = pmargin = nan_m

        # envelopes (drawn) and the bounds around each contact's ξ (plotted)
        samples: dict[tuple[int, int], EnvelopeSample] = {}
        tol = self.envelope_tolerance
        scale = self.polygon.scale

        def sample(i: int, edge: int) -> EnvelopeSample:
            found = samples.get((i, edge))
            if found is None:
                cached = self._samples.get((i, edge))
                if cached is not None and tol > 0.0:
                    cx, cy, cb = cached[0]
                    if abs(x - cx) <= tol and abs(y - cy) <= tol and abs(beta - cb) * scale <= tol:
                        samples[(i, edge)] = cached[1]
                        return cached[1]
                found = samples[(i, edge)] = self._envelope(i, edge).at(X, st.t)
                self._samples[(i, edge)] = ((x, y, beta), found)
            return found

        drawn = [(i, edge) for i in range(self.m) for edge in self._edges_drawn(plant, i)]
        rows["segments"].append(self._segments(drawn, lambda i, edge: sample(i, edge).feasible))
        bands = []
        for i in range(self.m):
            band = (nan, nan)
            if modes[i] is not ContactMode.SEPARATED:
                feasible = sample(i, contacts[i].edge).feasible
                if feasible:
                    band = min(feasible, key=lambda iv: 0.0 if iv[0] <= xi[i] <= iv[1]
                               else min(abs(xi[i] - iv[0]), abs(xi[i] - iv[1])))
            bands.append(band)
        law_xi = [nan] * self.m
        if desired is not None:
            for j, i in enumerate(self.sliding):
                if 3 + j < desired.size:
                    law_xi[i] = float(desired[3 + j])
        self._append_series(rows, X, xi, modes, desired, None if output is None else output.error,
                            fn + ft + pfn + pft, margin + pmargin, bands, law_xi, nan_m, nan_m)

    def _failure_marker(self, kind: FailureKind, failure, plant: PlantLike):
        """The red outline marking ``failure`` at ``plant``'s state (module docstring), or None."""
        if kind is FailureKind.INTERRUPTED or plant.state is None:
            return None
        st = plant.state
        names = [f.name for f in self.fingers]
        i = names.index(failure.contact) if failure.contact in names else None
        if i is None:  # no one contact: the object
            X = st.X
            c_, s_ = math.cos(X[2]), math.sin(X[2])
            strips = [self._object_closed @ np.array([[c_, s_], [-s_, c_]]) + X[:2]]
        else:
            frames, chains = self._kinematics(st.q)
            if kind is FailureKind.COLLISION:
                link = None
                for ev in reversed(plant.events):
                    if ev.contact == failure.contact and ev.kind == EventKind.COLLISION and "link" in ev.values:
                        link = int(ev.values["link"])
                        break
                shapes = [(j, pts) for j, pts in self._writer.scene.fingers[i][1] if link is None or j == link]
                strips = [(pts @ frames[2 * i + j][:3, :3].T + frames[2 * i + j][:3, 3])[:, :2] for j, pts in shapes]
                if not strips:  # a finger without collision shapes: its chain
                    strips = [chains[i]]
            else:
                strips = [chains[i, 2] + np.vstack([_circle(0.004), _circle(0.004)[:1]])]
        return rr.LineStrips2D([s * _MM for s in strips], radii=1.2, colors=_colours([_rgba(_DANGER)]),
                               labels=[f"{kind.value}: {failure.reason}"], show_labels=True, draw_order=40.0)

"""What one logged step's rows are (:class:`StepRow`: the raw data the scene draws and the plotted values), built
from a supervised step (:class:`SupervisedStep`: a record of the simulation loop or a compiled stretch's step) by
:func:`supervised_row`; :mod:`~regrasp.rollout.recording.measure` builds them from the plant itself. A block of
rows becomes the plots' columns here (:func:`series_columns`) and the scene's in
:class:`~regrasp.rollout.recording.scene.Scene`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
import rerun as rr
from numpy.typing import ArrayLike

from ...core.contact import ContactMode
from ...core.intervals import danger_zones
from ...core.planar import wrap_angle
from ...supervisor.types import ContactPhase
from .hand import HandDrawing

if TYPE_CHECKING:
    from ...plants.project.state import PlantContact
    from ...plants.simulation import StepRecord

__all__ = ["BAND_LINES", "MODE_CODES", "PHASE_CODES", "ZONE_LINES", "Layout", "Segment", "Series", "StepRow",
           "SupervisedStep", "band_fill", "mode_codes", "poses", "segments", "series", "series_columns",
           "supervised_row"]

#: Contact mode → the value plotted under ``plots/mode`` (a ContactMode equals its string, so either looks up).
MODE_CODES = {ContactMode.FIXED: 0, ContactMode.SLIDING: 1, ContactMode.SEPARATED: 2}
#: Supervisor phase → the value plotted under ``plots/phase/<finger>``.
PHASE_CODES = {ContactPhase.FIXED: 0, ContactPhase.PRIMING: 1, ContactPhase.SLIDING: 2, ContactPhase.SETTLING: 3}

#: One drawn feasible interval: (finger, edge, slot: the how-many-th envelope drawn along that edge, lo, hi [m]).
Segment = tuple[int, int, int, float, float]


@dataclass(frozen=True)
class Layout:
    """What every row holds: the fingers as drawn (and their kinematics), the contacts whose ξ are the tracking
    error's reduced coordinates (``sliding``) and the danger zones' width (a fraction of each interval)."""

    hand: HandDrawing
    sliding: tuple[int, ...]
    danger_fraction: float

    @property
    def n_errors(self) -> int:
        """Entries of the tracking error: x, y, β and one ξ per sliding contact."""
        return 3 + len(self.sliding)

    def object_error(self, error: ArrayLike) -> np.ndarray:
        """A control law's error cut to the object's entries (x, y, β) and padded with NaN to the error series."""
        out = np.full(self.n_errors, np.nan)
        out[:3] = np.asarray(error, dtype=float)[:3]
        return out


class Series(NamedTuple):
    """One logged step's plotted values, in the plots' units (module docstring of
    :mod:`regrasp.rollout.recording`: mm, degrees, N, codes; NaN where absent), per plot entity. Arrays, not lists:
    a recording buffers its rows, and buffered lists (~20 a row) made the garbage collector run a full collection
    (~70 ms) inside a rollout; it does not track arrays."""

    error: np.ndarray  #: ``plots/error/position`` (x, y, each ξ [mm]) and ``plots/error/angle`` (β [deg])
    xi: np.ndarray  #: ``plots/xi/<finger>``, per finger its seven series (m, 7)
    force: np.ndarray  #: ``plots/force``
    cone_margin: np.ndarray  #: ``plots/cone_margin``
    mode: np.ndarray  #: ``plots/mode``
    phase: np.ndarray  #: ``plots/phase/<finger>``, per finger (m, 1)


class StepRow(NamedTuple):
    """One logged step's rows: what the scene draws (hand frame, metres, object frame for the edges) and the
    plotted values. Arrays only (and the row's two tuples): a recording buffers its rows, and every buffered
    container counts towards the garbage collector's next collection (a full one costs ~70-100 ms in a process that
    has planned; arrays are not tracked).

    Attributes:
        pose: The object's pose after the step as drawn (cos β, sin β, x, y).
        desired: The desired pose, likewise, or None (no ghost).
        frames: The fingers' joint frames (:meth:`HandDrawing.kinematics`).
        chains: The fingers' chains (m, 3, 2) [m].
        edges: Each contact's edge now (m,).
        modes: Each contact's mode now, as its :data:`MODE_CODES` (m,).
        surface: The plant's contact forces (f_n, f_t) per contact (m, 2) [N], or None.
        predicted: The controller's predicted contact forces in the hand frame (m, 2) [N], or None.
        segments: The feasible intervals drawn (S, 5) (:func:`segments`).
        series: The plotted values.
        xi: Each contact's ξ now (m,) [m]: where a curved object's contacts' frames are drawn (an edge's frame is
            the same along it), or None.
    """

    pose: np.ndarray
    desired: np.ndarray | None
    frames: np.ndarray
    chains: np.ndarray
    edges: np.ndarray
    modes: np.ndarray
    surface: np.ndarray | None
    predicted: np.ndarray | None
    segments: np.ndarray
    series: Series
    xi: np.ndarray | None = None


class SupervisedStep(NamedTuple):
    """What a supervised step gives a recording (a :class:`~regrasp.plants.simulation.StepRecord`'s fields, or a
    compiled stretch's outputs for that step), per contact where shaped (m, ...).

    Attributes:
        X: The object's pose after the step (x, y [m], β [rad]).
        q: The joint angles after the step (2m,) [rad].
        surface: The plant's contact forces at the step's start (f_n, f_t) (m, 2) [N].
        predicted: The law's predicted contact forces, hand frame (m, 2) [N].
        predicted_surface: The same as (f_n, f_t) (m, 2) [N].
        feasible: Per contact the supervisor's envelope's feasible intervals ``[(lo, hi), ...]`` [m].
        phases: Per contact the supervisor's phase.
        xi: Each contact's ξ after the step [m].
        error: The law's tracking error (its first three entries, x, y [m] and β [rad], are plotted).
        plant_cone: The plant's cone margins μ f_n - |f_t| [N].
        predicted_cone: The law's [N].
        bounds: The feasible interval holding each ξ (m, 2) [m].
        reference_xi: The law's ξ_d [m] (NaN: none).
        planned_xi: The schedule's ξ_d [m] (NaN: none).
    """

    X: ArrayLike
    q: ArrayLike
    surface: ArrayLike
    predicted: ArrayLike
    predicted_surface: ArrayLike
    feasible: Sequence[Sequence[tuple[float, float]]]
    phases: Sequence[ContactPhase]
    xi: ArrayLike
    error: ArrayLike
    plant_cone: ArrayLike
    predicted_cone: ArrayLike
    bounds: ArrayLike
    reference_xi: ArrayLike
    planned_xi: ArrayLike

    @classmethod
    def from_record(cls, record: StepRecord) -> SupervisedStep:
        """A supervised record's step: the state after it, its forces and margins, the law's output and the
        supervisor's view at its start."""
        ps, sup, control = record.plant, record.supervision, record.command.control
        return cls(ps.state.X, ps.state.q, ps.forces_surface, control.contact_forces, control.contact_forces_surface,
                   [e.feasible for e in sup.envelopes], sup.phases, ps.xi, control.error, record.cone_margins,
                   control.cone_margins, sup.bounds, sup.reference_xi, sup.planned_xi)


def poses(X: ArrayLike, desired: np.ndarray | None) -> tuple[np.ndarray, np.ndarray | None]:
    """The object's pose ``X`` and the desired pose (``desired``'s first three entries, or None) as drawn: each
    (cos β, sin β, x, y)."""
    x, y, beta = np.asarray(X, dtype=float).tolist()
    ghost = None if desired is None else np.array([math.cos(desired[2]), math.sin(desired[2]), desired[0],
                                                   desired[1]])
    return np.array([math.cos(beta), math.sin(beta), x, y]), ghost


def segments(edges: Iterable[tuple[int, int]],
             feasible_of: Callable[[int, int], Sequence[tuple[float, float]]]) -> np.ndarray:
    """The intervals drawn for the (finger, edge) pairs ``edges``: ``feasible_of(finger, edge)``'s, each with its
    slot, the how-many-th envelope along its edge (the drawing offsets them from the edge); (S, 5): finger, edge,
    slot, lo, hi [m] (:data:`Segment`)."""
    out = []
    slot: dict[int, int] = {}
    for i, edge in edges:
        k = slot.get(edge, 0)
        slot[edge] = k + 1
        for lo, hi in feasible_of(i, edge):
            out.append((i, edge, k, lo, hi))
    return np.array(out, dtype=float).reshape(-1, 5)


def series(layout: Layout, X: ArrayLike, xi: Sequence[float], modes: Sequence[ContactMode],
           desired: np.ndarray | None, output_error: ArrayLike | None, forces: list[float], margins: list[float],
           bands: Sequence[Sequence[float]], law_xi: Sequence[float], planned_xi: Sequence[float],
           phases: Sequence[float]) -> Series:
    """One step's plotted values from the pose ``X`` and each contact's ``xi`` [m] after it: the tracking error
    against ``desired`` (S_d) when known, else ``output_error`` (else NaN); ``forces`` (f_n..., f_t..., predicted
    f_n..., f_t... [N]) and ``margins`` (the plant's, then the predicted [N]) as they are; ``bands`` (m, 2) the
    feasible interval holding each ξ [m] (NaN: none); ``law_xi``, ``planned_xi`` per contact [m] (NaN: none);
    ``phases`` the phase codes (NaN: no supervisor)."""
    nan = math.nan
    x, y, beta = np.asarray(X, dtype=float).tolist()
    if desired is not None:
        d = desired.tolist()
        err = [d[0] - x, d[1] - y, wrap_angle(d[2] - beta)] + [nan] * (layout.n_errors - 3)
        for j, i in enumerate(layout.sliding):
            if 3 + j < len(d):
                err[3 + j] = d[3 + j] - xi[i]
    elif output_error is not None:
        err = np.asarray(output_error, dtype=float).tolist()
    else:
        err = [nan] * layout.n_errors
    err[0] *= 1000.0
    err[1] *= 1000.0
    err[2] = math.degrees(err[2])
    f = layout.danger_fraction
    xi_rows, phase_rows = [], []
    for i in range(len(modes)):
        row = [nan] * 7
        if modes[i] is not ContactMode.SEPARATED:
            lo, hi = bands[i]
            (_, lo_zone), (hi_zone, _) = danger_zones(lo, hi, f)
            row = [xi[i], law_xi[i], lo, hi, lo_zone, hi_zone, planned_xi[i]]
        xi_rows.append([v * 1000.0 for v in row])
        phase_rows.append([phases[i]])
    return Series(error=np.array(err[:3] + [v * 1000.0 for v in err[3:]]), xi=np.array(xi_rows),
                  force=np.array(forces, dtype=float), cone_margin=np.array(margins, dtype=float),
                  mode=np.array([float(MODE_CODES.get(mo, 2)) for mo in modes]), phase=np.array(phase_rows))


def supervised_row(layout: Layout, contacts: Sequence[PlantContact], step: SupervisedStep,
                   desired: np.ndarray | None) -> StepRow:
    """A supervised step's row, from the step alone (the contacts' edges and modes now): nothing is recomputed."""
    frames, chains = layout.hand.kinematics(step.q)
    modes = [c.mode for c in contacts]
    edges = [c.edge for c in contacts]
    surface = np.array(step.surface, dtype=float)
    pred = np.asarray(step.predicted_surface, dtype=float)
    feasible = step.feasible
    values = series(
        layout, step.X, np.asarray(step.xi, dtype=float).tolist(), modes, desired, layout.object_error(step.error),
        surface[:, 0].tolist() + surface[:, 1].tolist() + pred[:, 0].tolist() + pred[:, 1].tolist(),
        np.asarray(step.plant_cone, dtype=float).tolist() + np.asarray(step.predicted_cone, dtype=float).tolist(),
        np.asarray(step.bounds, dtype=float).tolist(), np.asarray(step.reference_xi, dtype=float).tolist(),
        np.asarray(step.planned_xi, dtype=float).tolist(),
        [float(PHASE_CODES.get(ph, math.nan)) for ph in step.phases])
    pose, ghost = poses(step.X, desired)
    return StepRow(pose, ghost, frames, chains, np.array(edges, dtype=np.intp), mode_codes(modes), surface,
                   np.array(step.predicted, dtype=float), segments(enumerate(edges), lambda i, _edge: feasible[i]),
                   values, np.array(step.xi, dtype=float))


def mode_codes(modes: Sequence[ContactMode]) -> np.ndarray:
    """The contacts' modes as their :data:`MODE_CODES` (an unknown one: separated)."""
    return np.array([MODE_CODES.get(mo, 2) for mo in modes], dtype=np.int8)


#: How many lines fill a ξ panel's band (``plots/xi/<finger>/band``): between the danger zones, and in each zone.
BAND_LINES, ZONE_LINES = 10, 2


def band_fill(xi: np.ndarray) -> np.ndarray:
    """The lines filling a block of ξ rows' band (n, 7) [mm] (series 2-5: lo, hi and where the danger zones start):
    :data:`BAND_LINES` evenly inside the safe part, then :data:`ZONE_LINES` inside each danger zone, (n, B + 2 Z);
    NaN where the row's band is."""
    lo, hi, lo_zone, hi_zone = xi[:, 2:3], xi[:, 3:4], xi[:, 4:5], xi[:, 5:6]
    safe = (np.arange(BAND_LINES) + 0.5) / BAND_LINES
    zone = (np.arange(ZONE_LINES) + 0.5) / ZONE_LINES
    return np.hstack([lo_zone + safe * (hi_zone - lo_zone), lo + zone * (lo_zone - lo),
                      hi_zone + zone * (hi - hi_zone)])


def series_columns(rows: Sequence[StepRow], keys: Sequence[str]) -> Iterator[tuple[str, rr.ComponentColumnList]]:
    """``(entity path, columns)`` of the plots for a block of rows (one row per step), in a fixed order: the tracking
    error in two entities of one unit each (``plots/error/position`` x, y and each reduced ξ [mm];
    ``plots/error/angle`` β [deg]), each finger's ξ panel and the lines filling its band (:func:`band_fill`), the
    forces, cone margins, modes and phases."""
    error = np.array([r.series.error for r in rows], dtype=float)
    yield "plots/error/position", _scalars(np.delete(error, 2, axis=1))
    yield "plots/error/angle", _scalars(error[:, 2:3])
    for i, key in enumerate(keys):
        xi = np.array([r.series.xi[i] for r in rows], dtype=float)
        yield f"plots/xi/{key}", _scalars(xi)
        yield f"plots/xi/{key}/band", _scalars(band_fill(xi))
    yield "plots/force", _scalars([r.series.force for r in rows])
    yield "plots/cone_margin", _scalars([r.series.cone_margin for r in rows])
    yield "plots/mode", _scalars([r.series.mode for r in rows])
    for i, key in enumerate(keys):
        yield f"plots/phase/{key}", _scalars([r.series.phase[i] for r in rows])


def _scalars(values) -> rr.ComponentColumnList:
    return rr.Scalars.columns(scalars=np.array(values, dtype=float))

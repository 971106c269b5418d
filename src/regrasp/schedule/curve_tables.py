r"""The lattice's force tables on a curved object (:mod:`regrasp.schedule.curve_forces` does the exact test).

The same tables as on polygons (:func:`~regrasp.schedule.force_tables.edge_force_tables`: per layer, cell of the
other contacts and move vector, the axis contact's feasible positions; the middle of every move, one slider's too:
on an arc the normal turns between the cells; the break-aways), each entry the longest run of feasible cells of the
axis contact, widened by a quarter cell on both sides (the tables are float32; a quarter cell never reaches a
neighbour). In the layer tables each contact's force polygon is also cut by its joints' torque limits at that layer
and cell (exact: the torques are affine in the contact's own force, :mod:`regrasp.schedule.torque`), where polygons
only take a necessary condition.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from ..core.curves import CurvedObject
from .curve_forces import MAX_POLYGON, clip_polygons, feasible_runs, mode_polygon, wrench_maps
from .force_polytope import ForceLimits
from .force_tables import assemble_tables
from .torque import TorqueModel

if TYPE_CHECKING:
    from ..core.contact import Friction
    from ..core.trajectory import TrajectorySample
    from ..envelope.finger_envelope import EnvelopeSample, FingerEnvelope

__all__ = ["chained_samples", "curve_force_tables", "feasible_span", "forces_exist", "required_wrench"]


def chained_samples(envelope: FingerEnvelope, poses: np.ndarray, times: np.ndarray,
                    near: float | None = None) -> list[EnvelopeSample]:
    """A finger's envelope samples at ``poses`` (T, 3) and ``times`` (T,) [s] on a curve, each window next to the
    previous one's (the first next to ``near`` [m], if given): ξ unwrapped along the trajectory."""
    out = []
    for t, pose in zip(times, poses):
        out.append(envelope.at(pose, float(t), near=near))
        near = out[-1].xi_foot
    return out


def feasible_span(samples: list[EnvelopeSample], h: float) -> tuple[float, float]:
    """The smallest and the largest feasible ξ [m] of a contact's envelope ``samples`` on a curve (its lattice's
    extent); with none feasible, a cell either side of the first sample's window centre."""
    ends = [(lo, hi) for s in samples for lo, hi in s.feasible]
    if not ends:
        return samples[0].xi_foot - h, samples[0].xi_foot + h
    return min(lo for lo, _ in ends), max(hi for _, hi in ends)


def required_wrench(mass: float, inertia: float, gravity: np.ndarray, sample: TrajectorySample) -> np.ndarray:
    r"""The wrench the contacts must exert on the object at each of a trajectory ``sample``'s times, object frame
    (T, 3) [N, N, N m]: :math:`(R(\beta)^T m (a - g),\ I\alpha)`."""
    F = mass * (sample.acceleration[:, :2] - np.asarray(gravity, dtype=float))
    c, s = np.cos(sample.pose[:, 2]), np.sin(sample.pose[:, 2])
    return np.column_stack([c * F[:, 0] + s * F[:, 1], -s * F[:, 0] + c * F[:, 1], inertia * sample.acceleration[:, 2]])


def curve_force_tables(curve: CurvedObject, torque: TorqueModel, sample: TrajectorySample,
                       middle: TrajectorySample, early: TrajectorySample, lead: float, combos: np.ndarray,
                       friction: tuple[Friction, ...], limits: ForceLimits, grids: list[np.ndarray], axis: int,
                       admissible: np.ndarray, speed: float, overshoot: float = 0.0,
                       joints: list[np.ndarray] | None = None) -> tuple:
    """The lattice's tables for contacts on ``curve`` (module docstring; the arguments as
    :func:`~regrasp.schedule.force_tables.edge_force_tables`'s, and ``torque`` the fingers' torque model,
    ``admissible`` the envelope tables (layers, m, n_max) (the other cells are not tested), ``speed`` [m/s] the
    lattice's slide speed, ``joints`` the fingers' joint angles at the layers and cells if known). Returns (lo, hi,
    blo, bhi, slots, mid_lo, mid_hi)."""
    m = len(grids)
    n_layers = len(sample.pose)
    n_max = max(len(g) for g in grids)
    h = grids[0][1] - grids[0][0] if len(grids[0]) > 1 else 0.0
    mu_s = [f.static for f in friction]
    rows = int(np.prod([len(grids[j]) for j in range(m) if j != axis]))
    gravity = torque.hand.gravity_in_hand
    tol = 1e-9 * max(1.0, limits.f_max)
    maps_cache: dict[tuple[int, float], np.ndarray] = {}
    torque_cache: dict[tuple[int, int], tuple] = {}

    def maps(i: int, shift: float) -> np.ndarray:
        key = (i, float(shift))
        if key not in maps_cache:
            maps_cache[key] = wrench_maps(curve, grids[i] - shift)
        return maps_cache[key]

    def torque_rows(i: int, d: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Contact i's torque half-planes at the layers and cells, sliding in direction d: rows (T, K, 4, 2),
        offsets (T, K, 4) (NaN: no limit), reachable (T, K)."""
        if (i, d) not in torque_cache:
            xi = np.broadcast_to(grids[i], (n_layers, len(grids[i])))
            c = torque.contact(i, sample.pose, sample.velocity, sample.acceleration, xi, d * speed,
                               joints=None if joints is None else joints[i])
            g = np.zeros(c.wrench.shape[:2] + (4, 2))
            beta = np.full(c.wrench.shape[:2] + (4,), np.nan)
            for j in range(2):
                e = torque.effort[i, j]
                if not math.isfinite(e):
                    continue
                a, b, w = c.normal[..., j], c.tangential[..., j], c.wrench[..., j]
                g[..., 2 * j, 0], g[..., 2 * j, 1], beta[..., 2 * j] = -a, -b, w - e  # w + a λ + b τ <= e
                g[..., 2 * j + 1, 0], g[..., 2 * j + 1, 1], beta[..., 2 * j + 1] = a, b, -e - w  # ... >= -e
            torque_cache[(i, d)] = (np.nan_to_num(g), beta, c.reachable)
        return torque_cache[(i, d)]

    def table(ratios, smp=sample, shift=None, keep=False, lim=limits):
        shifts = np.zeros(m) if shift is None else np.asarray(shift, dtype=float)
        floors = lim.floors(ratios)
        polygons = np.zeros((n_layers, m, n_max, MAX_POLYGON, 2))
        counts = np.zeros((n_layers, m, n_max), dtype=np.int64)
        for i in range(m):
            base = mode_polygon(ratios[i], mu_s[i], floors[i], lim)
            k = len(grids[i])
            if keep and torque.limited:
                d = 0 if ratios[i] is None else int(np.sign(ratios[i]))
                g, beta, reachable = torque_rows(i, d)
                polygons[:, i, :k], counts[:, i, :k] = clip_polygons(base, g, beta, reachable)
            else:
                polygons[:, i, :k, :len(base)] = base
                counts[:, i, :k] = len(base)
        runs = feasible_runs([maps(i, shifts[i]) for i in range(m)], polygons, counts,
                             required_wrench(curve.mass, curve.inertia, gravity, smp), admissible, axis, tol)
        grid = grids[axis]
        found = runs[..., 1] >= runs[..., 0]
        out = np.empty((2, n_layers, rows), dtype=np.float32)
        out[0] = np.where(found, grid[np.clip(runs[..., 0], 0, len(grid) - 1)] - 0.25 * h, np.inf)
        out[1] = np.where(found, grid[np.clip(runs[..., 1], 0, len(grid) - 1)] + 0.25 * h, -np.inf)
        return out

    return assemble_tables(table, sample, middle, early, lead, combos, friction, limits, h, (n_layers, rows),
                           overshoot, middle_from=1)



def forces_exist(curve: CurvedObject, xi: np.ndarray, ratios: Sequence[float | None], static_mu: Sequence[float],
                 limits: ForceLimits, wrench: np.ndarray,
                 torques: np.ndarray | None = None, effort: np.ndarray | None = None) -> bool:
    """Whether a force system exists with the contacts at ``xi`` (m,) [m] on ``curve`` in the mode ``ratios`` (None:
    fixed; else τ/λ), with ``limits`` and the required ``wrench`` (3,) (:func:`required_wrench`); with ``torques``
    (m, 2, 3) (per contact and joint (w, a, b): the torque w + a λ + b τ, :class:`~regrasp.schedule.torque.
    ContactTorques`) and ``effort`` (m, 2) [N m], within the joints' limits too. The exact test of
    :func:`~regrasp.schedule.curve_forces.feasible_runs` at one position."""
    m = len(xi)
    floors = limits.floors(ratios)
    polygons = np.zeros((1, m, 1, MAX_POLYGON, 2))
    counts = np.zeros((1, m, 1), dtype=np.int64)
    for i in range(m):
        base = mode_polygon(ratios[i], static_mu[i], floors[i], limits)
        if torques is None or effort is None:
            polygons[0, i, 0, :len(base)], counts[0, i, 0] = base, len(base)
            continue
        g, beta = np.zeros((1, 1, 4, 2)), np.full((1, 1, 4), np.nan)
        for j in range(2):
            if math.isfinite(effort[i, j]):
                w, a, b = torques[i, j]
                g[0, 0, 2 * j], beta[0, 0, 2 * j] = (-a, -b), w - effort[i, j]
                g[0, 0, 2 * j + 1], beta[0, 0, 2 * j + 1] = (a, b), -effort[i, j] - w
        reachable = np.array([[bool(np.all(np.isfinite(torques[i])))]])
        polygons[:, i], counts[:, i] = clip_polygons(base, np.nan_to_num(g), beta, reachable)
    runs = feasible_runs([wrench_maps(curve, [x]) for x in xi], polygons, counts, np.asarray(wrench)[None],
                         np.ones((1, m, 1), dtype=bool), 0, 1e-9 * max(1.0, limits.f_max))
    return bool(runs[0, 0, 1] >= runs[0, 0, 0])

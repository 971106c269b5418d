"""The lattice's force tables on polygons (:func:`edge_force_tables`: per layer, cell of the other contacts and move
vector, the interval of the axis contact's feasible positions, from the force polytope's vertices) and the joint
torque limits' necessary condition in them (:func:`torque_tables`); :mod:`regrasp.schedule.problem` builds the
problem with them, ``docs/derivations.md`` ("The lattice program") describes the checks."""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterable
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from ..core.contact import Friction
from .force_polytope import ForceGeometry, ForceLimits, force_vertices, xi_intervals
from .tables import cut_tables
from .torque import TorqueModel

if TYPE_CHECKING:
    from ..core.trajectory import TrajectorySample

__all__ = ["assemble_tables", "breakaway_limits", "edge_force_tables", "slide_ratios", "torque_tables"]


def breakaway_limits(limits: ForceLimits) -> ForceLimits:
    """The limits a break-away is planned with: what the executor's internal force keeps at a priming in its last
    fallback (:mod:`regrasp.supervisor.fallbacks`), the held contacts' friction margin (its
    ``fallback_friction_margin``, the planner's ``friction_margin``) and ``f_min``; its floors are given up first and
    its cone margin [N] is a target, not a constraint, so ``slider_floor``, ``holder_preload`` and ``cone_margin``
    do not apply (a priming lasts a few milliseconds on the nominal plant)."""
    return replace(limits, slider_floor=0.0, holder_preload=0.0, cone_margin=0.0)


def slide_ratios(direction: Iterable[int], friction: Iterable[Friction], breaking: int | Iterable[int] | None = None,
                 overshoot: float = 0.0) -> list[float | None]:
    """Per contact None (fixed) or the signed force ratio τ/λ = s μ_k (s (μ_s + ``overshoot``) for the contact or
    contacts ``breaking``: the executor primes a break-away past the static cone's edge)."""
    primed = set() if breaking is None else {breaking} if isinstance(breaking, (int, np.integer)) else set(breaking)
    return [None if d == 0 else d * (f.static + overshoot if i in primed else f.kinetic)
            for i, (d, f) in enumerate(zip(direction, friction))]


def edge_force_tables(geo: ForceGeometry, sample: TrajectorySample, middle: TrajectorySample,
                      early: TrajectorySample, lead: float, combos: np.ndarray, friction: tuple[Friction, ...],
                      limits: ForceLimits, grids: list[np.ndarray], axis: int, overshoot: float = 0.0) -> tuple:
    """The lattice's interval tables (float32): the modes at the layers; for two or more sliders at
    each interval's middle (``middle``: the trajectory there, layer k's entry for the interval ending
    at it) with the sliders half a cell back; and where μ_s + ``overshoot`` > μ_k the break-away of the contacts
    that start together (primed together to μ_s + ``overshoot``, with :func:`breakaway_limits`), both at the layer
    and where they really start, ``early`` (the trajectory half a ramp before the layer) with the other sliders
    ``lead`` cells back."""
    m = len(grids)
    n_layers = len(sample.pose)
    vertices: list = []  # per move vector, the polytope's vertices at the layers
    others = np.array(list(itertools.product(*[grids[i] for i in range(m) if i != axis]))).reshape(-1, m - 1)
    mu_s = np.array([f.static for f in friction])
    h = grids[0][1] - grids[0][0] if len(grids[0]) > 1 else 0.0
    columns = [i for i in range(m) if i != axis]

    def table(ratios, smp=sample, shift=None, keep=False, lim=limits):
        """(lo, hi) per layer and cell of the others, with the positions ``shift`` [m] (m,) back (``keep``: keep the
        polytope's vertices; ``lim``: the limits)."""
        grid = others if shift is None else others - np.array([shift[i] for i in columns])
        fv = force_vertices(geo, smp.pose[:, 2], smp.acceleration, ratios, mu_s, lim)
        if keep:
            vertices.append(fv)
        out = np.empty((2, n_layers, len(others)), dtype=np.float32)
        back = 0.0 if shift is None else shift[axis]  # the axis position x - back must be inside
        for k in range(n_layers):
            lo, hi = xi_intervals(*fv.at(k), axis, grid)
            out[0, k], out[1, k] = lo + back, hi + back
        return out

    lo, hi, blo, bhi, slots, mid_lo, mid_hi = assemble_tables(table, sample, middle, early, lead, combos, friction,
                                                              limits, h, (n_layers, len(others)), overshoot)
    return lo, hi, blo, bhi, slots, mid_lo, mid_hi, vertices


def assemble_tables(table: Callable, sample: TrajectorySample, middle: TrajectorySample, early: TrajectorySample,
                    lead: float, combos: np.ndarray, friction: tuple[Friction, ...], limits: ForceLimits, h: float,
                    shape: tuple[int, int], overshoot: float = 0.0, middle_from: int = 2) -> tuple:
    """The lattice's interval tables (:func:`edge_force_tables`) from ``table(ratios, smp=sample, shift=None,
    keep=False, lim=limits)``, which gives (lo, hi) (2, layers, rows) for a mode (``ratios``, the trajectory ``smp``,
    the positions ``shift`` [m] (m,) back, ``keep``: the mode's own tables, ``lim``: the limits); ``shape``: (layers,
    rows of the other contacts' cells); ``h``: the cell [m]; ``middle_from``: the fewest sliders whose moves get a
    middle table (the others': +-inf). Returns (lo, hi, blo, bhi, slots, mid_lo, mid_hi)."""
    n_layers, rows = shape
    M, m = combos.shape
    lo = np.empty((n_layers, rows, M), dtype=np.float32)
    hi = np.empty_like(lo)
    mid_lo = np.full_like(lo, -np.inf)
    mid_hi = np.full_like(lo, np.inf)
    for mu, d in enumerate(combos):
        lo[:, :, mu], hi[:, :, mu] = table(slide_ratios(d, friction), keep=True)
        if np.count_nonzero(d) >= middle_from:
            mid_lo[:, :, mu], mid_hi[:, :, mu] = table(slide_ratios(d, friction), middle, 0.5 * h * np.asarray(d))
    needs = np.array([[d[i] != 0 and friction[i].static + overshoot > friction[i].kinetic + 1e-12 for i in range(m)]
                      for d in combos])
    # one check per move vector u and set S of the contacts that start breaking away in it together (the executor
    # primes them at once): the slot of every starter mask (bit i: contact i starts) is that of its contacts in need
    slots = np.full((M, 2 ** m), -1, dtype=np.int64)
    blo = bhi = None
    if needs.any():
        checks: dict[tuple[int, int], int] = {}
        for mu in range(M):
            for bits in range(1, 2 ** m):
                if any((bits >> i) & 1 and combos[mu, i] == 0 for i in range(m)):
                    continue  # (only sliders start)
                primed = sum(1 << i for i in range(m) if (bits >> i) & 1 and needs[mu, i])
                if primed:
                    slots[mu, bits] = checks.setdefault((mu, primed), len(checks))
        blo = np.empty((n_layers, rows, len(checks)), dtype=np.float32)
        bhi = np.empty_like(blo)
        for (mu, primed), slot in checks.items():
            breaking = [i for i in range(m) if (primed >> i) & 1]
            ratios = slide_ratios(combos[mu], friction, breaking=breaking, overshoot=overshoot)
            at_layer = table(ratios, lim=breakaway_limits(limits))
            others_back = lead * h * np.where(np.isin(np.arange(m), breaking), 0, combos[mu])
            real = table(ratios, early, others_back, lim=breakaway_limits(limits))
            blo[:, :, slot] = np.maximum(at_layer[0], real[0])
            bhi[:, :, slot] = np.minimum(at_layer[1], real[1])
    return lo, hi, blo, bhi, slots, mid_lo, mid_hi




def torque_tables(torque: TorqueModel, sample: TrajectorySample, grids: list[np.ndarray], combos: np.ndarray,
                  vertices: list, speed: float, axis: int, lo: np.ndarray, hi: np.ndarray, env_ok: np.ndarray,
                  joints: list | None = None) -> tuple[np.ndarray, tuple | None]:
    """The joint torque limits' necessary condition in the force tables (module docstring of
    :mod:`regrasp.schedule.torque`): per layer and move vector, a state whose other contacts sit on a cell that no
    force within a joint's limit allows is dropped (its interval emptied), and the axis's interval is cut to the
    span of its allowed cells (a superset: the verification checks exactly). Changes ``lo`` and ``hi`` in place;
    returns the excess table (:meth:`~regrasp.schedule.torque.TorqueModel.cell_excess`) and the tables as they were
    (None when the limits excluded no cell); ``env_ok``: the envelope tables (a cell they exclude is not cut
    again)."""
    excess = torque.cell_excess(sample, grids, combos, vertices, speed, joints)
    # (N + 1, M, m, n_max); NaN: unreachable, and cells outside the envelopes: the envelope's business
    allowed = ~(excess > 0.0).any(axis=-1) | ~env_ok[:, None]
    return excess, cut_tables(allowed, grids, axis, lo, hi)

r"""The decomposition planner's force checks: the polytope's vertices per mode, and a block's tables.

A contact mode (who slides, which way) at one time has the force polytope P of :mod:`regrasp.schedule.force_polytope`,
and positions ξ admit a force system iff :math:`\min_v \varphi_v(\xi) \le 0 \le \max_v \varphi_v(\xi)` with
:math:`\varphi_v(\xi) = \lambda_v \cdot \xi - q_v`. With all contacts but a block (i, j) frozen at known positions, the
frozen terms are constants, :math:`\varphi_v = \lambda_{v,i}\xi_i + \lambda_{v,j}\xi_j + \sum_f \lambda_{v,f}\xi_f -
q_v`, and for each cell of i the feasible ξ_j form the interval :math:`[\min_v \rho_v, \max_v \rho_v]`,
:math:`\rho_v = (q_v - \sum_f \lambda_{v,f}\xi_f - \lambda_{v,i}\xi_i)/\lambda_{v,j}` (λ_j ≥ f_min > 0): one
product of the vertices with the cells of i gives a whole table over the block's cells.

:class:`ModeVertices` computes each mode's vertices at every layer on its first use (the modes a descent meets: at
most ``max_sliders`` sliders, O(m²) modes for two); :func:`block_tables` builds the tables
:func:`~regrasp.schedule.block_dp.block_dp` reads for one block and the frozen path, with the exact lattice's checks
(:mod:`regrasp.schedule.lattice`): the mode at both ends of an interval, its middle with two sliders (the sliders half
a cell back), the union move where one contact stops as another starts, and the break-away of the contacts that start
together, primed together on their static edges (by ``prime_overshoot``) where μ_s + overshoot > μ_k, with the limits
of :func:`~regrasp.schedule.problem.breakaway_limits`, at the layer and half a ramp earlier.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from scipy.ndimage import binary_erosion

from .block_dp import PAIR_MOVES
from .force_polytope import force_vertices
from .problem import breakaway_limits, slide_ratios

if TYPE_CHECKING:
    from .problem import Problem

__all__ = ["BlockTables", "ModeVertices", "block_tables", "pair_table"]

#: Slack [m] of the interval tests (the exact lattice's)
TOL = 1e-8


class ModeVertices:
    """The force polytope's vertices per sample kind ("layer": at the layers, "middle": at the middle of the interval
    ending at each layer, "early": half a ramp before each layer) and mode (the contacts' ratios), each computed once
    for every layer on its first use."""

    def __init__(self, problem: Problem):
        traj = problem.scenario.trajectory
        times = problem.times

        def sample(t: np.ndarray):
            return traj.sample(np.clip(t, traj.t_start, traj.t_end))

        self._samples = {"layer": sample(times), "middle": sample(np.append(times[0], 0.5 * (times[1:] + times[:-1]))),
                         "early": sample(times - 0.5 * problem.settings.ramp)}
        self._geometry = problem.geometry
        self._limits = problem.limits
        self._mu_s = [f.static for f in problem.friction]
        self._cache: dict = {}

    @property
    def modes(self) -> int:
        """How many (sample kind, mode) pairs have been computed."""
        return len(self._cache)

    def at(self, kind: str, ratios: tuple, k: int, breakaway: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """(λ (V, m), q (V,)) of the polytope's vertices at layer k (V = 0: no force system at all); ``breakaway``:
        with the limits a break-away is planned with (:func:`~regrasp.schedule.problem.breakaway_limits`)."""
        key = (kind, ratios, breakaway)
        found = self._cache.get(key)
        if found is None:
            found = self._cache[key] = self._compute(self._samples[kind], ratios, breakaway)
        return found[k]

    def _compute(self, smp, ratios: tuple, breakaway: bool) -> list:
        limits = breakaway_limits(self._limits) if breakaway else self._limits
        fv = force_vertices(self._geometry, smp.pose[:, 2], smp.acceleration, ratios, self._mu_s, limits)
        return [tuple(np.ascontiguousarray(a) for a in fv.at(k)) for k in range(len(fv.valid))]


def pair_table(lam: np.ndarray, q: np.ndarray, xi: np.ndarray, i: int, j: int, gi: np.ndarray,
               gj: np.ndarray, margin: float = 0.0, moves: np.ndarray | None = None) -> np.ndarray:
    """Which block positions (ξ_i, ξ_j) ∈ ``gi`` × ``gj`` [m] admit a force system of the polytope (λ, q) with the
    other contacts at ``xi`` [m] (m,) (its entries i and j ignored): (n_i, n_j) bool (module docstring). With a
    ``margin`` [m] (``RegraspSettings.position_margin``, whole cells of the grids), every position with each contact
    that moves (``moves``, (m,) in {-1, 0, 1}) where planned or up to the margin behind (a slide that lags) must admit
    one: the moving other contacts at each of their shifts, the block's cells and their neighbours behind (off the
    grid: none)."""
    if len(lam) == 0:
        return np.zeros((len(gi), len(gj)), dtype=bool)
    others = np.ones(lam.shape[1], dtype=bool)
    others[[i, j]] = False
    moves = np.zeros(lam.shape[1], dtype=int) if moves is None or margin <= 0.0 else np.asarray(moves, dtype=int)
    behind = (moves != 0) & others
    shifts = np.zeros((1, lam.shape[1]))
    if behind.any():
        shifts = np.zeros((2 ** int(behind.sum()), lam.shape[1]))
        shifts[:, behind] = np.array(list(itertools.product((0.0, 1.0), repeat=int(behind.sum())))) \
            * (-margin * moves[behind])
    const = q[:, None] - lam[:, others] @ (xi[others][None, :] + shifts[:, others]).T  # (V, E)
    rho = (const[:, :, None] - lam[:, i, None, None] * gi[None, None, :]) / lam[:, j, None, None]  # (V, E, n_i)
    lo, hi = rho.min(axis=0), rho.max(axis=0)
    ok = ((lo[:, :, None] - TOL <= gj[None, None, :]) & (gj[None, None, :] <= hi[:, :, None] + TOL)).all(axis=0)
    if moves[i] or moves[j]:
        h = gi[1] - gi[0] if len(gi) > 1 else margin
        cells = math.ceil(margin / h - 1e-9)
        structure = np.zeros((2 * cells + 1, 2 * cells + 1), dtype=bool)
        along = [slice(cells, cells + 1) if d == 0 else slice(0, cells + 1) if d > 0 else slice(cells, 2 * cells + 1)
                 for d in (moves[i], moves[j])]
        structure[tuple(along)] = True
        ok = binary_erosion(ok, structure=structure, border_value=0)
    return ok


@dataclass(eq=False)
class BlockTables:
    """What :func:`~regrasp.schedule.block_dp.block_dp` reads for one block (its module docstring), and the frozen
    contacts' constant cost ``frozen_cost`` (their slides, proximity and moves)."""

    env_ok: np.ndarray
    prox: np.ndarray
    adm: np.ndarray
    new_ok: np.ndarray
    old_ok: np.ndarray
    trans_idx: np.ndarray
    trans_tab: np.ndarray
    init_ok: np.ndarray
    frozen_cost: float


def _mode_key(d: np.ndarray, friction, breaking: tuple[int, ...] | None = None, overshoot: float = 0.0) -> tuple:
    return tuple(slide_ratios(d.tolist(), friction, breaking, overshoot))


def block_tables(problem: Problem, verts: ModeVertices, cells: np.ndarray, moves: np.ndarray, block: tuple[int, int],
                 p_max: int, bans: dict) -> BlockTables:
    """The tables of block (i, j) with the other contacts frozen on the path (``cells``, ``moves``), (N + 1, m) each;
    ``bans``: {layer: [(cells, moves) of a whole state]} to count as failures (the verification's)."""
    i, j = block
    lat, settings, friction = problem.lattice, problem.settings, problem.friction
    L, m = len(cells), cells.shape[1]
    gi, gj = np.asarray(problem.grids[i]), np.asarray(problem.grids[j])
    ni, nj = len(gi), len(gj)
    n_max = max(ni, nj)
    env_ok = np.zeros((L, 2, n_max), dtype=bool)
    prox = np.zeros((L, 2, n_max))
    for s, c in enumerate(block):
        env_ok[:, s, :len(problem.grids[c])] = lat.env_ok[:, c, :len(problem.grids[c])]
        prox[:, s, :len(problem.grids[c])] = lat.proximity[:, c, :len(problem.grids[c])]
    xi = np.array([[problem.grids[c][cells[k, c]] for c in range(m)] for k in range(L)])
    frozen = [c for c in range(m) if c not in block]
    fz = moves.copy()
    fz[:, [i, j]] = 0
    h, lead = settings.xi_resolution, 0.5 * settings.ramp / problem.dt
    margin = settings.position_margin
    nb = len(PAIR_MOVES)
    full = np.repeat(fz[:, None, :], nb, axis=1)  # (L, nb, m): the whole move vector with each block move
    full[:, :, i], full[:, :, j] = PAIR_MOVES[None, :, 0], PAIR_MOVES[None, :, 1]
    count = np.count_nonzero(full, axis=2)
    adm = (count <= p_max) & ~(lat.rest_only[:, None] & (count > 0))
    new_ok = np.ones((L, nb, ni, nj), dtype=bool)
    old_ok = np.ones((L, nb, ni, nj), dtype=bool)
    trans_idx = np.full((L, nb, nb), -1, dtype=np.int64)
    tabs = []
    needs_break = [f.static + settings.prime_overshoot > f.kinetic + 1e-12 for f in friction]

    def table(kind: str, ratios: tuple, k: int, shift: np.ndarray | None = None, breakaway: bool = False) -> np.ndarray:
        lam, q = verts.at(kind, ratios, k, breakaway)
        moves = np.array([0 if r is None else int(np.sign(r)) or 1 for r in ratios])
        if shift is None:
            return pair_table(lam, q, xi[k], i, j, gi, gj, margin, moves)
        return pair_table(lam, q, xi[k] - shift, i, j, gi - shift[i], gj - shift[j], margin, moves)

    for k in range(1, L):
        for b in range(nb):
            if not adm[k, b]:
                continue
            d = full[k, b]
            ratios = _mode_key(d, friction)
            new_ok[k, b] = table("layer", ratios, k)
            if count[k, b] >= 2:
                new_ok[k, b] &= table("middle", ratios, k, 0.5 * h * d)
            old_ok[k, b] = table("layer", ratios, k - 1)
        cached: dict = {}
        for a in range(nb):
            if not adm[k - 1, a]:
                continue
            old = full[k - 1, a]
            for b in range(nb):
                if not adm[k, b]:
                    continue
                new = full[k, b]
                if np.any((new != 0) & (old != 0) & (new != old)):
                    trans_idx[k, a, b] = -2
                    continue
                union = np.where(new != 0, new, old)
                if np.count_nonzero(union) > p_max:
                    trans_idx[k, a, b] = -2
                    continue
                starters = tuple(c for c in range(m) if new[c] != 0 and old[c] == 0 and needs_break[c])
                check_union = not (np.array_equal(union, new) or np.array_equal(union, old))
                if not (check_union or starters):
                    continue
                key = (tuple(union.tolist()), starters)
                if key not in cached:
                    ok = table("layer", _mode_key(union, friction), k - 1) if check_union \
                        else np.ones((ni, nj), dtype=bool)
                    if starters:  # (the contacts that start together are primed together)
                        ratios = _mode_key(union, friction, starters, settings.prime_overshoot)
                        back = lead * h * np.where(np.isin(np.arange(m), starters), 0, union)
                        ok = ok & table("layer", ratios, k - 1, breakaway=True) & table("early", ratios, k - 1, back,
                                                                                        breakaway=True)
                    cached[key] = len(tabs)
                    tabs.append(ok)
                trans_idx[k, a, b] = cached[key]
    init_ok = table("layer", tuple([None] * m), 0)
    index = {tuple(d): b for b, d in enumerate(PAIR_MOVES.tolist())}
    for k, states in bans.items():
        for c, d in states:
            if all(c[f] == cells[k, f] and d[f] == fz[k, f] for f in frozen):
                new_ok[k, index[(d[i], d[j])], c[i], c[j]] = False
    K, mc = lat.slide_cost, lat.move_cost
    frozen_cost = 0.0
    for f in frozen:
        starts = np.count_nonzero((moves[1:, f] != 0) & (moves[:-1, f] == 0))
        frozen_cost += K * starts + lat.proximity[np.arange(L), f, cells[:, f]].sum() + mc * np.count_nonzero(
            moves[:, f])
    trans_tab = np.array(tabs, dtype=bool).reshape(-1, ni, nj) if tabs else np.ones((1, ni, nj), dtype=bool)
    return BlockTables(env_ok, prox, adm, new_ok, old_ok, trans_idx, trans_tab, init_ok, float(frozen_cost))

r"""Slides the plant can carry out: the Painlevé condition (:mod:`regrasp.dynamics.painleve`) in the planner.

A slide is planned only where the sliders' normal response A stays a P-matrix with every slider's kinetic ratio
scaled by ``RegraspSettings.sliding_friction_factor`` F (well-posed with F times the model's friction): near its
boundary a slider's normal force needs torques known to a vanishing precision, and past it the contact jams or
lifts off, whatever the controller does. The condition depends on the configuration only (positions, not
velocities or forces).

* **The lattice** (:func:`slide_mask`): per layer, move vector and cell of its one slider, whether
  :math:`A_{ii} > 0`, and per pair of cells of its two sliders, whether their 2x2 A is a P-matrix (the fixed
  contacts' fingers welded to the object), for some positions of the fixed contacts, sampled over their
  envelope-admissible cells (``samples`` per contact, ends included), at both ends of the interval that ends at the
  layer (a slide's start is a cell back, a layer earlier). A necessary condition up to that sampling (A depends on the
  fixed contacts only through their fingers' inertia seen through the object); the cells and pairs it excludes cut
  the force tables as the torque limits' do (:func:`~regrasp.schedule.tables.cut_tables`). With more sliders: each
  one's diagonal entry.
* **The verification** (:func:`violations`): A at the schedule's own positions, every principal minor, at every
  sample where a contact slides. What it finds between two layers, or at a held contact's position the sampling
  missed, the planner re-plans around (:mod:`regrasp.schedule.planner`: the move vector kept out of a widening window
  of layers, as for forces that fail between layers).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..core.contact import Friction
from ..dynamics.painleve import composite_inverse_mass, is_p_matrix, sliding_response
from ..model.scenario import Scenario
from .torque import TorqueModel

if TYPE_CHECKING:
    from ..core.trajectory import TrajectorySample

__all__ = ["ContactGeometry", "contact_geometry", "lattice_geometry", "slide_mask", "violations"]


@dataclass(frozen=True, eq=False)
class ContactGeometry:
    r"""One contact on a grid of samples (T times, K positions): its tip point relative to the object's centre of
    mass ``points`` (T, K, 2) [m] and its finger's tip mobility ``mobility`` (T, K, 2, 2) [1/kg], NaN where the finger
    cannot reach; the edge's inward ``normal`` and ξ direction ``tangent`` (T, 2), on a curve per cell (T, K, 2); all in
    the hand frame."""

    points: np.ndarray
    mobility: np.ndarray
    normal: np.ndarray
    tangent: np.ndarray

    @property
    def reachable(self) -> np.ndarray:
        """(T, K) bool."""
        return np.isfinite(self.mobility[..., 0, 0])


def contact_geometry(torque: TorqueModel, scenario: Scenario, i: int, pose: np.ndarray, xi: np.ndarray,
                     joints: np.ndarray | None = None) -> ContactGeometry:
    """Contact i's :class:`ContactGeometry` at object poses ``pose`` (T, 3) and positions ``xi`` (T, K) [m]
    (``joints``: its finger's joint angles there, :meth:`~regrasp.schedule.torque.TorqueModel.joint_angles`)."""
    edge = scenario.polygon.edge(scenario.contacts[i].edge)
    xi = np.asarray(xi, dtype=float)
    c, s = np.cos(pose[:, 2]), np.sin(pose[:, 2])
    rot = np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], 1)  # (T, 2, 2)
    q = torque.joint_angles(i, pose, xi) if joints is None else joints
    if getattr(edge, "curved", False):  # the frame at each cell's ξ
        local, normal, _ = (v.reshape(xi.shape + v.shape[1:]) for v in edge.curve.frames(xi.reshape(-1)))
        tangent = np.stack([-normal[..., 1], normal[..., 0]], axis=-1)
        return ContactGeometry(np.einsum("tij,tkj->tki", rot, local), torque.tip_mobility(i, q),
                               np.einsum("tij,tkj->tki", rot, normal), np.einsum("tij,tkj->tki", rot, tangent))
    local = edge.xi_origin + xi[..., None] * edge.xi_direction  # (T, K, 2), object frame
    points = np.einsum("tij,tkj->tki", rot, local)
    return ContactGeometry(points, torque.tip_mobility(i, q), rot @ edge.inward_normal, rot @ edge.xi_direction)


def lattice_geometry(torque: TorqueModel, scenario: Scenario, grids: list[np.ndarray], sample: TrajectorySample,
                     joints: list[np.ndarray] | None = None) -> list[ContactGeometry]:
    """The contacts' geometry at the lattice's layers and cells (``sample``: the trajectory at the layers;
    ``joints``: the fingers' joint angles there, if known)."""
    return [contact_geometry(torque, scenario, i, sample.pose, np.broadcast_to(g, (len(sample.time), len(g))),
                             None if joints is None else joints[i]) for i, g in enumerate(grids)]


def slide_mask(geometry: list[ContactGeometry], combos: np.ndarray, friction: tuple[Friction, ...], factor: float,
               env_ok: np.ndarray, mass: float, inertia: float, samples: int = 5) -> tuple[np.ndarray, dict]:
    """The lattice's condition (module docstring) from :func:`lattice_geometry`'s ``geometry``, at both ends of the
    interval that ends at each layer (at the layer, and at the layer before with the sliders a cell back): per cell,
    (N + 1, M, m, n_max) bool, True where the contact does not slide in the move vector, is not envelope-admissible
    (the envelope's business) or can slide well-posed there (the diagonal entry); and per move vector with two sliders
    (a, b), ``{mu: (a, b, (N + 1, n_a, n_b) bool)}``: where the pair's 2x2 response is a P-matrix (True where either
    cell is not admissible)."""
    layers, M, m = env_ok.shape[0], len(combos), len(geometry)
    n_max = env_ok.shape[2]
    out = np.ones((layers, M, m, n_max), dtype=bool)
    pairs: dict[int, tuple] = {}
    cache: dict[tuple, np.ndarray] = {}
    for mu, d in enumerate(combos.tolist()):
        fixed = tuple(j for j in range(m) if d[j] == 0)
        sliders = [j for j in range(m) if d[j] != 0]
        if not sliders:
            continue
        ratios = {j: d[j] * factor * friction[j].kinetic for j in sliders}
        if len(sliders) == 2:
            key = tuple((j, d[j]) for j in sliders) + (fixed,)
            if key not in cache:
                cache[key] = _both_ends(_mask(geometry, sliders, ratios, fixed, env_ok, mass, inertia, samples),
                                        [d[j] for j in sliders])
            pairs[mu] = (sliders[0], sliders[1], cache[key])
            continue
        for i in sliders:  # (one slider; or more: their diagonals)
            one = (i, d[i], fixed)
            if one not in cache:
                cache[one] = _both_ends(_mask(geometry, [i], ratios, fixed, env_ok, mass, inertia, samples), [d[i]])
            out[:, mu, i, :cache[one].shape[1]] = cache[one]
    return out, pairs


def _both_ends(ok: np.ndarray, moves: list[int]) -> np.ndarray:
    """A slide's condition at both ends of the interval that ends at each layer: ``ok`` (N + 1, K_a[, K_b]) at the
    layer, and at the layer before with each slider one cell back (``moves``: the sliders' directions; a cell whose
    start is off the grid keeps its own value)."""
    out = ok.copy()
    index = [slice(1, None)]
    before = [slice(0, -1)]
    for d in moves:
        index.append(slice(max(d, 0), ok.shape[len(index)] + min(d, 0)))
        before.append(slice(max(-d, 0), ok.shape[len(before)] + min(-d, 0)))
    out[tuple(index)] &= ok[tuple(before)]
    return out


def _wrenches(points: np.ndarray, force: np.ndarray) -> np.ndarray:
    """The wrenches (f, p × f) (N + 1, K, 3) of one force per layer, ``force`` (N + 1, 1, 2), at ``points``
    (N + 1, K, 2)."""
    f = np.broadcast_to(force, points.shape)
    return np.concatenate([f, (points[..., 0] * f[..., 1] - points[..., 1] * f[..., 0])[..., None]], -1)


def _picks(g: ContactGeometry, env_ok_j: np.ndarray, samples: int) -> tuple[np.ndarray, np.ndarray]:
    """Per layer, ``samples`` admissible and reachable cells of a held contact spread over its admissible ones (the
    ends included; repeated when it has fewer), (N + 1, samples) int, and whether it has any, (N + 1,) bool."""
    ok = env_ok_j[:, :g.points.shape[1]] & g.reachable
    out = np.zeros((len(ok), samples), dtype=int)
    for k, row in enumerate(ok):
        cells = np.flatnonzero(row)
        if cells.size:
            out[k] = cells[np.linspace(0, len(cells) - 1, samples).round().astype(int)]
    return out, ok.any(axis=1)


def _mask(geometry, sliders: list[int], ratios: dict, fixed: tuple, env_ok, mass: float, inertia: float,
          samples: int) -> np.ndarray:
    """(N + 1, K_a) for one slider, (N + 1, K_a, K_b) for two, of :func:`slide_mask` (the ``fixed`` held)."""
    layers = env_ok.shape[0]
    rows = np.arange(layers)[:, None]
    picked = [_picks(geometry[j], env_ok[:, j], samples) for j in fixed]
    held = np.array(list(itertools.product(range(samples), repeat=len(fixed))), dtype=int).reshape(-1, len(fixed))
    points = np.stack([geometry[j].points[rows, picked[a][0][:, held[:, a]]] for a, j in enumerate(fixed)], 2)
    mobs = np.stack([geometry[j].mobility[rows, picked[a][0][:, held[:, a]]] for a, j in enumerate(fixed)], 2)
    inv_c = composite_inverse_mass(mass, inertia, points, mobs)  # (N + 1, C, 3, 3)
    gn, gf, own, free = [], [], [], []
    for i in sliders:
        g = geometry[i]
        if g.normal.ndim == 3:  # (on a curve: per cell)
            n, push = g.normal, g.normal + ratios[i] * g.tangent
        else:
            n, push = g.normal[:, None, :], g.normal[:, None, :] + ratios[i] * g.tangent[:, None, :]
        gn.append(_wrenches(g.points, n))
        gf.append(_wrenches(g.points, push))
        own.append(np.einsum("lki,lkij,lkj->lk", np.broadcast_to(n, g.points.shape), g.mobility,
                             np.broadcast_to(push, g.points.shape)))
        free.append(~(env_ok[:, i, :g.points.shape[1]] & g.reachable))  # (N + 1, K): not the condition's business
    nowhere = ~np.all([ok for _, ok in picked], axis=0) if fixed else np.zeros(layers, dtype=bool)
    with np.errstate(invalid="ignore"):
        left = [g[:, None] @ inv_c for g in gn]  # (N + 1, C, K, 3): gnᵀ M_c⁻¹ per held sample and cell
        A_aa = own[0][:, None, :] + (left[0] * gf[0][:, None]).sum(-1)  # (N + 1, C, K_a)
        if len(sliders) == 1:
            return (A_aa.max(axis=1) > 0.0) | free[0] | nowhere[:, None]
        A_bb = own[1][:, None, :] + (left[1] * gf[1][:, None]).sum(-1)
        A_ab = left[0] @ np.swapaxes(gf[1], -1, -2)[:, None]  # (N + 1, C, K_a, K_b)
        A_ba = np.swapaxes(left[1] @ np.swapaxes(gf[0], -1, -2)[:, None], -1, -2)
        ok = (A_aa[:, :, :, None] > 0.0) & (A_bb[:, :, None, :] > 0.0) & \
            (A_aa[:, :, :, None] * A_bb[:, :, None, :] - A_ab * A_ba > 0.0)
    return ok.any(axis=1) | free[0][:, :, None] | free[1][:, None, :] | nowhere[:, None, None]


def violations(torque: TorqueModel, scenario: Scenario, times: np.ndarray, pose: np.ndarray, xi: np.ndarray,
               direction: np.ndarray, friction: tuple[Friction, ...], factor: float) -> list[tuple[float, str, int]]:
    """The verification's exact check (module docstring) at the samples ``times`` [s] with the object at ``pose``
    (n, 3), the contacts at ``xi`` (n, m) [m] and sliding in ``direction`` (n, m) (0: fixed): (time, what, contact)
    per sample where the sliders' response is not a P-matrix at F times their kinetic ratios."""
    rows = np.flatnonzero(np.any(direction != 0, axis=1))
    if rows.size == 0:
        return []
    m = xi.shape[1]
    geo = [contact_geometry(torque, scenario, i, pose[rows], xi[rows, i:i + 1]) for i in range(m)]
    points = np.stack([g.points[:, 0] for g in geo], 1)
    normals = np.stack([g.normal if g.normal.ndim == 2 else g.normal[:, 0] for g in geo], 1)
    tangents = np.stack([g.tangent if g.tangent.ndim == 2 else g.tangent[:, 0] for g in geo], 1)
    mobility = np.stack([g.mobility[:, 0] for g in geo], 1)
    mass, inertia = scenario.polygon.mass, scenario.polygon.inertia
    out = []
    for modes in {tuple(r) for r in direction[rows].tolist()}:
        sel = np.flatnonzero((direction[rows] == modes).all(axis=1))
        ratios = [None if d == 0 else d * factor * f.kinetic for d, f in zip(modes, friction)]
        reach = np.isfinite(mobility[sel]).all(axis=(1, 2, 3))
        A = sliding_response(mass, inertia, np.where(reach[:, None, None], points[sel], 0.0), normals[sel],
                             tangents[sel], np.where(reach[:, None, None, None], mobility[sel], np.eye(2)), ratios)
        ok = is_p_matrix(A) | ~reach  # (an unreachable position: the envelope's business)
        sliders = [j for j, d in enumerate(modes) if d != 0]
        for a in np.flatnonzero(~ok):
            s = sel[a]
            diagonal = np.diag(A[a])
            worst = int(np.argmin(diagonal)) if diagonal.min() <= 0.0 else 0
            i = sliders[worst]
            out.append((float(times[rows[s]]), f"painleve ({scenario.contacts[i].finger.name} sliding "
                        f"{'+' if modes[i] > 0 else '-'}xi is not well-posed at {factor:g} x mu_k)", i))
    return sorted(out)

r"""The regrasp schedule planner: the slides of every contact, planned jointly over the trajectory.

The object trajectory is fixed and known before manipulation begins (paper §4), so the regrasps
are planned ahead, offline like the envelope of §2, with the physics as constraints. At every time
the schedule keeps

* each contact inside its feasible envelope (Definition 2.2) with ``envelope_margin``;
* a force system that moves the object along the trajectory (Newton–Euler with its acceleration):
  every slider on its **kinetic** cone edge in its direction, every fixed contact inside its
  **static** cone with ``cone_margin``, ``f_min`` ≤ f_n ≤ ``f_max`` (:mod:`regrasp.force_polytope`),
  and a starting slider able to break away on its static edge;
* at most ``max_sliders`` = min(m - 1, 2m - 3) contacts sliding at once (p < m, 2m ≥ 3 + p);
* slides at most ``max_slide_speed`` and ``max_slide_acceleration``, each from rest to rest in one
  direction with the smooth profile of :mod:`regrasp.schedule`.

**Method.** A dynamic program over a lattice of time layers (step
Δt = ``xi_resolution`` / ``max_slide_speed``) and contact cells (``xi_resolution``)
(:mod:`regrasp.schedule_lattice`). The lattice path moves a slider one cell per step; its slides
become smooth profiles that accelerate over ``ramp`` = v / ``max_slide_acceleration`` centred on the
path's corners, so they deviate from it by at most v·ramp/8 (covered by a planning buffer on the
envelope margin). The envelope is checked on a window of sub-samples around each layer, the forces
at the layers. The planner then **verifies** its schedule on a finer time grid (envelopes at the
schedule's exact positions, forces in the exact modes, break-away at each slide's start, all with
the exact margins) and re-plans around any violation (``max_repairs`` times).

**Objective**, in this order: (1) every constraint above, at the required margins; (2) the fewest
slides; (3) the least time near the envelope's bounds: the sum over layers and contacts of
max(0, ``comfort_margin`` - margin) / (``comfort_margin`` - ``envelope_margin``), plus 0.05 per
moving contact and step (less sliding). Larger required margins cost slides: plan with several to
see the trade-off.

**Periodic trajectories** get a periodic schedule over one period (the same contacts at its end as
at its start). A free-start program over one period gives a lower bound on the slides; a second
period, started from the first's end values, gives the best two-period path, whose middle state is
in the steady regime; the program then runs from that state with the end held to it (and from up to
``period_candidates`` such states). ``slides_lower_bound`` = max(free, ⌈two periods / 2⌉): a
periodic schedule with as many slides is optimal.

When no schedule exists, :class:`~regrasp.schedule.NoScheduleError` says until when one survives
and which constraint ran out (:mod:`regrasp.schedule_diagnosis`).
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .envelope import FingerEnvelope, Geometry
from .exceptions import InvalidParameterError
from .force_polytope import ForceGeometry, ForceLimits, force_system, force_vertices, xi_intervals
from .scenario import Scenario
from .schedule import NoScheduleError, RegraspSchedule, ScheduleLimit, Slide, first_minimum, slides_at
from .schedule_diagnosis import diagnose
from .schedule_lattice import Lattice, cells_of, flat_index, motion_combos, path, run
from .validation import as_finite_array, as_positive_float

__all__ = ["RegraspSettings", "plan_regrasps"]

Progress = Callable[[int, int], None]


@dataclass(frozen=True)
class RegraspSettings:
    """What the regrasp planner guarantees, and its resolution.

    Attributes:
        envelope_margin: Every contact stays this far inside its feasible set [m] (≥ half the
            ``xi_resolution``, so that a one-cell move stays inside too).
        cone_margin: Every fixed contact keeps μ_s f_n - |f_t| ≥ this [N].
        f_min, f_max: Every contact's normal force within [f_min, f_max] [N].
        max_slide_speed: Fastest slide [m/s]; with ``xi_resolution`` it sets the time step.
        max_slide_acceleration: Largest slide acceleration [m/s²] (≥ max_slide_speed² /
            xi_resolution: a slide's ramps fit in one time step).
        xi_resolution: Cell size of the contact grid [m].
        max_sliders: Most contacts sliding at once (None: min(m - 1, 2m - 3)).
        comfort_margin: Envelope margin [m] above which a contact costs nothing (the objective's
            third term; None: ``envelope_margin`` + 4 mm).
        envelope_substeps: Envelope sub-samples per time step in the lattice's windows.
        verify_substeps: Samples per time step of the planner's own verification.
        periodic: Plan a periodic schedule (None: when the trajectory is periodic and its domain
            covers a period).
        geometry: Envelope geometry, ``"ideal"`` or ``"urdf"`` (None: the scenario's).
        max_repairs: Re-plans after a failed verification before giving up.
        period_candidates: End states of the free program tried as a periodic schedule's start.
    """

    envelope_margin: float = 1e-3
    cone_margin: float = 0.1
    f_min: float = 0.2
    f_max: float = 20.0
    max_slide_speed: float = 0.05
    max_slide_acceleration: float = 5.0
    xi_resolution: float = 1e-3
    max_sliders: int | None = None
    comfort_margin: float | None = None
    envelope_substeps: int = 4
    verify_substeps: int = 8
    periodic: bool | None = None
    geometry: str | None = None
    max_repairs: int = 8
    period_candidates: int = 3

    def __post_init__(self):
        for name in ("max_slide_speed", "max_slide_acceleration", "xi_resolution", "f_min", "f_max"):
            as_positive_float(name, getattr(self, name))
        for name in ("envelope_margin", "cone_margin"):
            as_positive_float(name, getattr(self, name), allow_zero=True)
        if self.comfort_margin is None:
            object.__setattr__(self, "comfort_margin", self.envelope_margin + 4e-3)
        as_positive_float("comfort_margin", self.comfort_margin)
        ForceLimits(self.f_min, self.f_max, self.cone_margin)
        if self.envelope_margin < 0.5 * self.xi_resolution:
            raise InvalidParameterError("envelope_margin", self.envelope_margin,
                                        f">= xi_resolution / 2 = {0.5 * self.xi_resolution:g} m")
        if self.comfort_margin <= self.envelope_margin:
            raise InvalidParameterError("comfort_margin", self.comfort_margin,
                                        f"> envelope_margin = {self.envelope_margin:g} m")
        if self.ramp > self.time_step * (1 + 1e-9):
            raise InvalidParameterError(
                "max_slide_acceleration", self.max_slide_acceleration,
                f">= max_slide_speed^2 / xi_resolution = {self.max_slide_speed ** 2 / self.xi_resolution:g} m/s^2")
        for name, least in (("envelope_substeps", 1), ("verify_substeps", 1), ("max_repairs", 0),
                            ("period_candidates", 1)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < least:
                raise InvalidParameterError(name, value, f"an integer >= {least}")
        if self.max_sliders is not None and (isinstance(self.max_sliders, bool) or not isinstance(self.max_sliders, int)
                                             or self.max_sliders < 1):
            raise InvalidParameterError("max_sliders", self.max_sliders, "an integer >= 1, or None")
        if self.periodic not in (None, True, False):
            raise InvalidParameterError("periodic", self.periodic, "True, False or None")
        if self.geometry is not None:
            try:
                Geometry(self.geometry)
            except ValueError:
                raise InvalidParameterError("geometry", self.geometry, "'ideal', 'urdf' or None") from None

    @property
    def time_step(self) -> float:
        """The lattice's nominal time step [s]: one cell at the fastest slide."""
        return self.xi_resolution / self.max_slide_speed

    @property
    def ramp(self) -> float:
        """A slide's acceleration time [s]."""
        return self.max_slide_speed / self.max_slide_acceleration


def trajectory_period(trajectory) -> float | None:
    """The trajectory's period [s] if it is periodic (an ellipse, or waypoints with a periodic
    boundary), else None."""
    period = getattr(trajectory, "period", None)
    if period is not None and math.isfinite(period) and period > 0:
        return float(period)
    if getattr(trajectory, "boundary", None) == "periodic":
        return trajectory.t_end - trajectory.t_start
    return None


@dataclass(eq=False)
class Problem:
    """A scenario's planning problem on its lattice (built by :func:`build_problem`).

    Attributes (besides the scenario's): ``times`` the layers [s], ``dt`` the step [s], ``grids``
    the contact cells [m], ``envelopes`` per contact, ``sub_samples`` its envelope samples at the
    sub-sample times ``sub_times``, ``lattice``, ``limits`` (the planning limits, with buffers).
    """

    scenario: Scenario
    settings: RegraspSettings
    names: tuple
    friction: tuple
    periodic: bool
    times: np.ndarray
    dt: float
    grids: list
    envelopes: list
    sub_times: np.ndarray
    sub_samples: list
    geometry: ForceGeometry
    limits: ForceLimits
    envelope_buffer: float
    lattice: Lattice
    start_cells: np.ndarray | None


def _cell_margins(sample, grid: np.ndarray) -> np.ndarray:
    """Each cell's envelope margin [m] in one sample (EnvelopeSample.margin, vectorised)."""
    out = np.full(len(grid), -np.inf)
    for lo, hi in sample.feasible:
        out = np.maximum(out, np.minimum(grid - lo, hi - grid))
    return out


def _ratios(direction, friction, breaking: int | None = None) -> list:
    """Per contact None (fixed) or the signed force ratio τ/λ = s μ_k (s μ_s for ``breaking``)."""
    return [None if d == 0 else d * (f.static if i == breaking else f.kinetic)
            for i, (d, f) in enumerate(zip(direction, friction))]


def build_problem(scenario: Scenario, settings: RegraspSettings, *, start_time=None, xi0=None,
                  t_end=None) -> Problem:
    """The lattice of the module docstring for ``scenario`` (``xi0``: start positions [m], which then
    lie on the grid; ``start_time``/``t_end``: the horizon [s], default the trajectory's domain or,
    periodic, its first period)."""
    traj = scenario.trajectory
    contacts = scenario.contacts
    m = len(contacts)
    if m < 2:
        raise InvalidParameterError("scenario", scenario.name, "at least two fingers (2m >= 3 + p)")
    t0 = traj.t_start if start_time is None else as_finite_array("start_time", start_time, ()).item()
    t1 = traj.t_end if t_end is None else as_finite_array("t_end", t_end, ()).item()
    if not traj.t_start <= t0 < t1 <= traj.t_end + 1e-9:
        raise InvalidParameterError("start_time", (t0, t1), f"a horizon inside [{traj.t_start}, {traj.t_end}] s")
    period = trajectory_period(traj)
    periodic = settings.periodic
    if periodic is None:
        periodic = period is not None and t1 - t0 >= period - 1e-9
    if periodic:
        if period is None or t1 - t0 < period - 1e-9:
            raise InvalidParameterError("periodic", True, "a periodic trajectory whose domain covers a period")
        t1 = t0 + period
    n_steps = max(2, int(math.floor((t1 - t0) / settings.time_step + 1e-9)))
    dt = (t1 - t0) / n_steps
    times = t0 + dt * np.arange(n_steps + 1)
    h = settings.xi_resolution
    edges = [scenario.polygon.edge(c.edge) for c in contacts]
    start = None if xi0 is None else as_finite_array("xi0", xi0, (m,))
    grids = []
    for i, e in enumerate(edges):
        anchor = 0.0 if start is None else float(start[i])
        lo, hi = e.xi_range
        if start is not None and not lo - 1e-12 <= anchor <= hi + 1e-12:
            raise InvalidParameterError("xi0", start.tolist(), f"positions on the edges ({contacts[i].finger.name}: "
                                        f"[{lo:.6g}, {hi:.6g}] m)")
        cells = np.arange(math.ceil((lo - anchor) / h - 1e-9), math.floor((hi - anchor) / h + 1e-9) + 1)
        grids.append(anchor + h * cells)
    start_cells = None if start is None else np.array([int(np.argmin(np.abs(g - x))) for g, x in zip(grids, start)])
    geometry = Geometry(settings.geometry or scenario.geometry.value)
    envelopes = [FingerEnvelope(c.finger, scenario.polygon, c.edge, geometry=geometry, tip_clearance=c.tip_clearance)
                 for c in contacts]
    q = settings.envelope_substeps
    sub_times = t0 + (dt / q) * np.arange(n_steps * q + 1)
    poses = traj.pose(np.clip(sub_times, traj.t_start, traj.t_end))
    sub_samples = [[env.at(pose, float(t)) for t, pose in zip(sub_times, poses)] for env in envelopes]
    friction = tuple(c.friction for c in contacts)
    p_max = min(m - 1, 2 * m - 3) if settings.max_sliders is None else min(settings.max_sliders, m - 1, 2 * m - 3)
    combos = motion_combos(m, p_max)
    ramp = settings.ramp
    speed = h / dt
    envelope_buffer = speed * ramp / 8.0 + 1e-5
    lattice_env, proximity = _envelope_tables(sub_samples, grids, q, n_steps, settings, envelope_buffer, periodic)
    geo = ForceGeometry.of(scenario.polygon, [c.edge for c in contacts], mass=scenario.polygon.mass,
                           inertia=scenario.polygon.inertia, gravity=scenario.gravity_in_hand)
    sample = traj.sample(np.clip(times, traj.t_start, traj.t_end))
    jerk = np.abs(np.diff(sample.acceleration[:, :2], axis=0)).max(initial=0.0)
    limits = ForceLimits(settings.f_min, settings.f_max,
                         settings.cone_margin * 1.02 + geo.mass * jerk + 1e-4)
    axis = int(np.argmax([len(g) for g in grids]))
    middle = traj.sample(np.clip(np.append(times[0], 0.5 * (times[1:] + times[:-1])), traj.t_start, traj.t_end))
    early = traj.sample(np.clip(times - 0.5 * ramp, traj.t_start, traj.t_end))
    lo, hi, blo, bhi, slots, mid_lo, mid_hi = _force_tables(geo, sample, middle, early, 0.5 * ramp / dt, combos,
                                                            friction, limits, grids, axis)
    rest_only = np.zeros(n_steps + 1, dtype=bool)
    rest_only[[0, 1, n_steps]] = True
    move_cost = 0.05
    lattice = Lattice(times, grids, combos, lattice_env, proximity, axis, lo, hi, mid_lo, mid_hi, blo, bhi, slots,
                      rest_only,
                      slide_cost=1.0 + (n_steps + 1) * m * (1.0 + move_cost), move_cost=move_cost)
    return Problem(scenario, settings, tuple(c.finger.name for c in contacts), friction, bool(periodic), times, dt,
                   grids, envelopes, sub_times, sub_samples, geo, limits, envelope_buffer, lattice, start_cells)


def _envelope_tables(sub_samples, grids, q, n_steps, settings, buffer, periodic: bool):
    """(admissible, proximity) per layer, contact and cell over each layer's window [t_{k-1}, t_{k+1}]
    (wrapped around the period's ends when ``periodic``: the first and the last layer are one time)."""
    m, n_max = len(grids), max(len(g) for g in grids)
    ok = np.zeros((n_steps + 1, m, n_max), dtype=bool)
    proximity = np.ones((n_steps + 1, m, n_max))
    em, comfort = settings.envelope_margin, settings.comfort_margin
    for i, grid in enumerate(grids):
        margins = np.array([_cell_margins(s, grid) for s in sub_samples[i]])  # (sub-samples, cells)
        windows = [margins[max(0, (k - 1) * q):min(n_steps * q, (k + 1) * q) + 1].min(axis=0)
                   for k in range(n_steps + 1)]
        if periodic:
            windows[0] = windows[n_steps] = np.minimum(windows[0], windows[n_steps])
        for k, window in enumerate(windows):
            ok[k, i, :len(grid)] = window >= em + buffer
            proximity[k, i, :len(grid)] = np.clip((comfort - window) / (comfort - em), 0.0, 1.0)
    return ok, proximity


def _force_tables(geo, sample, middle, early, lead: float, combos, friction, limits, grids, axis):
    """The lattice's interval tables (float32): the modes at the layers; for two or more sliders at
    each interval's middle (``middle``: the trajectory there, layer k's entry for the interval ending
    at it) with the sliders half a cell back; and where μ_s > μ_k the break-away of each starting
    contact, both at the layer and where it really starts, ``early`` (the trajectory half a ramp
    before the layer) with the other sliders ``lead`` cells back."""
    m = len(grids)
    n_layers = len(sample.pose)
    others = np.array(list(itertools.product(*[grids[i] for i in range(m) if i != axis]))).reshape(-1, m - 1)
    mu_s = np.array([f.static for f in friction])
    M = len(combos)
    h = grids[0][1] - grids[0][0] if len(grids[0]) > 1 else 0.0
    columns = [i for i in range(m) if i != axis]

    def table(ratios, smp=sample, shift=None):
        """(lo, hi) per layer and cell of the others, with the positions ``shift`` [m] (m,) back."""
        grid = others if shift is None else others - np.array([shift[i] for i in columns])
        fv = force_vertices(geo, smp.pose[:, 2], smp.acceleration, ratios, mu_s, limits)
        out = np.empty((2, n_layers, len(others)), dtype=np.float32)
        back = 0.0 if shift is None else shift[axis]  # the axis position x - back must be inside
        for k in range(n_layers):
            lo, hi = xi_intervals(*fv.at(k), axis, grid)
            out[0, k], out[1, k] = lo + back, hi + back
        return out

    lo = np.empty((n_layers, len(others), M), dtype=np.float32)
    hi = np.empty_like(lo)
    mid_lo = np.full_like(lo, -np.inf)
    mid_hi = np.full_like(lo, np.inf)
    for mu, d in enumerate(combos):
        lo[:, :, mu], hi[:, :, mu] = table(_ratios(d, friction))
        if np.count_nonzero(d) >= 2:
            mid_lo[:, :, mu], mid_hi[:, :, mu] = table(_ratios(d, friction), middle, 0.5 * h * np.asarray(d))
    needs = np.array([[d[i] != 0 and friction[i].static > friction[i].kinetic + 1e-12 for i in range(m)]
                      for d in combos])
    slots = np.full((M, m), -1, dtype=np.int64)
    blo = bhi = None
    if needs.any():
        pairs = list(zip(*np.nonzero(needs)))
        blo = np.empty((n_layers, len(others), len(pairs)), dtype=np.float32)
        bhi = np.empty_like(blo)
        for slot, (mu, i) in enumerate(pairs):
            slots[mu, i] = slot
            ratios = _ratios(combos[mu], friction, breaking=int(i))
            at_layer = table(ratios)
            others_back = lead * h * np.where(np.arange(m) == i, 0, combos[mu])
            real = table(ratios, early, others_back)
            blo[:, :, slot] = np.maximum(at_layer[0], real[0])
            bhi[:, :, slot] = np.minimum(at_layer[1], real[1])
    return lo, hi, blo, bhi, slots, mid_lo, mid_hi


def _slides(problem: Problem, cells: np.ndarray, moves: np.ndarray) -> tuple[Slide, ...]:
    """The lattice path's runs of moves as smooth slides (module docstring)."""
    times, ramp = problem.times, problem.settings.ramp
    out = []
    for i, grid in enumerate(problem.grids):
        k = 1
        while k < len(moves):
            d = int(moves[k, i])
            if d == 0:
                k += 1
                continue
            first = k
            while k + 1 < len(moves) and moves[k + 1, i] == d:
                k += 1
            out.append(Slide(i, problem.names[i], d, float(times[first - 1] - ramp / 2), float(times[k] + ramp / 2),
                             float(grid[cells[first - 1, i]]), float(grid[cells[k, i]]), ramp))
            k += 1
    return tuple(sorted(out, key=lambda s: (s.start, s.contact)))


def _schedule(problem: Problem, cells, moves, seconds: float, lower_bound, verified_min, *,
              forces: bool = True) -> RegraspSchedule:
    """The schedule of a lattice path, sampled at the layers with its force systems (without them,
    NaN, when not ``forces``: a draft to verify)."""
    slides = _slides(problem, cells, moves)
    m = len(problem.names)
    times = problem.times[:len(cells)]
    xi_start = np.array([problem.grids[i][cells[0, i]] for i in range(m)])
    periodic = problem.periodic and len(cells) == len(problem.times)
    at = slides_at(xi_start, slides, times)
    q = problem.settings.envelope_substeps
    envelope_margin = np.array([[problem.sub_samples[i][k * q].margin(float(at.xi[k, i])) for i in range(m)]
                                for k in range(len(times))])
    traj = problem.scenario.trajectory
    sample = traj.sample(np.clip(times, traj.t_start, traj.t_end))
    limits = ForceLimits(problem.settings.f_min, problem.settings.f_max, problem.settings.cone_margin)
    mu_s = [f.static for f in problem.friction]
    normal, cone = np.full((len(times), m), np.nan), np.full((len(times), m), np.nan)
    for k in range(len(times) if forces else 0):
        system = force_system(problem.geometry, sample.pose[k, 2], sample.acceleration[k], at.xi[k],
                              _ratios(at.direction[k], problem.friction), mu_s, limits)
        normal[k] = system.normal
        cone[k] = np.where(at.direction[k] == 0, system.cone_margins, np.nan)
    env_min, env_at = verified_min if verified_min is not None else first_minimum(envelope_margin, times,
                                                                                 problem.names)
    cone_min, cone_at = first_minimum(cone, times, problem.names)
    return RegraspSchedule(
        names=problem.names, edges=tuple(c.edge for c in problem.scenario.contacts), t_start=float(times[0]),
        t_end=float(times[-1]), periodic=periodic,
        xi_start=xi_start, slides=slides, times=times, xi=at.xi, xi_dot=at.xi_dot, xi_ddot=at.xi_ddot,
        sliding=at.direction, envelope_margin=envelope_margin, cone_margin=cone, normal_force=normal,
        required_envelope_margin=problem.settings.envelope_margin, required_cone_margin=problem.settings.cone_margin,
        min_envelope_margin=env_min, min_envelope_margin_at=env_at, min_cone_margin=cone_min, min_cone_margin_at=cone_at,
        planning_seconds=seconds, slides_lower_bound=lower_bound)


def verify(problem: Problem, schedule: RegraspSchedule, substeps: int) -> tuple[list, tuple]:
    """The planner's own check of ``schedule`` on ``substeps`` samples per step, with the exact margins:
    (violations as (time [s], what, contact index or None), (smallest envelope margin [m], (time, name)))."""
    settings = problem.settings
    traj = problem.scenario.trajectory
    n = int(round((schedule.t_end - schedule.t_start) / problem.dt * substeps))
    times = schedule.t_start + (schedule.t_end - schedule.t_start) * np.arange(n + 1) / max(n, 1)
    at = schedule.at(times)
    sample = traj.sample(np.clip(times, traj.t_start, traj.t_end))
    violations = []
    q = problem.settings.envelope_substeps
    step = substeps // q if substeps % q == 0 else 0  # every step-th time is a lattice sub-sample

    def envelope(i: int, j: int):
        if step and j % step == 0 and j // step < len(problem.sub_samples[i]):
            return problem.sub_samples[i][j // step]
        return problem.envelopes[i].at(sample.pose[j], float(times[j]))

    margins = np.array([[envelope(i, j).margin(float(at.xi[j, i])) for i in range(len(problem.envelopes))]
                        for j in range(len(times))])
    for k, i in zip(*np.nonzero(margins < settings.envelope_margin - 1e-12)):
        violations.append((float(times[k]), "envelope", int(i)))
    limits = ForceLimits(settings.f_min, settings.f_max, settings.cone_margin)
    mu_s = [f.static for f in problem.friction]
    checks = [(k, tuple(at.direction[k]), None) for k in range(len(times))]
    starts = []
    for s in schedule.slides:  # break-away: the slider on its static edge as it starts
        t = np.array([s.start])
        st = schedule.at(t + 1e-9)
        starts.append((s, float(s.start), st.direction[0], schedule.at(t).xi[0], traj.sample(
            np.clip(t, traj.t_start, traj.t_end))))
    groups: dict[tuple, list] = {}
    for k, direction, _ in checks:
        groups.setdefault(direction, []).append(k)
    for direction, ks in groups.items():
        ks = np.array(ks)
        fv = force_vertices(problem.geometry, sample.pose[ks, 2], sample.acceleration[ks],
                            _ratios(direction, problem.friction), mu_s, limits)
        for j, k in enumerate(ks):
            if not _holds(*fv.at(j), at.xi[k]):
                violations.append((float(times[k]), "forces", None))
    for s, t, direction, xi, smp in starts:
        fv = force_vertices(problem.geometry, smp.pose[:, 2], smp.acceleration,
                            _ratios(direction, problem.friction, breaking=s.contact), mu_s, limits)
        if not _holds(*fv.at(0), xi):
            violations.append((t, "breakaway", s.contact))
    return sorted(violations), first_minimum(margins, times, problem.names)


def _holds(lam: np.ndarray, offset: np.ndarray, xi: np.ndarray) -> bool:
    """Whether positions ``xi`` admit a force system of the polytope with vertices (λ, q)."""
    if len(lam) == 0:
        return False
    phi = lam @ xi - offset
    return phi.min() <= 1e-10 and phi.max() >= -1e-10


def _bans(problem: Problem, violations, cells, moves) -> dict:
    """The path's states at the layers around each violation, to exclude when re-planning."""
    index = {tuple(d): mu for mu, d in enumerate(problem.lattice.combos.tolist())}
    bans: dict[int, list] = {}
    for t, _, _ in violations:
        k = int((t - problem.times[0]) / problem.dt)
        for j in (k, k + 1):
            if 0 <= j < len(cells):
                bans.setdefault(j, []).append((index[tuple(moves[j].tolist())], cells[j].copy()))
    return bans


def _merge(a: dict, b: dict) -> dict:
    out = {k: list(v) for k, v in a.items()}
    for k, v in b.items():
        out.setdefault(k, []).extend(v)
    return out


def _periodic_from(problem: Problem, start, bans: dict):
    """The cheapest periodic path through ``start`` (global cells): (value, cells, moves), or None."""
    lat = problem.lattice
    N = lat.layers - 1
    periodic = run(lat, start=start, bans=bans, end=start)
    value = periodic.value(start) if periodic.last_layer == N else math.inf
    if not math.isfinite(value):
        return None
    return (value, *path(lat, periodic, N, 0, flat_index(start, periodic.boxes[N])))


def _slide_count(moves: np.ndarray) -> int:
    """The slides a lattice path starts (a contact moving after resting)."""
    return int(sum(1 for k in range(1, len(moves)) for d, e in zip(moves[k], moves[k - 1]) if d and not e))


def _solve(problem: Problem, bans: dict, hint=None) -> tuple:
    """(cells, moves, lower bound on the slides or None) of the best schedule, or raise; ``hint``: the
    start of the last periodic schedule, tried first when re-planning around ``bans``."""
    lat = problem.lattice
    N = lat.layers - 1
    K = lat.slide_cost
    if hint is not None and problem.start_cells is None:
        found = _periodic_from(problem, hint, bans)
        if found is not None:
            return found[1], found[2], None
    given = problem.start_cells
    free = run(lat, start=given, bans=bans, end=given if problem.periodic else None)
    if free.last_layer < N:
        partial = None
        if free.last_layer >= 0:
            _, mu, p = free.best()
            partial = _schedule(problem, *path(lat, free, free.last_layer, mu, p), 0.0, None, None)
        raise diagnose(problem, free, partial)
    if problem.periodic and given is not None:
        if not math.isfinite(free.value(given)):
            raise NoScheduleError(float(problem.times[-1]), ScheduleLimit.PERIODIC, problem.names,
                                  "no schedule from the given start positions ends the period where it starts")
        return (*path(lat, free, N, 0, flat_index(given, free.boxes[N])), None)
    value, mu, p = free.best()
    lower = None if given is not None else int(value // K)
    if not problem.periodic:
        return (*path(lat, free, N, mu, p), lower)
    # a second period started from the first's end values: its best path's start (the middle of the
    # best two-period path) is in the steady regime, a good start for a periodic schedule
    second = run(lat, bans=bans, init=free)
    candidates = []
    if second.last_layer == N:
        two, mu2, p2 = second.best()
        lower = max(lower, math.ceil(int(two // K) / 2))
        cells2, moves2 = path(lat, second, N, mu2, p2)
        if np.array_equal(cells2[0], cells2[-1]) and _slide_count(moves2) <= lower:
            return cells2, moves2, lower  # the best two-period path repeats its second period
        candidates += [cells2[0], cells2[-1]]
    candidates.append(cells_of(p, free.boxes[N]))
    best, tried = None, set()
    for start in candidates[:problem.settings.period_candidates]:
        if tuple(start) in tried:
            continue
        tried.add(tuple(start))
        found = _periodic_from(problem, start, bans)
        if found is not None and (best is None or found[0] < best[0]):
            best = found
            if int(found[0] // K) <= lower:
                break  # as few slides as any schedule: optimal
    if best is None:
        raise NoScheduleError(float(problem.times[-1]), ScheduleLimit.PERIODIC, problem.names,
                              f"no schedule ends a period where it starts (tried {len(tried)} start states; "
                              f"a non-periodic one with {lower} slide(s) exists: settings.periodic = False)")
    return best[1], best[2], lower


def plan_regrasps(scenario: Scenario, settings: RegraspSettings = RegraspSettings(), *, start_time=None, xi0=None,
                  t_end=None, progress: Progress | None = None) -> RegraspSchedule:
    """Plan the slides of every contact over the scenario's trajectory (module docstring).

    Args:
        scenario: Fingers, edges, object, trajectory, gravity and friction.
        settings: Margins, limits and resolution.
        start_time: Start of the horizon [s] (default: the trajectory's start).
        xi0: The contacts' positions at ``start_time`` [m] (default: chosen by the planner).
        t_end: End of the horizon [s] (default: the trajectory's end, or one period).
        progress: Called as ``progress(done, total)`` as the stages finish.

    Raises:
        NoScheduleError: no schedule satisfies the constraints (with the diagnosis).
    """
    if not isinstance(scenario, Scenario):
        raise InvalidParameterError("scenario", scenario, "a Scenario (regrasp.load_scenario)")
    if not isinstance(settings, RegraspSettings):
        raise InvalidParameterError("settings", settings, "a RegraspSettings")
    start = time.perf_counter()
    total = 3 + settings.max_repairs
    problem = build_problem(scenario, settings, start_time=start_time, xi0=xi0, t_end=t_end)
    if progress is not None:
        progress(1, total)
    bans: dict = {}
    hint = lower = None
    for attempt in range(settings.max_repairs + 1):
        cells, moves, bound = _solve(problem, bans, hint)
        lower = bound if attempt == 0 else lower
        hint = cells[0] if problem.periodic else None
        if progress is not None:
            progress(2 + attempt, total)
        draft = _schedule(problem, cells, moves, 0.0, lower, None, forces=False)
        violations, verified = verify(problem, draft, settings.verify_substeps)
        if not violations:
            schedule = _schedule(problem, cells, moves, time.perf_counter() - start, lower, verified)
            if progress is not None:
                progress(total, total)
            return schedule
        bans = _merge(bans, _bans(problem, violations, cells, moves))
    t, what, i = violations[0]
    raise NoScheduleError(t, ScheduleLimit.VERIFICATION, problem.names if i is None else (problem.names[i],),
                          f"the schedule still fails its verification after {settings.max_repairs} re-plans "
                          f"({len(violations)} violations, the first: {what} at t = {t:.3f} s)")


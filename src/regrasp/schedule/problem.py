r"""The regrasp planner's problem: its settings, and the lattice built from a scenario.

:func:`build_problem` samples each contact's feasible envelope on a fine time grid, turns it into
the lattice's envelope tables (admissible cells over each layer's window, with the planning buffer,
and the proximity cost), and computes the force tables of every move vector from the force
polytope (:mod:`regrasp.schedule.force_tables`), as :mod:`regrasp.schedule.lattice` reads them. Where a joint has a
torque limit, the tables also drop the cells that no force within it allows (a necessary condition; the planner's
verification checks the limits exactly, :mod:`regrasp.schedule.torque`). On a curved object the contacts' frames turn
with ξ and the tables come from :mod:`regrasp.schedule.curve_tables` instead (the torque limits exact in them). The
method and its buffers are described in :mod:`regrasp.schedule.planner` and ``docs/derivations.md``
("§4, planned ahead").
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ..core.contact import DEFAULT_CONE_MARGIN
from ..core.curves import CurvedObject
from ..core.exceptions import InvalidParameterError
from ..core.validation import as_count, as_finite_array, as_flag, as_positive_float, check_fields
from ..envelope.finger_envelope import FingerEnvelope
from ..model.geometry import Geometry, as_geometry
from ..model.scenario import Scenario
from .curve_forces import tangent_geometry
from .curve_tables import chained_samples, curve_force_tables, feasible_span
from .force_polytope import ForceGeometry, ForceLimits
from .force_tables import breakaway_limits, edge_force_tables, slide_ratios, torque_tables
from .lattice import Lattice, motion_combos
from .tables import cut_tables, erode_tables
from .torque import TorqueModel
from .well_posed import lattice_geometry, slide_mask

if TYPE_CHECKING:
    from ..core.trajectory import Trajectory

__all__ = ["Problem", "RegraspSettings", "breakaway_limits", "build_problem", "slide_ratios", "trajectory_period"]

#: The largest force tables a problem may build [bytes] (four float32 tables per layer, cell of the
#: other contacts and move vector: about 80 MiB for the three-finger paper scenario)
_TABLE_BUDGET = 2 * 2**30


@dataclass(frozen=True)
class RegraspSettings:
    """What the regrasp planner guarantees, and its resolution.

    Attributes:
        envelope_margin: Every contact stays this far inside its feasible set [m] (≥ half the
            ``xi_resolution``, so that a one-cell move stays inside too).
        cone_margin: Every fixed contact keeps (μ_s - ``friction_margin``) f_n - |f_t| ≥ this [N].
        f_min, f_max: Every contact's normal force within ``[f_min, f_max]`` [N].
        friction_margin: Every fixed contact also keeps |f_t| <= (μ_s - this) f_n [-] (a coefficient, unlike
            ``cone_margin``: it grows with the load). A planned force system must be one the executor's
            internal-force law accepts: its held contacts keep ``InternalForceSettings.friction_margin`` where the
            forces allow, then its ``fallback_friction_margin``, then its ``last_friction_margin`` (0 in
            :meth:`~regrasp.supervisor.settings.SupervisorSettings.robust`: the model's cone), so 0 here is what
            that executor accepts; plan with its fallback margin (0.05) for an executor without a last one.
        prime_overshoot: Plan each break-away with the slider's friction ratio at μ_s + this [-]: the executor's
            priming overshoot at its start (``ExecutorSettings.prime_overshoot``, 0.01 in
            :meth:`~regrasp.supervisor.settings.SupervisorSettings.robust`), where the nominal plant breaks away.
            Contacts that start together are primed together and checked so (:mod:`regrasp.schedule.lattice`), and
            a break-away is checked with the limits of the executor's last fallback (:func:`breakaway_limits`).
        slider_floor: A sliding (or breaking-away) contact pushes with at least this [N] ...
        holder_preload: ... and the held ones with at least this while any contact slides [N] (0: ``f_min``):
            on a compliant contact the slider is the one that loses its load first, and the holders take what a
            slider's hop or a break-away sheds (``docs/derivations.md``, "Keeping the loads"); the executor keeps
            the same floors (:meth:`~regrasp.supervisor.settings.SupervisorSettings.robust`).
        max_slide_speed: Fastest slide [m/s]; with ``xi_resolution`` it sets the time step.
        max_slide_acceleration: Largest slide acceleration [m/s²] (≥ max_slide_speed² /
            xi_resolution: a slide's ramps fit in one time step).
        xi_resolution: Cell size of the contact grid [m].
        max_sliders: Most contacts sliding at once (None: min(m - 1, 2m - 3) for the exact lattice; the decomposition
            planner caps it at 2, so that its modes number O(m²): polynomial in m).
        comfort_margin: Envelope margin [m] above which a contact costs nothing (the objective's
            third term; None: ``envelope_margin`` + 4 mm).
        envelope_substeps: Envelope sub-samples per time step in the lattice's windows.
        verify_substeps: Samples per time step of the planner's own verification.
        periodic: Plan a periodic schedule (None: when the trajectory is periodic and its domain
            covers a period).
        geometry: Envelope geometry, a :class:`~regrasp.model.geometry.Geometry` or its string (None: the
            scenario's).
        max_repairs: Re-plans after a failed verification before giving up.
        period_candidates: Distinct start states tried for a periodic schedule, in order: the middle and the end of
            the best two-period path, the free program's best end state, then the cheapest states at rest at the
            two-period program's end. None found from them is not a proof that none exists
            (``ScheduleLimit.SEARCH``).
        position_margin: Every position of the sliders from the planned ones to this behind them (each slider where
            planned or lagging by up to this, the held contacts where planned) has a force system too [m]: a slide
            that lags its plan keeps its forces. Near the edge of the positions that have forces the loads needed
            grow without bound (two sliders on opposite edges: the friction couple against the normal forces'
            moment), so a plan that grazes it fails on the plant as soon as a slide lags. The lattice asks it of whole
            cells (``xi_resolution``, rounded up), the verification of every slider where planned and this behind
            (2^p positions).
        sliding_friction_factor: Plan a slide only where the sliders' contact problem stays well-posed (no
            Painlevé paradox: :mod:`regrasp.schedule.well_posed`) with this many times each slider's kinetic friction
            [-] (≥ 1; None: no check). Near the paradox a slider's normal force needs torques known to a vanishing
            precision; 1.25 leaves the plant 25 % more friction than the model, and a slider at the model's friction
            at least a fifth of its frictionless normal mobility.
        method: The planner: ``"exact"`` (the lattice's dynamic program over all contacts at once, exponential in
            their number), ``"decomposition"`` (block-coordinate descent over pairs of contacts,
            :mod:`regrasp.schedule.decomposition`: polynomial, not a proof of optimality) or None: the exact one when
            its force tables fit in their budget (three fingers), else the decomposition.
    """

    envelope_margin: float = 1e-3
    cone_margin: float = DEFAULT_CONE_MARGIN
    f_min: float = 0.2
    f_max: float = 20.0
    friction_margin: float = 0.0
    prime_overshoot: float = 0.01
    slider_floor: float = 0.3
    holder_preload: float = 0.3
    max_slide_speed: float = 0.05
    max_slide_acceleration: float = 5.0
    xi_resolution: float = 1e-3
    max_sliders: int | None = None
    comfort_margin: float | None = None
    envelope_substeps: int = 4
    verify_substeps: int = 8
    periodic: bool | None = None
    geometry: Geometry | None = None
    max_repairs: int = 8
    period_candidates: int = 3
    method: str | None = None
    position_margin: float = 1e-3
    sliding_friction_factor: float | None = 1.25

    def __post_init__(self):
        check_fields(self, as_positive_float, ("max_slide_speed", "max_slide_acceleration", "xi_resolution", "f_min",
                                               "f_max"))
        check_fields(self, as_positive_float, ("envelope_margin", "cone_margin", "friction_margin", "prime_overshoot",
                                               "slider_floor", "holder_preload", "position_margin"), allow_zero=True)
        if self.comfort_margin is None:
            object.__setattr__(self, "comfort_margin", self.envelope_margin + 4e-3)
        check_fields(self, as_positive_float, ("comfort_margin",))
        check_fields(self, as_count, ("envelope_substeps", "verify_substeps", "period_candidates"), 1)
        check_fields(self, as_count, ("max_repairs",))
        check_fields(self, as_count, ("max_sliders",), 1, optional=True)
        check_fields(self, as_flag, ("periodic",), optional=True)
        check_fields(self, as_positive_float, ("sliding_friction_factor",), optional=True)
        if self.sliding_friction_factor is not None and self.sliding_friction_factor < 1.0:
            raise InvalidParameterError("sliding_friction_factor", self.sliding_friction_factor, ">= 1 (or None)")
        if self.geometry is not None:
            object.__setattr__(self, "geometry", as_geometry("geometry", self.geometry, "'ideal', 'urdf' or None"))
        self.force_limits()
        if self.method is not None and not (isinstance(self.method, str) and self.method in ("exact",
                                                                                           "decomposition")):
            raise InvalidParameterError("method", self.method, "'exact', 'decomposition' or None")
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

    @classmethod
    def of(cls, scenario: Scenario, **options: object) -> "RegraspSettings":
        """The settings ``options`` (keyword arguments as the constructor's) for ``scenario``: its ``[planner]``
        ``xi_resolution``, if it gives one, unless ``options`` do."""
        if scenario.xi_resolution is not None and "xi_resolution" not in options:
            options = {"xi_resolution": scenario.xi_resolution, **options}
        return cls(**options)

    @property
    def time_step(self) -> float:
        """The lattice's nominal time step [s]: one cell at the fastest slide."""
        return self.xi_resolution / self.max_slide_speed

    def force_limits(self, cone_margin: float | None = None) -> ForceLimits:
        """The force limits these settings plan with (``cone_margin``: another margin [N] than theirs)."""
        return ForceLimits(self.f_min, self.f_max, self.cone_margin if cone_margin is None else cone_margin,
                           self.slider_floor, self.holder_preload, self.friction_margin)

    @property
    def ramp(self) -> float:
        """A slide's acceleration time [s]."""
        return self.max_slide_speed / self.max_slide_acceleration


def trajectory_period(trajectory: Trajectory) -> float | None:
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
    sub-sample times ``sub_times``, ``lattice``, ``limits`` (the planning limits, with buffers), ``torque`` the
    fingers' joint torque limits (:class:`~regrasp.schedule.torque.TorqueModel`), ``torque_excess`` the lattice's
    torque table where a joint has a limit (:meth:`~regrasp.schedule.torque.TorqueModel.cell_excess`) and
    ``free_tables`` the force tables (lo, hi) before the limits cut them (None: they cut nothing), ``posed_tables``
    the tables before the slides' well-posedness cut them (:mod:`regrasp.schedule.well_posed`; None: it cut nothing)
    and ``posed_mask`` its conditions (per cell, per pair of sliders: :func:`~regrasp.schedule.well_posed.slide_mask`).
    ``geometry`` is None on a curved object (:meth:`geometry_at`).
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
    geometry: ForceGeometry | None
    limits: ForceLimits
    envelope_buffer: float
    lattice: Lattice
    start_cells: np.ndarray | None
    torque: TorqueModel | None = None
    torque_excess: np.ndarray | None = None
    free_tables: tuple | None = None
    exact: bool = True
    posed_tables: tuple | None = None
    posed_mask: tuple | None = None

    @property
    def curved(self) -> bool:
        """Whether the object is curved (its contacts' frames turn with ξ)."""
        return self.geometry is None

    def geometry_at(self, xi: ArrayLike) -> ForceGeometry:
        """The force balance's constants with the contacts at ``xi`` [m]: the polygon's ``geometry``, or on a curve
        the contacts' tangent lines there (:func:`~regrasp.schedule.curve_forces.tangent_geometry`)."""
        if self.geometry is not None:
            return self.geometry
        obj = self.scenario.polygon
        return tangent_geometry(obj, xi, mass=obj.mass, inertia=obj.inertia, gravity=self.scenario.gravity_in_hand)


def _cell_margins(sample, grid: np.ndarray) -> np.ndarray:
    """Each cell's envelope margin [m] in one sample (EnvelopeSample.margin, vectorised)."""
    out = np.full(len(grid), -np.inf)
    for lo, hi in sample.feasible:
        out = np.maximum(out, np.minimum(grid - lo, hi - grid))
    return out


def build_problem(scenario: Scenario, settings: RegraspSettings, *, start_time: float | None = None,
                  xi0: ArrayLike | None = None, t_end: float | None = None,
                  force_tables: bool | None = True) -> Problem:
    """The lattice of the module docstring for ``scenario`` (``xi0``: start positions [m], which then
    lie on the grid; ``start_time``/``t_end``: the horizon [s], default the trajectory's domain or,
    periodic, its first period; ``force_tables``: False for the decomposition planner's problem, without the
    force and torque tables (``exact`` False, at most ``max_sliders`` or 2 sliders), None: with them when they fit in
    their budget)."""
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
    curved = isinstance(scenario.polygon, CurvedObject)
    geometry = scenario.check_geometry(settings.geometry or scenario.geometry.value)
    envelopes = [FingerEnvelope(c.finger, scenario.polygon, c.edge, geometry=geometry, tip_clearance=c.tip_clearance)
                 for c in contacts]
    q = settings.envelope_substeps
    sub_times = t0 + (dt / q) * np.arange(n_steps * q + 1)
    poses = traj.pose(np.clip(sub_times, traj.t_start, traj.t_end))
    if curved:  # (each window next to the last: ξ unwrapped along the trajectory, from the start positions if given)
        sub_samples = [chained_samples(env, poses, sub_times, None if start is None else float(start[i]))
                       for i, env in enumerate(envelopes)]
    else:
        sub_samples = [[env.at(pose, float(t)) for t, pose in zip(sub_times, poses)] for env in envelopes]
    grids = []
    for i, e in enumerate(edges):
        anchor = 0.0 if start is None else float(start[i])
        lo, hi = feasible_span(sub_samples[i], h) if curved else e.xi_range
        if start is not None and not lo - 1e-12 <= anchor <= hi + 1e-12 and not curved:
            raise InvalidParameterError("xi0", start.tolist(), f"positions on the edges ({contacts[i].finger.name}: "
                                        f"[{lo:.6g}, {hi:.6g}] m)")
        if curved and start is not None:  # (the lattice holds the start, wherever the envelopes are)
            lo, hi = min(lo, anchor), max(hi, anchor)
        cells = np.arange(math.ceil((lo - anchor) / h - 1e-9), math.floor((hi - anchor) / h + 1e-9) + 1)
        grids.append(anchor + h * cells)
    start_cells = None if start is None else np.array([int(np.argmin(np.abs(g - x))) for g, x in zip(grids, start)])
    friction = tuple(c.friction for c in contacts)
    for c in contacts:
        if not settings.friction_margin < c.friction.static:
            raise InvalidParameterError("friction_margin", settings.friction_margin,
                                        f"a friction margin below every contact's mu_s ({c.finger.name}: "
                                        f"{c.friction.static:g})")
    p_max = min(m - 1, 2 * m - 3) if settings.max_sliders is None else min(settings.max_sliders, m - 1, 2 * m - 3)
    combos = motion_combos(m, p_max)
    sizes = sorted(len(g) for g in grids)
    table_bytes = 4 * 4 * (n_steps + 1) * int(np.prod(sizes[:-1])) * len(combos)  # lo, hi, mid lo, mid hi
    if force_tables is None:
        force_tables = table_bytes <= _TABLE_BUDGET
    if curved and not force_tables:
        raise InvalidParameterError("scenario", scenario.name, "a curved object's lattice with force tables (the "
                                    "decomposition planner takes polygons only; coarsen xi_resolution or lower "
                                    "max_sliders so that the tables fit)")
    if not force_tables:
        combos = motion_combos(m, min(settings.max_sliders or 2, m - 1, 2 * m - 3))
    if force_tables and table_bytes > _TABLE_BUDGET:
        raise InvalidParameterError(
            "scenario", scenario.name,
            f"a lattice whose force tables fit in {_TABLE_BUDGET / 2**30:.0f} GiB: {m} contacts with "
            f"{' x '.join(map(str, sizes))} cells and {len(combos)} move vectors over {n_steps + 1} layers need "
            f"{table_bytes / 2**30:.1f} GiB (coarsen xi_resolution, or lower max_sliders)")
    ramp = settings.ramp
    speed = h / dt
    envelope_buffer = speed * ramp / 8.0 + 1e-5
    lattice_env, proximity = _envelope_tables(sub_samples, grids, q, n_steps, settings, envelope_buffer, periodic)
    geo = None if curved else ForceGeometry.of(scenario.polygon, [c.edge for c in contacts],
                                                mass=scenario.polygon.mass, inertia=scenario.polygon.inertia,
                                                gravity=scenario.gravity_in_hand)
    sample = traj.sample(np.clip(times, traj.t_start, traj.t_end))
    jerk = np.abs(np.diff(sample.acceleration[:, :2], axis=0)).max(initial=0.0)
    limits = settings.force_limits(settings.cone_margin * 1.02 + scenario.polygon.mass * jerk + 1e-4)
    torque = TorqueModel(scenario)
    joints = [torque.joint_angles(i, sample.pose, np.broadcast_to(g, (len(times), len(g))))
              for i, g in enumerate(grids)] if force_tables and (torque.limited or settings.sliding_friction_factor
                                                                  is not None) else None
    axis = int(np.argmax([len(g) for g in grids]))
    middle = traj.sample(np.clip(np.append(times[0], 0.5 * (times[1:] + times[:-1])), traj.t_start, traj.t_end))
    early = traj.sample(np.clip(times - 0.5 * ramp, traj.t_start, traj.t_end))
    if force_tables and curved:  # (the joint torque limits exact in the tables)
        lo, hi, blo, bhi, slots, mid_lo, mid_hi = curve_force_tables(
            scenario.polygon, torque, sample, middle, early, 0.5 * ramp / dt, combos, friction, limits, grids, axis,
            lattice_env, speed, settings.prime_overshoot, joints)
        vertices = None
    elif force_tables:
        lo, hi, blo, bhi, slots, mid_lo, mid_hi, vertices = edge_force_tables(
            geo, sample, middle, early, 0.5 * ramp / dt, combos, friction, limits, grids, axis,
            settings.prime_overshoot)
    if force_tables:
        cells = math.ceil(settings.position_margin / h - 1e-9)
        if cells:  # (every position of the sliders up to the margin behind a state's has forces too)
            sizes = [len(grids[i]) for i in range(m) if i != axis]
            order = [i for i in range(m) if i != axis] + [axis]
            moving = combos[:, order]
            slot_moving = np.zeros((0 if blo is None else blo.shape[2], m), dtype=int)
            for mu, bits in zip(*np.nonzero(slots >= 0)):
                slot_moving[slots[mu, bits]] = moving[mu]
            for a, b, mv in ((lo, hi, moving), (mid_lo, mid_hi, moving), (blo, bhi, slot_moving)):
                if a is not None:
                    erode_tables(a, b, sizes, h, mv, cells)
    else:  # (the decomposition planner checks the forces itself: empty tables)
        lo = hi = mid_lo = mid_hi = np.empty((n_steps + 1, 0, len(combos)), dtype=np.float32)
        blo = bhi = vertices = None
        slots = np.full((len(combos), m), -1, dtype=np.int64)
    torque_excess, free_tables, posed_tables, posed = None, None, None, None
    if force_tables and settings.sliding_friction_factor is not None:  # (the decomposition: its verification's)
        posed, pairs = slide_mask(lattice_geometry(torque, scenario, grids, sample, joints), combos, friction,
                                  settings.sliding_friction_factor, lattice_env, scenario.polygon.mass,
                                  scenario.polygon.inertia)
        posed_tables = cut_tables(posed, grids, axis, lo, hi, pairs)
    if torque.limited and force_tables and not curved:
        torque_excess, free_tables = torque_tables(torque, sample, grids, combos, vertices, speed, axis, lo, hi,
                                                    lattice_env, joints)
    del vertices
    rest_only = np.zeros(n_steps + 1, dtype=bool)
    rest_only[[0, 1, n_steps]] = True
    move_cost = 0.05
    lattice = Lattice(times, grids, combos, lattice_env, proximity, axis, lo, hi, mid_lo, mid_hi, blo, bhi, slots,
                      rest_only,
                      slide_cost=1.0 + (n_steps + 1) * m * (1.0 + move_cost), move_cost=move_cost)
    return Problem(scenario, settings, tuple(c.finger.name for c in contacts), friction, bool(periodic), times, dt,
                   grids, envelopes, sub_times, sub_samples, geo, limits, envelope_buffer, lattice, start_cells, torque,
                   torque_excess, free_tables, bool(force_tables), posed_tables,
                   None if posed_tables is None else (posed, pairs))


def _window(k: int, q: int, n_steps: int) -> slice:
    """Layer k's sub-samples, its window [t_{k-1}, t_{k+1}] (``q`` sub-samples a step)."""
    return slice(max(0, (k - 1) * q), min(n_steps * q, (k + 1) * q) + 1)


def window_margin(problem: Problem, k: int, i: int, xi: float) -> tuple[float, float]:
    """Contact i's least envelope margin [m] at ``xi`` [m] over layer k's window, as the lattice's envelope tables
    take it (periodic: the first and the last layer are one time), and the time [s] of that least margin."""
    n_steps, q = len(problem.times) - 1, problem.settings.envelope_substeps
    layers = [k] if not problem.periodic or k not in (0, n_steps) else [0, n_steps]
    found = []
    for layer in layers:
        window = _window(layer, q, n_steps)
        found += [(problem.sub_samples[i][j].margin(xi), float(problem.sub_times[j]))
                  for j in range(window.start, window.stop)]
    return min(found)


def _envelope_tables(sub_samples, grids, q, n_steps, settings, buffer, periodic: bool):
    """(admissible, proximity) per layer, contact and cell over each layer's window [t_{k-1}, t_{k+1}]
    (wrapped around the period's ends when ``periodic``: the first and the last layer are one time)."""
    m, n_max = len(grids), max(len(g) for g in grids)
    ok = np.zeros((n_steps + 1, m, n_max), dtype=bool)
    proximity = np.ones((n_steps + 1, m, n_max))
    em, comfort = settings.envelope_margin, settings.comfort_margin
    for i, grid in enumerate(grids):
        margins = np.array([_cell_margins(s, grid) for s in sub_samples[i]])  # (sub-samples, cells)
        windows = [margins[_window(k, q, n_steps)].min(axis=0) for k in range(n_steps + 1)]
        if periodic:
            windows[0] = windows[n_steps] = np.minimum(windows[0], windows[n_steps])
        for k, window in enumerate(windows):
            ok[k, i, :len(grid)] = window >= em + buffer
            proximity[k, i, :len(grid)] = np.clip((comfort - window) / (comfort - em), 0.0, 1.0)
    return ok, proximity

r"""Robustness studies: many seeded rollouts of one scenario under model errors and noise, across processes or Ray.

A study plans the regrasp schedule once (with the model), then runs ``runs`` rollouts. Run :math:`i` draws its
plant's errors, and seeds its sensor and actuator noise, from ``numpy.random.SeedSequence(seed).spawn(runs)[i]``
(:func:`~regrasp.study.draws.draw_runs`; what is perturbed: :mod:`regrasp.model.perturbation`). The results are
the same however many workers run them, in whatever order, on processes or on Ray.

Where runs go: this process (``workers=1``), a pool of ``workers`` spawned processes, or a Ray cluster
(``ray_address``: ``"local"`` starts one on this machine; a cluster's address is checked, and reached, first:
:mod:`regrasp.study.ray_cluster`).
A job carries the scenario itself (pickled: the fingers' models, not file paths), so Ray workers on other
machines need no copy of the files.

The success rate comes with a Wilson score interval (:func:`wilson_interval`). With ``interruptible``, Ctrl-C ends
a study at once and keeps what it finished: the runs that ran to their end (the ones under way are dropped, so no
run is judged by a Ctrl-C), in run order (:attr:`StudyResult.interrupted`).
"""

from __future__ import annotations

import math
import time
from collections import Counter
from collections.abc import Callable, Iterator, Sequence
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..core.curves import CurveFace
from ..core.events import FailureKind
from ..core.exceptions import InvalidParameterError
from ..core.validation import MAX_WORKERS, as_count, as_finite_float, as_integer, expect_type
from ..model.perturbation import Perturbation
from ..model.softness import ContactSoftness, SoftnessRanges
from ..plants.spec import PlantSpec
from .draws import RunDraw, draw_runs
from .pool import process_runs
from .ray_cluster import check_ray_address, ray_runs, require_ray

if TYPE_CHECKING:
    from ..envelope.planner import PlanResult
    from ..model.scenario import Scenario
    from ..rollout.build import Rollout
    from ..schedule.schedule import RegraspSchedule
    from ..supervisor.settings import SupervisorSettings

__all__ = ["RunOutcome", "StudyResult", "build_run", "check_placement", "run_once", "run_study", "sweep_study",
           "wilson_interval"]

#: z of a two-sided 95 % interval.
Z_95 = 1.959963984540054


def wilson_interval(successes: int, runs: int, z: float = Z_95) -> tuple[float, float]:
    r"""The Wilson score interval of a binomial proportion :math:`\hat p = k / n`:

    .. math:: \frac{\hat p + z^2 / 2n \pm z \sqrt{\hat p (1 - \hat p) / n + z^2 / 4n^2}}{1 + z^2 / n}

    (E. B. Wilson, 1927). Unlike the normal approximation it stays inside [0, 1] and is not empty at
    :math:`k = 0` or :math:`k = n`. The interval always contains :math:`\hat p` (exactly: rounding
    alone would leave the upper end a hair below 1 at :math:`k = n`, or the lower above 0 at :math:`k = 0`).
    """
    k, n = as_integer("successes", successes), as_integer("runs", runs, 1)
    if n > 2**53:
        raise InvalidParameterError("runs", runs, "a count of at most 2**53 (exact as a float)")
    if k > n:
        raise InvalidParameterError("successes", successes, f"at most runs = {n}")
    z = as_finite_float("z", z)
    p = k / n
    denominator = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / denominator
    half = z * math.sqrt(p * (1.0 - p) / n + z * z / (4 * n * n)) / denominator
    return min(p, max(0.0, centre - half)), max(p, min(1.0, centre + half))


@dataclass(frozen=True)
class RunOutcome:
    """What one run of a study did.

    Attributes:
        draw: Its seed and drawn model errors.
        success: It reached the end without a failure.
        failure_kind: The :class:`~regrasp.core.events.FailureKind` value, or None.
        failure_time: When it failed [s], or None.
        failure_contact: The finger the failure names, or None.
        min_cone_margin: Its smallest cone margin of a contact held fixed [N] (None: no step had one, as a run
            failing at its first step).
        min_envelope_margin: Its smallest envelope margin [m] (None: likewise).
        max_object_error: Its largest object position error after the transient [m] (None: the run ended
            before the transient did).
        max_orientation_error: Its largest orientation error after the transient [rad] (None: likewise).
        slides: Its slides, all fingers.
        replans: Its re-plans.
        wall_seconds: Its wall time [s].
    """

    draw: RunDraw
    success: bool
    failure_kind: str | None
    failure_time: float | None
    failure_contact: str | None
    min_cone_margin: float | None
    min_envelope_margin: float | None
    max_object_error: float | None
    max_orientation_error: float | None
    slides: int
    replans: int
    wall_seconds: float


def _finite_or_none(x: float) -> float | None:
    """``x``, or None for a NaN or an infinity (no sample: a JSON document holds no NaN or inf)."""
    return float(x) if math.isfinite(x) else None


def build_run(scenario: Scenario, draw: RunDraw, schedule: RegraspSchedule | None, duration: float,
              perturbation: Perturbation, settings: SupervisorSettings | None = None,
              plant: PlantSpec = PlantSpec(), plan: PlanResult | None = None) -> Rollout:
    """One run of a study, ready to run: the rollout of ``scenario`` on ``plant`` with ``draw``'s model errors and
    the noise of ``perturbation`` seeded by ``draw.seed``, supervised with ``settings`` (None: the rollout's
    default, :meth:`~regrasp.supervisor.settings.SupervisorSettings.robust` told the actuation delay). Run it with a
    recorder to look at a failed run on a rerun timeline (``regrasp study --replay I --rrd FILE``). ``plan``: the
    scenario's envelope plan, if computed already (a study computes it once for all its runs)."""
    from ..rollout.build import build_rollout
    from ..rollout.spec import RunSpec

    run = RunSpec(duration=duration, seed=draw.seed, sensor_noise=perturbation.sensor_noise(),
                  actuator_noise=perturbation.actuator_noise())
    return build_rollout(scenario, run, schedule=schedule, settings=settings, plan=plan,
                         plant=replace(soften(plant, draw.softness), errors=draw.errors))


def soften(plant: PlantSpec, softness: ContactSoftness | None) -> PlantSpec:
    """``plant`` with contacts of ``softness`` (None: as it is); only a compliant plant (MuJoCo) has any."""
    if softness is None:
        return plant
    if plant.kind != "mujoco":
        raise InvalidParameterError("softness", softness, f"no drawn contact softness on the {plant.kind} plant "
                                    "(solref and solimp are MuJoCo's; the project plant's contacts are rigid): a study "
                                    "on --plant mujoco")
    from ..plants.mujoco.mjcf import MujocoSettings

    settings = MujocoSettings() if plant.settings is None else plant.settings
    solimp = settings.solimp[:2] + (softness.solimp_width,) + settings.solimp[3:]
    return replace(plant, settings=replace(settings, tip_radius=softness.tip_radius,
                                           time_constant=softness.time_constant, solimp=solimp))


def run_once(scenario: Scenario, draw: RunDraw, schedule: RegraspSchedule | None, duration: float,
             perturbation: Perturbation, settings: SupervisorSettings | None = None,
             plant: PlantSpec = PlantSpec(), plan: PlanResult | None = None, *,
             interruptible: bool = False) -> RunOutcome:
    """:func:`build_run`'s rollout, run: what it did (``interruptible``: Ctrl-C ends it with an ``interrupted``
    failure, as :meth:`~regrasp.rollout.build.Rollout.run` does, rather than raising)."""
    r = build_run(scenario, draw, schedule, duration, perturbation, settings, plant, plan).run(
        interruptible=interruptible)
    f = r.failure
    return RunOutcome(draw, r.success, None if f is None else f.kind.value, None if f is None else f.time,
                      None if f is None else f.contact, _finite_or_none(r.min_cone_margin),
                      _finite_or_none(r.min_envelope_margin),
                      _finite_or_none(r.max_object_error_after_transient),
                      _finite_or_none(r.max_orientation_error_after_transient), sum(r.regrasps.values()), r.replans,
                      r.wall_seconds)


@dataclass(frozen=True)
class StudyResult:
    """A study's runs and their summary.

    Attributes:
        scenario: The scenario file (or name).
        runs: The outcomes of the runs that ran to their end, in run order (by ``draw.index``).
        perturbation: What was perturbed, and by how much.
        seed: The study's seed.
        duration: Each run's simulated time [s].
        workers: The processes that ran it (Ray: the cluster's CPUs).
        backend: ``"process"`` or ``"ray"``.
        plant: ``"project"``, ``"mujoco"`` or ``"drake"``.
        wall_seconds: The study's wall time [s] (the plan included).
        plan_seconds: The plan's wall time [s].
        softness: The ranges each run's contact softness was drawn from, or None.
        requested_runs: The runs the study was asked for (None: ``len(runs)``); more than ran when Ctrl-C ended it.
    """

    scenario: str
    runs: tuple[RunOutcome, ...]
    perturbation: Perturbation
    seed: int
    duration: float
    workers: int
    backend: str
    wall_seconds: float
    plan_seconds: float
    plant: str = "project"
    softness: SoftnessRanges | None = None
    requested_runs: int | None = None

    @property
    def interrupted(self) -> bool:
        """Whether Ctrl-C ended the study before all its runs ran."""
        return self.requested_runs is not None and len(self.runs) < self.requested_runs

    @property
    def successes(self) -> int:
        return sum(r.success for r in self.runs)

    @property
    def success_rate(self) -> float:
        """Successes over the runs that ran (NaN when none did)."""
        return self.successes / len(self.runs) if self.runs else math.nan

    @property
    def interval(self) -> tuple[float, float]:
        """The success rate's Wilson 95 % interval ([0, 1] when no run ran: nothing is known)."""
        return wilson_interval(self.successes, len(self.runs)) if self.runs else (0.0, 1.0)

    @property
    def failures(self) -> dict[str, int]:
        """Failed runs per failure kind."""
        return dict(Counter(r.failure_kind for r in self.runs if not r.success))

    def to_json_dict(self) -> dict:
        """A JSON-serialisable dict (the ``regrasp study --json`` document)."""
        lo, hi = self.interval
        return {"scenario": self.scenario, "seed": self.seed, "duration": self.duration, "workers": self.workers,
                "backend": self.backend, "plant": self.plant, "perturbation": asdict(self.perturbation),
                "softness": None if self.softness is None else asdict(self.softness),
                "runs": len(self.runs), "requested_runs": self.requested_runs or len(self.runs),
                "interrupted": self.interrupted, "successes": self.successes,
                "success_rate": _finite_or_none(self.success_rate),
                "wilson_95": [lo, hi],
                "failures": self.failures, "wall_seconds": self.wall_seconds, "plan_seconds": self.plan_seconds,
                "outcomes": [{**{f.name: getattr(r, f.name) for f in fields(r)}, "draw": r.draw.to_json_dict()}
                             for r in self.runs]}


def _on_processes(workers: int, shared: tuple, draws: tuple[RunDraw, ...]) -> Iterator[RunOutcome]:
    """The runs' outcomes as they finish: in this process (a run ended by Ctrl-C raises KeyboardInterrupt, it is
    not an outcome) or on a pool of ``workers`` processes (closing the generator terminates the pool)."""
    if workers == 1:
        for draw in draws:
            outcome = run_once(*shared[:1], draw, *shared[1:], interruptible=True)
            if outcome.failure_kind == FailureKind.INTERRUPTED.value:
                raise KeyboardInterrupt
            yield outcome
        return
    yield from process_runs(workers, run_once, shared, draws)  # (closing it terminates the workers)


def run_study(scenario: str | Path | Scenario, runs: int, *, seed: int = 0,
              perturbation: Perturbation = Perturbation(), duration: float | None = None, periods: int | None = None,
              workers: int = 1, ray_address: str | None = None, schedule: RegraspSchedule | None = None,
              settings: SupervisorSettings | None = None, plant: PlantSpec | str = "project",
              softness: SoftnessRanges | None = None,
              progress: Callable[[int, int], None] | None = None, interruptible: bool = False,
              finished: Sequence[RunOutcome] = ()) -> StudyResult:
    """Plan the schedule once, then run ``runs`` seeded rollouts (module docstring).

    Args:
        scenario: A scenario file, or a loaded :class:`~regrasp.model.scenario.Scenario`.
        runs: How many runs (at most ``MAX_RUNS``).
        seed: The study's seed.
        perturbation: What is perturbed, and by how much.
        duration: Each run's length [s], as in :func:`~regrasp.rollout.build.build_rollout` (default: the
            trajectory's domain).
        periods: Each run's length in periods, instead (as in :func:`~regrasp.rollout.build.build_rollout`).
        workers: Processes (1: this one, at most ``MAX_WORKERS``); with Ray, the CPUs of a local cluster.
        ray_address: None (processes), ``"local"`` (a Ray cluster on this machine), ``"auto"`` or a cluster's
            address (:mod:`regrasp.study.ray_cluster`: reached within seconds, before the plan, or a
            :class:`~regrasp.core.exceptions.ClusterConnectionError`).
        schedule: The schedule every run starts with (default: planned here with the model, with the cone margin
            rollouts keep by default): a planning stack that studies one plan under several perturbations plans
            it once.
        settings: The supervisor's settings in every run (None: the rollout's default).
        plant: The plant every run is on, as :func:`~regrasp.rollout.build.build_rollout` takes it (a
            :class:`~regrasp.plants.spec.PlantSpec` without model errors: each run draws its own, or a kind's name).
        softness: The ranges each run draws its contacts' softness from
            (:class:`~regrasp.model.softness.SoftnessRanges`; a compliant plant only), or None (the plant's own).
        progress: Called as ``progress(done, runs)`` once the runs start (done = 0), then after each run.
        interruptible: Ctrl-C (KeyboardInterrupt) ends the study at once with the runs it finished
            (:attr:`StudyResult.interrupted`) instead of propagating; the runs under way are dropped and the
            workers stopped. Before the first run (while planning) it propagates.
        finished: Runs of this very study that ran already (a resumed study: :func:`~regrasp.study.resume.
            finished_runs` reads them from a ``study.json``): they are kept, not run again, each checked to be the
            draw of its index.
    """
    from ..model.scenario import Scenario, load_scenario
    from ..rollout.build import build_rollout
    from ..rollout.spec import RunSpec
    from ..schedule.planner import plan_regrasps

    start = time.perf_counter()
    workers = as_count("workers", workers, 1, MAX_WORKERS)
    plant = PlantSpec.of(plant)
    if plant.errors != PlantSpec().errors:
        raise InvalidParameterError("plant", plant, "a PlantSpec without model errors (each run draws its own)")
    expect_type("perturbation", perturbation, Perturbation, "a Perturbation")
    if ray_address is not None:  # (before planning: an address where no cluster answers is said within seconds)
        ray_address = check_ray_address(ray_address).text
        require_ray()
    if not isinstance(scenario, Scenario):
        scenario = load_scenario(scenario)
    name = str(scenario.path) if scenario.path is not None else scenario.name
    if softness is not None:
        soften(plant, softness.draw(np.random.default_rng(0)))  # (a rigid plant refuses before any planning)
    draws = draw_runs(runs, seed, perturbation, len(scenario.contacts), softness)
    outcomes = _checked_finished(finished, draws)
    run = RunSpec(duration=duration, periods=periods)
    _, length = run.resolve(scenario)  # (a run of no step, or longer than the trajectory allows: refused first)
    backend = "process" if ray_address is None else "ray"
    if len(outcomes) == len(draws):  # (all finished already: nothing to plan or run)
        return StudyResult(name, tuple(sorted(outcomes, key=lambda o: o.draw.index)), perturbation, int(seed), length,
                           workers, backend, time.perf_counter() - start, 0.0, plant.kind, softness, len(draws))
    if schedule is None:
        schedule = plan_regrasps(scenario)
    probe = build_rollout(scenario, run, schedule=schedule, settings=settings, plant=plant)
    check_placement(scenario, probe.schedule.at(scenario.trajectory.t_start).xi if probe.schedule else None,
                    perturbation.contact_position, probe.supervisor.plan)
    plan_seconds = time.perf_counter() - start
    # the schedule and the envelope plan are computed once for every run (they depend on the model only)
    shared = (scenario, probe.schedule, probe.duration, perturbation, settings, plant, probe.supervisor.plan)
    ran = {o.draw.index for o in outcomes}
    todo = tuple(d for d in draws if d.index not in ran)
    source = (o for o in ()) if not todo else _on_processes(workers, shared, todo) if ray_address is None else \
        ray_runs(ray_address, workers, run_once, shared, todo)
    try:
        if progress is not None:
            progress(len(outcomes), len(draws))  # (planned: the runs start)
        for outcome in source:
            outcomes.append(outcome)
            if progress is not None:
                progress(len(outcomes), len(draws))
    except KeyboardInterrupt:
        if not interruptible:
            raise
    finally:
        source.close()  # (stops the workers, or cancels the Ray tasks, that are still running)
    return StudyResult(name, tuple(sorted(outcomes, key=lambda o: o.draw.index)), perturbation, int(seed),
                       probe.duration, workers, backend, time.perf_counter() - start, plan_seconds, plant.kind,
                       softness, len(draws))


def _checked_finished(finished: Sequence[RunOutcome], draws: tuple[RunDraw, ...]) -> list[RunOutcome]:
    """``finished`` as a list, each outcome checked to be the run of its index in this study (same draw), once."""
    out, seen = [], set()
    for o in finished:
        expect_type("finished", o, RunOutcome, "RunOutcomes of this study")
        i = o.draw.index
        if not (0 <= i < len(draws)) or i in seen or o.draw != draws[i]:
            raise InvalidParameterError("finished", o.draw, f"runs of this study, once each (run {i} is not the "
                                        f"draw of index {i} of these {len(draws)} runs, or is there twice)")
        seen.add(i)
        out.append(o)
    return out


def check_placement(scenario: Scenario, xi0: Sequence[float] | np.ndarray | None, half_width: float,
                    plan: PlanResult | None = None) -> None:
    """Every placement error a study can draw (ξ0 ± ``half_width`` [m] about each planned ξ0 [m]) keeps each fingertip
    where it can be placed: on a polygon, on its edge (the edge's ξ range); on a curved object, where every ξ is on
    the object, inside the finger's feasible envelope at the start (the feasible interval of ``plan``'s sample at the
    trajectory's start holding ξ0, moved by whole perimeters to it; no check without a plan). Nothing to check
    without ξ0 or with no error.

    Raises:
        InvalidParameterError: ``contact_position``, a half-width that can place a fingertip off its edge or
            outside its envelope (or a planned ξ0 outside that envelope already).
    """
    if xi0 is None or half_width == 0.0:
        return
    for i, (c, x) in enumerate(zip(scenario.contacts, xi0)):
        edge = scenario.polygon.edge(c.edge)
        if isinstance(edge, CurveFace):
            if plan is not None:  # (the plan's sample at the trajectory's start)
                k = int(np.argmin(np.abs(np.asarray(plan.times) - scenario.trajectory.t_start)))
                _check_curve_placement(c.finger.name, float(x), half_width, edge.period,
                                       plan.fingers[i].samples[k].feasible)
            continue
        lo, hi = edge.xi_range
        if not (lo <= x - half_width and x + half_width <= hi):
            raise InvalidParameterError("contact_position", half_width,
                                        f"a placement error that keeps {c.finger.name} on its edge (xi0 = "
                                        f"{x * 1e3:.2f} mm on [{lo * 1e3:.2f}, {hi * 1e3:.2f}] mm)")


def _check_curve_placement(name: str, x: float, half_width: float, period: float,
                           feasible: Sequence[tuple[float, float]]) -> None:
    """:func:`check_placement` of one contact at ξ0 = ``x`` [m] on a curve of perimeter ``period`` [m] whose
    finger's feasible set at the start is ``feasible`` (intervals [m], any representative of ξ)."""
    for lo, hi in feasible:
        shift = period * round((x - 0.5 * (lo + hi)) / period)
        lo, hi = lo + shift, hi + shift
        if lo <= x <= hi:
            if lo <= x - half_width and x + half_width <= hi:
                return
            raise InvalidParameterError("contact_position", half_width,
                                        f"a placement error that keeps {name} inside its feasible envelope at the "
                                        f"start (xi0 = {x * 1e3:.2f} mm in [{lo * 1e3:.2f}, {hi * 1e3:.2f}] mm)")
    raise InvalidParameterError("contact_position", half_width,
                                f"a planned start inside {name}'s feasible envelope to place it around (xi0 = "
                                f"{x * 1e3:.2f} mm is in none of its feasible intervals at the start)")


def sweep_study(scenario: str | Path | Scenario, runs: int, name: str, values: Sequence[float], *,
                perturbation: Perturbation = Perturbation(), progress: Callable[[int, int], None] | None = None,
                **options: object) -> tuple[StudyResult, ...]:
    """One study per value of one perturbation (``name``, a :class:`~regrasp.model.perturbation.Perturbation` field),
    the others as ``perturbation`` gives them: success against that perturbation's size. The schedule is planned
    once; every study has the same seed, so the k-th runs of two studies differ only in that perturbation.
    ``options``: :func:`run_study`'s. ``progress(done, total)`` counts runs over all the studies. With
    ``interruptible``, Ctrl-C ends the sweep with the studies so far, the last one interrupted."""
    from ..model.scenario import Scenario, load_scenario

    if not isinstance(name, str) or name not in {f.name for f in fields(Perturbation)}:
        raise InvalidParameterError("name", name, "a Perturbation field (" + ", ".join(f.name for f in
                                                                                     fields(Perturbation)) + ")")
    if isinstance(values, (str, bytes)) or not hasattr(values, "__len__") or not 1 <= len(values) <= 100:
        raise InvalidParameterError("values", values, "1 to 100 sizes")
    expect_type("perturbation", perturbation, Perturbation, "a Perturbation")
    perturbations = [replace(perturbation, **{name: v}) for v in values]  # (each checked by Perturbation)
    if not isinstance(scenario, Scenario):
        scenario = load_scenario(scenario)
    if options.get("schedule") is None:
        from ..schedule.planner import plan_regrasps

        options["schedule"] = plan_regrasps(scenario)
    out = []
    for k, p in enumerate(perturbations):
        step = None if progress is None else (lambda done, total, k=k: progress(k * total + done,
                                                                               len(perturbations) * total))
        try:
            out.append(run_study(scenario, runs, perturbation=p, progress=step, **options))
        except KeyboardInterrupt:  # (between two studies' runs)
            if not options.get("interruptible"):
                raise
            break
        if out[-1].interrupted:
            break
    return tuple(out)

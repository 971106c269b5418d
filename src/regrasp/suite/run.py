"""Running a suite: each variant drawn (:mod:`regrasp.suite.variants`), planned (the envelope, then the schedule) and,
with a schedule, run on the plant; in this process, on a pool of processes or on Ray, as a study's runs are
(:func:`~regrasp.study.pool.process_runs`, :func:`~regrasp.study.ray_cluster.ray_runs`).

A variant is planned as ``regrasp plan --regrasp`` plans (:func:`~regrasp.envelope.planner.plan_scenario`, then
:func:`~regrasp.schedule.planner.plan_regrasps` with the default settings) and run as a study's run is
(:func:`~regrasp.study.study.run_once`: the scheduled policy, the rollout's default supervisor settings, the same
success criterion), with no model error and no noise: the plant is the model. Its planning is timed
(``time.perf_counter``) and its peak memory measured (:mod:`regrasp.suite.memory`: the worker's peak resident set
size). On a pool of processes each worker gets its share of the cores for numba's threads (the schedule's lattice
is parallel), so that the workers do not oversubscribe them. A job carries the spec (the base scenario's document
and absolute file paths): Ray workers on other machines need the scenario's and the URDFs' files at the same paths.

The results are the same whatever the workers and their order (each variant depends only on the spec and its index);
the timings and memory are not. With ``interruptible``, Ctrl-C ends a suite at once and keeps the variants that
finished.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterator
from pathlib import Path

from ..core.events import FailureKind
from ..core.exceptions import InvalidParameterError, RegraspError
from ..core.validation import MAX_COUNT, MAX_WORKERS, as_count, expect_type
from ..plants.spec import PlantSpec
from ..study.pool import process_runs
from ..study.ray_cluster import check_ray_address, ray_runs, require_ray
from .memory import peak_memory, reset_peak_memory
from .result import NO_SCHEDULE, REFUSED, SCHEDULED, SuiteResult, VariantOutcome
from .spec import SuiteSpec, load_suite_spec
from .variants import draw_variant, variant_scenario

__all__ = ["run_suite", "run_variant"]

#: How many variants this process has planned (the first plan loads the planner's compiled kernels: ``cold``).
_PLANNED = {"count": 0}


def run_variant(spec: SuiteSpec, index: int, plant: PlantSpec = PlantSpec(), periods: int = 2,
                plan_only: bool = False, *, interruptible: bool = False) -> VariantOutcome:
    """Variant ``index`` of ``spec``: drawn, planned (timed, its peak memory measured) and, with a schedule and
    unless ``plan_only``, run on ``plant`` for ``periods`` periods (a trajectory that is not periodic: its whole
    domain). A variant that its scenario or the planner refuses (a typed error), or that has no schedule, is an
    outcome that says why, not an error. ``interruptible``: Ctrl-C ends its rollout with an ``interrupted``
    failure (it propagates while planning)."""
    from ..envelope.planner import plan_scenario
    from ..model.perturbation import Perturbation
    from ..rollout.spec import RunSpec
    from ..schedule.planner import plan_regrasps
    from ..schedule.problem import trajectory_period
    from ..schedule.schedule import NoScheduleError
    from ..study.draws import RunDraw
    from ..study.study import run_once

    variant = draw_variant(spec, index)
    common = {"index": variant.index, "entropy": variant.entropy, "parameters": variant.values}
    try:
        scenario = variant_scenario(spec, variant)
    except RegraspError as exc:
        return VariantOutcome(**common, fingers=0, status=REFUSED, limit=type(exc).__name__, reason=str(exc))
    common["fingers"] = len(scenario.contacts)
    cold = _PLANNED["count"] == 0
    _PLANNED["count"] += 1
    reset = reset_peak_memory()
    start = time.perf_counter()
    schedule = plan = envelope_seconds = None
    try:
        plan = plan_scenario(scenario)
        envelope_seconds = time.perf_counter() - start
        schedule = plan_regrasps(scenario)
    except NoScheduleError as exc:
        common.update(status=NO_SCHEDULE, limit=exc.limit.value, contacts=exc.contacts, reason=str(exc),
                      latest_time=exc.latest_time)
    except RegraspError as exc:
        common.update(status=REFUSED, limit=type(exc).__name__, reason=str(exc))
    seconds = time.perf_counter() - start
    peak = peak_memory(reset)
    common.update(plan_seconds=seconds, envelope_seconds=envelope_seconds, cold=cold,
                  peak_memory=None if peak is None else peak.bytes,
                  memory_upper_bound=peak is not None and peak.upper_bound)
    if schedule is None:
        return VariantOutcome(**common)
    common.update(status=SCHEDULED, slides=len(schedule.slides))
    if plan_only:
        return VariantOutcome(**common)
    run = RunSpec(periods=periods) if trajectory_period(scenario.trajectory) is not None else RunSpec()
    try:
        _, duration = run.resolve(scenario)
        r = run_once(scenario, RunDraw(variant.index, variant.entropy), schedule, duration, Perturbation(), None,
                     plant, plan, interruptible=interruptible)
    except RegraspError as exc:  # (a rollout that cannot start: said, as a failure of its own kind)
        return VariantOutcome(**common, success=False, failure_kind="error", reason=f"{type(exc).__name__}: {exc}")
    return VariantOutcome(**common, success=r.success, failure_kind=r.failure_kind, failure_time=r.failure_time,
                          failure_contact=r.failure_contact, run_seconds=r.wall_seconds)


def _here(shared: tuple, indices: tuple[int, ...]) -> Iterator[VariantOutcome]:
    """The variants in this process, in order (a rollout ended by Ctrl-C raises KeyboardInterrupt)."""
    spec, *rest = shared
    for index in indices:
        outcome = run_variant(spec, index, *rest, interruptible=True)
        if outcome.failure_kind == FailureKind.INTERRUPTED.value:
            raise KeyboardInterrupt
        yield outcome


def run_suite(spec: SuiteSpec | str | Path, *, workers: int = 1, ray_address: str | None = None,
              plant: PlantSpec | str = "project", periods: int = 2, plan_only: bool = False,
              progress: Callable[[int, int], None] | None = None, interruptible: bool = False) -> SuiteResult:
    """Draw, plan and run every variant of ``spec`` (module docstring).

    Args:
        spec: A :class:`~regrasp.suite.spec.SuiteSpec`, or its file (:func:`~regrasp.suite.spec.load_suite_spec`).
        workers: Processes (1: this one, at most ``MAX_WORKERS``); with Ray, the CPUs of a local cluster.
        ray_address: None (processes), ``"local"`` (a Ray cluster on this machine), ``"auto"`` or a cluster's
            address (:mod:`regrasp.study.ray_cluster`: reached within seconds, first).
        plant: The plant the rollouts run on (a :class:`~regrasp.plants.spec.PlantSpec` without model errors, or a
            kind's name).
        periods: Each rollout's length in periods of its trajectory (one that is not periodic: its whole domain).
        plan_only: Plan every variant, run none.
        progress: Called as ``progress(done, variants)`` when the variants start (done = 0), then after each.
        interruptible: Ctrl-C ends the suite at once with the variants that finished (:attr:`SuiteResult.
            interrupted`) instead of propagating; those under way are dropped and the workers stopped.
    """
    start = time.perf_counter()
    if not isinstance(spec, SuiteSpec):
        spec = load_suite_spec(spec)
    workers = as_count("workers", workers, 1, MAX_WORKERS)
    periods = as_count("periods", periods, 1, MAX_COUNT)
    plan_only = bool(expect_type("plan_only", plan_only, bool, "True or False"))
    plant = PlantSpec.of(plant)
    if plant.errors != PlantSpec().errors:
        raise InvalidParameterError("plant", plant, "a PlantSpec without model errors (a suite's plant is the model)")
    if ray_address is not None:
        ray_address = check_ray_address(ray_address).text
        require_ray()
    shared = (spec, plant, periods, plan_only)
    indices = tuple(range(spec.variants))
    if ray_address is not None:
        source = ray_runs(ray_address, workers, run_variant, shared, indices)
    elif workers == 1:
        from ..kernels import ROLLOUT, warm_up

        warm_up(groups=ROLLOUT)  # (as a pool's worker does: no variant's wall time pays for them)
        source = _here(shared, indices)
    else:
        workers = min(workers, spec.variants)  # (the schedule's lattice is parallel: the cores shared out)
        source = process_runs(workers, run_variant, shared, indices, threads=max(1, (os.cpu_count() or 1) // workers))
    outcomes: list[VariantOutcome] = []
    try:
        if progress is not None:
            progress(0, spec.variants)
        for outcome in source:
            outcomes.append(outcome)
            if progress is not None:
                progress(len(outcomes), spec.variants)
    except KeyboardInterrupt:
        if not interruptible:
            raise
    finally:
        source.close()  # (stops the workers, or cancels the Ray tasks, still running)
    return SuiteResult(spec.name, spec.where, str(spec.scenario), spec.seed, spec.variants,
                       tuple(v.key for v in spec.varied), tuple(sorted(outcomes, key=lambda o: o.index)),
                       plant.kind, periods, plan_only, workers, "process" if ray_address is None else "ray",
                       time.perf_counter() - start)


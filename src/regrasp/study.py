r"""Robustness studies: many seeded rollouts of one scenario under drawn model errors, across processes.

A study plans the regrasp schedule once (with the model), then runs ``runs`` rollouts. Each one draws its
plant's errors from its own seed: run :math:`i` uses ``numpy.random.SeedSequence(seed).spawn(runs)[i]``.
The draws, and so the results, are the same however many workers run them, and in whatever order.

Perturbations (:class:`Perturbation`), each a relative half-width :math:`h` [-]: the plant's value is the
model's times a factor drawn uniformly from :math:`[1 - h, 1 + h]`:

* ``mass``: the object's mass;
* ``inertia``: the object's rotational inertia (drawn on its own);
* ``mu``: every fingertip's :math:`\mu_s` and :math:`\mu_k` together;
* ``link_mass``: every finger link's mass and inertia (one factor for all links).

The controllers and the planner keep the model's values. The success rate comes with a Wilson score
interval (:func:`wilson_interval`).
"""

from __future__ import annotations

import math
import multiprocessing
import time
from collections import Counter
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from .exceptions import InvalidParameterError
from .validation import as_finite_float, as_integer, expect_type

__all__ = ["Perturbation", "RunDraw", "RunOutcome", "StudyResult", "draw_runs", "run_study", "wilson_interval"]

#: The most runs one study takes (a study of 2 periods of trajectory 2 is about 25 s of wall time per run today).
MAX_RUNS = 100_000

#: z of a two-sided 95 % interval.
Z_95 = 1.959963984540054


def wilson_interval(successes: int, runs: int, z: float = Z_95) -> tuple[float, float]:
    r"""The Wilson score interval of a binomial proportion :math:`\hat p = k / n`:

    .. math:: \frac{\hat p + z^2 / 2n \pm z \sqrt{\hat p (1 - \hat p) / n + z^2 / 4n^2}}{1 + z^2 / n}

    (E. B. Wilson, 1927). Unlike the normal approximation it stays inside [0, 1] and is not empty at
    :math:`k = 0` or :math:`k = n`.
    """
    k, n = as_integer("successes", successes), as_integer("runs", runs, 1)
    if k > n:
        raise InvalidParameterError("successes", successes, f"at most runs = {n}")
    z = as_finite_float("z", z)
    p = k / n
    denominator = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / denominator
    half = z * math.sqrt(p * (1.0 - p) / n + z * z / (4 * n * n)) / denominator
    return max(0.0, centre - half), min(1.0, centre + half)


@dataclass(frozen=True)
class Perturbation:
    """Relative half-widths [-] of the plant's model errors (0: the model's value exactly).

    Attributes:
        mass: The object's mass, times U(1 - mass, 1 + mass).
        mu: Every fingertip's μ_s and μ_k, times U(1 - mu, 1 + mu).
        inertia: The object's rotational inertia, times U(1 - inertia, 1 + inertia).
        link_mass: The finger links' masses and inertias, times U(1 - link_mass, 1 + link_mass).
    """

    mass: float = 0.0
    mu: float = 0.0
    inertia: float = 0.0
    link_mass: float = 0.0

    def __post_init__(self) -> None:
        for name in ("mass", "mu", "inertia", "link_mass"):
            if not 0.0 <= as_finite_float(name, getattr(self, name)) < 1.0:
                raise InvalidParameterError(name, getattr(self, name), "a relative half-width in [0, 1)")


@dataclass(frozen=True)
class RunDraw:
    """One run's seed and the factors drawn from it.

    Attributes:
        index: The run's number in the study (0-based).
        entropy: The run's seed, as the spawned ``SeedSequence``'s words (to repeat the run alone).
        mass_scale: The plant's object mass over the model's [-].
        mu_scale: The plant's μ over the model's [-].
        inertia_scale: The plant's object inertia over the model's [-].
        link_mass_scale: The plant's link masses and inertias over the URDFs' [-].
    """

    index: int
    entropy: tuple[int, ...]
    mass_scale: float
    mu_scale: float
    inertia_scale: float = 1.0
    link_mass_scale: float = 1.0


def draw_runs(runs: int, seed: int, perturbation: Perturbation) -> tuple[RunDraw, ...]:
    """The ``runs`` draws of a study (module docstring: one spawned seed per run)."""
    runs = as_integer("runs", runs, 1)
    if runs > MAX_RUNS:
        raise InvalidParameterError("runs", runs, f"at most {MAX_RUNS} runs")
    expect_type("perturbation", perturbation, Perturbation, "a Perturbation")
    out = []
    for i, child in enumerate(np.random.SeedSequence(as_integer("seed", seed)).spawn(runs)):
        rng = np.random.default_rng(child)
        mass, mu, inertia, links = rng.uniform(-1.0, 1.0, 4).tolist()
        p = perturbation
        out.append(RunDraw(i, tuple(int(w) for w in child.generate_state(4)), 1.0 + p.mass * mass, 1.0 + p.mu * mu,
                           1.0 + p.inertia * inertia, 1.0 + p.link_mass * links))
    return tuple(out)


@dataclass(frozen=True)
class RunOutcome:
    """What one run of a study did.

    Attributes:
        draw: Its seed and factors.
        success: It reached the end without a failure.
        failure_kind: The :class:`~regrasp.events.FailureKind` value, or None.
        failure_time: When it failed [s], or None.
        min_cone_margin: Its smallest cone margin of a fixed contact [N].
        min_envelope_margin: Its smallest envelope margin [m].
        max_object_error: Its largest object position error after the transient [m] (None: the run ended
            before the transient did).
        slides: Its slides, all fingers.
        wall_seconds: Its wall time [s].
    """

    draw: RunDraw
    success: bool
    failure_kind: str | None
    failure_time: float | None
    min_cone_margin: float
    min_envelope_margin: float
    max_object_error: float | None
    slides: int
    wall_seconds: float


def _run(job: tuple[str, RunDraw, object, float]) -> RunOutcome:
    """One run (a module-level function, so that a worker process can be handed it)."""
    from .rollout import build_rollout
    from .scenario import load_scenario

    path, draw, schedule, duration = job
    rollout = build_rollout(load_scenario(path), duration=duration, schedule=schedule,
                            plant_mass_scale=draw.mass_scale, plant_mu_scale=draw.mu_scale,
                            plant_inertia_scale=draw.inertia_scale, plant_link_mass_scale=draw.link_mass_scale)
    r = rollout.run(interruptible=False)
    return RunOutcome(draw, r.success, None if r.failure is None else r.failure.kind.value,
                      None if r.failure is None else r.failure.time, r.min_cone_margin, r.min_envelope_margin,
                      None if math.isnan(r.max_object_error_after_transient) else r.max_object_error_after_transient,
                      sum(r.regrasps.values()), r.wall_seconds)


@dataclass(frozen=True)
class StudyResult:
    """A study's runs and their summary.

    Attributes:
        scenario: The scenario file.
        runs: The outcomes, in run order.
        perturbation: The half-widths drawn from.
        seed: The study's seed.
        duration: Each run's simulated time [s].
        workers: The processes that ran it.
        wall_seconds: The study's wall time [s] (the plan included).
    """

    scenario: str
    runs: tuple[RunOutcome, ...]
    perturbation: Perturbation
    seed: int
    duration: float
    workers: int
    wall_seconds: float

    @property
    def successes(self) -> int:
        return sum(r.success for r in self.runs)

    @property
    def success_rate(self) -> float:
        return self.successes / len(self.runs)

    @property
    def interval(self) -> tuple[float, float]:
        """The success rate's Wilson 95 % interval."""
        return wilson_interval(self.successes, len(self.runs))

    @property
    def failures(self) -> dict[str, int]:
        """Failed runs per failure kind."""
        return dict(Counter(r.failure_kind for r in self.runs if not r.success))

    def to_json_dict(self) -> dict:
        """A JSON-serialisable dict (the ``regrasp study --json`` document)."""
        lo, hi = self.interval
        return {"scenario": self.scenario, "seed": self.seed, "duration": self.duration, "workers": self.workers,
                "perturbation": asdict(self.perturbation), "runs": len(self.runs), "successes": self.successes,
                "success_rate": self.success_rate, "wilson_95": [lo, hi], "failures": self.failures,
                "wall_seconds": self.wall_seconds,
                "outcomes": [{**asdict(r), "draw": {**asdict(r.draw), "entropy": list(r.draw.entropy)}}
                             for r in self.runs]}


def run_study(scenario_path: str | Path, runs: int, *, seed: int = 0, perturbation: Perturbation = Perturbation(),
              duration: float | None = None, periods: int | None = None, workers: int = 1,
              progress: Callable[[int, int], None] | None = None) -> StudyResult:
    """Plan the schedule once, then run ``runs`` seeded rollouts on ``workers`` processes (1: in this one).

    ``duration``/``periods`` as in :func:`~regrasp.rollout.build_rollout` (default: the trajectory's domain).
    """
    from .rollout import DEFAULT_CONE_MARGIN, build_rollout
    from .scenario import load_scenario
    from .schedule_planner import RegraspSettings, plan_regrasps

    start = time.perf_counter()
    workers = as_integer("workers", workers, 1)
    draws = draw_runs(runs, seed, perturbation)
    path = str(Path(scenario_path))
    scenario = load_scenario(path)
    probe = build_rollout(scenario, duration=duration, periods=periods,
                          schedule=plan_regrasps(scenario, RegraspSettings(cone_margin=DEFAULT_CONE_MARGIN)))
    jobs = [(path, d, probe.schedule, probe.duration) for d in draws]
    outcomes: list[RunOutcome] = []
    if workers == 1:
        for job in jobs:
            outcomes.append(_run(job))
            if progress is not None:
                progress(len(outcomes), len(jobs))
    else:
        # "spawn", not Linux's default "fork": the parent has run OpenMP code (planning), and forking such a
        # process aborts the child ("fork() called from a process already using GNU OpenMP")
        with ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn")) as pool:
            for outcome in pool.map(_run, jobs):
                outcomes.append(outcome)
                if progress is not None:
                    progress(len(outcomes), len(jobs))
    return StudyResult(path, tuple(outcomes), perturbation, int(seed), probe.duration, workers,
                       time.perf_counter() - start)

"""A suite's results: what each variant did (:class:`VariantOutcome`) and the summary over them
(:class:`SuiteResult`): the fraction with a schedule, why the others have none (grouped), success given a schedule,
the failures by kind, the planning time and peak memory percentiles; as JSON and back.

A plan that ends without a schedule ends for a *physical* reason when its limit is one of :data:`PHYSICAL_LIMITS`
(the envelopes, the slide speeds, the forces, periodicity, the joints' torques, the slides' well-posedness); a
verification that kept failing or a variant the planner refused is not one (:attr:`SuiteResult.unexplained`).
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, fields

import numpy as np

from ..study.study import wilson_interval

__all__ = ["NO_SCHEDULE", "PERCENTILES", "PHYSICAL_LIMITS", "REFUSED", "SCHEDULED", "SuiteResult", "VariantOutcome",
           "percentiles"]

#: A variant's status: planned, a schedule found.
SCHEDULED = "scheduled"
#: Planned, no schedule (:class:`~regrasp.schedule.schedule.NoScheduleError`; its limit says why).
NO_SCHEDULE = "no_schedule"
#: Refused: its scenario, or the planner, refused the variant with a typed error (the error's type is its limit).
REFUSED = "refused"
#: The limits (:class:`~regrasp.schedule.schedule.ScheduleLimit` values) that are physical reasons for no schedule.
PHYSICAL_LIMITS = ("envelope", "speed", "forces", "periodic", "torque", "painleve")
#: The percentiles a suite reports: (label, percent).
PERCENTILES = (("p50", 50.0), ("p90", 90.0), ("p95", 95.0), ("max", 100.0))


def percentiles(values: list[float]) -> dict[str, float] | None:
    """The :data:`PERCENTILES` of ``values`` (numpy's linear interpolation), or None when there are none."""
    if not values:
        return None
    arr = np.asarray(values, dtype=float)
    return {label: float(np.percentile(arr, q)) for label, q in PERCENTILES}


@dataclass(frozen=True)
class VariantOutcome:
    """What one variant did.

    Attributes:
        index: Its number in the suite.
        entropy: Its seed words (:class:`~regrasp.suite.variants.Variant`).
        parameters: Its drawn values, (key, value) in the spec's order.
        fingers: Its number of fingers (0: its scenario could not be built).
        status: :data:`SCHEDULED`, :data:`NO_SCHEDULE` or :data:`REFUSED`.
        limit: Without a schedule: the planner's limit (a ScheduleLimit value), or the refusing error's type name.
        contacts: The contacts the limit names.
        reason: Without a schedule: the planner's or the error's message.
        latest_time: Without a schedule: the latest time any admissible state survives [s] (None: refused).
        slides: With a schedule: its slides (per period when it is periodic).
        plan_seconds: The planning's wall time [s], envelope and schedule (None: refused before planning).
        envelope_seconds: The envelope plan's part of it [s].
        peak_memory: The worker process's peak resident set size while planning [B] (None: not measured).
        memory_upper_bound: True when that peak could not be reset before planning: the process's peak so far.
        cold: The first plan in its process (it also loaded the planner's compiled kernels).
        success: The rollout on the plant succeeded (None: not run: no schedule, or plan only).
        failure_kind: Its failure's kind (a FailureKind value), or None.
        failure_time: When it failed [s], or None.
        failure_contact: The finger the failure names, or None.
        run_seconds: The rollout's wall time [s], or None.
    """

    index: int
    entropy: tuple[int, ...]
    parameters: tuple[tuple[str, object], ...]
    fingers: int
    status: str
    limit: str | None = None
    contacts: tuple[str, ...] = ()
    reason: str | None = None
    latest_time: float | None = None
    slides: int | None = None
    plan_seconds: float | None = None
    envelope_seconds: float | None = None
    peak_memory: int | None = None
    memory_upper_bound: bool = False
    cold: bool = False
    success: bool | None = None
    failure_kind: str | None = None
    failure_time: float | None = None
    failure_contact: str | None = None
    run_seconds: float | None = None

    @property
    def scheduled(self) -> bool:
        return self.status == SCHEDULED

    @property
    def physical(self) -> bool:
        """Whether it has a schedule, or has none for a physical reason (:data:`PHYSICAL_LIMITS`)."""
        return self.scheduled or (self.status == NO_SCHEDULE and self.limit in PHYSICAL_LIMITS)

    @property
    def ran(self) -> bool:
        """Whether its rollout ran."""
        return self.success is not None

    @property
    def outcome(self) -> str:
        """In one word: ``success``, the failure's kind, ``scheduled`` (not run), or why there is no schedule
        (``no_schedule: <limit>``, ``refused: <error>``)."""
        if self.ran:
            return "success" if self.success else str(self.failure_kind)
        if self.scheduled:
            return SCHEDULED
        return f"{self.status}: {self.limit}"

    def to_json_dict(self) -> dict:
        doc = {f.name: getattr(self, f.name) for f in fields(self)}
        doc.update(entropy=list(self.entropy), contacts=list(self.contacts),
                   parameters={k: v for k, v in self.parameters})
        return doc

    @classmethod
    def from_json_dict(cls, doc: dict) -> VariantOutcome:
        """The outcome :meth:`to_json_dict` wrote."""
        values = dict(doc)
        values.update(entropy=tuple(doc["entropy"]), contacts=tuple(doc["contacts"]),
                      parameters=tuple(doc["parameters"].items()))
        return cls(**values)


@dataclass(frozen=True)
class SuiteResult:
    """A suite's variants and their summary.

    Attributes:
        name: The suite's name.
        spec: The spec's file (or name).
        scenario: The base scenario's file.
        seed: The suite's seed.
        requested: The variants it was asked for.
        varied: The varied keys, in the spec's order.
        outcomes: The variants that finished, in index order.
        plant: The plant the rollouts ran on (``project``, ``mujoco``, ``drake``).
        periods: Each rollout's periods (a periodic trajectory; else its whole domain).
        plan_only: Planned only, no rollout.
        workers: The processes that ran it (Ray: the CPUs asked for).
        backend: ``"process"`` or ``"ray"``.
        wall_seconds: The suite's wall time [s].
    """

    name: str
    spec: str
    scenario: str
    seed: int
    requested: int
    varied: tuple[str, ...]
    outcomes: tuple[VariantOutcome, ...]
    plant: str = "project"
    periods: int = 2
    plan_only: bool = False
    workers: int = 1
    backend: str = "process"
    wall_seconds: float = 0.0

    @property
    def interrupted(self) -> bool:
        """Whether Ctrl-C ended it before every variant finished."""
        return len(self.outcomes) < self.requested

    @property
    def scheduled(self) -> tuple[VariantOutcome, ...]:
        return tuple(o for o in self.outcomes if o.scheduled)

    @property
    def schedule_interval(self) -> tuple[float, float]:
        """The fraction with a schedule's Wilson 95 % interval ([0, 1]: no variant finished)."""
        return wilson_interval(len(self.scheduled), len(self.outcomes)) if self.outcomes else (0.0, 1.0)

    @property
    def reasons(self) -> list[tuple[str, str, tuple[str, ...], tuple[int, ...]]]:
        """Why the variants without a schedule have none, grouped by (status, limit, contacts): (status, limit,
        contacts, the variants' indices), the largest group first."""
        groups: dict[tuple[str, str, tuple[str, ...]], list[int]] = {}
        for o in self.outcomes:
            if not o.scheduled:
                groups.setdefault((o.status, str(o.limit), o.contacts), []).append(o.index)
        ordered = sorted(groups.items(), key=lambda kv: (-len(kv[1]), kv[0]))
        return [(status, limit, contacts, tuple(indices)) for (status, limit, contacts), indices in ordered]

    @property
    def unexplained(self) -> tuple[VariantOutcome, ...]:
        """The variants whose plan ended without a schedule and without a physical reason (:data:`PHYSICAL_LIMITS`)."""
        return tuple(o for o in self.outcomes if not o.physical)

    @property
    def ran(self) -> tuple[VariantOutcome, ...]:
        """The variants whose rollout ran."""
        return tuple(o for o in self.outcomes if o.ran)

    @property
    def successes(self) -> int:
        return sum(bool(o.success) for o in self.ran)

    @property
    def success_interval(self) -> tuple[float, float]:
        """Success given a schedule: its Wilson 95 % interval over the rollouts that ran ([0, 1]: none ran)."""
        return wilson_interval(self.successes, len(self.ran)) if self.ran else (0.0, 1.0)

    @property
    def failures(self) -> dict[str, int]:
        """Failed rollouts per failure kind."""
        return dict(Counter(str(o.failure_kind) for o in self.ran if not o.success))

    @property
    def plan_seconds(self) -> dict[str, float] | None:
        """The planning times' :data:`PERCENTILES` [s] (every variant that was planned), or None."""
        return percentiles([o.plan_seconds for o in self.outcomes if o.plan_seconds is not None])

    @property
    def peak_memory(self) -> dict[str, float] | None:
        """The planning's peak memory :data:`PERCENTILES` [B], or None."""
        return percentiles([o.peak_memory for o in self.outcomes if o.peak_memory is not None])

    def to_json_dict(self) -> dict:
        """A JSON-serialisable dict (the ``regrasp suite --json`` document): the settings, the summary and every
        variant's outcome."""
        lo, hi = self.schedule_interval
        slo, shi = self.success_interval
        n = len(self.outcomes)
        return {"name": self.name, "spec": self.spec, "scenario": self.scenario, "seed": self.seed,
                "requested": self.requested, "varied": list(self.varied), "plant": self.plant,
                "periods": self.periods, "plan_only": self.plan_only, "workers": self.workers,
                "backend": self.backend, "wall_seconds": self.wall_seconds, "variants": n,
                "interrupted": self.interrupted, "scheduled": len(self.scheduled),
                "schedule_fraction": len(self.scheduled) / n if n else None, "schedule_wilson_95": [lo, hi],
                "reasons": [{"status": s, "limit": limit, "contacts": list(c), "variants": list(i)}
                            for s, limit, c, i in self.reasons],
                "unexplained": [o.index for o in self.unexplained],
                "ran": len(self.ran), "successes": self.successes,
                "success_rate": self.successes / len(self.ran) if self.ran else None,
                "success_wilson_95": [slo, shi], "failures": self.failures,
                "plan_seconds": self.plan_seconds, "peak_memory_bytes": self.peak_memory,
                "memory_upper_bound": any(o.memory_upper_bound for o in self.outcomes),
                "outcomes": [o.to_json_dict() for o in self.outcomes]}

    @classmethod
    def from_json_dict(cls, doc: dict) -> SuiteResult:
        """The result :meth:`to_json_dict` wrote (its summary is recomputed from the outcomes)."""
        names = {f.name for f in fields(cls)} - {"outcomes", "varied"}
        values = {k: doc[k] for k in names if k in doc}
        return cls(varied=tuple(doc["varied"]), outcomes=tuple(VariantOutcome.from_json_dict(o)
                                                                for o in doc["outcomes"]), **values)


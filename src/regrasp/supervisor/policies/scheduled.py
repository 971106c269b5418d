r"""The schedule-following policy (:class:`ScheduledPolicy`, its settings :class:`ScheduledSettings`).

:class:`ScheduledPolicy` follows a :class:`~regrasp.schedule.schedule.RegraspSchedule` planned ahead
(:func:`~regrasp.schedule.planner.plan_regrasps`): it primes each slide ``prime_lead`` before the
schedule starts it and hands the executor the slide's profile as ξ_d(t). It **re-plans** from the
measured state over the rest of the run (``replan(t, xi)``, logged with the reason) when a slide ends
more than ``time_tolerance`` early or late or more than ``xi_tolerance`` from its planned end, or
when a contact's runtime envelope margin falls below ``margin_fraction`` of the planned one. A
re-plan waits until no slide is under way; a failed re-plan is logged and the old schedule kept.
:class:`~regrasp.supervisor.policies.paper.PaperPolicy` is the paper's danger-zone heuristic;
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from typing import TYPE_CHECKING

import numpy as np

from ...core.events import Event, EventKind
from ...core.exceptions import InvalidParameterError, RegraspError
from ...schedule.schedule import RegraspSchedule
from ..monitor import EnvelopeReading
from ..settings import ScheduledSettings
from ..types import ContactPhase, SlideEnd, SlideOrder, SlideProfile

if TYPE_CHECKING:
    from ...core.measurement import Measurement

__all__ = ["ScheduledPolicy"]




class ScheduledPolicy:
    """Follows a regrasp schedule and re-plans it when reality drifts (module docstring).

    Args:
        schedule: The schedule (a periodic one repeats).
        names: Finger names, contact order.
        replan: (t [s], measured ξ (m,) [m]) -> a new schedule from there over the rest of the run, or
            None (never re-plan). It may raise :class:`~regrasp.core.exceptions.RegraspError` (logged).
        settings: :class:`ScheduledSettings`.
    """

    name = "scheduled"

    def __init__(self, schedule: RegraspSchedule, names: Iterable[str], *,
                 replan: Callable[..., RegraspSchedule] | None = None,
                 settings: ScheduledSettings = ScheduledSettings()):
        if not isinstance(schedule, RegraspSchedule):
            raise InvalidParameterError("schedule", schedule, "a RegraspSchedule (regrasp.plan_regrasps)")
        self.names = tuple(names)
        if schedule.m != len(self.names):
            raise InvalidParameterError("schedule", schedule.names, f"a schedule of {len(self.names)} contacts")
        self.settings = settings
        period = schedule.t_end - schedule.t_start
        if schedule.periodic and settings.decision_period >= period:
            raise InvalidParameterError("settings.decision_period", settings.decision_period,
                                        f"a decision period shorter than the schedule's period ({period:.6g} s)")
        self.replan_function = replan
        self.schedules: list[tuple[float, RegraspSchedule]] = []  # (from when, schedule), the last in force
        self.replans = 0
        self._pending: str | None = None     # why a re-plan is due (done once no slide is under way)
        self._cooldown_until = -math.inf
        self._next_decision = -math.inf      # decide at the first step at or after it (settings.decision_period)
        self._phases: tuple = ()             # the phases at the last decision
        self.adopt(schedule, schedule.t_start)

    @property
    def schedule(self) -> RegraspSchedule:
        """The schedule in force."""
        return self.schedules[-1][1]

    def adopt(self, schedule: RegraspSchedule, since: float) -> None:
        """Follow ``schedule`` from ``since`` [s] on (a re-plan's, or one a planning stack hands over); the slides
        already issued are forgotten, the schedules before stay in :attr:`schedules`."""
        self.schedules.append((float(since), schedule))
        self._issued: set[tuple[int, int]] = set()  # (period, slide index)
        self._since = float(since)

    def _event(self, out: list, t: float, i: int | None, kind: EventKind, detail: str, **values) -> None:
        out.append(Event(float(t), "" if i is None else self.names[i], kind, detail, values=values))

    def planned_xi(self, t: float | np.ndarray) -> np.ndarray:
        """ξ where the schedule in force puts each contact at time(s) ``t`` [s]: (m,), or (k, m) for k times."""
        return self.schedule.at(t if isinstance(t, np.ndarray) else float(t)).xi

    def planned_xi_series(self, times: np.ndarray) -> np.ndarray:
        """:meth:`planned_xi` at each of ``times`` [s] (k,) with the schedule that was in force then (the last
        one adopted at or before it), (k, m)."""
        times = np.asarray(times, dtype=float)
        since = np.array([s for s, _ in self.schedules])
        which = np.maximum(np.searchsorted(since, times, side="right") - 1, 0)
        out = np.empty((times.size, len(self.names)))
        for j in np.unique(which).tolist():
            at = which == j
            out[at] = self.schedules[j][1].at(times[at]).xi
        return out

    def _occurrences(self, t: float):
        """(period k, slide index, slide, offset [s]) of the schedule's slides around time t."""
        sch = self.schedule
        if not sch.periodic:
            for n, s in enumerate(sch.slides):
                yield 0, n, s, 0.0
            return
        period = sch.t_end - sch.t_start
        k0 = math.floor((t - sch.t_start) / period)
        for k in (k0, k0 + 1):
            for n, s in enumerate(sch.slides):
                yield k, n, s, k * period

    def _planned_margin(self, t: float) -> np.ndarray:
        sch = self.schedule
        k = min(int(sch.times.searchsorted(sch.local_time_at(t))), len(sch.times) - 1)
        return sch.envelope_margin[k]

    def propose(self, meas: Measurement, reading: EnvelopeReading, phases: Sequence[ContactPhase],
                out: list[Event]) -> list[SlideOrder]:
        t = float(meas.t)
        if t < self._next_decision and tuple(phases) == self._phases:
            return []  # nothing happened and nothing is due before the next decision
        self._phases = tuple(phases)
        orders = self._decide(meas, reading, phases, out)
        self._next_decision = self._decision_after(t)
        return orders

    def quiet_until(self, phases: Sequence[ContactPhase]) -> float:
        """Until when [s] :meth:`propose` is sure to return nothing while the phases stay ``phases``: the next
        decision's time (-inf: it decides at the next step). Compiled stretches (:mod:`regrasp.rollout.stretch`) end
        there."""
        return self._next_decision if tuple(phases) == self._phases else -math.inf

    def stretch_view(self, t: float) -> dict | None:
        """What a compiled stretch (:mod:`regrasp.rollout.stretch`) from time ``t`` [s] needs to take this policy's
        decisions where they are sure to order nothing (no slide due, no re-plan pending, the margins above their
        threshold; any other decision is handed to :meth:`propose`): when the next slide is due [s], when the stretch
        must end at the latest (the schedule period's end, past which other slides come into view) [s], the re-plan
        test's terms and the schedule's planned margins; None when a re-plan is pending."""
        if self._pending is not None:
            return None
        sch = self.schedule
        due = math.inf
        lead = self.settings.prime_lead
        for k, n, slide, offset in self._occurrences(t):
            start = slide.start + offset
            if (k, n) not in self._issued and start >= self._since - 1e-9:
                due = min(due, start - lead - 1e-9)
        end = math.inf
        if sch.periodic:
            period = sch.t_end - sch.t_start
            end = sch.t_start + (math.floor((t - sch.t_start) / period) + 1) * period
        return {"decision_period": self.settings.decision_period, "slide_due": due, "end": end,
                "replan": self.replan_function is not None, "cooldown_until": self._cooldown_until,
                "margin_fraction": self.settings.margin_fraction, "schedule_start": sch.t_start,
                "schedule_end": sch.t_end, "periodic": sch.periodic, "times": sch.times,
                "margins": sch.envelope_margin}

    def take_stretch(self, next_decision: float) -> None:
        """After a compiled stretch that took this policy's decisions (none ordered anything): the next one's
        time [s]."""
        self._next_decision = float(next_decision)

    def _decision_after(self, t: float) -> float:
        """When the next decision is due after one at time ``t`` [s]: a period later, or at the next
        unissued slide's priming start (-inf: at the next step)."""
        period = self.settings.decision_period
        if period == 0.0:
            return -math.inf
        due = t + period - 1e-9  # (on the plant's clock, t + k dt may fall short of t + period by an ulp)
        lead = self.settings.prime_lead
        for k, n, slide, offset in self._occurrences(t):  # (this period and the next: period < P)
            start = slide.start + offset
            if (k, n) not in self._issued and start >= self._since - 1e-9:
                due = min(due, start - lead - 1e-9)
        return due

    def _decide(self, meas: Measurement, reading: EnvelopeReading, phases: Sequence[ContactPhase],
                out: list[Event]) -> list[SlideOrder]:
        """:meth:`propose`'s decision."""
        t = float(meas.t)
        s = self.settings
        idle = all(p is ContactPhase.FIXED for p in phases)
        if self._pending is None and t >= self._cooldown_until and self.replan_function is not None:
            planned = self._planned_margin(t)
            for i in range(len(self.names)):
                if reading.margins[i] < s.margin_fraction * planned[i]:
                    self._pending = (f"{self.names[i]}'s envelope margin {reading.margins[i] * 1e3:.2f} mm is below "
                                     f"{s.margin_fraction:g} x the planned {planned[i] * 1e3:.2f} mm")
                    break
        if self._pending is not None and idle:
            self._replan(meas, out)
        orders = []
        for k, n, slide, offset in self._occurrences(t):
            start = slide.start + offset
            if (k, n) in self._issued or start < self._since - 1e-9 or t < start - s.prime_lead - 1e-9:
                continue
            if start + slide.duration <= t:  # (missed entirely: only after a re-plan's start)
                self._issued.add((k, n))
                continue
            i = slide.contact
            if phases[i] is not ContactPhase.FIXED:
                continue  # its previous slide has not settled: the order waits (and will be late)
            self._issued.add((k, n))
            orders.append(SlideOrder(i, int(slide.direction), float(slide.end_xi), SlideProfile(slide, offset), start,
                                     slide.end + offset, why=f"scheduled {start:.3f}-{slide.end + offset:.3f} s"))
        return orders

    def notify(self, ends: list[SlideEnd], meas: Measurement, out: list[Event]) -> None:
        s = self.settings
        self._next_decision = -math.inf  # decide at the next step
        for end in ends:
            order = end.order
            if order.planned_end is None or self._pending is not None or self.replan_function is None:
                continue
            late = end.time - order.planned_end
            off = end.xi - order.target
            if abs(late) > s.time_tolerance or abs(off) > s.xi_tolerance:
                name = self.names[order.contact]
                self._pending = (f"{name}'s slide ended {end.kind.value} at t = {end.time:.3f} s, xi = "
                                 f"{end.xi * 1e3:.2f} mm (planned {order.planned_end:.3f} s, "
                                 f"{order.target * 1e3:.2f} mm)")

    def _replan(self, meas, out: list) -> None:
        t = float(meas.t)
        why, self._pending = self._pending, None
        self._cooldown_until = t + self.settings.replan_cooldown
        if self.replans >= self.settings.max_replans:
            self._event(out, t, None, EventKind.REPLAN_FAILED, f"{why}; no re-plan: max_replans = "
                        f"{self.settings.max_replans} reached")
            return
        self.replans += 1
        try:
            schedule = self.replan_function(t, meas.xi.copy())
        except RegraspError as exc:
            self._event(out, t, None, EventKind.REPLAN_FAILED, f"{why}; re-plan failed: {exc}; keeping the schedule")
            return
        self.adopt(schedule, t)
        self._event(out, t, None, EventKind.REPLAN, f"{why}; re-planned from t = {t:.3f} s: {len(schedule.slides)} "
                    f"slide(s) to t = {schedule.t_end:.3f} s", slides=len(schedule.slides), until=schedule.t_end)

r"""The paper's regrasp heuristic (§4) as a policy: slide a contact out of its danger zone.

At each step, for each fixed contact whose margin to the nearer bound of its feasible interval is
below ``danger_fraction`` × the interval's width (its *danger zone*), or that the plan squeezes within
``reaction_time`` (without a plan: that a bound reaches at its current rate within it), the policy
orders a slide to the middle of what stays feasible over ``target_horizon`` (the planner's
prefix-intersection rule), driven by the executor's second-order filter, but only if
:func:`~regrasp.dynamics.sliding.sliding_feasibility` accepts that direction at ``path_checks`` points from the
contact to the target (at the desired pose and acceleration of when the filter passes there).
Otherwise it looks for a slide of another contact that makes it possible and orders that first
(``enabling``), or logs why and waits. It orders at most one slide at a time, so p ≤ 1.

This is the baseline the scheduled policy (:class:`~regrasp.supervisor.policies.scheduled.ScheduledPolicy`) is compared
with: it decides from the present, one contact at a time, and cannot see that a slide it postpones
will become impossible.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from ...core.events import Event, EventKind
from ...core.intervals import intersect, widest
from ...dynamics.internal_force.solver import InternalForceSolver
from ...dynamics.sliding import sliding_feasibility
from ..monitor import EnvelopeReading, interval_of
from ..types import ContactPhase, SlideOrder

if TYPE_CHECKING:
    from ...core.measurement import Measurement
    from ..settings import SupervisorSettings
    from ..types import SlideEnd, SupervisorContext

__all__ = ["PaperPolicy"]


def _single_intervals(samples) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(lo, hi, single) per planned sample: the bounds where the feasible set is one interval."""
    single = np.array([len(s.feasible) == 1 for s in samples])
    lo = np.array([s.feasible[0][0] if len(s.feasible) == 1 else np.nan for s in samples])
    hi = np.array([s.feasible[0][1] if len(s.feasible) == 1 else np.nan for s in samples])
    return lo, hi, single


class PaperPolicy:
    """The danger-zone heuristic (module docstring).

    Args:
        context: A :class:`~regrasp.supervisor.types.SupervisorContext` (hand, grasp, trajectory, friction,
            object mass and inertia, the plan).
        settings: A :class:`~regrasp.supervisor.settings.SupervisorSettings` (danger zone, horizons, predicate
            margins, enabling search; the slide filter's ω_n and the priming overshoot).
    """

    name = "paper"

    def __init__(self, context: SupervisorContext, settings: SupervisorSettings):
        self.c = context
        self.settings = settings
        self.paper, self.executor = settings.paper, settings.executor
        m = context.hand.m
        plan = context.plan
        self._plan_bounds = None if plan is None else [_single_intervals(f.samples) for f in plan.fingers]
        self._rejected: dict[int, tuple] = {}    # last logged rejection per contact (once per obstacle)
        self._in_danger = [False] * m
        self._recheck = [-math.inf] * m         # when a rejected slide may be asked about again
        self._enable_recheck = [-math.inf] * m  # when to search for an enabling slide again
        self._feasibility = InternalForceSolver(settings.paper.feasibility)  # the predicate's persistent QP

    def planned_xi(self, t: float) -> np.ndarray:
        """No planned contact positions (NaN per contact)."""
        return np.full(self.c.hand.m, np.nan)

    def notify(self, ends: list[SlideEnd], meas: Measurement, out: list[Event]) -> None:
        """Nothing to learn from a finished slide."""

    def _event(self, out: list, t: float, i: int, kind: EventKind, detail: str, **values) -> None:
        out.append(Event(float(t), self.c.names[i], kind, detail, values=values))

    # ------------------------------------------------------------------ the plan
    def _plan_index(self, t: float) -> int:
        return max(0, int(np.searchsorted(self.c.plan.times, t, side="right")) - 1)

    def _squeezed_ahead(self, i: int, t: float, xi: float) -> float | None:
        """The first planned time within ``reaction_time`` where ξ is in a danger zone or outside."""
        times = self.c.plan.times
        k0 = self._plan_index(t)
        k1 = int(np.searchsorted(times, t + self.paper.reaction_time, side="right"))
        lo, hi, single = (a[k0:k1] for a in self._plan_bounds[i])
        bad = single & (np.minimum(xi - lo, hi - xi) < self.paper.danger_fraction * (hi - lo))
        samples = self.c.plan.fingers[i].samples
        for k in np.flatnonzero(~single):
            sample = samples[k0 + k]
            iv = interval_of(sample, xi)
            bad[k] = iv is None or sample.margin(xi) < self.paper.danger_fraction * (iv[1] - iv[0])
        hits = np.flatnonzero(bad)
        return float(times[k0 + hits[0]]) if hits.size else None

    def kept_feasible(self, i: int, t: float,
                      interval: tuple[float, float]) -> tuple[tuple[float, float], float | None]:
        """The widest piece of ``interval`` the plan keeps feasible for contact i over
        [t, t + target_horizon] (or its longest prefix with a non-empty intersection), and until when."""
        if self.c.plan is None:
            return interval, None
        prefix, until = (interval,), None
        for sample in self.c.plan.fingers[i].samples[self._plan_index(t):]:
            if sample.time > t + self.paper.target_horizon:
                break
            nxt = intersect(prefix, sample.feasible)
            if not nxt:
                break
            prefix, until = nxt, sample.time
        return widest(prefix), until

    # ------------------------------------------------------------------ the predicate
    def _verdict(self, i: int, direction: float, xi, target: float, t: float):
        """The predicate at ``path_checks`` points of contact i's slide from xi[i] to ``target``:
        (the first rejection, or the last acceptance; the ξ_i [m] where it was asked)."""
        s, c = self.paper, self.c
        n = s.path_checks
        duration = 6.0 / self.executor.omega_n  # a critically damped filter covers ~98 % of a step in 6/ω_n
        xi = np.array(xi, dtype=float)
        start = xi[i]
        for k in range(n):
            fraction = k / (n - 1) if n > 1 else 0.0
            xi[i] = start + fraction * (target - start)
            desired = c.trajectory.sample(min(t + fraction * duration, c.trajectory.t_end))
            # where it starts, the priming asks for μ_s + overshoot (it must break away); on the way μ_k
            edge_mu = c.friction[i].static + self.executor.prime_overshoot if k == 0 else None
            verdict = sliding_feasibility(
                c.grasp, desired.pose, xi, desired.acceleration, i, direction, c.friction,
                object_mass=c.object_mass, object_inertia=c.object_inertia, gravity_in_hand=c.hand.gravity_in_hand,
                settings=s.feasibility, solver=self._feasibility, edge_mu=edge_mu)
            if not verdict.possible:
                break
        return verdict, float(xi[i])

    def _enabling(self, meas, reading: EnvelopeReading, phases, i: int, direction: float, target: float):
        """A slide of another fixed contact k after which contact i's rejected slide is possible:
        (k, ξ_k*) with the nearest such ξ_k* over the candidates, or None."""
        s = self.paper
        later = meas.t + 6.0 / self.executor.omega_n  # contact i slides once k has arrived
        for k in range(self.c.hand.m):
            lo, hi = reading.bounds[k]
            if k == i or phases[k] is not ContactPhase.FIXED or not math.isfinite(hi - lo):
                continue
            (plo, phi), _ = self.kept_feasible(k, meas.t, (lo, hi))
            keep = s.danger_fraction * (phi - plo)
            candidates = np.linspace(plo + keep, phi - keep, s.enabling_candidates) if phi - plo > 0 else []
            for target_k in sorted(candidates, key=lambda x: abs(x - meas.xi[k])):
                if abs(target_k - meas.xi[k]) < 2.0 * self.executor.arrive_tolerance:
                    continue
                moved = meas.xi.copy()
                moved[k] = target_k
                if not self._verdict(i, direction, moved, target, later)[0].possible:
                    continue
                if self._verdict(k, 1.0 if target_k > meas.xi[k] else -1.0, meas.xi, target_k, meas.t)[0].possible:
                    return k, float(target_k)
        return None

    # ------------------------------------------------------------------ the decision
    def propose(self, meas: Measurement, reading: EnvelopeReading, phases: Sequence[ContactPhase],
                out: list[Event]) -> list[SlideOrder]:
        """At most one slide order, for the most urgently endangered contact whose slide is possible."""
        s = self.paper
        danger = []
        for i in range(self.c.hand.m):
            lo, hi = reading.bounds[i]
            width = hi - lo
            if not np.isfinite(width) or phases[i] is not ContactPhase.FIXED:
                self._in_danger[i] = False
                continue
            why, urgency = "", meas.t
            if reading.margins[i] < s.danger_fraction * width:
                why = "in the danger zone"
            elif self.c.plan is not None:
                when = self._squeezed_ahead(i, meas.t, meas.xi[i])
                if when is not None:
                    why, urgency = f"the plan squeezes it at t = {when:.3f} s", when
            else:
                reach = reading.time_to_bound(i, meas.xi[i])
                if reach < s.reaction_time:
                    why = f"a bound arrives in {reach:.3f} s"
            if why and not self._in_danger[i]:
                self._event(out, meas.t, i, EventKind.DANGER, f"xi = {meas.xi[i] * 1e3:.2f} mm, feasible "
                            f"[{lo * 1e3:.2f}, {hi * 1e3:.2f}] mm, margin {reading.margins[i] * 1e3:.2f} mm: {why}",
                            xi=float(meas.xi[i]), lo=float(lo), hi=float(hi), margin=float(reading.margins[i]))
            if not why:
                self._rejected.pop(i, None)
            self._in_danger[i] = bool(why)
            if why:
                danger.append((urgency, reading.margins[i] / width, i))
        if not s.regrasp or not danger or any(p is not ContactPhase.FIXED for p in phases):
            return []
        for *_, i in sorted(danger):  # the soonest squeezed first
            if meas.t < self._recheck[i]:
                continue
            (plo, phi), until = self.kept_feasible(i, meas.t, tuple(reading.bounds[i]))
            target = 0.5 * (plo + phi)
            if abs(target - meas.xi[i]) < 2.0 * self.executor.arrive_tolerance:
                continue  # already where a slide would take it
            direction = 1 if target > meas.xi[i] else -1
            verdict, where = self._verdict(i, direction, meas.xi, target, meas.t)
            if verdict.possible:
                self._rejected.pop(i, None)
                return [SlideOrder(i, direction, float(target), why=f"feasible [{plo * 1e3:.2f}, {phi * 1e3:.2f}] mm"
                                   + (f", planned feasible until t = {until:.3f} s" if until is not None else ""))]
            key = (direction, verdict.obstacle, where != meas.xi[i])
            if self._rejected.get(i) != key:  # log each kind of rejection once per danger episode
                self._event(out, meas.t, i, EventKind.SLIDE_REJECTED,
                            f"slide {'+' if direction > 0 else '-'}xi rejected: {verdict.reason}"
                            + (f" (at xi = {where * 1e3:.2f} mm on the way)" if where != meas.xi[i] else "")
                            + "; waiting", direction=direction, at_xi=where)
                self._rejected[i] = key
            self._recheck[i] = meas.t + s.recheck_time
            if s.enabling and meas.t >= self._enable_recheck[i]:
                self._enable_recheck[i] = meas.t + s.enabling_recheck_time
                found = self._enabling(meas, reading, phases, i, direction, target)
                if found is not None:
                    k, target_k = found
                    return [SlideOrder(k, 1 if target_k > meas.xi[k] else -1, target_k,
                                       why=f"to let {self.c.names[i]} slide {'+' if direction > 0 else '-'}xi")]
        return []

r"""Regrasp policies: who decides which contact slides, where and when.

A policy *proposes*; the executor (:class:`~regrasp.supervisor.executor.SlideExecutor`) runs; the envelope
monitor (:class:`~regrasp.supervisor.monitor.EnvelopeMonitor`) watches. Every policy has

* ``propose(meas, reading, phases, out) -> list[SlideOrder]``: the slides to start now, given the
  measurement, the monitor's reading and each contact's phase (decisions it logs go to ``out``);
* ``notify(ends, meas, out)``: how the slides it ordered ended;
* ``planned_xi(t) -> (m,)``: where it plans each contact to be at time t [m] (NaN: no plan).

and may have, for the compiled stretches of a rollout (:mod:`regrasp.rollout.stretch`: the steps between decisions
in one compiled call), ``quiet_until(phases)``: until when ``propose`` is sure to return nothing while the
phases stay the same; and ``stretch_view(t)`` / ``take_stretch(next_decision)``: what the compiled code needs
to take the decisions that order nothing itself (:class:`ScheduledPolicy`'s: no slide due, no re-plan
pending, every margin above its threshold). A policy without them is asked at every step.

:class:`NoRegraspPolicy` never slides; :class:`OrderedSlidesPolicy` starts given slides at given times
(one slide on its own, e.g. Figure 3.4's on a plant); the schedule-following
:class:`~regrasp.supervisor.policies.scheduled.ScheduledPolicy` and the paper's
:class:`~regrasp.supervisor.policies.paper.PaperPolicy` are in their own modules.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Protocol

import numpy as np

from ...core.events import Event
from ...core.exceptions import InvalidParameterError
from ...core.measurement import Measurement
from ...core.validation import as_integer, expect_sequence_of
from ..monitor import EnvelopeReading
from ..types import ContactPhase, SlideEnd, SlideOrder

__all__ = ["NoRegraspPolicy", "OrderedSlidesPolicy", "Policy"]


class Policy(Protocol):
    """What the supervisor asks of a policy (module docstring)."""

    name: str

    def propose(self, meas: Measurement, reading: EnvelopeReading, phases: Sequence[ContactPhase],
                out: list[Event]) -> list[SlideOrder]: ...

    def notify(self, ends: list[SlideEnd], meas: Measurement, out: list[Event]) -> None: ...

    def planned_xi(self, t: float) -> np.ndarray: ...


class NoRegraspPolicy:
    """Never slides: every contact stays where it is (for comparison runs)."""

    name = "none"

    def __init__(self, m: int):
        self.m = int(m)

    def propose(self, meas: Measurement, reading: EnvelopeReading, phases: Sequence[ContactPhase],
                out: list[Event]) -> list[SlideOrder]:
        return []

    def quiet_until(self, phases: Sequence[ContactPhase]) -> float:
        """It never proposes: inf (see :meth:`ScheduledPolicy.quiet_until`)."""
        return math.inf

    def notify(self, ends: list[SlideEnd], meas: Measurement, out: list[Event]) -> None:
        pass

    def planned_xi(self, t: float) -> np.ndarray:
        return np.full(self.m, np.nan)


class OrderedSlidesPolicy:
    """Starts each given :class:`~regrasp.supervisor.types.SlideOrder` at its ``planned_start`` [s] (a contact that is
    not fixed then gets its order when it is), and nothing else.

    Args:
        orders: The slides, each with a ``planned_start``.
        m: The number of contacts.
    """

    name = "ordered"

    def __init__(self, orders: Sequence[SlideOrder], m: int):
        orders = expect_sequence_of("orders", orders, SlideOrder, "SlideOrders")
        if not all(o.planned_start is not None for o in orders):
            raise InvalidParameterError("orders", orders, "SlideOrders, each with a planned_start")
        self.m = as_integer("m", m, least=1)
        if not all(o.contact < self.m for o in orders):
            raise InvalidParameterError("orders", orders, f"slides of contacts 0 to {self.m - 1}")
        self.orders = sorted(orders, key=lambda o: o.planned_start)

    def propose(self, meas: Measurement, reading: EnvelopeReading, phases: Sequence[ContactPhase],
                out: list[Event]) -> list[SlideOrder]:
        due = [o for o in self.orders if o.planned_start <= meas.t + 1e-9 and phases[o.contact] is ContactPhase.FIXED]
        for o in due:
            self.orders.remove(o)
        return due

    def notify(self, ends: list[SlideEnd], meas: Measurement, out: list[Event]) -> None:
        pass

    def planned_xi(self, t: float) -> np.ndarray:
        return np.full(self.m, np.nan)

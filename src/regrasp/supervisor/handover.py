r"""The handover hold: at a phase change, every contact's load is released over a time, not in one step.

At a phase change (a contact primed, sliding, settling or fixed again) the law's contact modes and cone edges change,
and the internal-force QP's least squeeze with them: a contact's planned normal force can fall from 0.76 N to its
0.3 N floor in one control step (the default scenario's first priming, MuJoCo study run 87). On a rigid contact the
plant follows; on a compliant one the finger's pad unloads faster than the fingertip's motion can follow and the
contact carries nothing for a few milliseconds: it separates. The hold keeps, as a floor in the laws, each contact's
predicted normal force of the step before the change and releases it linearly,

.. math::
    f_{\mathrm{floor},i}(t) = \min\bigl(f_{\max},\ \bar f_{n,i}\bigr)\,
        \max\Bigl(0,\ 1 - \frac{t - t_c}{T_h}\Bigr),

with :math:`t_c` the change's time, :math:`T_h` ``ExecutorSettings.handover_time`` and :math:`f_{\max}`
``handover_load_max``. A change within a hold starts a new one from the loads of the step before it: a contact primed
past its static cone pushes harder (its tangential force is capped by its cone), and that load, not the one it had
before the priming, is what it must keep when it starts to slide (holding the lesser of the two dropped a break-away
from 1.17 N to 0.49 N in one step on MuJoCo, and it chattered off its edge). The floors
are floors like the others (:meth:`~regrasp.supervisor.executor.SlideExecutor.floors`): where no forces meet them the
fallbacks give them up (:mod:`regrasp.supervisor.fallbacks`). Derived and measured in ``docs/derivations.md``,
"Contact health and keeping the loads".
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["HandoverHold"]


class HandoverHold:
    """The hold of one executor's contacts (module docstring).

    Args:
        m: The number of contacts.
        time: :math:`T_h` [s] (0: no hold).
        load_max: :math:`f_{\\max}` [N].
    """

    def __init__(self, m: int, time: float, load_max: float):
        self.time = float(time)
        self.load_max = float(load_max)
        self._loads = np.zeros(m)            # the last step's predicted normal forces [N]
        self._held = np.zeros(m)             # the loads the hold began with [N]
        self._since = -math.inf              # t_c [s]
        self._phases: tuple | None = None    # the phases of the last step the hold saw

    def note(self, loads_n: np.ndarray) -> None:
        """The predicted normal forces [N] of the step just computed (the law's, or a compiled stretch's last)."""
        self._loads = np.nan_to_num(np.asarray(loads_n, dtype=float), nan=0.0)  # (a step whose solve the compiled
        # path handed over may leave no prediction: no load to hold)

    def changed(self, phases: tuple) -> bool:
        """Whether ``phases`` differ from those of the last step seen (:meth:`see`) and start a hold (never with no
        hold time: the compiled stretches then need not stop at a change)."""
        return self.time > 0.0 and self._phases is not None and tuple(phases) != self._phases

    def active(self, t: float) -> bool:
        """Whether a hold lasts at ``t`` [s]."""
        return t - self._since < self.time

    def see(self, phases: tuple, t: float) -> None:
        """A step at ``t`` [s] with the contacts in ``phases``: a change from the last step's phases starts a hold."""
        phases = tuple(phases)
        if self.changed(phases):
            self._held = np.clip(self._loads, 0.0, self.load_max)
            self._since = t
        self._phases = phases

    def floors(self, t: float) -> np.ndarray:
        """Each contact's floor [N] at ``t`` [s] (zeros where no hold lasts)."""
        if not self.active(t):
            return np.zeros_like(self._held)
        return self._held * max(0.0, 1.0 - (t - self._since) / self.time)

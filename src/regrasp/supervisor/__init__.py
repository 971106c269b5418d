"""``regrasp.supervisor``: Paper §4, at run time: the regrasp supervisor (:class:`RegraspSupervisor`; a monitor watches
the runtime envelopes, a policy proposes slides, an executor runs them), its settings (one tree,
:class:`SupervisorSettings`) and value types; the policies are :mod:`regrasp.supervisor.policies`."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..core.lazy import lazy_exports

if TYPE_CHECKING:
    from .executor import SlideExecutor  # noqa: F401
    from .monitor import EnvelopeMonitor, EnvelopeReading  # noqa: F401
    from .settings import ExecutorSettings, MonitorSettings, PaperSettings, ScheduledSettings, SupervisorSettings  # noqa: F401
    from .supervisor import RegraspSupervisor  # noqa: F401
    from .types import ContactPhase, SlideEnd, SlideOrder, SupervisorContext, SupervisorOutput  # noqa: F401

__getattr__, __dir__, __all__ = lazy_exports(__name__)

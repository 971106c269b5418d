"""``regrasp.envelope``: Paper §2: where a fingertip may touch a moving object. The line geometry of a finger and an
edge (conditions I-IV, the reachable set), one finger's feasible envelope on one edge or on a curved object's
boundary (:class:`FingerEnvelope`, ``ideal`` segments or URDF shapes; :mod:`~regrasp.envelope.curve` for curves),
following it from step to step (:class:`EnvelopeTracker`), the planner over a trajectory (:func:`plan`,
:func:`plan_scenario`) and its figures."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..core.lazy import lazy_exports

if TYPE_CHECKING:
    from .curve import CurveGeometry, CurveSolution  # noqa: F401
    from .curve_evaluator import CurveEvaluator  # noqa: F401
    from .evaluator import ClosedForm, EnvelopeEvaluator  # noqa: F401
    from .finger_envelope import EnvelopeSample, FingerEnvelope  # noqa: F401
    from .line import Condition, EdgeLine, condition_of, reachable_on_line  # noqa: F401
    from .planner import FingerPlan, InfeasibleInterval, PlanResult, plan, plan_scenario  # noqa: F401
    from .plotting import write_plan_figures  # noqa: F401
    from .tracker import EnvelopeTracker  # noqa: F401

__getattr__, __dir__, __all__ = lazy_exports(__name__)

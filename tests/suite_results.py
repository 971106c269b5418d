"""Suite results made by hand (no planning): every status, failure and limit."""

import numpy as np

from regrasp.suite.result import SuiteResult, VariantOutcome

KEYS = ("trajectory.omega", "trajectory.a", "object.mass")


def outcome(i: int, rng: np.random.Generator, **fields) -> VariantOutcome:
    params = tuple((k, float(rng.uniform(1.0, 2.0))) for k in KEYS)
    base = dict(index=i, entropy=(1, 2, 3, i), parameters=params, fingers=3, plan_seconds=float(rng.uniform(3, 9)),
                envelope_seconds=0.05, peak_memory=int(rng.uniform(4e8, 6e8)), cold=i == 0)
    base.update(fields)
    return VariantOutcome(**base)


def made_result(n: int = 20, **options) -> SuiteResult:
    """``n`` variants: no schedule (forces, finger1) at 3, 4 and 9; a verification that kept failing at 5; refused
    at 6; a separation at 7 and an unplanned slip at 8; the others succeed."""
    rng = np.random.default_rng(0)
    special = {
        3: dict(status="no_schedule", limit="forces", contacts=("finger1",), reason="r", latest_time=1.0),
        4: dict(status="no_schedule", limit="forces", contacts=("finger1",), reason="r", latest_time=1.2),
        9: dict(status="no_schedule", limit="forces", contacts=("finger1",), reason="r", latest_time=1.3),
        5: dict(status="no_schedule", limit="verification", contacts=("palm",), reason="v", latest_time=2.0),
        6: dict(status="refused", limit="ScenarioError", reason="bad", fingers=0, plan_seconds=None,
                envelope_seconds=None, peak_memory=None),
        7: dict(status="scheduled", slides=4, success=False, failure_kind="separation", failure_time=1.7,
                failure_contact="finger2", run_seconds=0.5),
        8: dict(status="scheduled", slides=4, success=False, failure_kind="unplanned_slip", failure_time=4.1,
                failure_contact="palm", run_seconds=0.5),
    }
    outcomes = [outcome(i, rng, **special.get(i, dict(status="scheduled", slides=4, success=True, run_seconds=0.5)))
                for i in range(n)]
    values = dict(name="made", spec="examples/suites/made.toml",
                  scenario="examples/scenarios/paper_trajectory_2_three_fingers.toml", seed=5, requested=n,
                  varied=KEYS, outcomes=tuple(outcomes), wall_seconds=10.0)
    values.update(options)
    return SuiteResult(**values)

"""Issue 13's examples: every bad input ends in a typed, one-line error naming what is wrong (or in a
valid result without NaN or inf), never a traceback from deep inside a library, a NaN or a silent accept.

Each case is one of the issue's numbered classes (the number in its id).
"""

import math
from pathlib import Path

import numpy as np
import pytest

from regrasp import (
    ConvexPolygon,
    EllipseTrajectory,
    Finger,
    FingerContact,
    Grasp,
    Plant,
    PlantContact,
    WaypointTrajectory,
    condition_of,
    load_scenario,
    planar_2r_urdf,
    reachable_on_line,
    sliding_feasibility,
)
from regrasp.exceptions import RegraspError
from regrasp.hand import Hand
from regrasp.validation import as_finite_float

ROOT = Path(__file__).resolve().parents[1]
URDF = ROOT / "urdf" / "planar_2r_finger.urdf"
FINGER = Finger.from_urdf(URDF, base_in_hand=(-0.05, 0.0, np.pi / 2), configuration="left", name="f")
BOX = ConvexPolygon.rectangle(0.1, 0.04, mass=0.08)


def plant(**kwargs):
    hand = Hand([FINGER, FINGER.with_placement(base_in_hand=(0.05, 0.0, np.pi / 2), configuration="right",
                                               name="g")])
    contacts = kwargs.pop("contacts", [PlantContact(1, "fixed", 0.0), PlantContact(3, "fixed", 0.0)])
    return Plant(hand, BOX, contacts, friction=0.5, **kwargs)


CASES = {
    "1 huge integer": lambda: as_finite_float("mass", 10**400),
    "1 huge integer in a rectangle": lambda: ConvexPolygon.rectangle(10**400, 0.04),
    "1 huge integer in an ellipse": lambda: EllipseTrajectory(0.0, 0.1, 10**400, 0.05, 2.0),
    "1 huge integer in a URDF": lambda: planar_2r_urdf(10**400, 0.05),
    "4 omega with an infinite period": lambda: EllipseTrajectory(0.0, 0.1, 0.09, 0.05, 1e-308),
    "5 a waypoint pose of 1.8e308": lambda: WaypointTrajectory([0.0, 1.0, 2.0], [[0, 0, 0], [1.8e308, 0, 0], [0, 0, 0]]),
    "12 b = 1e308 overflows the velocity": lambda: EllipseTrajectory(0.0, 0.1, 0.09, 1e308, 2.0),
    "12 beta_a = 1e308 overflows the acceleration": lambda: EllipseTrajectory(0.0, 0.1, 0.09, 0.05, 2.0,
                                                                               beta_a=1e308),
    "12 a plant step of 0.5 s": lambda: plant(dt=0.5),
    "12 a NaN reset time": lambda: plant().reset(np.zeros(4), np.zeros(4), np.array([0.0, 0.12, 0.0]), np.zeros(3),
                                                  t=np.float32("nan")),
    "13 complex numbers": lambda: as_finite_float("x", 1 + 1j),
    "13 stop_on with numbers": lambda: plant(stop_on=[1.0, 2.0]),
    "13 reachable_on_line with NaN": lambda: reachable_on_line(0.05, math.nan, 0.05, 1),
    "13 condition_of with a negative link": lambda: condition_of(0.05, -1.0),
    "13 a negative inertia in the predicate": lambda: sliding_feasibility(
        Grasp(BOX, [1, 3], ["fixed", "fixed"]), [0.0, 0.12, 0.0], [0.0, 0.0], [0.0, 0.0, 0.0], 0, 1, 0.5,
        object_mass=0.08, object_inertia=-1.0),
    "13 omega as a string": lambda: EllipseTrajectory(0.0, 0.1, 0.09, 0.05, "2"),
    "13 an edge as a string": lambda: FingerContact(FINGER, "1"),
    "13 a fixed contact off its edge": lambda: plant(contacts=[PlantContact(1, "fixed", 0.5),
                                                               PlantContact(3, "fixed", 0.0)]),
    "11 a grasp with a NaN edge": lambda: Grasp(BOX, [math.nan, 3], ["fixed", "fixed"]),
    "11 a finger from an integer": lambda: Finger.from_urdf(5),
    "11 a scenario from an integer": lambda: load_scenario(123),
    "11 friction as a string": lambda: Plant(Hand([FINGER]), BOX, [PlantContact(1, "fixed", 0.0)], friction="abc"),
    "11 a contact with a huge xi": lambda: plant(contacts=[PlantContact(1, "fixed", 1e308), PlantContact(3, "fixed", 0.0)]),
    "15 a rectangle 1e308 high": lambda: ConvexPolygon.rectangle(0.1, 1e308),
}


def _no_nan(value) -> bool:
    """Whether a result holds no NaN or inf (arrays, numbers, and trajectories' derivatives)."""
    if isinstance(value, EllipseTrajectory | WaypointTrajectory):
        t = value.times(5)
        return all(np.isfinite(f(t)).all() for f in (value.pose, value.velocity, value.acceleration))
    if isinstance(value, (int, float, np.ndarray)):
        return bool(np.all(np.isfinite(value)))
    return True


@pytest.mark.parametrize("case", list(CASES), ids=list(CASES))
def test_a_bad_input_is_a_typed_one_line_error_or_a_valid_result(case):
    try:
        result = CASES[case]()
    except RegraspError as exc:
        text = str(exc)
        assert "\n" not in text and len(text) < 400, text
        return
    assert result is not None and _no_nan(result), (case, result)
    if case.startswith(("12", "13", "11", "15")):
        pytest.fail(f"{case}: accepted ({result!r})")

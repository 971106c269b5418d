"""Issue 13's examples: every bad input ends in a typed, one-line error naming what is wrong (or in a
valid result without NaN or inf), never a traceback from deep inside a library, a NaN or a silent accept.

Each case is one of the issue's numbered classes (the number in its id).
"""

import math
from pathlib import Path

import numpy as np
import pytest

from hang_guard import HANG_SECONDS
from regrasp import (
    ConvexPolygon,
    EllipseTrajectory,
    Finger,
    Grasp,
    Plant,
    PlantContact,
    RunSpec,
    WaypointTrajectory,
    build_rollout,
    load_scenario,
    plan,
    planar_2r_urdf,
)
from regrasp.core.exceptions import RegraspError
from regrasp.core.validation import as_finite_float
from regrasp.dynamics import sliding_feasibility
from regrasp.envelope import condition_of, reachable_on_line
from regrasp.model import FingerContact
from regrasp.model.hand import Hand

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
    "5 a waypoint pose of 1.8e308": lambda: WaypointTrajectory([0.0, 1.0, 2.0],
                                                               [[0, 0, 0], [1.8e308, 0, 0], [0, 0, 0]]),
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
    "11 a contact with a huge xi": lambda: plant(contacts=[PlantContact(1, "fixed", 1e308),
                                                           PlantContact(3, "fixed", 0.0)]),
    "15 a rectangle 1e308 high": lambda: ConvexPolygon.rectangle(0.1, 1e308),
    "11 plan with a string polygon": lambda: plan([FingerContact(FINGER, 1)], "abc", EllipseTrajectory(0, 0.12, 0.09,
                                                                                                     0.05, 2.0)),
    "11 plan with a string trajectory": lambda: plan([FingerContact(FINGER, 1)], BOX, "abc"),
    "11 a hand of integers": lambda: Hand([1, 2]),
    "11 rollout settings as a number": lambda: build_rollout(load_scenario(ROOT / "examples" / "scenarios" /
                                                                          "paper_trajectory_2.toml"),
                                                             regrasp_settings=5),
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


def test_a_closed_loop_or_a_rollout_of_a_billion_seconds_is_refused():
    from regrasp import build_rollout
    from regrasp.dynamics.control import Gains
    from regrasp.dynamics.laws import FixedContactController
    from regrasp.dynamics.reduced import ReducedModel
    from regrasp.plants import run_closed_loop

    sc = load_scenario(ROOT / "examples" / "scenarios" / "paper_trajectory_2.toml")
    with pytest.raises(RegraspError, match="duration"):
        build_rollout(sc, RunSpec(duration=1e9), policy="paper")
    with pytest.raises(RegraspError, match="periods"):
        build_rollout(sc, RunSpec(periods=10**6), policy="paper")
    p = plant()
    model = ReducedModel(p.hand, Grasp(BOX, [1, 3], ["fixed", "fixed"]), [0.0, 0.0])
    law = FixedContactController(model, Gains.critically_damped(20.0, 3))
    with pytest.raises(RegraspError, match="duration"):
        run_closed_loop(p, law, lambda t: (np.zeros(3), np.zeros(3), np.zeros(3)), 10**9)


def test_every_public_name_loads_and_the_command_line_starts_without_the_heavy_libraries():
    import subprocess
    import sys

    import regrasp

    for name in regrasp.__all__:
        assert getattr(regrasp, name) is not None, name
    code = ("import sys, regrasp.cli.main; regrasp.cli.main.build_parser(); "
            "print(sorted(m for m in ('pinocchio', 'coal', 'scipy', 'rerun', 'numba') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=HANG_SECONDS,
                         check=True).stdout
    assert out.strip() == "[]"


@pytest.mark.parametrize("n, ok", [(252, True), (253, False), (2000, False)])
def test_a_polygon_coal_cannot_take_is_a_polygon_error_with_the_limit(n, ok):
    from regrasp.core.exceptions import PolygonError

    a = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    polygon = ConvexPolygon.from_vertices(0.05 * np.c_[np.cos(a), np.sin(a)], mass=0.1)
    if ok:
        assert polygon.to_coal(0.1) is not None
        return
    with pytest.raises(PolygonError, match=f"{n}-gon.*up to 252 vertices"):
        polygon.to_coal(0.1)


URDF_TEXT = URDF.read_text()


@pytest.mark.parametrize("text, says", [
    ("", "XML_ERROR_EMPTY_DOCUMENT"),
    ("<robot", "XML_ERROR_PARSING_ELEMENT"),
    (URDF_TEXT.replace('<mass value="0.04"/>', '<mass value="-1"/>', 1), "mass -1 kg"),
    (URDF_TEXT.replace('<mass value="0.015"/>', '<mass value="nan"/>', 1), "mass 0 kg"),  # (urdfdom reads NaN as 0)
    (URDF_TEXT.replace('ixx="7.2e-07"', 'ixx="-1"', 1), "principal moments -1"),
    (URDF_TEXT.replace('<origin xyz="0.045 0 0"', '<origin xyz="1e300 0 0"', 1), "placed 1e+300 m from its joint"),
    (URDF_TEXT.replace('izz="2.625e-06"', 'izz="1e300"', 1), "of at most 1e+12 kg m^2"),
    (URDF_TEXT.replace('izz="2.625e-06"', 'izz="1e9"', 1), "the joint-space mass matrix is singular or ill-"),
], ids=["empty", "not XML", "negative mass", "NaN mass", "negative inertia", "a distal link 1e300 m long",
        "a distal inertia of 1e300", "a distal inertia 1e14 times the proximal link's"])
def test_a_bad_urdf_is_one_line_with_urdfdom_kept_off_stderr(tmp_path, capfd, text, says):
    from regrasp.core.exceptions import FingerModelError

    path = tmp_path / "finger.urdf"
    path.write_text(text)
    with pytest.raises(FingerModelError) as info:
        Finger.from_urdf(path)
    message = str(info.value)
    assert says in message and "\n" not in message
    assert capfd.readouterr().err == ""  # urdfdom's own lines went into the message, not the terminal


def test_huge_links_and_infinite_positions_are_refused():
    from regrasp.core.exceptions import InvalidParameterError
    from regrasp.envelope.finger_envelope import FingerEnvelope

    with pytest.raises(InvalidParameterError, match="l2"):
        planar_2r_urdf(0.1, 1e300)
    sample = FingerEnvelope(FINGER, BOX, 1).at([0.0, 0.12, 0.0])
    with pytest.raises(InvalidParameterError, match="xi"):
        sample.margin(math.inf)


def _recorder(rrd_path, **options):
    from regrasp.rollout.recording.recorder import RolloutRecorder

    return RolloutRecorder(plant(), rrd_path=rrd_path, **options)


def _settings(kind: str, **fields):
    if kind == "regrasp":
        from regrasp.schedule.planner import RegraspSettings

        return RegraspSettings(**fields)
    if kind == "mujoco":
        from regrasp.plants.mujoco.mjcf import MujocoSettings

        return MujocoSettings(**fields)
    if kind == "softness":
        from regrasp.model.softness import ContactSoftness

        return ContactSoftness(**fields)
    from regrasp.plants.drake.model import DrakeSettings

    return DrakeSettings(**fields)


#: Issue 25's library reproducers: (case, the parameter its error must name).
ISSUE_25 = {
    "1 a recorder path of 5": (lambda: _recorder(5), "rrd_path"),
    "1 a recorder path in /proc": (lambda: _recorder("/proc/x.rrd"), "rrd_path"),
    "1 a recorder path with NUL": (lambda: _recorder("a\0b.rrd"), "rrd_path"),
    "1 a recorder path of 300 characters": (lambda: _recorder("x" * 300 + ".rrd"), "rrd_path"),
    "3 periods = 10**400": (lambda: build_rollout(load_scenario(ROOT / "examples" / "scenarios" /
                                                                "paper_trajectory_2.toml"),
                                                  RunSpec(periods=10**400), policy="none"), "periods"),
    "3 envelope_substeps = 10**400": (lambda: _settings("regrasp", envelope_substeps=10**400), "envelope_substeps"),
    "3 a decimation of 10**21": (lambda: _recorder(None, spawn=True, decimation=10**21), "decimation"),
    "4 a run of 1e-5 s": (lambda: build_rollout(load_scenario(ROOT / "examples" / "scenarios" /
                                                              "paper_trajectory_2.toml"),
                                                RunSpec(duration=1e-5), policy="none"), "duration"),
    "5 a MuJoCo tip radius of 1e300": (lambda: _settings("mujoco", tip_radius=1e300), "tip_radius"),
    "5 a Drake tip radius of 1": (lambda: _settings("drake", tip_radius=1.0), "tip_radius"),
    "5 a softness tip radius of 1 m": (lambda: _settings("softness", time_constant=1e-3, solimp_width=1e-4,
                                                         tip_radius=1.0), "tip_radius"),
}


@pytest.mark.parametrize("case", list(ISSUE_25), ids=list(ISSUE_25))
def test_issue_25_library_reproducers_are_typed_one_line_errors_naming_the_parameter(case):
    from regrasp.core.exceptions import InvalidParameterError

    make, name = ISSUE_25[case]
    with pytest.raises(InvalidParameterError) as info:
        make()
    assert info.value.name == name and "\n" not in str(info.value), str(info.value)


def test_numpy_integers_are_counts():
    assert _settings("regrasp", envelope_substeps=np.int64(2)).envelope_substeps == 2
    assert RunSpec(periods=np.int64(3)).periods == 3 and type(RunSpec(periods=np.int64(3)).periods) is int

"""Every public entry point, each argument in turn replaced by a bad value (None, a string, NaN, inf, -1, 1e308,
an object, an empty list, True, 10**400, a complex number, a list with a NaN, a 3-D array).

The outcome is a :class:`~regrasp.core.exceptions.RegraspError` with a one-line message, or a result without NaN or
inf; never another exception from deep inside numpy, Pinocchio or coal. Values no number can be (an object, a
complex number, a NaN) are never accepted. (``cone_margin`` is left out: it is an arithmetic kernel on floats and
arrays in the control and plant loops, documented as unchecked.)
"""

import importlib
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from regrasp.core.exceptions import RegraspError
from regrasp.model.hand import Hand
from regrasp.model.sphere_tip import sphere_tip_torque
from regrasp.study.draws import draw_runs
from regrasp.study.study import wilson_interval

#: Where the public names are: the package and every subpackage's exports.
PACKAGES = ("regrasp", "regrasp.core", "regrasp.model", "regrasp.envelope", "regrasp.dynamics",
            "regrasp.dynamics.internal_force", "regrasp.plants", "regrasp.plants.mujoco", "regrasp.plants.drake",
            "regrasp.schedule", "regrasp.supervisor", "regrasp.supervisor.policies", "regrasp.rollout", "regrasp.study")


class _Public:
    """``R.Name``: the public name from whichever package exports it."""

    def __getattr__(self, name: str):
        for package in PACKAGES:
            module = importlib.import_module(package)
            if name in module.__all__:
                return getattr(module, name)
        raise AttributeError(name)


R = _Public()

ROOT = Path(__file__).resolve().parents[1]
URDF = ROOT / "urdf" / "planar_2r_finger.urdf"
SCENARIO = ROOT / "examples" / "scenarios" / "paper_trajectory_2.toml"

F1 = R.Finger.from_urdf(URDF, base_in_hand=(-0.05, 0.0, np.pi / 2), configuration="left", name="f")
F2 = F1.with_placement(base_in_hand=(0.05, 0.0, np.pi / 2), configuration="right", name="g")
BOX = R.ConvexPolygon.rectangle(0.1, 0.04, mass=0.08)
HAND = Hand([F1, F2])
GRASP = R.Grasp(BOX, [1, 3], ["fixed", "fixed"])
TRAJ = R.EllipseTrajectory(0.0, 0.12, 0.09, 0.05, 2.0)
SC = R.load_scenario(SCENARIO)
def plant(): return R.Plant(HAND, BOX, [R.PlantContact(1, "fixed", 0.0), R.PlantContact(3, "fixed", 0.0)], friction=0.5)
MODEL = R.ReducedModel(HAND, GRASP, [0.0, 0.0])
GAINS = R.Gains.critically_damped(20.0, 3)
X0 = np.array([0.0, 0.17, 0.0])
ENV = R.FingerEnvelope(F1, BOX, 1)
RESET_PLANT = plant()
RESET_PLANT.reset(np.zeros(4), np.zeros(4), X0, np.zeros(3))
SAMPLE = ENV.at(X0)
ENTRIES = {
 "ConvexPolygon.rectangle": (R.ConvexPolygon.rectangle, [0.1, 0.04], dict(mass=0.08)),
 "ConvexPolygon.from_vertices": (R.ConvexPolygon.from_vertices,
                                 [[[0.05, 0.02], [-0.05, 0.02], [-0.05, -0.02], [0.05, -0.02]]], dict(mass=0.08)),
 "BOX.edge": (BOX.edge, [1], {}),
 "BOX.vertices_in": (BOX.vertices_in, [X0], {}),
 "BOX.contains": (BOX.contains, [[[0.0, 0.0]]], {}),
 "Edge.point": (BOX.edge(1).point, [0.01], {}),
 "Edge.xi_of": (BOX.edge(1).xi_of, [[-0.05, 0.0]], {}),
 "Edge.contains_xi": (BOX.edge(1).contains_xi, [0.01], {}),
 "Friction": (R.Friction, [0.5, 0.4], {}),
 "Gains.critically_damped": (R.Gains.critically_damped, [20.0, 3], {}),
 "Gains": (R.Gains, [np.ones(3), np.ones(3)], {}),
 "EllipseTrajectory": (R.EllipseTrajectory, [0.0, 0.12, 0.09, 0.05, 2.0],
                       dict(beta0=0.0, beta_a=0.0, t_start=0.0, t_end=1.0)),
 "WaypointTrajectory": (R.WaypointTrajectory, [[0.0, 1.0, 2.0], [[0, 0.1, 0], [0.01, 0.1, 0], [0, 0.1, 0]]],
                        dict(boundary="natural")),
 "TRAJ.pose": (TRAJ.pose, [0.5], {}),
 "TRAJ.sample": (TRAJ.sample, [0.5], {}),
 "TRAJ.times": (TRAJ.times, [5], {}),
 "Finger.from_urdf": (R.Finger.from_urdf, [URDF],
                      dict(base_in_hand=(0.0, 0.0, 0.0), configuration="left", name="x", tip_frame="tip")),
 "Finger.with_placement": (F1.with_placement, [(0.0, 0.0, 0.0), "left", "n"], {}),
 "Finger.forward_kinematics": (F1.forward_kinematics, [[0.3, -0.5]], {}),
 "Finger.tip_jacobian": (F1.tip_jacobian, [[0.3, -0.5]], {}),
 "Finger.inverse_kinematics": (F1.inverse_kinematics, [[-0.02, 0.12]], {}),
 "Finger.theta2": (F1.theta2, [[0.3, -0.5]], {}),
 "Finger.configuration_of": (F1.configuration_of, [[0.3, -0.5]], {}),
 "Finger.joint_positions_in_hand": (F1.joint_positions_in_hand, [[0.3, -0.5]], {}),
 "Hand": (Hand, [[F1, F2]],
          dict(gravity_in_hand=(0.0, -9.81), damping=True, singular_threshold=1e4, link_mass_scale=1.0)),
 "Hand.dynamics": (HAND.dynamics, [np.zeros(4), np.zeros(4)], {}),
 "Hand.jacobian": (HAND.jacobian, [np.zeros(4)], {}),
 "Hand.tip_positions": (HAND.tip_positions, [np.zeros(4)], {}),
 "Hand.kinetic_energy": (HAND.kinetic_energy, [np.zeros(4), np.zeros(4)], {}),
 "Hand.potential_energy": (HAND.potential_energy, [np.zeros(4)], {}),
 "Hand.inverse_kinematics": (HAND.inverse_kinematics, [[[-0.05, 0.12], [0.05, 0.12]]], {}),
 "Hand.set_gravity": (HAND.set_gravity, [(0.0, -9.81)], {}),
 "Grasp": (R.Grasp, [BOX, [1, 3], ["fixed", "fixed"]], {}),
 "Grasp.grasp_matrix": (GRASP.grasp_matrix, [X0, [0.0, 0.0]], {}),
 "Grasp.points": (GRASP.points, [X0, [0.0, 0.0]], {}),
 "Grasp.force_basis": (GRASP.force_basis, [[], 0.5], {}),
 "PlantContact": (R.PlantContact, [1, "fixed", 0.0, 1.0], {}),
 "Plant": (R.Plant, [HAND, BOX, [R.PlantContact(1, "fixed", 0.0), R.PlantContact(3, "fixed", 0.0)]],
           dict(friction=0.5, dt=1e-3)),
 "ReducedModel": (R.ReducedModel, [HAND, GRASP, [0.0, 0.0]], dict(object_mass=0.08, object_inertia=1e-4)),
 "FixedContactController": (R.FixedContactController, [MODEL, GAINS], dict(friction=0.5)),
 "Proposition1Controller": (R.Proposition1Controller, [MODEL, GAINS], dict(friction=0.5)),
 "InternalForceSettings": (R.InternalForceSettings, [0.5, 0.05, 1e-9, 10.0, 0.0], {}),
 "FingerEnvelope": (R.FingerEnvelope, [F1, BOX, 1], dict(geometry="ideal", tip_clearance=0.01)),
 "FingerEnvelope.at": (ENV.at, [X0, 0.0], {}),
 "FingerEnvelope.line": (ENV.line, [X0], {}),
 "FingerEnvelope.tip_at": (ENV.tip_at, [X0, 0.0], {}),
 "EnvelopeSample.margin": (SAMPLE.margin, [0.0], {}),
 "condition_of": (R.condition_of, [0.05, 0.12], {}),
 "reachable_on_line": (R.reachable_on_line, [0.05, 0.12, 0.045, 1], {}),
 "planar_2r_urdf": (R.planar_2r_urdf, [0.1, 0.05], dict(radius1=0.008, radius2=0.007, mass1=0.04, mass2=0.02)),
 "FingerContact": (R.FingerContact, [F1, 1, 0.01, R.Friction(0.5)], {}),
 "plan": (R.plan, [SC.contacts, BOX, TRAJ], dict(samples=5, geometry="ideal")),
 "plan_scenario": (R.plan_scenario, [SC], dict(samples=5, geometry="ideal")),
 "RegraspSettings": (R.RegraspSettings, [], dict(envelope_margin=0.001, cone_margin=0.1, f_min=0.2, f_max=20.0)),
 "SupervisorSettings": (R.SupervisorSettings, [], dict(executor=R.ExecutorSettings(), monitor=R.MonitorSettings(),
                                                      paper=R.PaperSettings(), scheduled=R.ScheduledSettings())),
 "SupervisorSettings.robust": (R.SupervisorSettings.robust, ["urdf", 0.2], dict(actuation_delay=1, tip_radius=2.5e-4,
                                                                                hold_resolution=2e-6)),
 "ExecutorSettings": (R.ExecutorSettings, [], dict(omega_n=20.0, prime_time=0.02, settle_margin=0.05, integral=0.3)),
 "MonitorSettings": (R.MonitorSettings, [], dict(geometry="ideal", every=10, track=False)),
 "PaperSettings": (R.PaperSettings, [], dict(danger_fraction=0.1, reaction_time=0.4, path_checks=3)),
 "ModelErrors": (R.ModelErrors, [], dict(mass_scale=1.1, inertia_scale=0.9, link_mass_scale=1.0, mu_scale=0.9,
                                        mu_kinetic_scale=1.0, xi_offset=(1e-4, -1e-4))),
 "PlantSpec": (R.PlantSpec, ["project"], dict(errors=R.ModelErrors(mass_scale=1.1), friction=0.5)),
 "RunSpec": (R.RunSpec, [], dict(duration=1.0, dt=1e-3, seed=3, xi0=(0.0, 0.01), sensor_noise=R.SensorNoise(xi=1e-4),
                                actuator_noise=R.ActuatorNoise(delay=1))),
 "ScheduledSettings": (R.ScheduledSettings, [], dict(prime_lead=0.0, time_tolerance=0.05, xi_tolerance=0.001)),
 "sliding_feasibility": (R.sliding_feasibility, [GRASP, X0, [0.0, 0.0], [0.0, 0.0, 0.0], 0, 1.0, 0.5],
                         dict(object_mass=0.08, object_inertia=1e-4)),
 "default_tip_clearance": (R.default_tip_clearance, [F1], {}),
 "UrdfCollisionChecker": (R.UrdfCollisionChecker, [F1, BOX, 0.01], {}),
 "load_scenario": (R.load_scenario, [SCENARIO], {}),
 "measure_reduced_state": (R.measure_reduced_state, [RESET_PLANT, MODEL], {}),
 "sphere_tip_torque": (sphere_tip_torque, [[[1.0, 0.0], [-1.0, 0.0]], [[1.0, 0.2], [1.0, -0.3]], 2.5e-4], {}),
 "OrderedSlidesPolicy": (R.OrderedSlidesPolicy, [[R.SlideOrder(0, 1, 0.01, planned_start=0.1)], 2], {}),
 "SensorNoise": (R.SensorNoise, [1e-4, 1e-3, 1e-3, 1e-2, 2e-4, 1e-3, 0.01, 2e-3, 1], {}),
 "ActuatorNoise": (R.ActuatorNoise, [1e-3, 1], {}),
 "Disturbance": (R.Disturbance, [R.SensorNoise(xi=1e-4), R.ActuatorNoise(delay=1), np.random.default_rng(0)], {}),
 "Perturbation": (R.Perturbation, [], dict(mass=0.2, inertia=0.2, mu=0.2, contact_position=2e-4, position_noise=1e-4,
                                         slip_threshold=2e-3, slip_delay=1, torque_noise=1e-3, delay=1)),
 "wilson_interval": (wilson_interval, [19, 20], dict(z=1.96)),
 "draw_runs": (draw_runs, [3, 1, R.Perturbation(mass=0.1)], dict(contacts=2)),
}
try:  # the MuJoCo plant's entry points, with the extra installed
    import mujoco  # noqa: F401
except ImportError:
    pass
else:
    from regrasp.plants.mujoco.mjcf import eroded_vertices
    ENTRIES.update({
     "MujocoSettings": (R.MujocoSettings, [], dict(tip_radius=2.5e-4, timestep=1e-4, time_constant=5e-4, impratio=100.0,
                                                   noslip_iterations=0, object_thickness=0.02, contact_depth=1e-6)),
     "eroded_vertices": (eroded_vertices, [BOX, 2.5e-4], {}),
     "MujocoPlant": (R.MujocoPlant, [HAND, BOX, [R.PlantContact(1, "fixed", 0.0), R.PlantContact(3, "fixed", 0.0)]],
                     dict(friction=0.5, dt=1e-3, slip_speed=2e-3, stick_speed=1e-3, separation_gap=2.5e-5)),
    })

try:  # the Drake plant's entry points, with the extra installed
    import pydrake  # noqa: F401
except ImportError:
    pass
else:
    ENTRIES.update({
     "DrakeSettings": (R.DrakeSettings, [], dict(tip_radius=2.5e-4, time_step=1e-4, point_contact_stiffness=1e7,
                                                 hunt_crossley_dissipation=10.0, stiction_tolerance=1e-5,
                                                 near_rigid_threshold=1.0, object_thickness=0.02, contact_depth=4e-7)),
     "DrakePlant": (R.DrakePlant, [HAND, BOX, [R.PlantContact(1, "fixed", 0.0), R.PlantContact(3, "fixed", 0.0)]],
                    dict(friction=0.5, dt=1e-3, slip_speed=2e-3, stick_speed=1e-3, separation_gap=2.5e-5)),
    })


NEVER = (object(), 1 + 1j, math.nan, [math.nan, 0.0])
BAD = [None, "abc", math.nan, math.inf, -1.0, 1e308, NEVER[0], [], True, 10**400, NEVER[1], NEVER[3],
       np.zeros((2, 2, 2))]
#: results allowed an inf: InternalForceSettings' f_max (inf: no upper bound, its default)
INF_ALLOWED = {("InternalForceSettings", 3)}


def finite(value, depth: int = 0) -> bool:
    if depth > 3:
        return True
    if isinstance(value, (float, np.floating)):
        return math.isfinite(value)
    if isinstance(value, np.ndarray) and value.dtype.kind == "f":
        return bool(np.isfinite(value).all())
    if isinstance(value, (tuple, list)):
        return all(finite(v, depth + 1) for v in value)
    if hasattr(value, "__dataclass_fields__"):  # (an InternalForceSettings' f_max is inf by default: no upper bound)
        return all(finite(getattr(value, k), depth + 1) for k in value.__dataclass_fields__
                   if not (type(value).__name__ == "InternalForceSettings" and k == "f_max"))
    return True


def keys_of(entry: str) -> list:
    """The entry's argument slots: positions, then keyword names."""
    _, args, kwargs = ENTRIES[entry]
    return [*range(len(args)), *kwargs]


def call_with(entry: str, key, value):
    """The entry's valid call with the argument at ``key`` replaced by ``value``."""
    fn, args, kwargs = ENTRIES[entry]
    a, k = list(args), dict(kwargs)
    if isinstance(key, int):
        a[key] = value
    else:
        k[key] = value
    return fn(*a, **k)


@pytest.mark.parametrize("entry", list(ENTRIES), ids=list(ENTRIES))
def test_each_argument_bad_in_turn_is_a_typed_error_or_a_finite_result(entry):
    fn, args, kwargs = ENTRIES[entry]
    fn(*args, **kwargs)  # the valid call works
    problems = []
    for key in keys_of(entry):
        for bad in BAD:
            try:
                out = call_with(entry, key, bad)
            except RegraspError as exc:
                if "\n" in str(exc) or len(str(exc)) > 400:
                    problems.append(f"{key}={bad!r:.30}: a message of {len(str(exc))} characters or several lines")
                continue
            except Exception as exc:  # noqa: BLE001 (what this test looks for)
                problems.append(f"{key}={bad!r:.30}: {type(exc).__name__}: {str(exc)[:100]}")
                continue
            if any(bad is never for never in NEVER):
                problems.append(f"{key}={bad!r:.30}: accepted")
            elif not finite(out) and (entry, key) not in INF_ALLOWED:
                problems.append(f"{key}={bad!r:.30}: a result with NaN or inf")
    assert problems == [], "\n".join(problems)


SLOTS = [(entry, key) for entry in ENTRIES for key in keys_of(entry)]
generated = st.recursive(
    st.one_of(st.booleans(), st.none(), st.text(max_size=4), st.complex_numbers(allow_nan=True),
              st.floats(allow_nan=True, allow_infinity=True), st.integers(-(10**400), 10**400),
              st.sampled_from([np.float32("nan"), np.int64(-1), np.bool_(True), np.zeros(0), np.full(3, np.inf)])),
    lambda children: st.lists(children, max_size=4), max_leaves=6)


@settings(derandomize=True, database=None, max_examples=400, deadline=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(SLOTS), generated)
def test_a_generated_bad_argument_is_a_typed_error_or_a_finite_result(slot, value):
    """The same property, with hypothesis drawing the entry point, the argument and the value (nested lists of
    booleans, strings, complex numbers, NaN, inf, huge integers and numpy scalars)."""
    entry, key = slot
    try:
        out = call_with(entry, key, value)
    except RegraspError as exc:
        assert "\n" not in str(exc) and len(str(exc)) <= 400, str(exc)
        return
    assert not isinstance(value, complex), (entry, key, value)  # no argument is a complex number
    assert finite(out) or (entry, key) in INF_ALLOWED, (entry, key, value)

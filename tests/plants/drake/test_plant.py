"""Drake as a third plant (:mod:`regrasp.plants.drake`).

The model is Drake's parse of the URDFs, checked against Pinocchio's (the tips' forward kinematics, the links' masses
with the hand's mass scale) and the polygon (the object's mass and inertia, a tip placed on its edge starting
``contact_depth`` deep); the plant's reports against the object's weight and against the project's rigid plant (the
static forces of a hold, independently); its events (a pulled contact separates, a link driven into the object is a
collision, an open-loop push slips); Drake's friction law (μ_s is never used: a measured fact); the forward-dynamics
query against a step; and the plant through :class:`~regrasp.PlantSpec` and the command line.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pydrake")

from regrasp import (  # noqa: E402
    Finger,
    Grasp,
    Hand,
    PlantContact,
    PlantSpec,
    ReducedModel,
    RunSpec,
    build_rollout,
    load_scenario,
    planar_2r_urdf,
)
from regrasp.cli.main import main  # noqa: E402
from regrasp.core.contact import Friction  # noqa: E402
from regrasp.core.events import EventKind  # noqa: E402
from regrasp.core.exceptions import FingerModelError, InvalidParameterError, MissingDependencyError  # noqa: E402
from regrasp.dynamics.control import Gains  # noqa: E402
from regrasp.dynamics.laws import FixedContactController, Proposition3Controller  # noqa: E402
from regrasp.plants.closed_loop import run_closed_loop  # noqa: E402
from regrasp.plants.drake.model import DrakeSettings, build_drake, require_drake  # noqa: E402
from regrasp.plants.drake.plant import DrakePlant  # noqa: E402
from regrasp.plants.mujoco.mjcf import MujocoSettings  # noqa: E402
from regrasp.plants.project.plant import Plant  # noqa: E402
from regrasp.plants.simulation import PlantLike  # noqa: E402

ROOT = Path(__file__).resolve().parents[3]
SC2_PATH = ROOT / "examples" / "scenarios" / "paper_trajectory_2.toml"
SC2 = load_scenario(SC2_PATH)
XI0, MU, V0 = -0.0075, 0.3, 0.005  # Figure 3.4's grasp: both fingers 7.5 mm below the centre, μ = 0.3
X_HOLD = np.array([0.0, 0.12, 0.0])


def hand_of(sc, **kwargs):
    return Hand([c.finger for c in sc.contacts], gravity_in_hand=sc.gravity_in_hand, **kwargs)


def held(kind: str, friction=MU, settings: DrakeSettings = DrakeSettings(), **kwargs):
    """A plant of Figure 3.4's two-finger grasp at rest, both contacts fixed, and its reduced model."""
    hand = hand_of(SC2)
    contacts = [PlantContact(1, "fixed", XI0), PlantContact(3, "fixed", XI0)]
    plant = (DrakePlant(hand, SC2.polygon, contacts, friction=friction, settings=settings, **kwargs)
             if kind == "drake" else Plant(hand, SC2.polygon, contacts, friction=friction))
    model = ReducedModel(hand, Grasp(SC2.polygon, [1, 3], ["fixed", "fixed"]), [XI0, XI0])
    st = model.state(X_HOLD, np.zeros(3))
    plant.reset(st.q, st.q_dot, X_HOLD, np.zeros(3))
    return plant, model


def hold(plant, model, duration: float):
    law = FixedContactController(model, Gains.critically_damped(20.0, 3), MU)
    return run_closed_loop(plant, law, lambda t: (X_HOLD, np.zeros(3), np.zeros(3)), duration)


def surface_frames(X):
    c, s = math.cos(X[2]), math.sin(X[2])
    rot = np.array([[c, -s], [s, c]])
    return [np.array([rot @ SC2.polygon.edge(e).inward_normal, rot @ SC2.polygon.edge(e).xi_direction])
            for e in (1, 3)]


# ---------------------------------------------------------------------------- the model
def test_drakes_parse_is_the_urdfs_as_pinocchio_reads_them_and_the_object_the_polygon():
    hand = hand_of(SC2, link_mass_scale=1.3)
    plant = DrakePlant(hand, SC2.polygon, [PlantContact(1, "fixed", XI0), PlantContact(3, "fixed", XI0)],
                       object_mass=0.1, object_inertia=9e-5)
    assert isinstance(plant, PlantLike) and plant.mass == 0.1 and plant.inertia == pytest.approx(9e-5, rel=1e-12)
    rng = np.random.default_rng(7)
    for _ in range(5):
        q = rng.uniform(-math.pi, math.pi, 4)
        st = plant.reset(q, np.zeros(4), X_HOLD, np.zeros(3))
        for i, finger in enumerate(hand.fingers):
            tip = plant.built.tip_bodies[i].EvalPoseInWorld(plant.context).translation()
            np.testing.assert_allclose(tip[:2], finger.forward_kinematics(q[2 * i:2 * i + 2]), atol=1e-12)
        assert st.contact_work == 0.0
    for finger, links in zip(hand.fingers, plant.built.link_bodies):
        for k, body in enumerate(links):
            assert body.get_mass(plant.context) == pytest.approx(1.3 * finger.model.inertias[k + 1].mass, rel=1e-12)
    plant, _ = held("drake")
    # each tip starts with its centre on its edge's line (so contact_depth into the eroded prism), where placed
    assert plant.constraint_error(plant.state) < 1e-15
    assert [plant.contact_xi(plant.state, i)[0] for i in range(2)] == pytest.approx([XI0, XI0], abs=1e-12)


# ---------------------------------------------------------------------------- the plant's reports
def test_a_grasp_held_by_the_fixed_contact_law_stays_held_and_its_forces_carry_the_weight():
    plant, model = held("drake")
    log = hold(plant, model, 0.5)
    assert log.events == () and not log.stopped and plant.events == []
    forces = log.plant_forces
    assert forces[:, :, 0].min() > 3.5  # both squeeze throughout (the law's 3.92 N)
    # the sphere's couple r f_t, which the bare law does not model, tilts the object by about 10 mrad (as on MuJoCo)
    assert np.abs(log.errors[-1, :2]).max() < 2e-4 and abs(log.errors[-1, 2]) < 0.015
    assert plant.max_constraint_error < 1e-5  # the tips stay on their edges (µm of penetration)
    # at rest, the reported forces carry the weight (measured to 2 µN; m a is below 1e-5 N)
    total = sum(f.T @ fs for f, fs in zip(surface_frames(plant.state.X), forces[-1]))
    np.testing.assert_allclose(total, -SC2.polygon.mass * SC2.gravity_in_hand, atol=1e-4)


def test_the_static_forces_are_the_project_plants():
    """An independent check: a nearly point tip (r = 10 µm) held by the same law for 0.3 s reports the rigid plant's
    forces to 5 mN (0.13 % of the 3.9 N squeeze; measured 2.1 mN). What remains is Drake's regularized friction: a
    stuck contact at a fraction ρ of its cone creeps at ε ρ / √(1 − ρ²) (ε about 10 µm/s at a 0.1 ms step), finger 1
    (ρ = 0.83) 15 µm/s, 4.5 µm in 0.3 s, and the law, which holds its contacts where it placed them, answers with
    its feedback; the soft normal (0.4 µm at 3.9 N) and the 10 µm sphere's couple r f_t (10 µN m, a 0.1 mrad tilt
    turning the 0.78 N weight's components by 0.1 mN) add less than 0.5 mN."""
    rigid, model = held("project")
    soft, _ = held("drake", settings=DrakeSettings(tip_radius=1e-5))
    project, drake = hold(rigid, model, 0.3), hold(soft, model, 0.3)
    assert drake.events == ()
    np.testing.assert_allclose(drake.plant_forces[-1], project.plant_forces[-1], atol=5e-3)
    assert abs(soft.state.X[2]) < 5e-4


def test_drakes_discrete_solver_uses_mu_k_and_never_mu_s():
    """The hold law's torques, open loop, on Figure 3.4's grasp: finger 1 carries f_t / f_n = 0.25. With μ_k = 0.3 it
    stays; with μ_k = 0.2 it slides whatever μ_s is (0.3, where Coulomb's static friction would hold it): the runs
    with (μ_s, μ_k) = (0.3, 0.2) and (0.2, 0.2) are bit for bit the same, as are (0.6, 0.3) and (0.3, 0.3)."""
    _, model = held("project")
    tau = FixedContactController(model, Gains.critically_damped(20.0, 3), MU)(
        X_HOLD, np.zeros(3), X_HOLD, np.zeros(3), np.zeros(3)).tau

    def run(friction):
        plant, _ = held("drake", friction=friction, stop_on=())
        steps = [plant.step(tau) for _ in range(25)]
        return plant, np.array([s.forces_surface for s in steps]), np.array([s.slip for s in steps])

    runs = {f: run(f) for f in (Friction(0.3, 0.2), Friction(0.2), Friction(0.6, 0.3), Friction(0.3))}
    for a, b in ((Friction(0.3, 0.2), Friction(0.2)), (Friction(0.6, 0.3), Friction(0.3))):
        np.testing.assert_array_equal(runs[a][1], runs[b][1])
        np.testing.assert_array_equal(runs[a][2], runs[b][2])
        assert runs[a][0].friction == (Friction(a.kinetic),) * 2  # what the plant really has
    # finger 1 slides 22 mm in 25 ms at μ_k = 0.2 and creeps 0.4 µm at μ_k = 0.3
    assert runs[Friction(0.3, 0.2)][2][:, 0].sum() > 0.01 and abs(runs[Friction(0.3)][2][:, 0].sum()) < 5e-6
    assert EventKind.SLIP in [e.kind for e in runs[Friction(0.3, 0.2)][0].events if e.contact == "finger1"]
    assert runs[Friction(0.3)][0].events == []


def test_a_link_driven_into_the_object_is_a_collision_and_stops_the_plant():
    plant = DrakePlant(hand_of(SC2), SC2.polygon, [PlantContact(1, "separated"), PlantContact(3, "separated")],
                       friction=MU)
    plant.reset(np.zeros(4), np.zeros(4), [-0.05, 0.06, 0.0], np.zeros(3))  # finger 1's proximal link through the box
    step = plant.step(np.zeros(4))
    (event,) = [e for e in step.events if e.kind is EventKind.COLLISION]
    assert event.contact == "finger1" and event.values["link"] == 0 and event.values["depth"] > 1e-3
    assert plant.stopped
    with pytest.raises(InvalidParameterError, match="stopped"):
        plant.step(np.zeros(4))


def test_a_contact_pulled_away_separates():
    """Figure 3.4's downward slide needs both fingers to pull (the predicate's -0.87 N): they let go."""
    hand = hand_of(SC2)
    model = ReducedModel(hand, Grasp(SC2.polygon, [1, 3], ["sliding", "fixed"]), xi=[XI0, XI0])
    law = Proposition3Controller(model, Gains.critically_damped(20.0, 4), friction=MU)
    plant = DrakePlant(hand, SC2.polygon, [PlantContact(1, "sliding", XI0, -1.0), PlantContact(3, "fixed", XI0)],
                       friction=MU)
    S, S_dot = np.array([*X_HOLD, XI0]), np.array([0.0, 0.0, 0.0, -V0])
    st = model.state(S, S_dot)
    plant.reset(st.q, st.q_dot, X_HOLD, np.zeros(3))
    log = run_closed_loop(plant, law, lambda t: (S + S_dot * t, S_dot, np.zeros(4)), 0.1)
    separations = [e for e in log.events if e.kind is EventKind.SEPARATION]
    assert separations and separations[0].time < 0.01 and log.stopped
    assert separations[0].values["gap"] > plant.separation_gap and separations[0].values["normal_force"] <= 0.0


def test_the_forward_dynamics_query_is_one_of_drakes_steps():
    """``accelerations`` is the mean acceleration over one Drake step and that step's forces: a control step of
    one Drake step moves the velocities by exactly that and reports those forces."""
    s = DrakeSettings()
    plant, model = held("drake", dt=s.time_step)
    tau = FixedContactController(model, Gains.critically_damped(20.0, 3), MU)(
        X_HOLD, np.zeros(3), X_HOLD, np.zeros(3), np.zeros(3)).tau
    for _ in range(3):
        plant.step(tau)
    st = plant.state
    q_ddot, X_ddot, forces = plant.accelerations(st, tau)
    step = plant.step(tau)
    np.testing.assert_allclose(st.v + q_ddot * s.time_step, step.state.v, rtol=0, atol=1e-12)
    np.testing.assert_allclose(st.V + X_ddot * s.time_step, step.state.V, rtol=0, atol=1e-12)
    np.testing.assert_allclose(plant.surface_forces(st, forces), step.forces_surface, rtol=0, atol=1e-12)
    assert step.gap.shape == step.slip.shape == (2,) and (np.abs(step.gap) < 1e-6).all()  # both touch


# ---------------------------------------------------------------------------- the spec and the command line
def test_the_plant_spec_builds_it_and_the_command_line_runs_it(capsys):
    spec = PlantSpec("drake", DrakeSettings(tip_radius=5e-4))
    assert spec.tip_radius == 5e-4 and PlantSpec("drake").tip_radius == DrakeSettings().tip_radius
    rollout = build_rollout(SC2, RunSpec(duration=0.05), policy="none", plant=spec)
    assert isinstance(rollout.plant, DrakePlant) and rollout.plant.settings.tip_radius == 5e-4
    result = rollout.run()
    assert result.success and result.plant_event_counts() == {}
    code = main(["simulate", str(SC2_PATH), "--plant", "drake", "--tip-radius", "0.5", "--policy", "none",
                 "--duration", "0.03", "--json"])
    doc = json.loads(capsys.readouterr().out)
    assert code == 0 and doc["plant"] == "drake" and doc["success"] and doc["steps"] == 30


# ---------------------------------------------------------------------------- bad input and the extra
@pytest.mark.parametrize("field, value", [("tip_radius", 0.0), ("time_step", 2e-3), ("point_contact_stiffness", -1.0),
                                          ("hunt_crossley_dissipation", math.nan), ("approximation", "sap"),
                                          ("stiction_tolerance", 0.0), ("near_rigid_threshold", -1.0),
                                          ("object_thickness", math.inf), ("contact_depth", "deep")])
def test_bad_settings_are_typed_errors(field, value):
    with pytest.raises(InvalidParameterError, match=field):
        DrakeSettings(**{field: value})


def test_bad_plants_and_plant_options_are_typed_errors():
    hand = hand_of(SC2)
    contacts = [PlantContact(1, "fixed", XI0), PlantContact(3, "fixed", XI0)]
    with pytest.raises(InvalidParameterError, match="multiple"):
        DrakePlant(hand, SC2.polygon, contacts, dt=1.05e-3)
    with pytest.raises(InvalidParameterError, match="contacts"):
        DrakePlant(hand, SC2.polygon, contacts[:1])
    with pytest.raises(InvalidParameterError, match="stop_on"):
        DrakePlant(hand, SC2.polygon, contacts, stop_on=("crash",))
    with pytest.raises(InvalidParameterError, match="stick_speed"):
        DrakePlant(hand, SC2.polygon, contacts, slip_speed=1e-3, stick_speed=2e-3)
    with pytest.raises(InvalidParameterError, match="tip_radius"):  # the object cannot be eroded by 3 cm
        DrakePlant(hand, SC2.polygon, contacts, settings=DrakeSettings(tip_radius=0.03))
    plant = DrakePlant(hand, SC2.polygon, contacts)
    with pytest.raises(InvalidParameterError, match="reset"):
        plant.step(np.zeros(4))
    plant.reset(np.zeros(4), np.zeros(4), X_HOLD, np.zeros(3))
    with pytest.raises(InvalidParameterError, match="modes"):
        plant.accelerations(plant.state, np.zeros(4), modes=contacts)
    with pytest.raises(InvalidParameterError, match="tau"):
        plant.step(np.full(4, math.nan))
    with pytest.raises(InvalidParameterError, match="settings"):
        PlantSpec(settings=DrakeSettings())
    with pytest.raises(InvalidParameterError, match="DrakeSettings"):
        PlantSpec("drake", MujocoSettings())
    finger = Finger.from_urdf_string(planar_2r_urdf(0.1, 0.05), base_in_hand=(-0.05, 0.0, math.pi / 2))
    with pytest.raises(FingerModelError, match="URDF file"):
        build_drake([finger], SC2.polygon, [SC2.friction[0]])


def test_without_drake_the_extra_is_named(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "pydrake", None)  # import pydrake now raises ImportError
    with pytest.raises(MissingDependencyError, match=r"pip install 'regrasp\[drake\]'"):
        require_drake()
    assert main(["simulate", "--plant", "drake", "--duration", "0.1"]) == 2
    assert "pip install 'regrasp[drake]'" in capsys.readouterr().err


def test_the_command_lines_help_does_not_import_drake():
    code = "import sys, regrasp.cli.main\ntry:\n    regrasp.cli.main.main(['simulate', '--help'])\n" \
           "except SystemExit:\n    pass\n" \
           "print('pydrake' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip().splitlines()[-1] == "False"

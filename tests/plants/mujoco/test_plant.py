"""MuJoCo as a second plant (:mod:`regrasp.plants.mujoco.plant`; the model is checked in
``tests/plants/mujoco/test_mjcf.py``).

The plant's reports are checked against MuJoCo's raw contact forces and the object's weight; its events
(a link driven into the object is a collision, a pulled contact separates); and the targets of
``docs/derivations.md``, "A second plant: MuJoCo": the two-finger hold within twice the project plant's
orientation error at a 0.25 mm tip (and not without the held contacts following the sensed ones), Figure
3.4's upward slide starting and proceeding (and stalling without the sphere's couple), and a scheduled
three-finger rollout through its first double slide.
"""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

from regrasp import (  # noqa: E402
    Finger,
    Grasp,
    Hand,
    PlantContact,
    PlantSpec,
    ReducedModel,
    RegraspSettings,
    RegraspSupervisor,
    RunSpec,
    SupervisorSettings,
    WaypointTrajectory,
    build_rollout,
    load_scenario,
    plan_regrasps,
    planar_2r_urdf,
)
from regrasp.cli.main import main  # noqa: E402
from regrasp.core.events import EventKind  # noqa: E402
from regrasp.core.exceptions import FingerModelError, InvalidParameterError, MissingDependencyError  # noqa: E402
from regrasp.dynamics.control import Gains  # noqa: E402
from regrasp.dynamics.laws import FixedContactController, Proposition3Controller  # noqa: E402
from regrasp.plants.closed_loop import run_closed_loop  # noqa: E402
from regrasp.plants.mujoco.mjcf import MujocoSettings, build_mjcf, require_mujoco  # noqa: E402
from regrasp.plants.mujoco.plant import MujocoPlant  # noqa: E402
from regrasp.plants.project.plant import Plant  # noqa: E402
from regrasp.plants.simulation import PlantLike  # noqa: E402
from regrasp.rollout.build import Rollout  # noqa: E402
from regrasp.supervisor.policies.base import OrderedSlidesPolicy  # noqa: E402
from regrasp.supervisor.types import SlideOrder  # noqa: E402

ROOT = Path(__file__).resolve().parents[3]
SC2 = load_scenario(ROOT / "examples" / "scenarios" / "paper_trajectory_2.toml")
SC3 = load_scenario(ROOT / "examples" / "scenarios" / "paper_trajectory_2_three_fingers.toml")
R_TIP = 2.5e-4  # [m]
XI0, MU, V0 = -0.0075, 0.3, 0.005  # Figure 3.4: finger 1 7.5 mm below the centre, μ = 0.3, sliding up at 5 mm/s
X_HOLD = np.array([0.0, 0.12, 0.0])


def hand_of(sc):
    return Hand([c.finger for c in sc.contacts], gravity_in_hand=sc.gravity_in_hand)


# ---------------------------------------------------------------------------- the plant's reports
def held_plant(kind: str, xi=(XI0, XI0)):
    hand = hand_of(SC2)
    contacts = [PlantContact(1, "fixed", xi[0]), PlantContact(3, "fixed", xi[1])]
    plant = (MujocoPlant(hand, SC2.polygon, contacts, friction=MU) if kind == "mujoco"
             else Plant(hand, SC2.polygon, contacts, friction=MU))
    model = ReducedModel(hand, Grasp(SC2.polygon, [1, 3], ["fixed", "fixed"]), list(xi))
    st = model.state(X_HOLD, np.zeros(3))
    plant.reset(st.q, st.q_dot, X_HOLD, np.zeros(3))
    return plant, model


def test_both_plants_are_plant_like():
    assert isinstance(held_plant("mujoco")[0], PlantLike) and isinstance(held_plant("project")[0], PlantLike)


def test_a_static_hold_reports_mujocos_contact_forces_and_they_carry_the_weight():
    plant, model = held_plant("mujoco")
    law = FixedContactController(model, Gains.critically_damped(20.0, 3), MU)
    log = run_closed_loop(plant, law, lambda t: (X_HOLD, np.zeros(3), np.zeros(3)), 0.15)
    assert log.events == () and not log.stopped
    st = plant.state
    c, s = math.cos(st.X[2]), math.sin(st.X[2])
    rot = np.array([[c, -s], [s, c]])
    frames = [np.array([rot @ SC2.polygon.edge(e).inward_normal, rot @ SC2.polygon.edge(e).xi_direction])
              for e in (1, 3)]
    reported = log.plant_forces[-1]
    # the weight, balanced by the reported forces (the object is at rest: m a is below 1e-4 N)
    total = sum(f.T @ fs for f, fs in zip(frames, reported))
    np.testing.assert_allclose(total, -SC2.polygon.mass * SC2.gravity_in_hand, atol=1e-3)
    # and MuJoCo's own contact forces at the state now (mj_contactForce, the contact frame), in the surface frames
    raw = np.zeros((2, 2))
    data = plant.data
    mujoco.mj_forward(plant.model, data)
    tips = {plant.model.geom(g).id: i for i, g in enumerate(plant.mjcf.tip_geoms)}
    for j in range(data.ncon):
        con = data.contact[j]
        if con.geom[0] in tips or con.geom[1] in tips:
            f6 = np.zeros(6)
            mujoco.mj_contactForce(plant.model, data, j, f6)
            world = f6[:3] @ con.frame.reshape(3, 3)  # on geom 2
            i, sign = (tips[con.geom[0]], 1.0) if con.geom[0] in tips else (tips[con.geom[1]], -1.0)
            raw[i] += sign * world[:2]
    np.testing.assert_allclose([f @ r for f, r in zip(frames, raw)], reported, atol=2e-3)
    assert reported[:, 0].min() > 0.5  # both push


def test_a_link_driven_into_the_object_is_a_collision_and_stops_the_plant():
    hand = hand_of(SC2)
    plant = MujocoPlant(hand, SC2.polygon, [PlantContact(1, "separated"), PlantContact(3, "separated")], friction=MU)
    plant.reset(np.zeros(4), np.zeros(4), [-0.05, 0.06, 0.0], np.zeros(3))  # finger 1's proximal link through the box
    step = plant.step(np.zeros(4))
    (event,) = [e for e in step.events if e.kind is EventKind.COLLISION]
    assert event.contact == "finger1" and event.values["link"] == 0 and event.values["depth"] > 1e-3
    assert plant.stopped


def test_a_contact_pulled_away_separates():
    """Figure 3.4's downward slide needs both fingers to pull (the predicate's -0.87 N): they let go."""
    hand = hand_of(SC2)
    model = ReducedModel(hand, Grasp(SC2.polygon, [1, 3], ["sliding", "fixed"]), xi=[XI0, XI0])
    law = Proposition3Controller(model, Gains.critically_damped(20.0, 4), friction=MU)
    plant = MujocoPlant(hand, SC2.polygon, [PlantContact(1, "sliding", XI0, -1.0), PlantContact(3, "fixed", XI0)],
                        friction=MU)
    S, S_dot = np.array([*X_HOLD, XI0]), np.array([0.0, 0.0, 0.0, -V0])
    st = model.state(S, S_dot)
    plant.reset(st.q, st.q_dot, X_HOLD, np.zeros(3))
    log = run_closed_loop(plant, law, lambda t: (S + S_dot * t, S_dot, np.zeros(4)), 0.1)
    separations = [e for e in log.events if e.kind is EventKind.SEPARATION]
    assert separations and separations[0].time < 0.02 and log.stopped
    assert separations[0].values["gap"] > plant.separation_gap


# ---------------------------------------------------------------------------- the targets
@pytest.fixture(scope="module")
def holds():
    """The two-finger hold (paper_trajectory_2.toml, no regrasp, 1 s) on the project plant and on MuJoCo at a
    0.25 mm tip, with and without the held contacts following the sensed ones."""
    runs = {"project": build_rollout(SC2, RunSpec(duration=1.0), policy="none").run()}
    for name, hold in (("mujoco", 2e-6), ("mujoco, held where first touched", None)):
        settings = SupervisorSettings.robust(SC2.geometry.value, 0.2, tip_radius=R_TIP, hold_resolution=hold)
        runs[name] = build_rollout(SC2, RunSpec(duration=1.0), policy="none", settings=settings,
                                   plant=PlantSpec("mujoco", settings=MujocoSettings(tip_radius=R_TIP))).run()
    return runs


def test_the_two_finger_hold_stays_within_twice_the_project_plants_error(holds):
    project, mj = holds["project"], holds["mujoco"]
    assert project.success and mj.success and mj.plant_event_counts() == {}
    assert mj.max_orientation_error_after_transient <= 2.0 * project.max_orientation_error_after_transient
    assert mj.max_object_error_after_transient <= 2.0 * project.max_object_error_after_transient


def test_a_hold_that_ignores_the_rolling_tip_is_off_by_far_more(holds):
    """The sphere rolls (r Δθ along the edge) while held: a model that keeps the first position misplaces the
    normal forces' lever arms, and the orientation error is several times the project plant's."""
    project, stale = holds["project"], holds["mujoco, held where first touched"]
    assert stale.max_orientation_error_after_transient > 4.0 * project.max_orientation_error_after_transient


def figure_3_4_slide(kind: str, radius: float = R_TIP, start: float = 0.02, duration: float = 0.32, **settings):
    """Figure 3.4's upward slide of finger 1 at 5 mm/s while the object is held still, run by the supervisor's
    executor (primed past the cone edge, then Proposition 3), after ``start`` [s] of holding."""
    hand = hand_of(SC2)
    contacts = [PlantContact(1, "fixed", XI0), PlantContact(3, "fixed", XI0)]
    plant = (MujocoPlant(hand, SC2.polygon, contacts, friction=MU, settings=MujocoSettings(tip_radius=radius))
             if kind == "mujoco" else Plant(hand, SC2.polygon, contacts, friction=MU))
    st = ReducedModel(hand, Grasp(SC2.polygon, [1, 3], ["fixed", "fixed"]), [XI0, XI0]).state(X_HOLD, np.zeros(3))
    plant.reset(st.q, st.q_dot, X_HOLD, np.zeros(3))
    end = XI0 + V0 * (duration - start)
    order = SlideOrder(0, 1, end, reference=lambda t: (XI0 + V0 * max(0.0, t - start), V0 if t >= start else 0.0, 0.0),
                       planned_start=start, planned_end=duration)
    supervisor = RegraspSupervisor(hand, SC2.polygon, [1, 3], WaypointTrajectory([0.0, 1.0], [X_HOLD, X_HOLD]),
                                   [XI0, XI0], MU,
                                   settings=SupervisorSettings.robust("ideal", 0.2).with_executor(**settings),
                                   policy=OrderedSlidesPolicy([order], 2))
    result = Rollout(plant, supervisor, duration, ("finger1", "finger2"), "ordered").run()
    kinds = [e.kind for e in result.events]
    late = result.times > start + 0.05
    error = np.abs(result.xi[late, 0] - (XI0 + V0 * (result.times[late] - start))).max()
    return result, kinds, error


def test_figure_3_4s_slide_starts_and_proceeds_on_mujoco():
    """Primed with a break-away excess of 0.01 f_n (0.05 f_n throws a 5 g fingertip to ~25 mm/s in one 1 ms step,
    five times the slide's speed) and with the sphere's couple in the torques: one priming, no stop on the way."""
    project, project_kinds, project_error = figure_3_4_slide("project", prime_overshoot=0.01)
    result, kinds, error = figure_3_4_slide("mujoco", prime_overshoot=0.01, tip_radius=R_TIP)
    assert result.success and project.success
    assert kinds.count(EventKind.PRIME) == 1 and EventKind.STUCK not in kinds and kinds.count(EventKind.SLIP) == 1
    assert error < 1e-4 and project_error < 1e-4
    assert result.xi[-1, 0] == pytest.approx(project.xi[-1, 0], abs=5e-5)


def test_without_the_spheres_couple_figure_3_4s_slide_stalls_on_mujoco():
    result, kinds, error = figure_3_4_slide("mujoco", prime_overshoot=0.01, tip_radius=0.0)
    assert kinds.count(EventKind.STUCK) >= 2 and error > 1e-4


@pytest.mark.slow
def test_the_scheduled_three_finger_rollout_makes_its_first_double_slide_on_mujoco():
    """Both side fingers slide up together, 27 mm in [0.815, 1.366] s (a schedule of the first 1.6 s: the
    periodic one's first two slides, planned in a third of the time), every contact loaded throughout (the health
    criteria, :mod:`regrasp.core.health`) and inside its planned envelope margin."""
    schedule = plan_regrasps(SC3, RegraspSettings(cone_margin=0.2, periodic=False), t_end=1.6)
    assert [(s.contact, s.direction) for s in schedule.slides] == [(0, 1), (1, -1)]
    result = build_rollout(SC3, RunSpec(duration=1.45), schedule=schedule, plant="mujoco").run()
    assert result.success, result.failure
    assert result.regrasps == {"finger1": 1, "finger2": 1, "palm": 0} and result.replans == 0
    assert result.plant_event_counts() == {"slip": 2, "stick": 2}
    assert result.max_object_error_after_transient < 2e-4 and result.max_orientation_error_after_transient < 3e-3
    assert result.min_cone_margin > 0.0 and result.min_envelope_margin > schedule.required_envelope_margin
    assert all(h.least_held_force >= 0.05 and h.longest_zero_force < 2e-3 for h in result.health)


def test_a_mujoco_rollout_records_to_rerun(tmp_path):
    from regrasp import RolloutRecorder

    rollout = build_rollout(SC2, RunSpec(duration=0.03), policy="none", plant="mujoco")
    with RolloutRecorder(rollout.plant, rrd_path=tmp_path / "r.rrd", decimation=5) as recorder:
        result = rollout.run(recorder=recorder)
    assert result.success and (tmp_path / "r.rrd").stat().st_size > 10_000


# ---------------------------------------------------------------------------- bad input and the extra
def test_bad_plants_and_plant_options_are_typed_errors(tmp_path):
    hand = hand_of(SC2)
    contacts = [PlantContact(1, "fixed", XI0), PlantContact(3, "fixed", XI0)]
    with pytest.raises(InvalidParameterError, match="multiple"):
        MujocoPlant(hand, SC2.polygon, contacts, dt=1.05e-3)
    with pytest.raises(InvalidParameterError, match="plant"):
        build_rollout(SC2, policy="none", plant="bullet")
    with pytest.raises(InvalidParameterError, match="settings"):
        build_rollout(SC2, policy="none", plant=PlantSpec(settings=MujocoSettings()))
    text = planar_2r_urdf(0.1, 0.05)
    finger = Finger.from_urdf_string(text, base_in_hand=(-0.05, 0.0, math.pi / 2))
    with pytest.raises(FingerModelError, match="URDF file"):
        build_mjcf([finger], SC2.polygon, [SC2.friction[0]])


def test_without_mujoco_the_extra_is_named(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "mujoco", None)  # import mujoco now raises ImportError
    with pytest.raises(MissingDependencyError, match=r"pip install 'regrasp\[mujoco\]'"):
        require_mujoco()
    assert main(["simulate", "--plant", "mujoco", "--duration", "0.1"]) == 2
    assert "pip install 'regrasp[mujoco]'" in capsys.readouterr().err


def test_a_tip_radius_needs_the_mujoco_plant(capsys):
    assert main(["simulate", "--tip-radius", "0.25", "--duration", "0.1"]) == 2
    assert "--tip-radius" in capsys.readouterr().err


def test_the_command_lines_help_does_not_import_mujoco():
    code = "import sys, regrasp.cli.main\ntry:\n    regrasp.cli.main.main(['simulate', '--help'])\n" \
           "except SystemExit:\n    pass\n" \
           "print('mujoco' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip().splitlines()[-1] == "False"


def test_the_mujoco_plant_saturates_the_torques_at_the_joints_limits():
    """clip(τ, -effort, effort) before ``qfrc_applied``: a limited plant driven beyond its limits steps exactly as
    an unlimited one driven with the clipped torques, and logs each joint's saturation when it starts."""
    effort = np.array([0.05, 0.03] * 2)
    plants = []
    for e in (effort[:2], np.inf):
        hand = Hand([c.finger.with_placement(effort_limit=e) for c in SC2.contacts],
                    gravity_in_hand=SC2.gravity_in_hand)
        contacts = [PlantContact(1, "fixed", XI0), PlantContact(3, "fixed", XI0)]
        plant = MujocoPlant(hand, SC2.polygon, contacts, friction=MU, stop_on=())
        model = ReducedModel(hand, Grasp(SC2.polygon, [1, 3], ["fixed", "fixed"]), [XI0, XI0])
        st = model.state(X_HOLD, np.zeros(3))
        plant.reset(st.q, st.q_dot, X_HOLD, np.zeros(3))
        plants.append(plant)
    for k, tau in enumerate([np.array([0.2, -0.1, -0.2, 0.01])] * 2 + [np.array([0.01, 0.0, -0.01, 0.0])]):
        step = plants[0].step(tau)
        expected = plants[1].step(np.clip(tau, -effort, effort))
        assert np.array_equal(step.state.q, expected.state.q) and np.array_equal(step.state.X, expected.state.X)
        saturation = [(e.contact, int(e.values["joint"])) for e in step.events if e.kind is EventKind.SATURATION]
        assert saturation == ([(SC2.contacts[0].finger.name, 1), (SC2.contacts[0].finger.name, 2),
                               (SC2.contacts[1].finger.name, 1)] if k == 0 else [])
    assert plants[0].saturation.saturated == (False,) * 4

"""Robustness studies: the Wilson interval against a brute-force inversion of the score test, seeded draws that
do not depend on how many runs or workers there are, one study run in-process, on two worker processes and on a
local Ray with the same results, the scenario's [study] table and the command line's flags."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from regrasp import ModelErrors, PlantSpec, RunSpec, build_rollout, load_scenario
from regrasp.cli.main import main
from regrasp.core.exceptions import InvalidParameterError, ScenarioError
from regrasp.study.study import Perturbation, draw_runs, run_study, wilson_interval

pytestmark = pytest.mark.slow  # (rollouts, subprocesses: `pytest -m "not slow"` leaves them out)

ROOT = Path(__file__).resolve().parents[2]
SCENARIO = ROOT / "examples" / "scenarios" / "paper_trajectory_2_three_fingers.toml"


@pytest.mark.parametrize("k, n", [(0, 10), (5, 10), (10, 10), (19, 20), (190, 200), (1, 3)])
def test_wilson_interval_is_the_set_of_proportions_the_score_test_accepts(k, n):
    # independent: every p on a fine grid with |k/n - p| <= z sqrt(p (1 - p) / n)
    z = 1.959963984540054
    p = np.linspace(0.0, 1.0, 2_000_001)
    accepted = p[np.abs(k / n - p) <= z * np.sqrt(p * (1.0 - p) / n)]
    lo, hi = wilson_interval(k, n)
    assert lo == pytest.approx(accepted.min(), abs=1e-6) and hi == pytest.approx(accepted.max(), abs=1e-6)


def test_wilson_interval_contains_the_proportion_exactly_for_every_count():
    # rounding once left the upper end 1 - 1e-16 at k = n, and a plot's error bar negative
    for n in range(1, 301):
        for k in range(n + 1):
            lo, hi = wilson_interval(k, n)
            assert 0.0 <= lo <= k / n <= hi <= 1.0, (k, n)
        assert wilson_interval(0, n)[0] == 0.0 and wilson_interval(n, n)[1] == 1.0


def test_wilson_interval_textbook_values_and_bad_counts():
    assert wilson_interval(5, 10) == pytest.approx((0.2366, 0.7634), abs=1e-4)
    assert wilson_interval(0, 10) == pytest.approx((0.0, 0.2775), abs=1e-4)
    for k, n in ((3, 2), (-1, 5), (1, 0), (1.0, 5), (True, 5)):
        with pytest.raises(InvalidParameterError):
            wilson_interval(k, n)


def test_the_figures_of_a_study_whose_bins_all_succeed(tmp_path):
    # synthetic outcomes (no rollout): 200 runs, most bins all successes, one failure; once this raised
    # in matplotlib ("yerr must not contain negative values") and lost a 19-minute study
    from regrasp.study.plots import plot_study
    from regrasp.study.study import RunOutcome, StudyResult

    perturbation = Perturbation(mass=0.2, mu=0.2, contact_position=2e-4)
    draws = draw_runs(200, 3, perturbation, contacts=3)
    runs = tuple(RunOutcome(d, i != 7, None if i != 7 else "unplanned_slip", None if i != 7 else 0.5,
                            None if i != 7 else "finger1", 0.05, 4e-3, 1e-4, 1e-3, 8, 0, 1.0)
                 for i, d in enumerate(draws))
    result = StudyResult("synthetic", runs, perturbation, 3, 2.0, 1, "process", 1.0, 0.1)
    paths = plot_study(result, tmp_path)
    assert [p.name for p in paths] == ["study_success.png", "study_failure_times.png", "study_margins.png"]
    assert all(p.stat().st_size > 1000 for p in paths)


def test_draws_are_seeded_per_run_and_inside_the_half_widths():
    draws = draw_runs(50, 11, Perturbation(mass=0.2, mu=0.1))
    assert draw_runs(50, 11, Perturbation(mass=0.2, mu=0.1)) == draws
    assert draw_runs(20, 11, Perturbation(mass=0.2, mu=0.1)) == draws[:20]  # run i's seed is the i-th child
    assert draw_runs(50, 12, Perturbation(mass=0.2, mu=0.1)) != draws
    mass = np.array([d.errors.mass_scale for d in draws])
    mu = np.array([d.errors.mu_scale for d in draws])
    assert 0.8 <= mass.min() and mass.max() <= 1.2 and 0.9 <= mu.min() and mu.max() <= 1.1
    assert mass.std() > 0.05 and abs(np.corrcoef(mass, mu)[0, 1]) < 0.4  # spread, and drawn independently
    assert all(d.errors.mass_scale == d.errors.mu_scale == d.errors.object_inertia_scale
               == d.errors.link_mass_scale == 1.0
               for d in draw_runs(3, 0, Perturbation()))
    full = draw_runs(200, 3, Perturbation(mass=0.2, mu=0.2, inertia=0.2, link_mass=0.2))
    factors = np.array([[d.errors.mass_scale, d.errors.mu_scale, d.errors.object_inertia_scale,
                         d.errors.link_mass_scale] for d in full])
    assert (factors >= 0.8).all() and (factors <= 1.2).all()
    assert np.abs(np.corrcoef(factors.T) - np.eye(4)).max() < 0.25  # four independent draws
    offsets = np.array([d.errors.xi_offset for d in draw_runs(300, 4, Perturbation(contact_position=2e-4), contacts=3)])
    assert offsets.shape == (300, 3) and np.abs(offsets).max() <= 2e-4 and offsets.std() > 1e-4
    assert np.abs(np.corrcoef(offsets.T) - np.eye(3)).max() < 0.2  # one independent error per fingertip
    kinetic = np.array([d.errors.mu_kinetic_scale for d in draw_runs(100, 4, Perturbation(mu_kinetic=0.1))])
    assert 0.9 <= kinetic.min() and kinetic.max() <= 1.1 and kinetic.std() > 0.03
    for bad in (dict(mass=1.0), dict(mu=-0.1), dict(mass=math.nan), dict(mu="0.1"), dict(contact_position=0.02),
                dict(delay=-1), dict(xi_noise=math.inf), dict(slip_threshold=-1.0)):
        with pytest.raises(InvalidParameterError):
            Perturbation(**bad)
    with pytest.raises(InvalidParameterError, match="runs"):
        draw_runs(0, 1, Perturbation())


#: The issue's robustness perturbations (model errors, placement and sensing noise, a one-step delay).
TARGET = Perturbation(mass=0.2, inertia=0.2, mu=0.2, contact_position=2e-4, xi_noise=2e-4, position_noise=1e-4,
                      angle_noise=1e-3, delay=1)
FLAGS = ["--mass", "0.2", "--inertia", "0.2", "--mu", "0.2", "--contact-position", "0.0002", "--xi-noise", "0.0002",
         "--position-noise", "0.0001", "--angle-noise", "0.001", "--delay", "1"]


@pytest.fixture(scope="module")
def in_process():
    """Four short runs in this process: the reference the other back-ends must repeat exactly."""
    return run_study(SCENARIO, 4, seed=5, perturbation=TARGET, duration=0.15, workers=1)


def same_runs(local, doc):
    assert doc["runs"] == 4 and doc["successes"] == local.successes
    assert doc["wilson_95"] == pytest.approx(list(local.interval))
    for mine, theirs in zip(local.runs, doc["outcomes"]):
        assert (theirs["draw"]["mass_scale"] == mine.draw.errors.mass_scale
                and theirs["draw"]["mu_scale"] == mine.draw.errors.mu_scale)
        assert theirs["draw"]["xi_offset"] == list(mine.draw.errors.xi_offset)
        for key in ("success", "failure_kind", "failure_time", "min_cone_margin", "min_envelope_margin", "slides",
                    "max_orientation_error"):
            assert theirs[key] == getattr(mine, key), key


def test_a_study_gives_the_same_runs_on_one_process_and_on_two(in_process, capsys, tmp_path):
    assert main(["study", str(SCENARIO), "--runs", "4", "--seed", "5", *FLAGS, "--duration", "0.15", "--workers", "2",
                 "--json", "--plot", str(tmp_path)]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["workers"] == 2 and doc["backend"] == "process"
    same_runs(in_process, doc)
    assert len({r.draw.errors.mass_scale for r in in_process.runs}) == 4  # the runs do differ
    assert len({r.min_cone_margin for r in in_process.runs}) == 4
    names = ("study_success.png", "study_failure_times.png", "study_margins.png")
    assert all((tmp_path / name).stat().st_size > 1000 for name in names)
    assert json.loads((tmp_path / "study.json").read_text())["outcomes"] == doc["outcomes"]


def interrupt_after(runs):
    """A progress callback that presses Ctrl-C (raises KeyboardInterrupt) once ``runs`` runs have finished."""
    def progress(done, total):
        if done >= runs:
            raise KeyboardInterrupt
    return progress


@pytest.mark.parametrize("workers", [1, 2])
def test_ctrl_c_ends_a_study_with_the_runs_it_finished(in_process, workers):
    result = run_study(SCENARIO, 4, seed=5, perturbation=TARGET, duration=0.15, workers=workers,
                       progress=interrupt_after(2), interruptible=True)
    assert result.interrupted and result.requested_runs == 4 and len(result.runs) == 2
    indices = [r.draw.index for r in result.runs]
    assert indices == sorted(indices)  # in run order, whichever finished first
    for mine in result.runs:  # the runs it kept are the study's own, whole
        reference = in_process.runs[mine.draw.index]
        assert (mine.success, mine.min_cone_margin, mine.min_envelope_margin) == \
            (reference.success, reference.min_cone_margin, reference.min_envelope_margin)
    doc = result.to_json_dict()
    assert doc["interrupted"] and doc["runs"] == 2 and doc["requested_runs"] == 4 and len(doc["outcomes"]) == 2
    assert not in_process.interrupted and in_process.to_json_dict()["interrupted"] is False
    with pytest.raises(KeyboardInterrupt):  # (not interruptible: Ctrl-C propagates, the workers stopped)
        run_study(SCENARIO, 4, seed=5, perturbation=TARGET, duration=0.15, workers=workers,
                  progress=interrupt_after(1))


def test_a_resumed_study_keeps_its_finished_runs_and_runs_the_others(in_process, tmp_path, capsys):
    from regrasp.study.resume import finished_runs, read_study

    part = run_study(SCENARIO, 4, seed=5, perturbation=TARGET, duration=0.15, workers=1,
                     progress=interrupt_after(1), interruptible=True)
    (tmp_path / "study.json").write_text(json.dumps(part.to_json_dict()))
    doc = read_study(tmp_path)
    same = dict(scenario=str(SCENARIO), contacts=3, plant="project", duration=part.duration, seed=5, runs=4,
                perturbation=TARGET, softness=None)
    finished = finished_runs(doc, **same)
    assert finished == part.runs  # (read back whole: the draw regenerated, every field as written)
    whole = run_study(SCENARIO, 4, seed=5, perturbation=TARGET, duration=0.15, workers=1, finished=finished)
    assert not whole.interrupted and [r.draw.index for r in whole.runs] == [0, 1, 2, 3]
    for mine, reference in zip(whole.runs, in_process.runs):  # the same runs as a study never interrupted
        assert (mine.success, mine.min_cone_margin, mine.max_object_error) == \
            (reference.success, reference.min_cone_margin, reference.max_object_error)
    for key, value in (("seed", 6), ("perturbation", Perturbation(mass=0.1)), ("plant", "mujoco"), ("runs", 0),
                       ("contacts", 2)):
        with pytest.raises(InvalidParameterError, match="resume"):
            finished_runs(doc, **{**same, key: value})
    with pytest.raises(InvalidParameterError, match="finished"):  # (a run of another study)
        run_study(SCENARIO, 4, seed=6, perturbation=TARGET, duration=0.15, workers=1, finished=finished)
    assert main(["study", str(SCENARIO), "--resume", str(tmp_path / "nowhere")]) == 2
    assert "--resume" in capsys.readouterr().err


def test_a_study_interrupted_before_any_run_finished_says_so(tmp_path):
    from regrasp.study.plots import plot_study

    result = run_study(SCENARIO, 3, seed=5, duration=0.05, workers=1, progress=interrupt_after(0), interruptible=True)
    assert result.runs == () and result.interrupted and result.requested_runs == 3
    assert math.isnan(result.success_rate) and result.interval == (0.0, 1.0)
    doc = result.to_json_dict()
    assert doc["success_rate"] is None and doc["runs"] == 0 and json.loads(json.dumps(doc)) == doc
    paths = plot_study(result, tmp_path)
    assert len(paths) == 3 and all(p.stat().st_size > 1000 for p in paths)


def test_a_study_on_a_local_ray_gives_the_same_runs(in_process, capsys):
    pytest.importorskip("ray")
    assert main(["study", str(SCENARIO), "--runs", "4", "--seed", "5", *FLAGS, "--duration", "0.15", "--workers", "2",
                 "--ray", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["backend"] == "ray"
    same_runs(in_process, doc)


def test_a_run_replayed_alone_repeats_the_studys_run_and_records_it(in_process, capsys, tmp_path):
    rrd = tmp_path / "run2.rrd"
    code = main(["study", str(SCENARIO), "--seed", "5", *FLAGS, "--duration", "0.15", "--replay", "2",
                 "--rrd", str(rrd), "--json"])
    doc = json.loads(capsys.readouterr().out)
    run = in_process.runs[2]
    assert (code == (0 if run.success else 1) and doc["run"] == 2
            and doc["draw"]["xi_offset"] == list(run.draw.errors.xi_offset))
    assert doc["min_cone_margin"] == run.min_cone_margin and doc["min_envelope_margin"] == run.min_envelope_margin
    assert rrd.stat().st_size > 10_000
    assert main(["study", str(SCENARIO), "--rrd", str(rrd)]) == 2  # a recording needs --replay
    assert "--replay" in capsys.readouterr().err


def test_a_sweep_is_one_study_per_size_with_the_same_draws(capsys, tmp_path):
    from regrasp.study.study import sweep_study

    sc = load_scenario(SCENARIO)
    schedule = build_rollout(sc, RunSpec(duration=0.1)).schedule
    results = sweep_study(sc, 2, "xi_noise", [0.0, 4e-4], perturbation=Perturbation(mass=0.2, delay=1), seed=3,
                          duration=0.1, schedule=schedule)
    assert [r.perturbation.xi_noise for r in results] == [0.0, 4e-4]
    assert all(r.perturbation.mass == 0.2 and r.perturbation.delay == 1 for r in results)
    for a, b in zip(*(r.runs for r in results)):
        assert a.draw == b.draw  # the k-th runs differ only in the swept size
    assert results[0].runs[0].min_envelope_margin != results[1].runs[0].min_envelope_margin  # (the noisy xi)
    with pytest.raises(InvalidParameterError, match="name"):
        sweep_study(sc, 2, "bogus", [0.0], schedule=schedule, duration=0.1)
    with pytest.raises(InvalidParameterError, match="mass"):
        sweep_study(sc, 2, "mass", [0.1, 1.5], schedule=schedule, duration=0.1)
    assert main(["study", str(SCENARIO), "--runs", "2", "--duration", "0.05", "--workers", "1", "--sweep",
                 "angle-noise=0,0.001", "--plot", str(tmp_path), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["sweep"] == "angle_noise" and doc["values"] == [0.0, 0.001] and len(doc["studies"]) == 2
    assert (tmp_path / "study_sweep.png").stat().st_size > 1000 and (tmp_path / "study_sweep.json").exists()


def test_the_noise_is_seeded_per_run(in_process):
    """A run repeated alone from its draw repeats exactly (the study's runs used the envelope plan it computed
    once; alone, the run plans it again); another seed gives other noise."""
    from regrasp.study.draws import RunDraw
    from regrasp.study.study import run_once

    sc = load_scenario(SCENARIO)
    first = in_process.runs[0]
    schedule = build_rollout(sc, RunSpec(duration=0.15)).schedule
    alone = run_once(sc, first.draw, schedule, 0.15, TARGET)
    assert alone.min_cone_margin == first.min_cone_margin and alone.max_orientation_error is None
    other = RunDraw(first.draw.index, (1, 2, 3, 4), first.draw.errors)
    assert run_once(sc, other, schedule, 0.15, TARGET).min_cone_margin != first.min_cone_margin


def test_a_rollout_refuses_a_plan_of_another_scenario():
    from regrasp.core.exceptions import InvalidParameterError
    from regrasp.envelope.planner import plan_scenario

    sc = load_scenario(SCENARIO)
    two = load_scenario(ROOT / "examples" / "scenarios" / "paper_trajectory_2.toml")
    with pytest.raises(InvalidParameterError, match="plan"):
        build_rollout(sc, RunSpec(duration=0.05), plan=plan_scenario(two, samples=11))


def test_the_scenario_study_table_sets_the_perturbations_and_flags_override_it(tmp_path, capsys):
    text = SCENARIO.read_text().replace('urdf = "../../urdf/', f'urdf = "{ROOT / "urdf"}/')
    assert load_scenario(SCENARIO).study == TARGET  # the shipped scenario carries the perturbations
    text = text[:text.index("[study]")]
    path = tmp_path / "with_study.toml"
    path.write_text(text + "\n[study]\nmass = 0.1\ncontact_position = 0.0002\ndelay = 1\nangle_noise = 0.001\n")
    assert load_scenario(path).study == Perturbation(mass=0.1, contact_position=2e-4, delay=1, angle_noise=1e-3)
    assert main(["study", str(path), "--runs", "1", "--duration", "0.02", "--workers", "1", "--mass", "0.05",
                 "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["perturbation"]["mass"] == 0.05 and doc["perturbation"]["delay"] == 1
    assert doc["perturbation"]["angle_noise"] == 0.001
    for bad, key in (("mass = 1.5", "study.mass"), ("delay = 0.5", "study.delay"),
                     ("xi_nosie = 1e-4", "study.xi_nosie"), ("position_noise = -1e-4", "study.position_noise")):
        path.write_text(text + f"\n[study]\n{bad}\n")
        with pytest.raises(ScenarioError, match=key):
            load_scenario(path)


def test_a_placement_error_that_would_leave_the_edge_is_refused_before_the_runs():
    sc = load_scenario(SCENARIO)
    with pytest.raises(InvalidParameterError, match="contact_position"):
        run_study(sc, 2, perturbation=Perturbation(contact_position=0.0099), duration=0.01)


@pytest.mark.parametrize("args", [["--runs", "0"], ["--mass", "1.5"], ["--mu", "abc"], ["--workers", "0"],
                                  ["nowhere.toml"], ["--duration", "nan"], ["--delay", "-1"], ["--delay", "11"],
                                  ["--xi-noise", "-0.1"], ["--contact-position", "0.5"], ["--torque-noise", "inf"],
                                  ["--slip-delay", "1.5"], ["--tip-radius", "0.3"], ["--sweep", "bogus=1"],
                                  ["--sweep", "mass=0.1,2"], ["--sweep", "delay="], ["--sweep", "mass=0.1",
                                                                                     "--replay", "0"]])
def test_bad_study_arguments_exit_2_with_one_line(capsys, args):
    try:
        code = main(["study", *args])
    except SystemExit as exc:
        code = exc.code
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and err[-1].startswith(("regrasp study: error:", "regrasp: error:")), err


def test_the_plant_gets_the_drawn_errors_and_the_controllers_keep_the_model():
    from regrasp import build_rollout, load_scenario

    sc = load_scenario(SCENARIO)
    r = build_rollout(sc, RunSpec(duration=0.1), policy="none",
                      plant=PlantSpec(errors=ModelErrors(mass_scale=1.1, inertia_scale=0.85, link_mass_scale=1.2,
                                                         mu_scale=0.9)))
    assert r.plant.mass == pytest.approx(1.1 * sc.polygon.mass)
    assert r.plant.inertia == pytest.approx(0.85 * sc.polygon.inertia)
    assert r.plant.friction[0].static == pytest.approx(0.9 * sc.friction[0].static)
    assert r.plant.hand.link_mass_scale == 1.2
    assert r.supervisor.hand.link_mass_scale == 1.0
    q = np.zeros(r.plant.hand.nq) + 0.3
    plant_m = r.plant.hand.dynamics(q, np.zeros_like(q)).mass_matrix
    model_m = r.supervisor.hand.dynamics(q, np.zeros_like(q)).mass_matrix
    np.testing.assert_allclose(plant_m, 1.2 * model_m, rtol=1e-12, atol=1e-15)  # M is linear in the link inertias


def test_softness_is_drawn_after_the_model_errors_and_only_for_a_compliant_plant():
    """A study on MuJoCo draws each run's contact softness after its model errors (the errors are those of a study
    without softness); a softened MuJoCo plant has the drawn solref, solimp width and tip radius; the rigid plant
    refuses a softness."""
    from regrasp.model.softness import SoftnessRanges
    from regrasp.study.study import soften

    p = Perturbation(mass=0.2, mu=0.2)
    plain = draw_runs(5, 3, p, 3)
    soft = draw_runs(5, 3, p, 3, SoftnessRanges())
    assert [d.errors for d in plain] == [d.errors for d in soft]
    assert all(d.softness is None for d in plain) and len({d.softness for d in soft}) == 5
    s = soft[0].softness
    spec = soften(PlantSpec("mujoco"), s)
    assert (spec.settings.time_constant, spec.settings.solimp[2], spec.settings.tip_radius) == \
        (s.time_constant, s.solimp_width, s.tip_radius)
    assert spec.tip_radius == s.tip_radius  # (the controllers are told the radius)
    assert soften(PlantSpec("mujoco"), None) == PlantSpec("mujoco")
    with pytest.raises(InvalidParameterError, match="rigid"):
        soften(PlantSpec("project"), s)
    with pytest.raises(InvalidParameterError, match="rigid"):
        run_study(SCENARIO, 1, softness=SoftnessRanges(), duration=0.01)


def test_a_study_that_drew_softness_plots_the_success_rate_against_it():
    """A study with drawn contact softness shows it in its success figure: one panel per softness range wider than a
    point (the tip radius fixed here: no panel), after the model errors."""
    from regrasp.model.softness import SoftnessRanges
    from regrasp.study.plots import drawn_factors
    from regrasp.study.study import RunOutcome, StudyResult

    p = Perturbation(mass=0.2)
    ranges = SoftnessRanges(tip_radius=(5e-4, 5e-4))
    draws = draw_runs(6, 2, p, 3, ranges)
    runs = tuple(RunOutcome(d, i % 2 == 0, None, None, None, 0.1, 1e-3, None, None, 0, 0, 1.0)
                 for i, d in enumerate(draws))
    result = StudyResult("x", runs, p, 2, 1.0, 1, "process", 1.0, 0.0, "mujoco", ranges)
    factors = drawn_factors(result)
    assert list(factors) == ["mass", "time_constant", "solimp_width"]
    np.testing.assert_allclose(factors["time_constant"][1], [1e3 * d.softness.time_constant for d in draws])
    assert list(result.to_json_dict()["softness"]["tip_radius"]) == [5e-4, 5e-4]

"""Robustness studies: the Wilson interval against a brute-force inversion of the score test, seeded draws that
do not depend on how many runs or workers there are, and one study run in-process and on two worker processes."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from regrasp.cli import main
from regrasp.exceptions import InvalidParameterError
from regrasp.study import Perturbation, draw_runs, run_study, wilson_interval

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "examples" / "scenarios" / "paper_trajectory_2_three_fingers.toml"


@pytest.mark.parametrize("k, n", [(0, 10), (5, 10), (10, 10), (19, 20), (190, 200), (1, 3)])
def test_wilson_interval_is_the_set_of_proportions_the_score_test_accepts(k, n):
    # independent: every p on a fine grid with |k/n - p| <= z sqrt(p (1 - p) / n)
    z = 1.959963984540054
    p = np.linspace(0.0, 1.0, 2_000_001)
    accepted = p[np.abs(k / n - p) <= z * np.sqrt(p * (1.0 - p) / n)]
    lo, hi = wilson_interval(k, n)
    assert lo == pytest.approx(accepted.min(), abs=1e-6) and hi == pytest.approx(accepted.max(), abs=1e-6)


def test_wilson_interval_textbook_values_and_bad_counts():
    assert wilson_interval(5, 10) == pytest.approx((0.2366, 0.7634), abs=1e-4)
    assert wilson_interval(0, 10) == pytest.approx((0.0, 0.2775), abs=1e-4)
    for k, n in ((3, 2), (-1, 5), (1, 0), (1.0, 5), (True, 5)):
        with pytest.raises(InvalidParameterError):
            wilson_interval(k, n)


def test_draws_are_seeded_per_run_and_inside_the_half_widths():
    draws = draw_runs(50, 11, Perturbation(mass=0.2, mu=0.1))
    assert draw_runs(50, 11, Perturbation(mass=0.2, mu=0.1)) == draws
    assert draw_runs(20, 11, Perturbation(mass=0.2, mu=0.1)) == draws[:20]  # run i's seed is the i-th child
    assert draw_runs(50, 12, Perturbation(mass=0.2, mu=0.1)) != draws
    mass = np.array([d.mass_scale for d in draws])
    mu = np.array([d.mu_scale for d in draws])
    assert 0.8 <= mass.min() and mass.max() <= 1.2 and 0.9 <= mu.min() and mu.max() <= 1.1
    assert mass.std() > 0.05 and abs(np.corrcoef(mass, mu)[0, 1]) < 0.4  # spread, and drawn independently
    assert all(d.mass_scale == d.mu_scale == d.inertia_scale == d.link_mass_scale == 1.0
               for d in draw_runs(3, 0, Perturbation()))
    full = draw_runs(200, 3, Perturbation(mass=0.2, mu=0.2, inertia=0.2, link_mass=0.2))
    factors = np.array([[d.mass_scale, d.mu_scale, d.inertia_scale, d.link_mass_scale] for d in full])
    assert (factors >= 0.8).all() and (factors <= 1.2).all()
    assert np.abs(np.corrcoef(factors.T) - np.eye(4)).max() < 0.25  # four independent draws
    for bad in (dict(mass=1.0), dict(mu=-0.1), dict(mass=math.nan), dict(mu="0.1")):
        with pytest.raises(InvalidParameterError):
            Perturbation(**bad)
    with pytest.raises(InvalidParameterError, match="runs"):
        draw_runs(0, 1, Perturbation())


def test_a_study_gives_the_same_runs_on_one_process_and_on_two(capsys, tmp_path):
    local = run_study(SCENARIO, 3, seed=5, perturbation=Perturbation(mass=0.2, mu=0.2), duration=0.2, workers=1)
    assert main(["study", str(SCENARIO), "--runs", "3", "--seed", "5", "--mass", "0.2", "--mu", "0.2", "--duration",
                 "0.2", "--workers", "2", "--json", "--plot", str(tmp_path)]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["workers"] == 2 and doc["runs"] == 3 and doc["successes"] == local.successes
    assert doc["wilson_95"] == pytest.approx(list(local.interval))
    for mine, theirs in zip(local.runs, doc["outcomes"]):
        assert theirs["draw"]["mass_scale"] == mine.draw.mass_scale and theirs["draw"]["mu_scale"] == mine.draw.mu_scale
        for key in ("success", "failure_kind", "failure_time", "min_cone_margin", "min_envelope_margin", "slides"):
            assert theirs[key] == getattr(mine, key), key
    assert len({r.draw.mass_scale for r in local.runs}) == 3  # the runs do differ
    assert all((tmp_path / name).stat().st_size > 1000 for name in ("study_outcomes.png", "study_failure_times.png"))


@pytest.mark.parametrize("args", [["--runs", "0"], ["--mass", "1.5"], ["--mu", "abc"], ["--workers", "0"],
                                  ["nowhere.toml"], ["--duration", "nan"]])
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
    r = build_rollout(sc, policy="none", duration=0.1, plant_mass_scale=1.1, plant_inertia_scale=0.85,
                      plant_mu_scale=0.9, plant_link_mass_scale=1.2)
    assert r.plant.mass == pytest.approx(1.1 * sc.polygon.mass)
    assert r.plant.inertia == pytest.approx(0.85 * sc.polygon.inertia)
    assert r.plant.friction[0].static == pytest.approx(0.9 * sc.friction[0].static)
    assert r.plant.hand.link_mass_scale == 1.2
    assert r.supervisor.hand.link_mass_scale == 1.0
    q = np.zeros(r.plant.hand.nq) + 0.3
    plant_m = r.plant.hand.dynamics(q, np.zeros_like(q)).mass_matrix
    model_m = r.supervisor.hand.dynamics(q, np.zeros_like(q)).mass_matrix
    np.testing.assert_allclose(plant_m, 1.2 * model_m, rtol=1e-12, atol=1e-15)  # M is linear in the link inertias

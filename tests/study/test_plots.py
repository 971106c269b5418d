"""A study's figures on synthetic outcomes (no rollout): one colour per failure kind whatever the study, a sentence
for an empty case, titles that say what was run."""

import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.colors import to_rgba

from regrasp.core.figures import FAILURE_COLOURS
from regrasp.study.plots import plot_study, study_title
from regrasp.study.study import Perturbation, RunOutcome, StudyResult, draw_runs


def study(kinds, *, runs: int = 40) -> StudyResult:
    """``runs`` runs, run i failing with ``kinds[i]`` when it has one (None: a success)."""
    perturbation = Perturbation(mass=0.2)
    draws = draw_runs(runs, 3, perturbation, contacts=3)
    outcomes = []
    for i, d in enumerate(draws):
        kind = kinds[i] if i < len(kinds) else None
        outcomes.append(RunOutcome(d, kind is None, kind, None if kind is None else 0.1 + 0.01 * i,
                                   None if kind is None else "finger1", 0.05, 4e-3, 1e-4, 1e-3, 2, 0, 1.0))
    return StudyResult("examples/scenarios/synthetic.toml", tuple(outcomes), perturbation, 3, 1.0, 1, "process",
                       1.0, 0.1, plant="mujoco")


@pytest.fixture()
def figures(monkeypatch):
    """The figures a study draws, by file name (closing them is skipped)."""
    made = {}
    save = plt.Figure.savefig

    def keep(fig, path, *args, **kwargs):
        made[str(path).rsplit("/", 1)[-1]] = fig
        return save(fig, path, *args, **kwargs)

    monkeypatch.setattr(plt.Figure, "savefig", keep)
    monkeypatch.setattr(plt, "close", lambda fig=None: None)
    yield made
    for fig in made.values():
        plt.close(fig)


def bar_colours(fig) -> dict[str, tuple]:
    """The failure-time histogram's colour per failure kind (its legend)."""
    ax = fig.axes[0]
    handles, labels = ax.get_legend_handles_labels()
    return {label: tuple(h.get_facecolor()) for h, label in zip(handles, labels)}


def test_each_failure_kind_has_its_colour_whatever_the_other_kinds(figures, tmp_path):
    plot_study(study(["unplanned_slip", "collision", "unplanned_slip"]), tmp_path / "a")
    first = bar_colours(figures["study_failure_times.png"])
    plot_study(study(["separation", "unplanned_slip", "left_envelope", "control"]), tmp_path / "b")
    second = bar_colours(figures["study_failure_times.png"])
    assert set(first) == {"unplanned_slip", "collision"}
    assert set(second) == {"separation", "unplanned_slip", "left_envelope", "control"}
    assert first["unplanned_slip"] == second["unplanned_slip"] == to_rgba(FAILURE_COLOURS["unplanned_slip"])
    for kind, colour in {**first, **second}.items():
        assert colour == to_rgba(FAILURE_COLOURS[kind])
        assert colour != to_rgba("tab:green")  # (green is a success)


def test_a_study_without_failures_says_so_in_a_sentence(figures, tmp_path):
    plot_study(study([]), tmp_path, gravity=np.array([0.0, -9.81]))
    fig = figures["study_failure_times.png"]
    (ax,) = fig.axes
    assert not ax.axison  # no axis, no ticks (once: an empty plot of ±0.045 runs)
    texts = " ".join(t.get_text() for t in ax.texts)
    assert "no run failed" in texts and "synthetic on the mujoco plant, gravity down, scheduled policy" in texts


def test_study_titles_name_scenario_plant_gravity_and_policy(figures, tmp_path):
    result = study(["collision"])
    title = study_title(result, [0.0, 9.81])
    for words in ("synthetic", "mujoco plant", "gravity up", "scheduled policy", "seed 3", "40 runs"):
        assert words in title
    plot_study(result, tmp_path, gravity=[0.0, 9.81])
    assert title in figures["study_success.png"].get_suptitle()
    assert title in figures["study_failure_times.png"].axes[0].get_title()
    assert title in figures["study_margins.png"].get_suptitle()


def test_the_success_axis_starts_near_the_lowest_rate(figures, tmp_path):
    plot_study(study(["collision"], runs=400), tmp_path)  # 399 of 400 succeed: the axis must not run from 0
    bottom, top = figures["study_success.png"].axes[0].get_ylim()
    assert 0.7 < bottom < 0.95 and top > 1.0

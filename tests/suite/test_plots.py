"""A suite's figures: written, non-empty PNGs, also for a suite with nothing to draw; the most telling keys."""

from regrasp.suite.plots import SUITE_FIGURES, influential, plot_suite
from suite_results import made_result

PNG = b"\x89PNG\r\n\x1a\n"


def test_the_figures_are_written(tmp_path):
    paths = plot_suite(made_result(), tmp_path)
    assert [p.name for p in paths] == list(SUITE_FIGURES)
    for p in paths:
        data = p.read_bytes()
        assert data.startswith(PNG) and len(data) > 5000


def test_a_suite_with_nothing_to_draw_says_so(tmp_path):
    paths = plot_suite(made_result(0, requested=3), tmp_path)
    assert all(p.read_bytes().startswith(PNG) for p in paths)
    only_plans = made_result(4, plan_only=True)
    assert all(p.read_bytes().startswith(PNG) for p in plot_suite(only_plans, tmp_path / "plans"))


def test_the_most_telling_keys_come_first():
    r = made_result()
    assert sorted(influential(r)) == sorted(r.varied)
    good = made_result(3)  # (every variant succeeded: the spec's order)
    assert influential(good) == list(good.varied)

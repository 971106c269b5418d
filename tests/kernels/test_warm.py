"""Loading the kernels (``regrasp.kernels.warm``): the groups a rollout needs, the cache check, the background
workers that compile a cold cache."""

from __future__ import annotations

import pytest

from regrasp.kernels import warm


def test_a_rollout_needs_every_group_but_the_footprints():
    assert set(warm.ROLLOUT) == set(warm.ALL) - {"footprint"}
    assert set(warm.STEP) == set(warm.ROLLOUT) - {"stretch"}
    assert set(warm.GROUPS) == set(warm.ALL)
    staged = [g for stage in warm.STAGES for worker in stage for g in worker]
    assert len(staged) == len(set(staged)) and set(staged) <= set(warm.ALL)


def test_nothing_is_compiled_in_the_background_when_the_cache_has_it():
    """The session's kernels are loaded (tests/conftest.py): so cached, and no worker is started."""
    warm.warm_up()
    assert all(warm.is_cached(g) for g in warm.ALL)
    assert warm.compile_in_background(warm.ALL) == []
    assert not warm.compiling()


@pytest.mark.slow
def test_background_workers_report_each_group_and_end():
    """Two workers side by side, then one (here from the warm cache: a second each), counted as they finish."""
    job = warm.BackgroundCompile([[["finger"], ["reduced"]], [["plant"]]])
    seen = []
    job.wait(["finger", "reduced"], lambda done, total: seen.append((done, total)))
    assert seen[-1] == (2, 2) and {"finger", "reduced"} <= job.finished
    job.wait(job.groups)
    assert job.finished == {"finger", "reduced", "plant"} and not job.pending("plant")
    assert [d for d, _ in seen] == sorted(d for d, _ in seen)

"""The peak memory of a stretch of work: reset, then read back; without a reset, an upper bound."""

import sys

import numpy as np
import pytest

from regrasp.suite.memory import peak_memory, reset_peak_memory


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc/self/clear_refs is Linux's")
def test_the_peak_is_the_works_own():
    assert reset_peak_memory()
    before = peak_memory(True)
    big = np.ones(64 * 2**20 // 8)  # 64 MiB, touched
    during = peak_memory(True)
    del big
    assert not before.upper_bound and not during.upper_bound
    assert during.bytes - before.bytes >= 60 * 2**20
    assert reset_peak_memory()
    after = peak_memory(True)
    assert after.bytes < during.bytes  # (the high-water mark was reset)


def test_without_a_reset_the_peak_is_an_upper_bound():
    peak = peak_memory(False)
    assert peak is not None and peak.upper_bound and peak.bytes > 0

"""The peak memory of a stretch of work: reset, then read back; without a reset, an upper bound."""

import subprocess
import sys

import pytest

from hang_guard import HANG_SECONDS
from regrasp.suite.memory import peak_memory

_WORK = """
import numpy as np
from regrasp.suite.memory import peak_memory, reset_peak_memory
assert reset_peak_memory()
before = peak_memory(True)
big = np.ones(64 * 2**20 // 8)  # 64 MiB, touched
during = peak_memory(True)
del big
assert not before.upper_bound and not during.upper_bound
assert during.bytes - before.bytes >= 60 * 2**20, (before, during)
assert reset_peak_memory()
after = peak_memory(True)
assert after.bytes < during.bytes, (after, during)  # (the high-water mark was reset)
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc/self/clear_refs is Linux's")
def test_the_peak_is_the_works_own():
    """In a fresh process (a test process's own history, its freed pages and arenas, can hide a new allocation)."""
    proc = subprocess.run([sys.executable, "-c", _WORK], capture_output=True, text=True, timeout=HANG_SECONDS,
                          check=False)
    assert proc.returncode == 0, proc.stderr


def test_without_a_reset_the_peak_is_an_upper_bound():
    peak = peak_memory(False)
    assert peak is not None and peak.upper_bound and peak.bytes > 0

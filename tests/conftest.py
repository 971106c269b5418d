"""The test session's set-up: every compiled kernel loaded once, first.

numba compiles a kernel on its first call in a process (and caches it on disk, `cache=True`): on a fresh machine
the first test to touch a kernel pays the whole compile. Loading them all here, before any test, means no test
(and no subprocess one starts, which then reads the disk cache) races a cold compile against its timeout.
"""

import pytest


@pytest.fixture(scope="session", autouse=True)
def compiled_kernels():
    from regrasp.kernels import warm_up

    warm_up()

"""How long a test waits for a subprocess before calling it hung [s].

A guard against a hang only: never a time a slow, loaded or cold machine (numba compiling every kernel on first
use) could reach. Speed is measured by the benchmarks, not by the tests.
"""

#: Half an hour: no command a test starts takes a tenth of that on a loaded 2-core machine.
HANG_SECONDS = 1800

"""How long a test waits for a subprocess before calling it hung [s].

A guard against a hang only: never a time a slow, loaded or cold machine (numba compiling every kernel on first
use) could reach. Speed is measured by the benchmarks, not by the tests.
"""

#: Half an hour: no command a test starts takes a tenth of that on a loaded 2-core machine.
HANG_SECONDS = 1800


def interrupted_run(argv: list[str], cwd: object, marker: str = "(10%)") -> tuple[int, str, str]:
    """Run ``python -m regrasp.cli.main *argv`` in ``cwd``, send it SIGINT once its stderr shows ``marker``
    (event-driven: no clock to race), and return (exit status, stdout, the whole stderr)."""
    import signal
    import subprocess
    import sys

    proc = subprocess.Popen([sys.executable, "-m", "regrasp.cli.main", *argv], cwd=cwd, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    seen = []
    for line in proc.stderr:
        seen.append(line)
        if marker in line:
            break
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=HANG_SECONDS)
    return proc.returncode, out, "".join(seen) + err

"""A process's peak memory over a stretch of work (a variant's planning): its peak resident set size.

On Linux, :func:`reset_peak_memory` writes ``5`` to ``/proc/self/clear_refs``, which resets the kernel's high-water
mark of the process's resident set, and :func:`peak_memory` reads it back (``VmHWM`` in ``/proc/self/status``): the
peak over the work alone, threads included. Where that is not available (another system, a kernel that refuses the
write), :func:`peak_memory` falls back to ``resource.getrusage(RUSAGE_SELF).ru_maxrss``, the peak since the process
started, and says so: that number is an upper bound of the work's peak.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

__all__ = ["PeakMemory", "peak_memory", "reset_peak_memory"]

_CLEAR_REFS = Path("/proc/self/clear_refs")
_STATUS = Path("/proc/self/status")


@dataclass(frozen=True)
class PeakMemory:
    """A peak resident set size.

    Attributes:
        bytes: The peak [B].
        upper_bound: True when the high-water mark could not be reset: the process's peak since it started, an upper
            bound of the work's.
    """

    bytes: int
    upper_bound: bool


def reset_peak_memory() -> bool:
    """Reset this process's peak resident set size (Linux); whether it could."""
    try:
        _CLEAR_REFS.write_text("5")
    except OSError:
        return False
    return True


def _vm_hwm() -> int | None:
    """``VmHWM`` of ``/proc/self/status`` [B], or None."""
    try:
        for line in _STATUS.read_text().splitlines():
            if line.startswith("VmHWM:"):
                number, unit = line.split()[1:3]
                return int(number) * (1024 if unit.lower() == "kb" else 1)
    except (OSError, ValueError, IndexError):
        return None
    return None


def peak_memory(reset: bool) -> PeakMemory | None:
    """This process's peak resident set size since :func:`reset_peak_memory` (``reset``: what it returned), or,
    without a reset or ``VmHWM``, since the process started (an upper bound); None where neither can be read."""
    if reset:
        hwm = _vm_hwm()
        if hwm is not None:
            return PeakMemory(hwm, False)
    try:
        import resource
    except ImportError:  # (not a POSIX system)
        return None

    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return PeakMemory(int(rss) * (1 if sys.platform == "darwin" else 1024), True)  # (kB on Linux, B on macOS)

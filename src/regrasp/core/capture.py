"""Capturing what C and C++ libraries write straight to a file descriptor (not through Python).

urdfdom prints its parse errors on fd 2 before Pinocchio raises, and OSQP prints "Polishing not
needed" on fd 1 even with ``verbose=False``: a one-line error, or a JSON document on stdout, needs
them kept off the terminal. :func:`captured_fd` redirects the descriptor to a temporary file for the
duration and hands back what was written.
"""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile
from collections.abc import Iterator

__all__ = ["captured_fd"]


class Captured:
    """What a :func:`captured_fd` block wrote (``text``, filled in when the block ends)."""

    text = ""


@contextlib.contextmanager
def captured_fd(fd: int) -> Iterator[Captured]:
    """Redirect file descriptor ``fd`` (1 or 2) to a temporary file while the block runs; yields a
    :class:`Captured` whose ``text`` holds what was written. Where the descriptor cannot be duplicated
    (an embedded interpreter), nothing is captured."""
    captured = Captured()
    stream = sys.stdout if fd == 1 else sys.stderr if fd == 2 else None
    if stream is not None:
        stream.flush()
    try:
        saved = os.dup(fd)
    except OSError:
        yield captured
        return
    with tempfile.TemporaryFile() as sink:
        os.dup2(sink.fileno(), fd)
        try:
            yield captured
        finally:
            if stream is not None:
                stream.flush()
            os.dup2(saved, fd)
            os.close(saved)
            sink.seek(0)
            captured.text = sink.read().decode("utf-8", "replace")

"""What the command line's commands share: argument types (one parser maker for every numeric option, one for every
count, :func:`count_argument`), the progress bar, the output paths' checks, the default scenario and the plant
options."""

from __future__ import annotations

import argparse
import os
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, TextIO, TypeVar

from ..core.exceptions import InvalidParameterError
from ..core.validation import MAX_TIP_RADIUS, as_count, as_output_directory, as_output_path

if TYPE_CHECKING:
    from ..core.pad import Pad
    from ..plants.spec import PlantSpec

__all__ = ["DEFAULT_SCENARIO", "DEFAULT_SUITE", "STARTED", "KernelLoad", "ProgressBar", "add_plant_arguments",
           "compile_kernels", "count_argument", "nonnegative", "number_argument", "output_directory", "output_file",
           "pad_option", "plant_spec", "positive", "ray_address_argument"]

#: When the command line started (``time.monotonic()``, at the CLI's import, before any heavy import): a summary's
#: "in all" wall time counts imports, planning and compiling too.
STARTED = time.monotonic()

T = TypeVar("T", int, float)

#: The default scenario (in the source tree's examples/).
DEFAULT_SCENARIO = Path(__file__).resolve().parents[3] / "examples" / "scenarios" / \
    "paper_trajectory_2_three_fingers.toml"
#: The default suite's spec (in the source tree's examples/).
DEFAULT_SUITE = DEFAULT_SCENARIO.parents[1] / "suites" / "default.toml"


def number_argument(kind: type[T], expected: str, accept: Callable[[T], bool]) -> Callable[[str], T]:
    """A ``type=`` for argparse: ``kind(text)`` when ``accept`` takes it, else an ``ArgumentTypeError``
    saying ``expected`` (argparse turns it into one ``error:`` line and exit 2)."""
    def parse(text: str) -> T:
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {expected}, got {text!r}") from None
        if not accept(value):
            raise argparse.ArgumentTypeError(f"expected {expected}, got {text!r}")
        return value
    return parse


def positive(kind: type[T]) -> Callable[[str], T]:
    """A ``type=`` for a finite number > 0 of ``kind``."""
    return number_argument(kind, f"a finite {kind.__name__} > 0", lambda v: 0 < v < float("inf"))


#: A ``type=`` for a finite number >= 0.
nonnegative = number_argument(float, "a finite number >= 0", lambda v: 0.0 <= v < float("inf"))


def count_argument(least: int, most: int) -> Callable[[str], int]:
    """A ``type=`` for a count: an integer in [``least``, ``most``] (the library's :func:`~regrasp.core.validation.
    as_count`), else an ``ArgumentTypeError`` (one ``error:`` line naming the flag, exit 2): every integer flag."""
    expected = f"an integer in [{least}, {most}]"

    def parse(text: str) -> int:
        try:
            return as_count("count", int(text), least, most)
        except (ValueError, InvalidParameterError):  # (int() refuses 'abc', '1.5' and more than 4300 digits)
            raise argparse.ArgumentTypeError(f"expected {expected}, got {text!r}") from None
    return parse


def ray_address_argument(text: str) -> str:
    """``--ray ADDRESS``'s type: an address :func:`~regrasp.study.ray_cluster.parse_ray_address` takes (it is reached
    when the work starts, before any planning)."""
    from ..study.ray_cluster import parse_ray_address

    try:
        return parse_ray_address("--ray", text).text
    except InvalidParameterError as exc:
        raise argparse.ArgumentTypeError(f"expected {exc.expected}, got {text!r}") from None


class ProgressBar:
    """A one-line progress bar on stderr (done/total, elapsed and remaining time), drawn only when stderr is a
    terminal; with ``lines``, elsewhere (a pipe, a log file) a plain line at each tenth of the work instead."""

    def __init__(self, label: str, stream: TextIO = sys.stderr, *, lines: bool = False):
        self.label, self.stream = label, stream
        self.enabled = stream.isatty()
        self.lines = lines and not self.enabled
        self._last = -1
        self._start = time.monotonic()

    def __call__(self, done: int, total: int) -> None:
        if not (self.enabled or self.lines):
            return
        pct = int(100 * done / total)
        step = pct // 10 if self.lines else pct
        if step != self._last:
            self._last = step
            elapsed = time.monotonic() - self._start
            left = f", {elapsed * (total - done) / done:.0f} s left" if 0 < done < total else ""
            if self.lines:
                self.stream.write(f"{self.label}: {done}/{total} ({pct}%), {elapsed:.0f} s{left}\n")
            else:
                bar = "#" * (pct // 4) + "." * (25 - pct // 4)
                self.stream.write(f"\r{self.label} [{bar}] {pct:3d}% ({done}/{total}, {elapsed:.0f} s{left})  ")
                if done == total:
                    self.stream.write("\n")
            self.stream.flush()


#: Loading the kernels takes about a second from numba's disk cache; longer, they are being compiled [s].
COMPILE_NOTICE_AFTER = 2.0

#: The progress line's label while kernels compile.
COMPILING = "regrasp: compiling kernels (once per machine)"


class KernelLoad:
    """The numba kernels a command needs (``groups``, :data:`regrasp.kernels.warm.GROUPS`), loaded before its runs.

    Made at the command's start: on a cold disk cache (a machine's first run, a new numba) it starts compiling them in
    worker processes (:func:`~regrasp.kernels.warm.compile_in_background`) and says so on ``stream`` at once, so the
    command's planning goes on meanwhile; :meth:`finish` (or a plant's constructor, which loads them too) waits for
    them with a progress line on ``stream`` (drawn on a terminal, plain lines elsewhere) and loads them. On one
    core they compile in :meth:`finish`, said when that takes longer than a cache load (:data:`COMPILE_NOTICE_AFTER`).
    """

    def __init__(self, groups: tuple[str, ...] | None = None, quiet: bool = False, stream: TextIO = sys.stderr):
        from ..kernels.warm import ROLLOUT, compile_in_background, set_wait_progress

        self.groups = ROLLOUT if groups is None else groups
        self.quiet, self.stream = quiet, stream
        self.start = time.monotonic()
        self.bar = ProgressBar(COMPILING, stream, lines=True)
        self.background = compile_in_background(self.groups)
        self.said = bool(self.background) and not quiet
        if self.said:
            stream.write("regrasp: compiling the numba kernels once per machine and numba version, in worker "
                         "processes while this one goes on (about 20-30 s on 2 cores); later runs load them from "
                         "numba's cache in about a second\n")
            stream.flush()
            set_wait_progress(self.bar)

    def finish(self, stretches: bool = True) -> float:
        """Wait for the kernels and load them (without ``stretches``, not the stretch kernel while a worker still
        compiles it: a rollout decides, :meth:`regrasp.rollout.build.Rollout.run`); the seconds since the command
        asked for them."""
        from ..kernels import warm_up
        from ..kernels.warm import compiling, set_wait_progress

        later = not stretches and compiling("stretch")
        groups = tuple(g for g in self.groups if not (later and g == "stretch"))

        said = threading.Event()
        if self.said:
            said.set()

        def notice() -> None:
            said.set()
            self.stream.write("regrasp: compiling the numba kernels: once per machine and numba version, about 40 s "
                              "on one core; later runs load them from numba's cache in about a second\n")
            self.stream.flush()

        timer = threading.Timer(COMPILE_NOTICE_AFTER, notice)
        timer.daemon = True
        if not self.quiet and not self.said:
            timer.start()
        try:
            warm_up(progress=lambda done, total: self.bar(done, total) if said.is_set() else None, groups=groups)
        finally:
            timer.cancel()
            if not later:
                set_wait_progress(None)
        seconds = time.monotonic() - self.start
        if said.is_set():
            self.stream.write(f"regrasp: kernels compiled in {seconds:.0f} s" + (
                "; the stretch kernel goes on compiling in the background for the next runs (a short run takes its "
                "steps without it, the same steps)" if later and compiling("stretch") else "") + "\n")
            self.stream.flush()
        return seconds


def compile_kernels(quiet: bool = False, stream: TextIO = sys.stderr, groups: tuple[str, ...] | None = None) -> float:
    """Load the numba kernels ``groups`` (default those of a rollout) before the work starts (:class:`KernelLoad`
    made and finished at once); the seconds it took."""
    return KernelLoad(groups, quiet, stream).finish()


def output_directory(option: str, path: str | os.PathLike[str]) -> Path:
    """``path`` as a directory files can be written into (made if missing), or an
    :class:`~regrasp.core.exceptions.InvalidParameterError` naming ``option``
    (:func:`~regrasp.core.validation.as_output_directory`)."""
    directory = as_output_directory(option, path)
    try:
        directory.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InvalidParameterError(option, str(path), f"a directory that can be made ({exc.strerror or exc})") \
            from None
    return directory


def output_file(option: str, path: str | os.PathLike[str] | None) -> Path | None:
    """``path`` as a file that can be written (:func:`~regrasp.core.validation.as_output_path`), checked before any
    work, or None for None; else an :class:`~regrasp.core.exceptions.InvalidParameterError` naming ``option``."""
    return None if path is None else as_output_path(option, path)


#: ``--tip-radius``'s type: a radius in (0, MAX_TIP_RADIUS] [mm].
_TIP_RADIUS = number_argument(float, f"a radius in (0, {MAX_TIP_RADIUS * 1e3:g}] mm",
                              lambda v: 0.0 < v <= MAX_TIP_RADIUS * 1e3)


def add_plant_arguments(p: argparse.ArgumentParser) -> None:
    """``--plant``, ``--tip-radius`` and the pad options (read back by :func:`plant_spec`)."""
    p.add_argument("--plant", choices=("project", "mujoco", "drake"), default="project",
                   help="project: the full-coordinate plant with point contacts (default); mujoco: MuJoCo with sphere "
                        "tips and soft contacts (pip install 'regrasp[mujoco]'); drake: Drake with sphere tips and "
                        "compliant point contacts (pip install 'regrasp[drake]')")
    p.add_argument("--tip-radius", type=_TIP_RADIUS, metavar="MM",
                   help="--plant mujoco or drake: the fingertips' sphere radius [mm] (default 0.25)")
    p.add_argument("--pad-stiffness", type=positive(float), metavar="N_PER_M",
                   help="--plant project: compliant fingertip pads of this stiffness [N/m] (Kelvin-Voigt; the "
                        "reference path; default: the scenario's [pad], else rigid contacts)")
    p.add_argument("--pad-damping", type=nonnegative, metavar="N_S_PER_M",
                   help="with --pad-stiffness: the pads' damping [N s/m] (default 0)")
    p.add_argument("--pad-preload", type=nonnegative, metavar="N",
                   help="with --pad-stiffness: the force [N] of a tip placed on its edge (default 0.5)")


def plant_spec(args: argparse.Namespace) -> PlantSpec:
    """The plant ``--plant``, ``--tip-radius`` and the pad options (:func:`pad_option`) ask for; a missing extra
    (``mujoco``, ``drake``), a radius on the project's plant or a pad on another is an error before any work."""
    from ..plants.spec import PlantSpec

    if args.tip_radius is not None and args.plant not in ("mujoco", "drake"):
        raise InvalidParameterError("--tip-radius", args.tip_radius, "no radius unless --plant mujoco or drake (the "
                                    "project's plant has point contacts)")
    spec = PlantSpec(args.plant)  # (checks for the extra before any planning: it says at once that it is missing)
    pad = pad_option(args)
    if pad is not None:
        return PlantSpec(args.plant, pad=pad)
    if args.tip_radius is None or args.plant == "project":
        return spec
    return PlantSpec(args.plant, spec.settings_class()(tip_radius=args.tip_radius * 1e-3))


def pad_option(args: argparse.Namespace) -> Pad | None:
    """The pad ``--pad-stiffness``, ``--pad-damping`` and ``--pad-preload`` ask for (None: none asked); the last two
    need the first, and all need ``--plant project``."""
    from ..core.pad import DEFAULT_PAD_PRELOAD, Pad

    stiffness = getattr(args, "pad_stiffness", None)
    damping, preload = getattr(args, "pad_damping", None), getattr(args, "pad_preload", None)
    if stiffness is None:
        for name, value in (("--pad-damping", damping), ("--pad-preload", preload)):
            if value is not None:
                raise InvalidParameterError(name, value, "no pad option without --pad-stiffness")
        return None
    if args.plant != "project":
        raise InvalidParameterError("--pad-stiffness", stiffness, "no pad unless --plant project (MuJoCo and Drake "
                                    "have their own contact laws)")
    return Pad(stiffness, 0.0 if damping is None else damping, DEFAULT_PAD_PRELOAD if preload is None else preload)

"""What the package's PNG figures share (matplotlib, headless): pyplot on the Agg backend, a column of axes over a
common time axis, interval sets drawn as images, and writing a figure.

matplotlib is imported inside the functions, on first use, so that importing :mod:`regrasp` does not load it.
Plot lengths are in millimetres (:data:`MM`).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from .intervals import Intervals

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["ARC_STYLE", "FAILURE_COLOURS", "FAILURE_COLOUR", "MM", "SUCCESS_COLOUR", "gravity_words", "membership",
           "pyplot", "save_figure", "say_instead", "shade_arcs", "stacked_axes"]

#: Millimetres per metre: the figures' lengths are in mm.
MM = 1000.0

#: A success, in every figure; no failure kind is green.
SUCCESS_COLOUR = "tab:green"
#: A failure of any kind (a figure that does not tell them apart).
FAILURE_COLOUR = "tab:red"
#: Each failure kind's colour (a :class:`~regrasp.core.events.FailureKind` value), the same in every figure.
FAILURE_COLOURS = {"separation": "tab:purple", "unplanned_slip": "tab:orange", "collision": "tab:brown",
                   "left_envelope": "tab:pink", "left_edge": "tab:olive", "singular": "tab:gray",
                   "control": "tab:cyan", "no_schedule": "tab:blue", "interrupted": "black"}


def gravity_words(gravity: ArrayLike) -> str:
    """Gravity (2,) [m/s²] in the hand frame in words: ``gravity down`` / ``up`` / ``left`` / ``right`` when it
    points along an axis, ``no gravity``, else its components."""
    gx, gy = (float(v) for v in gravity)
    size = float(np.hypot(gx, gy))
    if size == 0.0:
        return "no gravity"
    for word, (ux, uy) in (("down", (0, -1)), ("up", (0, 1)), ("left", (-1, 0)), ("right", (1, 0))):
        if abs(gx - size * ux) + abs(gy - size * uy) < 1e-9 * size:
            return f"gravity {word}"
    return f"gravity ({gx:g}, {gy:g}) m/s²"


def pyplot() -> ModuleType:
    """``matplotlib.pyplot``, with the headless Agg backend selected (imported on first use)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def stacked_axes(n: int) -> tuple[Figure, np.ndarray]:
    """A figure of ``n`` axes in a column sharing their x (time) axis, 3.4 in high each; (figure, the (n,) axes)."""
    fig, axes = pyplot().subplots(n, 1, figsize=(9, 3.4 * n), sharex=True, squeeze=False)
    return fig, axes[:, 0]


def membership(times: np.ndarray, sets_per_sample: Sequence[Intervals], grid: np.ndarray) -> np.ndarray:
    """(len(grid), len(times)) boolean image: whether a ``grid`` value lies in the sample's interval set (one set per
    time of ``times``; the grid and the sets in the same unit)."""
    img = np.zeros((len(grid), len(times)), dtype=bool)
    for k, intervals in enumerate(sets_per_sample):
        for lo, hi in intervals:
            img[:, k] |= (grid >= lo) & (grid <= hi)
    return img


#: How an object's arcs are drawn across a ξ axis (:func:`shade_arcs`).
ARC_STYLE = dict(color="#6a51a3", alpha=0.13, lw=0)


def shade_arcs(ax: object, obj: object, lo: float, hi: float) -> bool:
    """Shade, across an axis of ξ [mm] from ``lo`` to ``hi`` [m], the arcs of a rounded polygon ``obj`` (its corners,
    labelled "arc k" at the axis' right end): where a contact on it is on a corner, not on an edge's straight part.
    Other objects have no pieces to tell apart (nothing drawn); whether any arc was drawn."""
    pieces = getattr(obj, "pieces_between", None)
    arcs = [] if pieces is None else [(k, a, b) for kind, k, a, b in pieces(lo, hi) if kind == "arc"]
    for k, a, b in arcs:
        ax.axhspan(a * MM, b * MM, **ARC_STYLE)
        ax.text(1.0, 0.5 * (a + b) * MM, f"arc {k} ", transform=ax.get_yaxis_transform(), ha="right", va="center",
                fontsize=7, color="#54278f")
    return bool(arcs)


def say_instead(ax: object, text: str) -> None:
    """An axis that has nothing to draw says so, in words (``text``), instead of showing empty ranges."""
    ax.set_axis_off()
    ax.text(0.5, 0.5, text, transform=ax.transAxes, ha="center", va="center", wrap=True)


def save_figure(fig: Figure, path: str | Path, layout: bool = True) -> Path:
    """Write ``fig`` to ``path`` (a PNG at 110 dpi; its directory made if missing, tight layout first when
    ``layout``) and close it; the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if layout:
        fig.tight_layout()
    fig.savefig(path, dpi=110)
    pyplot().close(fig)
    return path

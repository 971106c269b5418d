"""A robustness study's figures (PNG, headless): success against each drawn model error, failure times by
kind, and the runs' smallest margins."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ..core.figures import say_instead

if TYPE_CHECKING:
    from .study import StudyResult

__all__ = ["drawn_factors", "plot_study", "plot_sweep", "study_title"]

#: The drawn model errors a figure can show: (the perturbation's field, the axis label, the run's value).
_DRAWN = (
    ("mass", "plant mass / model mass [-]", lambda d: d.errors.mass_scale),
    ("inertia", "plant inertia / model inertia [-]", lambda d: d.errors.object_inertia_scale),
    ("mu", "plant μ / model μ [-]", lambda d: d.errors.mu_scale),
    ("mu_kinetic", "plant μ_k factor [-]", lambda d: d.errors.mu_kinetic_scale),
    ("link_mass", "plant link mass / URDF link mass [-]", lambda d: d.errors.link_mass_scale),
    ("contact_position", "largest placement error |δξ| [mm]",
     lambda d: 1e3 * max((abs(x) for x in d.errors.xi_offset), default=0.0)),
)


#: The drawn contact softness a figure can show (a study with ``softness``): (name, the axis label, the run's value).
_SOFTNESS = (
    ("time_constant", "contact solref time constant [ms]", lambda d: 1e3 * d.softness.time_constant),
    ("solimp_width", "contact solimp width [mm]", lambda d: 1e3 * d.softness.solimp_width),
    ("tip_radius", "tip radius [mm]", lambda d: 1e3 * d.softness.tip_radius),
)


def drawn_factors(result: StudyResult) -> dict[str, tuple[str, np.ndarray]]:
    """Each model error the study drew (its perturbation is not zero), then each contact softness it drew (a range
    wider than a point): name -> (axis label, value per run)."""
    sizes = result.perturbation.nonzero()
    out = {name: (label, np.array([value(r.draw) for r in result.runs]))
           for name, label, value in _DRAWN if name in sizes}
    if result.softness is not None:
        for name, label, value in _SOFTNESS:
            lo, hi = getattr(result.softness, name)
            if hi > lo:
                out[name] = (label, np.array([value(r.draw) for r in result.runs]))
    return out


def study_title(result: StudyResult, gravity: ArrayLike | None = None) -> str:
    """What a study's figure is of: the scenario, the plant, the gravity (``gravity`` (2,) [m/s²] in the hand frame,
    the scenario's; left out when None), the policy (a study's runs follow its schedule), the runs (and whether
    Ctrl-C cut the study short)."""
    from ..core.figures import gravity_words

    done = len(result.runs)
    runs = f"{done} of {result.requested_runs} runs" if result.interrupted else f"{done} runs"
    where = "" if gravity is None else f", {gravity_words(gravity)}"
    return (f"{Path(result.scenario).stem} on the {result.plant} plant{where}, scheduled policy, seed {result.seed}: "
            f"{runs} of {result.duration:.3g} s" + (" (interrupted)" if result.interrupted else ""))


def _bins(x: np.ndarray, ok: np.ndarray, bins: int) -> tuple[list[float], list[float], list[float], list[float]]:
    """The success rate in ``bins`` equal bins of x (the empty ones left out): (bin centres, rates, each rate's
    Wilson 95 % interval's lower and upper ends)."""
    from .study import wilson_interval

    edges = np.linspace(x.min(), x.max(), bins + 1) if x.max() > x.min() else np.array([x.min() - 0.5, x.min() + 0.5])
    which = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, len(edges) - 2)
    centres, rates, lows, highs = [], [], [], []
    for b in range(len(edges) - 1):
        inside = which == b
        n = int(inside.sum())
        if n == 0:
            continue
        k = int(ok[inside].sum())
        lo, hi = wilson_interval(k, n)
        centres.append(0.5 * (edges[b] + edges[b + 1]))
        rates.append(k / n)
        lows.append(lo)
        highs.append(hi)
    return centres, rates, lows, highs


def _binned(ax, x: np.ndarray, ok: np.ndarray, binned: tuple, bottom: float) -> None:
    """``binned`` (:func:`_bins`) with its intervals, and every run as a tick, on a rate axis from ``bottom`` to 1."""
    from ..core.figures import FAILURE_COLOUR, SUCCESS_COLOUR

    centres, rates, lows, highs = binned
    ax.errorbar(centres, rates, yerr=[np.subtract(rates, lows), np.subtract(highs, rates)], fmt="o-", capsize=3,
                color="black", label="success rate (Wilson 95 %)")
    pad = 0.04 * (1.0 - bottom)
    ax.plot(x[ok], np.full(ok.sum(), 1.0 + pad), "|", color=SUCCESS_COLOUR, ms=8, label="a success")
    ax.plot(x[~ok], np.full((~ok).sum(), bottom - pad), "|", color=FAILURE_COLOUR, ms=8, label="a failure")
    ax.set_ylim(bottom - 2.0 * pad, 1.0 + 2.0 * pad)


def _rate_floor(lows: Sequence[float]) -> float:
    """Where a success-rate axis starts: a tenth below the lowest interval end, rounded down to tenths, and not below
    0 (so that the range that matters is not squashed into a corner of [0, 1])."""
    return max(0.0, float(np.floor(10.0 * min(lows))) / 10.0 - 0.1)


def plot_study(result: StudyResult, directory: str | Path, *, gravity: ArrayLike | None = None) -> list[Path]:
    """Write the study's figures into ``directory`` (made if missing); their paths.

    * ``study_success.png``: the success rate against each drawn model error (binned, Wilson intervals);
    * ``study_failure_times.png``: when the failed runs failed, stacked by failure kind;
    * ``study_margins.png``: each run's smallest cone and envelope margins, successes and failures apart.

    Each names the scenario, the plant, the gravity (``gravity``, the scenario's) and the policy
    (:func:`study_title`); the failure kinds have their colours
    (:data:`~regrasp.core.figures.FAILURE_COLOURS`); a figure with nothing to draw says so in a sentence.
    """
    from matplotlib.ticker import MaxNLocator

    from ..core.figures import FAILURE_COLOUR, FAILURE_COLOURS, SUCCESS_COLOUR, pyplot

    plt = pyplot()

    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    runs = result.runs
    ok = np.array([r.success for r in runs], dtype=bool)
    paths = []
    factors = drawn_factors(result)
    title = study_title(result, gravity)
    if not runs:
        for name in ("study_success.png", "study_failure_times.png", "study_margins.png"):
            fig, ax = plt.subplots(figsize=(6.0, 2.0))
            say_instead(ax, f"{title}:\nno run finished")
            paths.append(directory / name)
            fig.savefig(paths[-1], dpi=110, bbox_inches="tight")
            plt.close(fig)
        return paths
    if factors:
        cols = min(4, len(factors))
        rows = -(-len(factors) // cols)
        fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.4 * rows + 0.4), squeeze=False,
                                 layout="constrained")
        binned = {name: _bins(x, ok, bins=min(6, max(1, len(runs) // 10))) for name, (_, x) in factors.items()}
        bottom = _rate_floor([lo for b in binned.values() for lo in b[2]])  # (one scale for every panel)
        for ax, (name, (label, x)) in zip(axes.flat, factors.items()):
            _binned(ax, x, ok, binned[name], bottom)
            ax.set_xlabel(label)
            ax.set_title(name)
        for ax in list(axes.flat)[len(factors):]:
            ax.set_axis_off()
        for row in axes:
            row[0].set_ylabel("success rate [-]")
        fig.legend(*axes[0][0].get_legend_handles_labels(), fontsize=7, loc="outside lower center", ncol=3,
                   frameon=False)  # (out of the panels: it would hide the failures' ticks)
        fig.suptitle(f"{title}: {result.successes}/{len(runs)} succeeded\n{result.perturbation.describe()}",
                     fontsize=9)
        paths.append(directory / "study_success.png")
        fig.savefig(paths[-1], dpi=110, bbox_inches="tight")
        plt.close(fig)

    bad = [r for r in runs if not r.success]
    kinds = sorted({r.failure_kind for r in bad})
    fig, ax = plt.subplots(figsize=(6.0, 3.5) if kinds else (6.0, 2.0))
    if kinds:
        ax.hist([[r.failure_time for r in bad if r.failure_kind == k] for k in kinds], bins=20,
                range=(0.0, result.duration), stacked=True, label=kinds,
                color=[FAILURE_COLOURS.get(k, FAILURE_COLOUR) for k in kinds])
        ax.set_xlabel("failure time [s]")
        ax.set_ylabel("runs")
        ax.yaxis.set_major_locator(MaxNLocator(integer=True))
        ax.set_title(f"{title}\n{len(bad)} of {len(runs)} runs failed", fontsize=9)
        ax.legend(fontsize=8)
    else:  # (an empty histogram's axes would run from -0.05 to 0.05 runs)
        say_instead(ax, f"{title}:\nno run failed")
    paths.append(directory / "study_failure_times.png")
    fig.savefig(paths[-1], dpi=110, bbox_inches="tight")
    plt.close(fig)

    fig, axes = plt.subplots(1, 2, figsize=(9.0, 3.5))
    for ax, values, label in ((axes[0], [r.min_cone_margin for r in runs], "smallest cone margin [N]"),
                              (axes[1], [None if r.min_envelope_margin is None else 1e3 * r.min_envelope_margin
                                         for r in runs], "smallest envelope margin [mm]")):
        values = np.array([np.nan if v is None else v for v in values], dtype=float)  # (None: not measured)
        finite = np.isfinite(values)
        if finite.any():
            lo, hi = values[finite].min(), values[finite].max()
            span = (lo, hi) if hi > lo else (lo - 0.5, hi + 0.5)
            ax.hist([values[finite & ok], values[finite & ~ok]], bins=20, range=span, stacked=True,
                    color=[SUCCESS_COLOUR, FAILURE_COLOUR], label=["success", "failure"])
            ax.set_xlabel(label)
            ax.set_ylabel("runs")
            ax.yaxis.set_major_locator(MaxNLocator(integer=True))
            ax.legend(fontsize=8)
        else:
            say_instead(ax, f"{label}:\nno run measured one")
    fig.suptitle(title, fontsize=9)
    paths.append(directory / "study_margins.png")
    fig.savefig(paths[-1], dpi=110, bbox_inches="tight")
    plt.close(fig)
    return paths


def plot_sweep(name: str, results: Sequence[StudyResult], path: str | Path, *,
               gravity: ArrayLike | None = None) -> Path:
    """``study_sweep.png``: each study's success rate (Wilson 95 % bars) and its runs' median smallest cone margin
    against the size of the perturbation ``name`` the studies differ in."""
    from ..core.figures import pyplot
    from ..model.perturbation import Perturbation

    plt = pyplot()
    path = Path(path)
    results = [r for r in results if r.runs]  # (a study Ctrl-C stopped before any run finished has no rate)
    if not results:
        fig, ax = plt.subplots(figsize=(6.0, 2.0))
        say_instead(ax, f"--sweep {name}: no run finished")
        fig.savefig(path, dpi=110, bbox_inches="tight")
        plt.close(fig)
        return path
    x = [getattr(r.perturbation, name) for r in results]
    x = [0.0 if v is None else float(v) for v in x]
    rates = [r.success_rate for r in results]
    bars = [r.interval for r in results]
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(6.0, 5.5), sharex=True)
    top.errorbar(x, rates, yerr=[[p - lo for p, (lo, _) in zip(rates, bars)], [hi - p for p, (_, hi) in zip(rates,
                                                                                                           bars)]],
                 fmt="o-", capsize=3)
    top.set_ylim(_rate_floor([lo for lo, _ in bars]) - 0.02, 1.02)
    top.set_ylabel("success rate [-]")
    rest = replace(results[0].perturbation, **{name: Perturbation.__dataclass_fields__[name].default})
    top.set_title(f"{study_title(results[0], gravity)} a size\nbesides {name}: {rest.describe()}", fontsize=8)
    medians = [[o.min_cone_margin for o in r.runs if o.min_cone_margin is not None] for r in results]
    bottom.plot(x, [float(np.median(m)) if m else np.nan for m in medians], "s-")
    bottom.set_ylabel("median smallest cone margin [N]")
    bottom.set_xlabel(name)
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return path

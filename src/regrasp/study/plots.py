"""A robustness study's figures (PNG, headless): success against each drawn model error, failure times by
kind, and the runs' smallest margins."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from .study import StudyResult

__all__ = ["drawn_factors", "plot_study", "plot_sweep"]

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


def _binned(ax, x: np.ndarray, ok: np.ndarray, bins: int) -> None:
    """The success rate in ``bins`` equal bins of x, with each bin's Wilson 95 % interval, and every run as a tick."""
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
        lows.append(k / n - lo)
        highs.append(hi - k / n)
    ax.errorbar(centres, rates, yerr=[lows, highs], fmt="o-", capsize=3, label="success rate (Wilson 95 %)")
    ax.plot(x[ok], np.full(ok.sum(), 1.04), "|", color="C2", ms=8, label="a success")
    ax.plot(x[~ok], np.full((~ok).sum(), -0.04), "|", color="C3", ms=8, label="a failure")
    ax.set_ylim(-0.1, 1.1)


def plot_study(result: StudyResult, directory: str | Path) -> list[Path]:
    """Write the study's figures into ``directory``; their paths.

    * ``study_success.png``: the success rate against each drawn model error (binned, Wilson intervals);
    * ``study_failure_times.png``: when the failed runs failed, stacked by failure kind;
    * ``study_margins.png``: each run's smallest cone and envelope margins, successes and failures apart.
    """
    from matplotlib.ticker import MaxNLocator

    from ..core.figures import pyplot

    plt = pyplot()

    directory = Path(directory)
    runs = result.runs
    ok = np.array([r.success for r in runs])
    paths = []
    factors = drawn_factors(result)
    if factors:
        fig, axes = plt.subplots(1, len(factors), figsize=(4.2 * len(factors), 3.8), squeeze=False)
        for ax, (name, (label, x)) in zip(axes[0], factors.items()):
            _binned(ax, x, ok, bins=min(6, max(1, len(runs) // 10)))
            ax.set_xlabel(label)
            ax.set_title(name)
        axes[0][0].set_ylabel("success rate [-]")
        axes[0][0].legend(fontsize=7, loc="lower left")
        fig.suptitle(f"{result.successes}/{len(runs)} succeeded; {result.perturbation.describe()}", fontsize=9)
        paths.append(directory / "study_success.png")
        fig.savefig(paths[-1], dpi=110, bbox_inches="tight")
        plt.close(fig)

    bad = [r for r in runs if not r.success]
    kinds = sorted({r.failure_kind for r in bad})
    fig, ax = plt.subplots(figsize=(6.0, 3.5))
    ax.hist([[r.failure_time for r in bad if r.failure_kind == k] for k in kinds] or [[]], bins=20,
            range=(0.0, result.duration), stacked=True, label=kinds or None)
    ax.set_xlabel("failure time [s]")
    ax.set_ylabel("runs")
    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_title(f"{len(bad)} of {len(runs)} runs failed")
    if kinds:
        ax.legend(fontsize=8)
    else:  # (an empty histogram's axis would run from -0.05 to 0.05 runs)
        ax.set_ylim(0.0, 1.0)
        ax.text(0.5, 0.5, "no run failed", transform=ax.transAxes, ha="center", va="center")
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
                    color=["C2", "C3"], label=["success", "failure"])
        ax.set_xlabel(label)
        ax.set_ylabel("runs")
        ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    axes[0].legend(fontsize=8)
    paths.append(directory / "study_margins.png")
    fig.savefig(paths[-1], dpi=110, bbox_inches="tight")
    plt.close(fig)
    return paths


def plot_sweep(name: str, results: Sequence[StudyResult], path: str | Path) -> Path:
    """``study_sweep.png``: each study's success rate (Wilson 95 % bars) and its runs' median smallest cone margin
    against the size of the perturbation ``name`` the studies differ in."""
    from ..core.figures import pyplot
    from ..model.perturbation import Perturbation
    from .study import wilson_interval

    plt = pyplot()
    x = [getattr(r.perturbation, name) for r in results]
    x = [0.0 if v is None else float(v) for v in x]
    rates = [r.success_rate for r in results]
    bars = [wilson_interval(r.successes, len(r.runs)) for r in results]
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(6.0, 5.5), sharex=True)
    top.errorbar(x, rates, yerr=[[p - lo for p, (lo, _) in zip(rates, bars)], [hi - p for p, (_, hi) in zip(rates,
                                                                                                           bars)]],
                 fmt="o-", capsize=3)
    top.set_ylim(-0.05, 1.05)
    top.set_ylabel("success rate [-]")
    rest = replace(results[0].perturbation, **{name: Perturbation.__dataclass_fields__[name].default})
    top.set_title(f"{len(results[0].runs)} runs a size; besides {name}: {rest.describe()}", fontsize=8)
    medians = [[o.min_cone_margin for o in r.runs if o.min_cone_margin is not None] for r in results]
    bottom.plot(x, [float(np.median(m)) if m else np.nan for m in medians], "s-")
    bottom.set_ylabel("median smallest cone margin [N]")
    bottom.set_xlabel(name)
    path = Path(path)
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return path

"""A suite's figures (PNG, headless): each variant's outcome over the two drawn values that tell the outcomes apart
most, the planning time and peak memory, and the outcomes counted by reason and failure kind.

Colours: a success green, a failure its kind's (:data:`~regrasp.core.figures.FAILURE_COLOURS`), no schedule blue
(the ``no_schedule`` colour; magenta without a physical reason), a refused variant black. A figure with nothing to
draw says so in a sentence.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..core.figures import say_instead

if TYPE_CHECKING:
    from .result import SuiteResult, VariantOutcome

__all__ = ["SUITE_FIGURES", "influential", "plot_suite", "suite_title"]

#: The figures :func:`plot_suite` writes.
SUITE_FIGURES = ("suite_outcomes.png", "suite_planning.png", "suite_reasons.png")
#: Refused variants' colour (no failure kind is black but ``interrupted``, which a suite never keeps).
_REFUSED = "black"
#: Scheduled, not run (a plan-only suite).
_PLANNED = "tab:green"
#: No schedule: a marker per limit (a ScheduleLimit value).
_LIMIT_MARKERS = {"envelope": "v", "speed": "^", "forces": "<", "periodic": ">", "torque": "D", "verification": "P"}
#: No schedule and no physical reason (a verification that kept failing).
_UNEXPLAINED = "magenta"


def suite_title(result: SuiteResult) -> str:
    """What a suite's figure is of: the suite and its spec, the base scenario, the plant (or plan only), the seed and
    the variants (and whether Ctrl-C cut it short)."""
    done = len(result.outcomes)
    variants = f"{done} of {result.requested} variants" if result.interrupted else f"{done} variants"
    where = "planned only" if result.plan_only else f"{result.periods} period(s) on the {result.plant} plant"
    return (f"suite {result.name} ({Path(result.spec).name}), variants of {Path(result.scenario).stem}: {variants}, "
            f"seed {result.seed}, {where}")


def _bad(o: VariantOutcome) -> bool:
    """Whether a variant did not reach the goal: no schedule, or a failed rollout."""
    return not o.scheduled or o.success is False


def _numbers(result: SuiteResult) -> dict[str, np.ndarray]:
    """Each varied key whose drawn values are all numbers: its value per finished variant."""
    out = {}
    for key in result.varied:
        values = [dict(o.parameters).get(key) for o in result.outcomes]
        if values and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values):
            out[key] = np.array(values, dtype=float)
    return out


def influential(result: SuiteResult) -> list[str]:
    """The numeric varied keys, those that tell the variants that reached the goal from those that did not most first
    (the difference of the two groups' means over the key's drawn spread); in the spec's order when every variant
    reached it, or none did."""
    numbers = _numbers(result)
    bad = np.array([_bad(o) for o in result.outcomes], dtype=bool)
    if not numbers or bad.all() or not bad.any():
        return list(numbers)

    def separation(x: np.ndarray) -> float:
        spread = float(np.ptp(x))
        return abs(float(x[bad].mean() - x[~bad].mean())) / spread if spread > 0 else 0.0

    return sorted(numbers, key=lambda k: -separation(numbers[k]))


def _style(o: VariantOutcome) -> tuple[str, str, str]:
    """(label, colour, marker) of a variant's outcome."""
    from ..core.figures import FAILURE_COLOUR, FAILURE_COLOURS, SUCCESS_COLOUR

    if o.scheduled:
        if o.success is None:
            return "scheduled (not run)", _PLANNED, "o"
        if o.success:
            return "success", SUCCESS_COLOUR, "o"
        return f"failed: {o.failure_kind}", FAILURE_COLOURS.get(str(o.failure_kind), FAILURE_COLOUR), "X"
    if o.status == "no_schedule":
        marker = _LIMIT_MARKERS.get(str(o.limit), "v")
        if o.physical:
            return f"no schedule: {o.limit}", FAILURE_COLOURS["no_schedule"], marker
        return f"no schedule: {o.limit} (no physical reason)", _UNEXPLAINED, marker
    return f"refused: {o.limit}", _REFUSED, "s"


def _outcomes(plt: object, result: SuiteResult, path: Path) -> Path:
    """``suite_outcomes.png``: each variant over the two most influential drawn values, by outcome."""
    keys = influential(result)[:2]
    title = suite_title(result)
    if not result.outcomes or not keys:
        fig, ax = plt.subplots(figsize=(7.0, 2.0))
        say_instead(ax, f"{title}:\n" + ("no variant finished" if not result.outcomes else "no numeric drawn value"))
        fig.savefig(path, dpi=110, bbox_inches="tight")
        plt.close(fig)
        return path
    numbers = _numbers(result)
    x = numbers[keys[0]]
    rng = np.random.default_rng(0)  # (a single key: the variants spread on y, to be told apart)
    y = numbers[keys[1]] if len(keys) > 1 else rng.uniform(-1.0, 1.0, len(x))
    styles = [_style(o) for o in result.outcomes]
    fig, ax = plt.subplots(figsize=(7.5, 5.5))
    for label in sorted({s[0] for s in styles}, key=lambda s: (s != "success", s)):
        pick = np.array([s[0] == label for s in styles])
        colour, marker = next((s[1], s[2]) for s in styles if s[0] == label)
        ax.scatter(x[pick], y[pick], c=colour, marker=marker, s=36, edgecolors="none" if marker != "o" else "white",
                   linewidths=0.5, label=f"{label} ({int(pick.sum())})", zorder=3 if label != "success" else 2)
    ax.set_xlabel(keys[0])
    if len(keys) > 1:
        ax.set_ylabel(keys[1])
    else:
        ax.set_yticks([])
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    ax.set_title(f"{title}\noutcome per variant over the drawn values that tell the outcomes apart most", fontsize=8)
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return path


def _distribution(ax: object, values: list[float], without: list[float], unit: str, what: str) -> None:
    """A histogram of ``values`` (with a schedule) stacked on ``without`` (no schedule), its empirical CDF on a second
    axis and its p50 and p95 as lines."""
    from matplotlib.ticker import MaxNLocator

    from ..core.figures import FAILURE_COLOURS, SUCCESS_COLOUR

    both = np.array(values + without, dtype=float)
    if not both.size:
        say_instead(ax, f"{what}: not measured")
        return
    lo, hi = float(both.min()), float(both.max())
    span = (lo, hi) if hi > lo else (lo - 0.5, hi + 0.5)
    ax.hist([values, without], bins=20, range=span, stacked=True,
            color=[SUCCESS_COLOUR, FAILURE_COLOURS["no_schedule"]],
            label=["with a schedule", "without"])
    ax.set_xlabel(f"{what} [{unit}]")
    ax.set_ylabel("variants")
    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    ordered = np.sort(both)
    cdf = ax.twinx()
    cdf.step(ordered, np.arange(1, ordered.size + 1) / ordered.size, where="post", color="black", lw=1.0,
             label="fraction at most (CDF)")
    cdf.set_ylim(0.0, 1.02)
    cdf.set_ylabel("fraction of variants [-]")
    for q, style in ((50, ":"), (95, "--")):
        value = float(np.percentile(both, q))
        ax.axvline(value, color="dimgray", ls=style, lw=1.0, label=f"p{q} {value:.3g} {unit}")
    handles, labels = ax.get_legend_handles_labels()
    more, extra = cdf.get_legend_handles_labels()
    ax.legend(handles + more, labels + extra, fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.17), ncol=3,
              frameon=False)  # (below the axes: it would hide bars)


def _planning(plt: object, result: SuiteResult, path: Path) -> Path:
    """``suite_planning.png``: the planning time and the planning's peak memory."""
    planned = [o for o in result.outcomes if o.plan_seconds is not None]
    fig, axes = plt.subplots(1, 2, figsize=(11.0, 4.6))
    _distribution(axes[0], [o.plan_seconds for o in planned if o.scheduled],
                  [o.plan_seconds for o in planned if not o.scheduled], "s", "planning time (envelope and schedule)")
    mb = [o for o in planned if o.peak_memory is not None]
    bound = any(o.memory_upper_bound for o in mb)
    _distribution(axes[1], [o.peak_memory / 2**20 for o in mb if o.scheduled],
                  [o.peak_memory / 2**20 for o in mb if not o.scheduled], "MiB",
                  "worker's peak RSS while planning" + (" (upper bound)" if bound else ""))
    cold = sum(o.cold for o in planned)
    fig.suptitle(f"{suite_title(result)}\nplanning time and memory of {len(planned)} variants ({cold} the first plan "
                 "in their process, which loads the planner's kernels too)", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return path


def _reasons(plt: object, result: SuiteResult, path: Path) -> Path:
    """``suite_reasons.png``: the variants counted by outcome: successes, failures by kind, no schedule by limit and
    contacts, refusals."""
    counts: dict[str, list] = {}
    for o in result.outcomes:
        label, colour, _ = _style(o)
        if not o.scheduled and o.contacts:
            label += f" ({', '.join(o.contacts)})"
        counts.setdefault(label, [0, colour])[0] += 1
    if not counts:
        fig, ax = plt.subplots(figsize=(7.0, 2.0))
        say_instead(ax, f"{suite_title(result)}:\nno variant finished")
        fig.savefig(path, dpi=110, bbox_inches="tight")
        plt.close(fig)
        return path
    from matplotlib.ticker import MaxNLocator

    rows = sorted(counts.items(), key=lambda kv: -kv[1][0])
    fig, ax = plt.subplots(figsize=(8.0, 1.2 + 0.4 * len(rows)))
    ax.barh(range(len(rows)), [n for _, (n, _) in rows], color=[c for _, (_, c) in rows])
    for i, (_, (n, _)) in enumerate(rows):
        ax.text(n, i, f" {n}", va="center", fontsize=8)
    ax.set_yticks(range(len(rows)), [label for label, _ in rows], fontsize=8)
    ax.invert_yaxis()
    ax.set_xlabel("variants")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlim(0, max(n for _, (n, _) in rows) * 1.15)
    ax.set_title(f"{suite_title(result)}\nvariants by outcome", fontsize=8)
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return path


def plot_suite(result: SuiteResult, directory: str | Path) -> list[Path]:
    """Write the suite's figures into ``directory`` (made if missing); their paths.

    * ``suite_outcomes.png``: each variant's outcome over the two drawn values that tell the outcomes apart most
      (:func:`influential`);
    * ``suite_planning.png``: the planning time and the worker's peak memory while planning (histograms, with and
      without a schedule, their CDF, p50 and p95);
    * ``suite_reasons.png``: the variants counted by outcome (success, failure kind, no schedule by limit and
      contacts, refused).
    """
    from ..core.figures import pyplot

    plt = pyplot()
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    makers = (_outcomes, _planning, _reasons)
    return [make(plt, result, directory / name) for make, name in zip(makers, SUITE_FIGURES)]

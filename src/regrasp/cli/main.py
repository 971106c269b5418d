"""The regrasp command line: ``regrasp plan`` (:mod:`regrasp.cli.plan`), ``regrasp simulate``
(:mod:`regrasp.cli.simulate`), ``regrasp study`` (:mod:`regrasp.cli.study`) and ``regrasp suite``
(:mod:`regrasp.cli.suite`).

Exit status: 0 success, 1 a result that says no (infeasible, a failed rollout), 2 bad input (a typed error, one
line on stderr), 130 interrupted.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from ..core.exceptions import RegraspError
from . import plan, simulate, study, suite

__all__ = ["build_parser", "main"]


def build_parser() -> argparse.ArgumentParser:
    """The ``regrasp`` parser and its commands."""
    from .. import __version__

    parser = argparse.ArgumentParser(prog="regrasp", description="Planar multifingered hands: plan feasible contacts, "
                                     "control sliding fingertips, regrasp dynamically.")
    parser.add_argument("--version", action="version", version=f"regrasp {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    plan.configure(sub.add_parser(
        "plan", help="feasibility and contact envelope of an object trajectory (paper §2)",
        description="Check a trajectory's feasibility and compute each finger's feasible-contact envelope. Exit "
                    "status 0: feasible, 1: infeasible, 2: bad input."))
    simulate.configure(sub.add_parser(
        "simulate", help="run a regrasping rollout on the plant (paper §4) and record it",
        description="Run a rollout: the supervisor and its policy drive the full-coordinate plant. Exit status 0: "
                    "success, 1: failure or no schedule, 2: bad input."))
    study.configure(sub.add_parser(
        "study", help="a robustness study: many seeded rollouts under model errors and noise",
        description="Plan the regrasp schedule once, then run seeded rollouts on plants whose model errors are drawn "
                    "around the model's, with sensing noise, torque noise and delays. Prints the success rate with a "
                    "Wilson 95 % interval, the failures by kind and time and the margins. The perturbations default "
                    "to the scenario's [study] table; a flag overrides its key. Exit status 0: the study ran, 2: bad "
                    "input, 130: Ctrl-C (the runs that finished are summarised and written first)."))
    suite.configure(sub.add_parser(
        "suite", help="a task suite: variants of a scenario drawn from a spec's ranges, planned and run",
        description="Draw variants of a scenario from the ranges and choices of a suite spec (TOML), plan each (the "
                    "envelope, then the regrasp schedule; timed, with the planning's peak memory) and run each "
                    "scheduled one on the plant. Prints the fraction with a schedule (Wilson 95 %), why the others "
                    "have none (grouped), success given a schedule, the failures by kind and the planning time and "
                    "memory percentiles. Exit status 0: the suite ran, 2: bad input (a spec's bad key is named), 130: "
                    "Ctrl-C (the variants that finished are summarised and written first)."))
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except RegraspError as exc:
        print(f"regrasp: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # (simulate ends its run itself and prints the partial result)
        print("regrasp: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

"""What each robustness change bought: one study's draws under eight supervisors, each adding one change.

Run: python examples/11_robustness_ablation.py [--runs N] [--periods P | --duration T] [--workers K] [--seed S]

The default scenario (trajectory 2, three fingers, the scheduled policy) is planned once. Every supervisor then
runs the same seeded runs: the plant's object mass, inertia and μ drawn within ±20 % of the model's, each
fingertip placed up to 0.2 mm off its plan, ξ sensed with 0.2 mm of noise, the object's pose with 0.1 mm and
1 mrad, and every torque applied one control step late (the issue-14 perturbations). The supervisors:

0. issue 12's robust settings (margins in cone ratio 0.05 and 0.2 N, integral action, growing priming, μ_k
   estimated while sliding, held contacts where they were last set);
1. + settling keeps 0.05 N of static margin (``settle_margin``);
2. + the supervisor is told the actuation delay: a slide settles until the torques in flight are its own;
3. + the kinetic friction estimate starts at the break-away (``breakaway_estimate``);
4. + the priming lasts until the contact moves the right way at 1 mm/s (``start_speed``);
5. + fixed contacts kept 0.1 inside their cones in ratio, 0.05 where no force allows more (``fallback_margin``);
6. + held contacts follow their sensed positions through a 20 ms filter (``hold_filter_time``, with a
   resolution of half the ξ noise);
7. + the loads kept (issue 24): sliders push >= 0.3 N, holders >= 0.3 N while a contact slides, the reflex:
   today's ``SupervisorSettings.robust``, as ``build_rollout`` sets it (the schedule is planned with today's
   ``RegraspSettings`` for every row).

Each row: successes, their Wilson 95 % interval, the smallest cone margin of any run, and the medians over the
runs of the largest object position and orientation errors after the first 0.5 s. The default (4 runs of
0.3 s) only shows the machinery; the table in docs/derivations.md took
``--runs 50 --periods 2`` (about 80 minutes on 2 cores).
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path
from statistics import median
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from regrasp.supervisor.settings import SupervisorSettings

SCENARIO = Path(__file__).resolve().parent / "scenarios" / "paper_trajectory_2_three_fingers.toml"


def variants(geometry: str, delay: int, hold_resolution: float) -> list[tuple[str, SupervisorSettings]]:
    """The supervisors of the docstring, each the one before plus one change."""
    from regrasp.core.contact import DEFAULT_CONE_MARGIN
    from regrasp.dynamics.internal_force.settings import InternalForceSettings
    from regrasp.supervisor.settings import SupervisorSettings

    today = SupervisorSettings.robust(geometry, DEFAULT_CONE_MARGIN, actuation_delay=delay,
                                      hold_resolution=hold_resolution)
    now = today.executor
    before = today.with_executor(settle_margin=0.0, actuation_delay=0, breakaway_estimate=False, start_speed=None,
                                 internal_force=InternalForceSettings(f_min=0.2,
                                                                      target_cone_margin=DEFAULT_CONE_MARGIN),
                                 hold_resolution=None, hold_filter_time=None, slider_floor=0.0, holder_preload=0.0,
                                 reflex_below=0.0, reflex_floor=0.0)
    steps = [("0 issue 12's robust settings", before)]
    steps.append(("1 + settle margin 0.05 N", steps[-1][1].with_executor(settle_margin=now.settle_margin)))
    steps.append(("2 + the delay told", steps[-1][1].with_executor(actuation_delay=now.actuation_delay)))
    steps.append(("3 + estimate at break-away", steps[-1][1].with_executor(breakaway_estimate=True)))
    steps.append(("4 + start speed 1 mm/s", steps[-1][1].with_executor(start_speed=now.start_speed)))
    steps.append(("5 + cone ratio margin 0.1", steps[-1][1].with_executor(internal_force=now.internal_force)))
    steps.append(("6 + held positions filtered", steps[-1][1].with_executor(hold_resolution=now.hold_resolution,
                                                                            hold_filter_time=now.hold_filter_time)))
    steps.append(("7 + the loads kept (issue 24)", steps[-1][1].with_executor(
        slider_floor=now.slider_floor, holder_preload=now.holder_preload, reflex_below=now.reflex_below,
        reflex_floor=now.reflex_floor)))
    if steps[-1][1] != today:
        raise SystemExit("the last variant is not SupervisorSettings.robust: update this example")
    return steps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=4, help="runs per supervisor (default 4)")
    span = parser.add_mutually_exclusive_group()
    span.add_argument("--periods", type=int, help="each run: P periods of the trajectory")
    span.add_argument("--duration", type=float, help="each run: T seconds (default 0.3 without --periods)")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1, help="worker processes (default: cores)")
    parser.add_argument("--seed", type=int, default=1, help="the study's seed (default 1)")
    args = parser.parse_args()
    # (imported after parsing: --help answers at once)
    from regrasp import load_scenario
    from regrasp.core.contact import DEFAULT_CONE_MARGIN
    from regrasp.schedule.planner import RegraspSettings, plan_regrasps
    from regrasp.study.study import Perturbation, run_study

    # the perturbations
    perturbation = Perturbation(mass=0.2, inertia=0.2, mu=0.2, contact_position=2e-4, xi_noise=2e-4,
                                position_noise=1e-4, angle_noise=1e-3, delay=1)
    duration = None if args.periods else (args.duration or 0.3)
    scenario = load_scenario(SCENARIO)
    schedule = plan_regrasps(scenario, RegraspSettings(cone_margin=DEFAULT_CONE_MARGIN))
    print(f"{args.runs} runs of {'%d periods' % args.periods if args.periods else '%g s' % duration} each, seed "
          f"{args.seed}: {perturbation.describe()}")
    print(f"{'supervisor':32s} {'success':>9s} {'Wilson 95 %':>15s}  {'min cone margin':>15s}  "
          f"{'median errors':>18s}  failures")
    for name, settings in variants(scenario.geometry.value, perturbation.delay, 0.5 * perturbation.xi_noise):
        r = run_study(scenario, args.runs, seed=args.seed, perturbation=perturbation, duration=duration,
                      periods=args.periods, workers=min(args.workers, args.runs), schedule=schedule, settings=settings)
        lo, hi = r.interval
        cones = [o.min_cone_margin for o in r.runs if o.min_cone_margin is not None]  # (None: no step measured one)
        cone = f"{min(cones):13.3f} N" if cones else f"{'n/a':>15s}"
        failures = ", ".join(f"{k} {v}" for k, v in sorted(r.failures.items())) or "none"
        position = [o.max_object_error for o in r.runs if o.max_object_error is not None]
        angle = [o.max_orientation_error for o in r.runs if o.max_orientation_error is not None]
        errors = f"{1e3 * median(position):.2f} mm {1e3 * median(angle):5.1f} mrad" if position else "-"
        print(f"{name:32s} {r.successes:4d}/{len(r.runs):<4d} [{lo:5.1%}, {hi:5.1%}]  {cone}  {errors:>18s}  "
              f"{failures}", flush=True)


if __name__ == "__main__":
    main()

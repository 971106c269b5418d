"""What keeping the loads buys on compliant contact: the scheduled regrasp on MuJoCo under five supervisors, each
adding one change, judged by the contact-health criteria (regrasp.core.health) that every plant shares.

Run: python examples/12_compliant_contacts.py [--periods P | --duration T] [--radii MM [MM ...]] [--plant KIND]

The default scenario (trajectory 2, three fingers) is planned, and run on MuJoCo's sphere tips (radius r, soft
contacts) with the model's own parameters. The supervisors (and the schedules they follow):

0. issue 23's: the plan and the laws keep f_n >= 0.2 N on every contact; the planner checks a break-away on the
   static cone's edge; no reflex;
1. + every slider pushes with >= 0.3 N, planned and executed (``slider_floor``);
2. + while any contact slides, the held ones push with >= 0.3 N, planned and executed (``holder_preload``);
3. + the reflex: a contact sensed below 0.1 N pushes with >= 0.4 N for 10 ms (``reflex_below`` ...): today's
   defaults;
4. + the planner checks the break-away at the executor's first priming overshoot, μ_s + 0.05
   (``RegraspSettings(prime_overshoot=0.05)``, not the default: it tightens the schedule).

Each row: the verdict (a held contact lost below 0.05 N for 2 ms or slipped 0.1 mm, a slider whose 5 ms average
falls below 0.05 N or that carries nothing for 2 ms), the least normal force of a held contact, the longest time
a contact carried nothing, the smallest static cone margin of a held contact, and the largest object error after
the first 0.5 s. The default (0.3 s at r = 0.25 mm) only shows the machinery; the table in docs/derivations.md
took ``--periods 2 --radii 0.25 1`` (about 3 minutes on 2 cores).
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from regrasp.schedule.planner import RegraspSettings
    from regrasp.supervisor.settings import SupervisorSettings

SCENARIO = "paper_trajectory_2_three_fingers.toml"


def variants(geometry: str, tip_radius: float) -> list[tuple[str, RegraspSettings, SupervisorSettings]]:
    """The supervisors of the docstring, each the one before plus one change, with the planner's settings."""
    from regrasp.core.contact import DEFAULT_CONE_MARGIN
    from regrasp.schedule.planner import RegraspSettings
    from regrasp.supervisor.settings import SupervisorSettings

    plan = RegraspSettings()
    primed = replace(plan, prime_overshoot=0.05)
    today = SupervisorSettings.robust(geometry, DEFAULT_CONE_MARGIN, tip_radius=tip_radius,
                                      slider_floor=plan.slider_floor, holder_preload=plan.holder_preload)
    now = today.executor
    plan0 = replace(plan, slider_floor=0.0, holder_preload=0.0, prime_overshoot=0.0)
    sup0 = today.with_executor(slider_floor=0.0, holder_preload=0.0, reflex_below=0.0, reflex_floor=0.0)
    plan1 = replace(plan0, slider_floor=plan.slider_floor)
    sup1 = sup0.with_executor(slider_floor=now.slider_floor)
    plan2 = replace(plan1, holder_preload=plan.holder_preload)
    sup2 = sup1.with_executor(holder_preload=now.holder_preload)
    return [("0 issue 23's", plan0, sup0), ("1 + slider floor 0.3 N", plan1, sup1),
            ("2 + holders pre-loaded 0.3 N", plan2, sup2), ("3 + reflex (today)", plan, today),
            ("4 + priming overshoot planned", primed, today)]


def main() -> None:
    p = argparse.ArgumentParser(prog="12_compliant_contacts.py", description=__doc__.splitlines()[0])
    span = p.add_mutually_exclusive_group()
    span.add_argument("--periods", type=int, help="run P periods of the trajectory (the schedule is periodic)")
    span.add_argument("--duration", type=float, default=None, help="run T seconds (default 0.3)")
    p.add_argument("--radii", type=float, nargs="+", default=[0.25], metavar="MM",
                   help="the fingertips' sphere radii [mm] (default 0.25)")
    p.add_argument("--plant", choices=("mujoco", "project"), default="mujoco", help="the plant (default mujoco)")
    args = p.parse_args()
    # (imported after parsing: --help answers at once)
    from regrasp import load_scenario
    from regrasp.plants.mujoco.mjcf import MujocoSettings
    from regrasp.plants.spec import PlantSpec
    from regrasp.rollout.build import build_rollout
    from regrasp.rollout.spec import RunSpec
    from regrasp.schedule.planner import plan_regrasps
    from regrasp.schedule.problem import trajectory_period

    sc = load_scenario(Path(__file__).resolve().parent / "scenarios" / SCENARIO)
    periodic = args.periods is not None
    duration = None if periodic else (0.3 if args.duration is None else args.duration)
    run = RunSpec(periods=args.periods) if periodic else RunSpec(duration=duration)
    length = args.periods * trajectory_period(sc.trajectory) if periodic else duration
    print(f"{SCENARIO} on the {args.plant} plant, {length:.3g} s per run")
    schedules: dict[RegraspSettings, object] = {}
    for radius in args.radii:
        r = radius * 1e-3 if args.plant == "mujoco" else 0.0
        plant = PlantSpec("mujoco", MujocoSettings(tip_radius=r)) if args.plant == "mujoco" else PlantSpec()
        print(f"\ntip radius {radius:g} mm" if args.plant == "mujoco" else "\npoint contacts")
        print(f"  {'supervisor':32s} {'verdict':44s} {'held min':>9s} {'no force':>9s} {'cone min':>9s} "
              f"{'error':>9s}")
        for name, planned, settings in variants(sc.geometry.value, r):
            if planned not in schedules:
                schedules[planned] = plan_regrasps(sc, planned if periodic else replace(planned, periodic=False),
                                                   t_end=None if periodic else sc.trajectory.t_start + duration)
            result = build_rollout(sc, run, settings=settings, regrasp_settings=planned,
                                   schedule=schedules[planned], plant=plant).run(interruptible=False)
            f = result.failure
            verdict = "success" if f is None else f"{f.kind.value} at {f.time:.3f} s ({f.contact})"
            held = min(h.least_held_force for h in result.health)
            zero = max(h.longest_zero_force for h in result.health)
            err = result.max_object_error_after_transient
            print(f"  {name:32s} {verdict:44s} {held:7.3f} N {zero * 1e3:6.0f} ms {result.min_cone_margin:7.3f} N "
                  f"{'-' if err != err else f'{err * 1e3:.3f} mm':>9s}")


if __name__ == "__main__":
    main()

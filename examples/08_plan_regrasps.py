"""Plan the regrasp schedule of paper trajectory 2 (the slides of every finger over a period) at
several required margins: what margins cost in slides.

Run: python examples/08_plan_regrasps.py [--scenario FILE] [--envelope-margins MM ...]
     [--cone-margins N ...] [--plot DIR]

For each pair of required margins (envelope [mm], cone [N]) it prints the number of slides per
period, the fewest any schedule needs (with a free start), the margins the schedule reaches, and
the planning time. With three fingers and gravity down (the default scenario) a periodic schedule
exists; with the paper's two fingers none does, and the planner says why.
"""

import argparse
from pathlib import Path

HERE = Path(__file__).resolve().parent


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenario", default=str(HERE / "scenarios" / "paper_trajectory_2_three_fingers.toml"),
                        help="scenario file (default: paper trajectory 2 with the palm finger)")
    parser.add_argument("--envelope-margins", type=float, nargs="+", default=[1.0, 2.0, 3.0], metavar="MM",
                        help="required envelope margins [mm] (default: 1 2 3)")
    parser.add_argument("--cone-margins", type=float, nargs="+", default=[0.1, 0.3], metavar="N",
                        help="required cone margins [N] (default: 0.1 0.3)")
    parser.add_argument("--plot", metavar="DIR", help="write each schedule's figure (paper Fig. 4.3) into DIR")
    args = parser.parse_args()
    # (imported after parsing: --help answers at once)
    from regrasp import NoScheduleError, RegraspSettings, load_scenario, plan_regrasps, plan_scenario
    from regrasp.schedule.plotting import plot_schedule

    scenario = load_scenario(args.scenario)
    print(f"{scenario.name}: {len(scenario.contacts)} fingers, {', '.join(str(f) for f in scenario.friction)}")
    print(f"{'envelope margin':>16} {'cone margin':>12} {'slides':>7} {'fewest':>7} {'reached: envelope':>18} "
          f"{'cone':>8} {'planning':>9}")
    plan = plan_scenario(scenario) if args.plot else None
    for em in args.envelope_margins:
        for cm in args.cone_margins:
            settings = RegraspSettings(envelope_margin=em * 1e-3, cone_margin=cm)
            try:
                s = plan_regrasps(scenario, settings)
            except NoScheduleError as exc:
                print(f"{em:>13.1f} mm {cm:>10.2f} N   none ({exc.limit.value} after t = {exc.latest_time:.2f} s)")
                continue
            per = "/period" if s.periodic else ""
            print(f"{em:>13.1f} mm {cm:>10.2f} N {len(s.slides):>4d}{per:7s} {s.slides_lower_bound:>4d} "
                  f"{s.min_envelope_margin * 1e3:>15.2f} mm {s.min_cone_margin:>6.3f} N {s.planning_seconds:>7.1f} s")
            if args.plot:
                plot_schedule(plan, s, Path(args.plot) / f"regrasp_{em:g}mm_{cm:g}N.png")


if __name__ == "__main__":
    main()

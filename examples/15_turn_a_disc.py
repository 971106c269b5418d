"""A disc turned in the hand further than any fixed grasp allows: the side fingers slide round it (issue 28).

Run: python examples/15_turn_a_disc.py [--resolution MM] [--periods N] [--plant project|mujoco] [--plot DIR]
On examples/scenarios/disc.toml (a 40 mm disc, 80 g, swung 0.8 rad either way each period while its centre follows a
small ellipse, two side fingers and a palm finger under it) it prints:

1. per finger, the largest turn of the disc that one fixed contact survives (from the §2 envelope: the feasible
   sets' intersection over the longest stretch of the swing), against the 1.6 rad the disc turns;
2. the periodic regrasp schedule (§4) planned on a lattice of ``--resolution`` mm cells (default 4, a few seconds;
   the scenario's own 2 mm, as ``regrasp plan --regrasp`` plans it, takes about a minute);
3. the rollout of that schedule for ``--periods`` periods (default 1) on the project plant or on MuJoCo
   (``--plant mujoco``, needs the mujoco extra), summed up as ``regrasp simulate`` does (the result, the tracking
   error, the margins, each contact's least force), and how far each contact went round the disc on the plant.

With ``--plot DIR`` it writes the schedule (paper Fig. 4.3's panel), the envelope figures, the rollout's band and
contact figure and its frames (the hand and the object at a few times) into DIR.
"""

import argparse
from pathlib import Path

SCENARIO = Path(__file__).resolve().parent / "scenarios" / "disc.toml"


def largest_fixed_turn(plan, finger) -> tuple[float, float, float]:
    """The largest turn of the object [rad] over which one contact stays feasible for ``finger`` (one fixed ξ in
    every sample's feasible set), and the window's times [s]."""
    from regrasp.core.intervals import intersect

    times, beta = plan.times, plan.poses[:, 2]
    best = (0.0, times[0], times[0])
    for a in range(len(times)):
        common = finger.samples[a].feasible
        for b in range(a, len(times)):
            common = intersect(common, finger.samples[b].feasible)
            if not common:
                break
            turn = float(beta[a:b + 1].max() - beta[a:b + 1].min())
            if turn > best[0]:
                best = (turn, float(times[a]), float(times[b]))
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--resolution", type=float, default=4.0, help="the lattice's cell [mm] (default 4)")
    parser.add_argument("--periods", type=int, default=1, help="periods to run (default 1)")
    parser.add_argument("--plant", choices=("project", "mujoco"), default="project", help="the plant (default project)")
    parser.add_argument("--plot", type=Path, help="write the figures into this directory")
    args = parser.parse_args()
    # (imported after parsing: --help answers at once)
    from regrasp import RunSpec, build_rollout, load_scenario, plan_scenario
    from regrasp.cli.simulate import plant_text, rollout_summary
    from regrasp.schedule.planner import RegraspSettings, plan_regrasps

    disc = load_scenario(SCENARIO)
    plan = plan_scenario(disc)
    swing = float(plan.poses[:, 2].max() - plan.poses[:, 2].min())
    print(f"{disc.name}: a disc of radius {disc.polygon.radius * 1e3:g} mm turned {swing:.2f} rad "
          f"(beta from {plan.poses[:, 2].min():+.2f} to {plan.poses[:, 2].max():+.2f} rad)")
    for finger in plan.fingers:
        turn, t0, t1 = largest_fixed_turn(plan, finger)
        verdict = "a fixed contact survives it all" if turn >= swing - 1e-12 else "it must slide"
        print(f"  {finger.name:8s} one fixed contact survives at most {turn:.2f} rad of it "
              f"(t in [{t0:.2f}, {t1:.2f}] s): {verdict}")

    h = args.resolution * 1e-3
    settings = RegraspSettings(xi_resolution=h, envelope_margin=max(1e-3, 0.5 * h))
    schedule = plan_regrasps(disc, settings)
    print(f"\nschedule on {args.resolution:g} mm cells: {len(schedule.slides)} slides per period of "
          f"{schedule.period:.3f} s, planned in {schedule.planning_seconds:.1f} s")
    for s in schedule.slides:
        print(f"  {s.name:8s} {'+' if s.direction > 0 else '-'}xi {s.start_xi * 1e3:6.1f} -> {s.end_xi * 1e3:6.1f} mm "
              f"in [{s.start:.3f}, {s.end:.3f}] s: {abs(s.end_xi - s.start_xi) / disc.polygon.radius:.2f} rad "
              "round the disc")

    rollout = build_rollout(disc, RunSpec(periods=args.periods), schedule=schedule, regrasp_settings=settings,
                            plan=plan, plant=args.plant)
    result = rollout.run()
    print("\n" + rollout_summary(result, disc, plant_text(args.plant, rollout.plant)))
    for i, name in enumerate(result.names):
        xi = result.xi[:, i]
        print(f"  {name}'s contact went round {float(xi.max() - xi.min()) / disc.polygon.radius:.2f} rad of the disc")
    if args.plot is not None:
        from regrasp.envelope.plotting import write_plan_figures
        from regrasp.rollout.plots import write_rollout_figures
        from regrasp.schedule.plotting import plot_schedule

        paths = [*write_plan_figures(plan, args.plot), plot_schedule(plan, schedule, args.plot / "regrasp.png"),
                 *write_rollout_figures(rollout, result, args.plot, plant=args.plant)]
        print("figures: " + ", ".join(str(p) for p in paths))
    if not result.success:
        raise SystemExit(1)


if __name__ == "__main__":
    main()

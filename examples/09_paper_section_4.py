"""The paper's §4 results, reproduced: regrasping rollouts of trajectories 1 and 2 on the plant.

Run: python examples/09_paper_section_4.py [--periods N] [--plot DIR]
For each of the paper's demonstrations it plans the regrasp schedule, runs the rollout on the
independent full-coordinate plant and prints what happened:

* Figure 4.3: trajectory 2, three fingers (a palm finger under the object), gravity down, the
  scheduled policy; next to it the paper's danger-zone heuristic and no regrasp, from the same grasp;
* Figure 4.4: trajectory 2 with gravity up (a third finger on top), the scheduled policy;
* Figure 4.2: trajectory 1, whose envelope empties: the schedule up to then, and the failure there;
* the paper's two-finger set-up: no schedule exists (the two-finger slide rule), and the heuristic's
  rollout fails.

With ``--plot DIR`` it writes the figures (per finger its band, planned and actual contact against
time; the hand and the object at a few times). ``--periods`` runs N periods of trajectory 2 (default 1;
the documentation's figures use 3).
"""

import argparse
from pathlib import Path

SCENARIOS = Path(__file__).resolve().parent / "scenarios"


def row(name, result) -> str:
    failure = "-" if result.success else f"{result.failure.kind.value} at {result.failure.time:.3f} s"
    slides = sum(result.regrasps.values())
    return (f"  {name:34s} {result.simulated_seconds:6.2f} s {slides:4d} {result.min_envelope_margin * 1e3:8.2f} mm "
            f"{result.min_cone_margin:7.3f} N  {failure}")


def figures(result, rollout, directory: Path | None, stem: str, frames: bool) -> None:
    if directory is None:
        return
    from regrasp.rollout.plots import plot_frames, plot_rollout

    named = dict(scenario=rollout.scenario, plant="project")
    paths = [plot_rollout(result, directory / f"{stem}.png", **named)]
    if frames:
        paths.append(plot_frames(result, rollout.supervisor.hand, rollout.plant.polygon,
                                 directory / f"{stem}_frames.png", **named))
    for p in paths:
        print(f"    figure: {p}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--periods", type=int, default=1, help="periods of trajectory 2 to run (default 1)")
    parser.add_argument("--plot", type=Path, help="write the figures into this directory")
    args = parser.parse_args()
    # (imported after parsing: --help answers at once)
    from regrasp import NoScheduleError, RunSpec, build_rollout, load_scenario

    header = f"  {'rollout':34s} {'reached':>8s} {'slides':>6s} {'envelope':>11s} {'cone':>9s}  failure"

    print(f"Figure 4.3: trajectory 2, three fingers, gravity down, {args.periods} period(s)")
    three = load_scenario(SCENARIOS / "paper_trajectory_2_three_fingers.toml")
    scheduled = build_rollout(three, RunSpec(periods=args.periods))
    start = scheduled.schedule.xi_start
    print(header)
    results = {}
    for policy, rollout in (("scheduled", scheduled),
                            ("paper", build_rollout(three, RunSpec(periods=args.periods, xi0=start), policy="paper")),
                            ("none", build_rollout(three, RunSpec(periods=args.periods, xi0=start), policy="none"))):
        results[policy] = result = rollout.run()
        print(row(f"{policy} policy", result))
        if policy == "scheduled":
            figures(result, rollout, args.plot, "fig_4_3_three_fingers", frames=False)
    ok = results["scheduled"]
    print(f"    scheduled: object error after 0.5 s {ok.max_object_error_after_transient / ok.object_width:.1e} of the "
          f"object's width; slides {ok.regrasps}; re-plans {ok.replans}; plant events {ok.plant_event_counts()}")

    print("\nFigure 4.4: trajectory 2, gravity up, a third finger on top")
    up = load_scenario(SCENARIOS / "paper_trajectory_2_gravity_up.toml")
    rollout = build_rollout(up, RunSpec(periods=args.periods))
    result = rollout.run()
    print(header)
    print(row("scheduled policy", result))
    figures(result, rollout, args.plot, "fig_4_4_gravity_up", frames=True)

    print("\nFigure 4.2: trajectory 1, two fingers")
    one = load_scenario(SCENARIOS / "paper_trajectory_1.toml")
    try:
        build_rollout(one)
    except NoScheduleError as exc:
        print(f"  no schedule beyond t = {exc.latest_time:.3f} s ({exc.limit.value}): {exc.reason}")
        rollout = build_rollout(one, schedule=exc.partial)
        result = rollout.run()
        print(header)
        print(row("its partial schedule", result))
        print(f"    {result.failure.reason}")
        figures(result, rollout, args.plot, "fig_4_2_trajectory_1", frames=True)

    print("\nThe paper's two-finger set-up (trajectory 2, gravity down)")
    two = load_scenario(SCENARIOS / "paper_trajectory_2.toml")
    try:
        build_rollout(two)
    except NoScheduleError as exc:
        print(f"  no schedule ({exc.limit.value}): {exc.rule or exc.reason}")
    result = build_rollout(two, policy="paper").run()
    print(header)
    print(row("paper policy", result))
    print(f"    {result.failure.reason if result.failure else 'success'}")


if __name__ == "__main__":
    main()

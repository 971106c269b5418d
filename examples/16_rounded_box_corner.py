"""A rounded box turned in the hand: the palm's contact slides from the bottom edge round a corner and back (issue 28).

Run: python examples/16_rounded_box_corner.py [--resolution MM] [--periods N] [--plant project|mujoco] [--plot DIR]
On examples/scenarios/rounded_box.toml (a 60 mm square box with 15 mm corners, 80 g, swung 0.8 rad either way each
period, two side fingers and a palm finger under it) it prints:

1. the box's pieces: ξ is the arc length round the whole boundary, the straight parts of the edges and the corners'
   arcs one after the other, so a contact slides from one onto the next;
2. the periodic regrasp schedule (§4) on a lattice of ``--resolution`` mm cells (default 3, seconds; the scenario's
   own 2 mm, as ``regrasp plan --regrasp`` plans it, about a minute), each slide with the pieces it starts and
   ends on;
3. the rollout for ``--periods`` periods (default 1) on the project plant or on MuJoCo (``--plant mujoco``, needs
   the mujoco extra), summed up as ``regrasp simulate`` does (the result, the tracking error, the margins), and for
   each contact the pieces it was on in the plant, how long, and the least normal force it carried there (a contact
   that carries no force is lost, on an arc as on an edge).

With ``--plot DIR`` it writes the schedule (paper Fig. 4.3's panel, the arcs shaded), the envelope figures, the
rollout's band and contact figure and its frames (the hand and the object at a few times) into DIR.
"""

import argparse
from pathlib import Path

SCENARIO = Path(__file__).resolve().parent / "scenarios" / "rounded_box.toml"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--resolution", type=float, default=3.0, help="the lattice's cell [mm] (default 3)")
    parser.add_argument("--periods", type=int, default=1, help="periods to run (default 1)")
    parser.add_argument("--plant", choices=("project", "mujoco"), default="project", help="the plant (default project)")
    parser.add_argument("--plot", type=Path, help="write the figures into this directory")
    args = parser.parse_args()
    # (imported after parsing: --help answers at once)
    import numpy as np

    from regrasp import RunSpec, build_rollout, load_scenario, plan_scenario
    from regrasp.cli.simulate import plant_text, rollout_summary
    from regrasp.schedule.planner import RegraspSettings, plan_regrasps

    box = load_scenario(SCENARIO)
    shape = box.polygon
    print(f"{box.name}: a {shape.label}, perimeter {shape.perimeter * 1e3:.1f} mm; its pieces (xi [mm], clockwise "
          "from the top edge's middle):")
    print("  " + ", ".join(f"{kind} {k} [{a * 1e3:.1f}, {b * 1e3:.1f}]" for kind, k, a, b in shape.piece_ranges()))

    plan = plan_scenario(box)
    h = args.resolution * 1e-3
    settings = RegraspSettings(xi_resolution=h, envelope_margin=max(1e-3, 0.5 * h))
    schedule = plan_regrasps(box, settings)
    print(f"\nschedule on {args.resolution:g} mm cells: {len(schedule.slides)} slides per period of "
          f"{schedule.period:.3f} s, planned in {schedule.planning_seconds:.1f} s")
    for s in schedule.slides:
        pieces = " -> ".join(dict.fromkeys("{} {}".format(*shape.piece(x)) for x in (s.start_xi, s.end_xi)))
        print(f"  {s.name:8s} {'+' if s.direction > 0 else '-'}xi {s.start_xi * 1e3:6.1f} -> {s.end_xi * 1e3:6.1f} mm "
              f"in [{s.start:.3f}, {s.end:.3f}] s ({pieces})")

    rollout = build_rollout(box, RunSpec(periods=args.periods), schedule=schedule, regrasp_settings=settings,
                            plan=plan, plant=args.plant)
    result = rollout.run()
    print("\n" + rollout_summary(result, box, plant_text(args.plant, rollout.plant)))
    print("  where the contacts were in the plant (its own positions and forces):")
    dt = float(np.median(np.diff(result.times)))
    for i, name in enumerate(result.names):
        on = np.array(["{} {}".format(*shape.piece(x)) for x in result.xi[:, i]])
        normal = result.forces_surface[:, i, 0]
        parts = [f"{piece} for {np.count_nonzero(on == piece) * dt:.2f} s (least normal force "
                 f"{normal[on == piece].min():.2f} N)" for piece in dict.fromkeys(on)]
        print(f"    {name}: xi in [{result.xi[:, i].min() * 1e3:.1f}, {result.xi[:, i].max() * 1e3:.1f}] mm, "
              + ", ".join(parts))
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

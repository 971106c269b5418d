"""Paper Figure 3.4 / Remark 3.3: which way can a finger slide on a block held against gravity?

Run: python examples/06_figure_3_4.py [--out DIR]
The paper's rectangle is held at its sides, gravity down, μ = 0.3 on both tips; finger 1 touches
7.5 mm below the centre of the left edge, finger 2 7.5 mm above the centre of the right edge.
With two fingers the contact forces are fixed by the object's balance, and a sliding tip's
friction points along its slide. Sliding finger 1 up lets its friction carry the weight. Sliding
it down would need both fingers to pull. Prints the predicate's verdict and forces for both
directions and writes figure_3_4.png.
"""

import argparse
from pathlib import Path

HERE = Path(__file__).resolve().parent


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default=".", help="directory for figure_3_4.png (default: here)")
    args = parser.parse_args()
    # (imported after parsing: --help answers at once)
    import numpy as np

    from regrasp import Friction, Grasp, load_scenario
    from regrasp.dynamics.plotting import plot_slide_feasibility
    from regrasp.dynamics.sliding import sliding_feasibility

    sc = load_scenario(HERE / "scenarios" / "paper_trajectory_2.toml")
    pose, xi, friction = np.array([0.0, 0.12, 0.0]), np.array([-0.0075, -0.0075]), Friction(0.3)
    grasp = Grasp(sc.polygon, [1, 3], ["fixed", "fixed"])
    results = [sliding_feasibility(grasp, pose, xi, np.zeros(3), 0, direction, friction, object_mass=sc.polygon.mass,
                                   object_inertia=sc.polygon.inertia, gravity_in_hand=sc.gravity_in_hand)
               for direction in (+1, -1)]
    for r in results:
        forces = ", ".join(f"finger{i + 1} (n {fn:+.3f} N, t {ft:+.3f} N)"
                           for i, (fn, ft) in enumerate(r.forces_surface))
        print(f"slide finger 1 {'up  ' if r.direction > 0 else 'down'}: {'possible  ' if r.possible else 'impossible'}"
              f" {forces}" + (f"  <- {r.reason}" if r.reason else ""))
    path = plot_slide_feasibility(sc.polygon, pose, [c.finger for c in sc.contacts], grasp.points(pose, xi), [1, 3],
                                  friction, results, Path(args.out) / "figure_3_4.png",
                                  gravity_in_hand=sc.gravity_in_hand,
                                  title="Remark 3.3 / Figure 3.4: a block held against gravity, finger 1 sliding")
    print(f"figure: {path}")


if __name__ == "__main__":
    main()

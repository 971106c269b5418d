"""Plan the paper's two trajectories (Examples 2.1 and 2.2) and compare the collision models.

Run: python examples/01_plan_paper_trajectories.py [--plot DIR]
Prints, for each trajectory and each geometry (ideal segments, URDF shapes with coal), the
verdict, why it fails where it does, and the contact each finger should start from.
"""

import argparse
from pathlib import Path

HERE = Path(__file__).resolve().parent


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--plot", metavar="DIR",
                        help="also write the figures of each plan into DIR/<scenario>_<geometry>/ (ideal and urdf)")
    args = parser.parse_args()
    # (imported after parsing: --help answers at once)
    from regrasp import load_scenario, plan_scenario
    from regrasp.envelope.plotting import write_plan_figures

    for name in ("paper_trajectory_1", "paper_trajectory_2"):
        scenario = load_scenario(HERE / "scenarios" / f"{name}.toml")
        for geometry in ("ideal", "urdf"):
            result = plan_scenario(scenario, geometry=geometry, samples=201)
            verdict = "feasible" if result.feasible else "INFEASIBLE"
            print(f"{name} [{geometry:5s}] {verdict}  ({result.seconds_per_sample * 1e6:.0f} us/finger/sample)")
            for f in result.fingers:
                why = "; ".join(f"{iv.reason} in [{iv.start:.2f}, {iv.end:.2f}] s" for iv in f.infeasible_intervals)
                start = ("none" if f.initial_xi is None else
                         f"xi0 = {f.initial_xi * 1e3:+.1f} mm (feasible until {f.initial_xi_feasible_until:.2f} s)")
                print(f"    {f.name}: {start}" + (f"; infeasible: {why}" if why else ""))
            if args.plot:
                write_plan_figures(result, Path(args.plot) / f"{name}_{geometry}")


if __name__ == "__main__":
    main()

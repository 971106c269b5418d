"""Use the planner as a library: your own finger URDF, a hexagonal object and a waypoint path.

Run: python examples/05_plan_with_your_own_finger.py
Builds everything in code (no scenario file): two copies of the shipped long-distal finger,
a regular hexagon, and a C2 spline through waypoints; then prints each finger's envelope at a
few times and whether one fixed grasp survives the whole motion.
"""

import argparse
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    argparse.ArgumentParser(description=__doc__.split("\n\n")[0]).parse_args()
    # (imported after parsing: --help answers at once)
    import numpy as np

    from regrasp import ConvexPolygon, Finger, WaypointTrajectory, plan
    from regrasp.model import FingerContact

    urdf = ROOT / "urdf" / "planar_2r_finger_long_distal.urdf"
    left = Finger.from_urdf(urdf, base_in_hand=(-0.045, 0.0, np.pi / 2), configuration="left", name="left")
    right = left.with_placement(base_in_hand=(0.045, 0.0, np.pi / 2), configuration="right", name="right")

    angles = np.deg2rad([0, 60, 120, 180, 240, 300])
    hexagon = ConvexPolygon.from_vertices(0.03 * np.c_[np.cos(angles), np.sin(angles)], density=20.0)
    # edge k runs from vertex k to vertex k+1: edge 3 is the lower-left side, edge 5 the lower-right one
    print(f"hexagon: mass {hexagon.mass:.3f} kg, inertia {hexagon.inertia:.2e} kg m^2")
    for k in (3, 5):
        e = hexagon.edge(k)
        print(f"  edge {k}: inward normal {np.round(e.inward_normal, 3)}, xi in [{e.xi_range[0]*1e3:.1f}, "
              f"{e.xi_range[1]*1e3:.1f}] mm")

    path = WaypointTrajectory(
        times=[0.0, 0.5, 1.0, 1.5, 2.0],
        poses=[[0.0, 0.085, 0.0], [0.02, 0.10, 0.4], [0.0, 0.115, 0.0], [-0.02, 0.10, -0.4], [0.0, 0.085, 0.0]],
        boundary="clamped",
    )
    result = plan([FingerContact(left, 3), FingerContact(right, 5)], hexagon, path, samples=81)
    print(f"verdict: {'feasible' if result.feasible else 'INFEASIBLE'}")
    for f in result.fingers:
        print(f"  {f.name} on edge {f.edge} ({f.configuration}):")
        for s in f.samples[::20]:
            feas = ", ".join(f"[{lo*1e3:+.1f}, {hi*1e3:+.1f}]" for lo, hi in s.feasible) or "empty"
            print(f"    t = {s.time:.2f} s  d = {s.d*1e3:+6.1f} mm  condition {s.condition.value:3s} "
                  f"feasible xi [mm]: {feas}")
        fixed = ", ".join(f"[{lo*1e3:+.1f}, {hi*1e3:+.1f}]" for lo, hi in f.fixed_grasp)
        print(f"    fixed grasp for the whole path: {fixed or 'none (a regrasp is needed)'}")


if __name__ == "__main__":
    main()

"""Regrasp as a planning stack would: hand, object and trajectory in code, a schedule, a rollout, metrics.

Run: python examples/04_regrasp_rollout.py [--periods N] [--plant-mass-scale S] [--plant-mu-scale S] [--rrd FILE]
Builds the paper's three-finger set-up in code (no scenario file): two side fingers on the left and
right edges of a 100 x 40 mm block and a palm finger under it, the block on the paper's trajectory 2
(an ellipse, one period pi seconds), gravity down. It plans the regrasp schedule
(``plan_regrasps``: every slide of every contact, jointly, with the physics as constraints), runs the
scheduled policy on the independent full-coordinate plant (optionally one that differs from the model),
and reads the result: success, tracking, slides, margins, and the supervisor's decisions.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from regrasp import Scenario

ROOT = Path(__file__).resolve().parents[1]


def three_finger_scenario() -> Scenario:
    """Paper trajectory 2 with a palm finger (as examples/scenarios/paper_trajectory_2_three_fingers.toml)."""
    import numpy as np

    from regrasp import ConvexPolygon, EllipseTrajectory, Finger, Friction, Geometry, Scenario
    from regrasp.model import FingerContact

    finger = ROOT / "urdf" / "planar_2r_finger.urdf"
    palm = ROOT / "urdf" / "planar_2r_palm_finger.urdf"
    up = np.pi / 2
    fingers = [
        FingerContact(Finger.from_urdf(finger, base_in_hand=(-0.05, 0.0, up), configuration="left", name="finger1"),
                      edge=1, friction=Friction(0.5)),
        FingerContact(Finger.from_urdf(finger, base_in_hand=(0.05, 0.0, up), configuration="right", name="finger2"),
                      edge=3, friction=Friction(0.5)),
        FingerContact(Finger.from_urdf(palm, base_in_hand=(0.03, -0.06, up), configuration="left", name="palm"),
                      edge=2, friction=Friction(0.5)),
    ]
    block = ConvexPolygon.rectangle(0.10, 0.04, mass=0.08)
    trajectory = EllipseTrajectory(cx=0.0, cy=0.12, a=0.09, b=0.05, omega=2.0)  # one period: pi s
    return Scenario(name="three fingers, in code", polygon=block, trajectory=trajectory, contacts=fingers,
                    gravity_in_hand=np.array([0.0, -9.81]), samples=801, geometry=Geometry.URDF)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--periods", type=int, default=1, help="periods of the trajectory to run (default 1)")
    parser.add_argument("--plant-mass-scale", type=float, default=1.0, help="the plant's object mass / the model's")
    parser.add_argument("--plant-mu-scale", type=float, default=1.0, help="the plant's friction / the model's")
    parser.add_argument("--rrd", type=Path, help="also write a rerun recording (open it with `rerun FILE`)")
    args = parser.parse_args()
    # (imported after parsing: --help answers at once)
    from regrasp import EventKind, ModelErrors, PlantSpec, RegraspSettings, RunSpec, build_rollout, plan_regrasps

    scenario = three_finger_scenario()
    schedule = plan_regrasps(scenario, RegraspSettings(cone_margin=0.2))
    print(f"schedule: {len(schedule.slides)} slides per period (no schedule has fewer than "
          f"{schedule.slides_lower_bound}), planned in {schedule.planning_seconds:.1f} s; it keeps every contact "
          f"{schedule.min_envelope_margin * 1e3:.2f} mm inside its envelope and every fixed one "
          f"{schedule.min_cone_margin:.3f} N inside its friction cone")
    for s in schedule.slides:
        print(f"  {s.name:8s} {'+xi' if s.direction > 0 else '-xi'} {s.start_xi * 1e3:6.1f} -> {s.end_xi * 1e3:6.1f} mm"
              f"  in [{s.start:.3f}, {s.end:.3f}] s")

    rollout = build_rollout(scenario, RunSpec(periods=args.periods), schedule=schedule,
                            plant=PlantSpec(errors=ModelErrors(mass_scale=args.plant_mass_scale,
                                                               mu_scale=args.plant_mu_scale)))
    recorder = None
    if args.rrd is not None:
        from regrasp import RolloutRecorder

        recorder = RolloutRecorder(rollout.plant, rrd_path=args.rrd, decimation=10, envelope_geometry="urdf")
    try:
        result = rollout.run(recorder=recorder)
    finally:
        if recorder is not None:
            recorder.close()

    print(f"rollout ({result.policy} policy, {args.periods} period(s), plant mass x{args.plant_mass_scale}, "
          f"mu x{args.plant_mu_scale}): " + ("success" if result.success else
                                              f"FAILED at t = {result.failure.time:.3f} s: {result.failure.reason}"))
    print(f"  object error after 0.5 s: {result.max_object_error_after_transient * 1e3:.4f} mm "
          f"({result.max_object_error_after_transient / result.object_width:.1e} of the object's width)")
    print(f"  slides: {result.regrasps}; re-plans: {result.replans}")
    print(f"  smallest envelope margin {result.min_envelope_margin * 1e3:.2f} mm ({result.min_envelope_margin_at[1]}), "
          f"smallest cone margin of a fixed contact {result.min_cone_margin:.3f} N ({result.min_cone_margin_at[1]})")
    slides = [e for e in result.events if e.kind in (EventKind.PRIME, EventKind.ARRIVED)]
    print(f"  the supervisor's first decisions ({len(result.events)} events in all):")
    for e in slides[:6]:
        print(f"    t = {e.time:.3f} s  {e.contact}: {e.kind.value} ({e.detail})")
    print(f"  {result.steps} steps in {result.wall_seconds:.1f} s ({result.realtime_factor:.2f}x real time)"
          + (f"; recording: {result.rrd}" if result.rrd else ""))


if __name__ == "__main__":
    main()

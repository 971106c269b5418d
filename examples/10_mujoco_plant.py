"""The same controllers on two plants: the project's (rigid point contacts) and MuJoCo's (sphere tips, soft contacts).

Run: python examples/10_mujoco_plant.py [--tip-radius MM] [--rollout SECONDS]
Needs the mujoco extra (pip install 'regrasp[mujoco]'). Prints, for each plant:
1. the paper's two-finger hold along trajectory 2 for 1 s (no regrasp): the object's tracking errors after the
   0.5 s transient and the plant's events;
2. Figure 3.4's upward slide of finger 1 at 5 mm/s while the object is held still, run by the supervisor's
   executor (primed past the cone edge, then Proposition 3): how often it was primed, how far the slider is from
   its plan, the object's error;
3. with --rollout T, the scheduled three-finger rollout (the default scenario of regrasp simulate) for T seconds.
On MuJoCo the laws know the tips' radius (the sphere's couple on the distal link), and held contacts follow their
sensed positions (a sphere rolls): docs/derivations.md, "A second plant: MuJoCo".
"""

import argparse
from pathlib import Path

SCENARIOS = Path(__file__).resolve().parent / "scenarios"
XI0, MU, SPEED, START, END = -0.0075, 0.3, 0.005, 0.02, 0.32  # Figure 3.4: finger 1 7.5 mm below the centre


def hold(sc, plant, radius):
    """The two-finger hold on ``plant``: (orientation error [mrad], position error [mm], events)."""
    from regrasp import MujocoSettings, PlantSpec, RunSpec, build_rollout

    spec = PlantSpec() if plant == "project" else PlantSpec("mujoco", MujocoSettings(tip_radius=radius))
    r = build_rollout(sc, RunSpec(duration=1.0), policy="none", plant=spec).run()
    return (r.max_orientation_error_after_transient * 1e3, r.max_object_error_after_transient * 1e3,
            r.plant_event_counts())


def figure_3_4(sc, plant, radius):
    """Figure 3.4's slide on ``plant``: (primings, largest |ξ - ξ_d| after 50 ms [mm], ξ at the end [mm],
    largest orientation error [mrad])."""
    import numpy as np

    from regrasp import (
        Grasp,
        Hand,
        MujocoSettings,
        Plant,
        PlantContact,
        ReducedModel,
        RegraspSupervisor,
        SupervisorSettings,
        WaypointTrajectory,
    )
    from regrasp.core.events import EventKind
    from regrasp.plants.mujoco import MujocoPlant
    from regrasp.rollout.build import Rollout
    from regrasp.supervisor import SlideOrder
    from regrasp.supervisor.policies import OrderedSlidesPolicy

    hand = Hand([c.finger for c in sc.contacts], gravity_in_hand=sc.gravity_in_hand)
    contacts = [PlantContact(1, "fixed", XI0), PlantContact(3, "fixed", XI0)]
    pose = np.array([0.0, 0.12, 0.0])
    p = (MujocoPlant(hand, sc.polygon, contacts, friction=MU, settings=MujocoSettings(tip_radius=radius))
         if plant == "mujoco" else Plant(hand, sc.polygon, contacts, friction=MU))
    st = ReducedModel(hand, Grasp(sc.polygon, [1, 3], ["fixed", "fixed"]), [XI0, XI0]).state(pose, np.zeros(3))
    p.reset(st.q, st.q_dot, pose, np.zeros(3))

    def planned(t):
        return XI0 + SPEED * max(0.0, t - START), SPEED if t >= START else 0.0, 0.0

    order = SlideOrder(0, 1, planned(END)[0], reference=planned, planned_start=START, planned_end=END)
    # a break-away excess of 0.01 f_n: 0.05 f_n throws MuJoCo's 5 g fingertip to ~25 mm/s in one step, 5x the slide's
    settings = SupervisorSettings.robust("ideal", 0.2, tip_radius=radius if plant == "mujoco" else 0.0)
    settings = settings.with_executor(prime_overshoot=0.01)
    supervisor = RegraspSupervisor(hand, sc.polygon, [1, 3], WaypointTrajectory([0.0, 1.0], [pose, pose]), [XI0, XI0],
                                   MU, settings=settings, policy=OrderedSlidesPolicy([order], 2))
    r = Rollout(p, supervisor, END, ("finger1", "finger2"), "ordered").run()
    late = r.times > START + 0.05
    error = np.abs(r.xi[late, 0] - [planned(t)[0] for t in r.times[late]]).max()
    primes = sum(e.kind is EventKind.PRIME for e in r.events)
    return primes, error * 1e3, r.xi[-1, 0] * 1e3, np.abs(r.object_error[:, 2]).max() * 1e3


def scheduled(sc, plant, radius, seconds):
    from regrasp import MujocoSettings, PlantSpec, RunSpec, build_rollout

    spec = PlantSpec() if plant == "project" else PlantSpec("mujoco", MujocoSettings(tip_radius=radius))
    r = build_rollout(sc, RunSpec(duration=seconds), plant=spec).run()
    outcome = "success" if r.success else f"{r.failure.kind.value} at {r.failure.time:.3f} s"
    slides = sum(r.regrasps.values())
    return (f"{outcome}, {slides} slides, error {r.max_object_error_after_transient * 1e3:.3f} mm / "
            f"{r.max_orientation_error_after_transient * 1e3:.2f} mrad, cone margin {r.min_cone_margin:.3f} N, "
            f"envelope margin {r.min_envelope_margin * 1e3:.2f} mm, events {r.plant_event_counts()}, "
            f"{r.wall_seconds:.1f} s wall")


def positive(text: str) -> float:
    value = float(text)
    if not 0.0 < value < float("inf"):
        raise argparse.ArgumentTypeError(f"{text}: expected a number > 0")
    return value


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--tip-radius", type=positive, default=0.25, metavar="MM", help="MuJoCo's tip radius [mm]")
    parser.add_argument("--rollout", type=positive, default=None, metavar="SECONDS",
                        help="also run the scheduled three-finger rollout this long on both plants")
    args = parser.parse_args()
    # (imported after parsing: --help answers at once)
    from regrasp import load_scenario

    radius = args.tip_radius * 1e-3
    two = load_scenario(SCENARIOS / "paper_trajectory_2.toml")
    print(f"MuJoCo: sphere tips of {args.tip_radius:g} mm, soft contacts, 0.1 ms steps under a 1 kHz zero-order hold")
    print("1. two-finger hold, 1 s: largest error after 0.5 s (orientation, position), plant events")
    for plant in ("project", "mujoco"):
        rot, pos, events = hold(two, plant, radius)
        print(f"   {plant:8} {rot:6.3f} mrad  {pos:6.4f} mm  {events or 'none'}")
    print("2. Figure 3.4, finger 1 slides up 1.5 mm at 5 mm/s: primings, |xi - xi_d| after 50 ms, xi at the end, "
          "largest orientation error")
    for plant in ("project", "mujoco"):
        primes, error, xi, rot = figure_3_4(two, plant, radius)
        print(f"   {plant:8} {primes} priming(s)  {error:6.3f} mm  {xi:7.3f} mm (planned "
              f"{(XI0 + SPEED * (END - START)) * 1e3:.3f})  {rot:6.2f} mrad")
    if args.rollout is not None:
        three = load_scenario(SCENARIOS / "paper_trajectory_2_three_fingers.toml")
        print(f"3. the scheduled three-finger rollout, {args.rollout:g} s")
        for plant in ("project", "mujoco"):
            print(f"   {plant:8} {scheduled(three, plant, radius, args.rollout)}")


if __name__ == "__main__":
    main()

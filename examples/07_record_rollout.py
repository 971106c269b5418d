"""Record example 03's slide to a rerun file (headless), or watch it live with --spawn.

Run: python examples/07_record_rollout.py [--rrd FILE] [--duration S] [--decimation N] [--spawn]
Then: rerun rollout.rrd    (the viewer; `pip install rerun-sdk` ships it)

The set-up is examples/03_slide_along_edge.py's: two fingers hold the paper's rectangle, finger 2
fixed on the right edge, finger 1 sliding up the left edge under Proposition 3 on the independent
plant. A RolloutRecorder (regrasp.rollout.recording.recorder) logs every control step: on the left the hand frame
in mm (the object and its desired pose, the fingers' URDF links, the contact forces, the friction
cones coloured by contact mode, each contact edge's feasible envelope with its danger zones), on
the right the tracking errors, each contact's ξ inside its feasible interval, the contact forces,
the cone margins and the contact modes. The file is finalised even if the run is interrupted
(Ctrl-C): the recorder is a context manager.

Prints where the file went, its size, and what recording cost per step next to the simulation.
"""

import argparse
import importlib.util
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def load_example_03():
    """examples/03_slide_along_edge.py as a module (its name starts with a digit)."""
    spec = importlib.util.spec_from_file_location("slide_along_edge", HERE / "03_slide_along_edge.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rrd", type=Path, default=Path("rollout.rrd"), help="output file (default: ./rollout.rrd)")
    parser.add_argument("--duration", type=float, default=1.0, help="simulated time [s] (default 1; example 03: 3)")
    parser.add_argument("--decimation", type=int, default=1, help="log every n-th control step (default 1)")
    parser.add_argument("--spawn", action="store_true", help="also stream to a rerun viewer it starts")
    args = parser.parse_args()
    # (imported after parsing: --help answers at once)
    from regrasp import Grasp, Hand, Plant, PlantContact, ReducedModel, load_scenario
    from regrasp.dynamics.control import Gains
    from regrasp.dynamics.laws import Proposition3Controller
    from regrasp.plants.closed_loop import run_closed_loop
    from regrasp.rollout.recording.recorder import RolloutRecorder

    ex = load_example_03()
    friction = ex.tip_friction()
    sc = load_scenario(HERE / "scenarios" / "paper_trajectory_2.toml")
    hand = Hand([c.finger for c in sc.contacts], gravity_in_hand=sc.gravity_in_hand)
    grasp = Grasp(sc.polygon, [1, 3], ["sliding", "fixed"])
    _, (lo, hi) = ex.slide_range(sc, grasp)
    model = ReducedModel(hand, grasp, xi=[lo, ex.XI_HOLD])
    reference = ex.make_reference(lo, hi)
    S0, S0_dot, _ = reference(0.0)
    st = model.state(S0, S0_dot)
    plant = Plant(hand, sc.polygon, [PlantContact(1, "sliding", lo, 1.0), PlantContact(3, "fixed", ex.XI_HOLD)],
                  friction=friction)
    plant.reset(st.q, st.q_dot, S0[:3], S0_dot[:3])
    controller = Proposition3Controller(model, Gains.critically_damped(40.0, 4), friction=friction)
    print(f"example 03's slide: finger 1 from xi = {lo * 1e3:.1f} mm towards {hi * 1e3:.1f} mm "
          f"({friction[0]} sliding, {friction[1]} holding), {args.duration:g} s at dt = {plant.dt * 1e3:g} ms")

    start = time.perf_counter()
    interrupted = False
    with RolloutRecorder(plant, rrd_path=args.rrd, spawn=args.spawn, decimation=args.decimation,
                         recording_name="example 07: slide along an edge") as rec:
        try:
            log = run_closed_loop(plant, controller, reference, args.duration, on_step=rec.hook(plant, reference))
        except KeyboardInterrupt:
            interrupted = True
    wall = time.perf_counter() - start  # includes close(): the last block and the file's footer
    recording = rec.seconds_per_step * rec.steps_logged
    steps = round(plant.state.t / plant.dt)

    path = args.rrd.resolve()
    print(f"\nwrote {path} ({path.stat().st_size / 1e6:.2f} MB): {rec.steps_logged} logged states "
          f"(step 0 = initial, then every {args.decimation} control step(s)) of {steps} simulated"
          + (" -- interrupted, the file is complete up to there" if interrupted else ""))
    print("timelines 'time' [s] and 'step'; entities scene/... (hand frame, mm), plots/..., events, model/...")
    simulation = (wall - recording) / max(steps, 1)
    print(f"recording cost: {rec.seconds_per_step * 1e6:.0f} us per logged step ({recording:.2f} s of "
          f"{wall:.2f} s wall); simulation + control: {simulation * 1e3:.2f} ms per step")
    if not interrupted:
        err = log.errors
        print(f"rollout: xi {log.S[0, 3] * 1e3:.1f} -> {log.S[-1, 3] * 1e3:.1f} mm, max sliding error "
              f"{abs(err[:, 3]).max() * 1e6:.1f} um, plant events: {len(log.events) or 'none'}")
    print(f"view it: rerun {path}")


if __name__ == "__main__":
    main()

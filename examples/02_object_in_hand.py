"""The full-coordinate plant on the paper's hand and rectangle, under hand-chosen joint torques.

Run: python examples/02_object_in_hand.py
The two fingers squeeze the rectangle against gravity with torques chosen once, by hand, from
the static balance: τ = g(q) + Jᵀ f, where each fingertip pushes 2 N along its inward normal
and carries half the object's weight. After 0.3 s finger 1 relaxes its squeeze to 0.3 N: the
weight it carries then needs more friction than μ = 0.5 gives, so it slips
while finger 2 keeps holding: the object drops past finger 1, whose tip runs up the edge
until it leaves it. Prints the plant's event log, the contact forces and the maximum constraint
drift.
"""

import argparse
from pathlib import Path

HERE = Path(__file__).resolve().parent


def main() -> None:
    argparse.ArgumentParser(description=__doc__.split("\n\n")[0]).parse_args()
    # (imported after parsing: --help answers at once)
    import numpy as np

    from regrasp import Friction, Hand, Plant, PlantContact, load_scenario

    sc = load_scenario(HERE / "scenarios" / "paper_trajectory_2.toml")
    hand = Hand([c.finger for c in sc.contacts], gravity_in_hand=sc.gravity_in_hand)
    pose = np.array([0.0, 0.12, 0.0])  # object centre and orientation in the hand frame
    # contacts at the middle of the left (edge 1) and right (edge 3) sides
    tips = np.array([[-0.05, 0.12], [0.05, 0.12]])
    q = hand.inverse_kinematics(tips)
    dyn = hand.dynamics(q, np.zeros(4))
    weight = sc.polygon.mass * 9.81

    def torques(squeeze_1: float, squeeze_2: float) -> np.ndarray:
        # force of each tip on the object: push inward (+x for finger 1, -x for finger 2) and
        # lift half the weight (friction along the vertical edges)
        f = np.array([squeeze_1, weight / 2, -squeeze_2, weight / 2])
        return dyn.nonlinear + dyn.jacobian.T @ f

    plant = Plant(hand, sc.polygon, [PlantContact(1, "fixed", 0.0), PlantContact(3, "fixed", 0.0)],
                  friction=Friction(0.5))  # mu_s = mu_k = 0.5; Friction(static, kinetic) for two
    plant.reset(q, np.zeros(4), pose, np.zeros(3))
    print(f"object {sc.polygon.mass:.3f} kg, weight {weight:.3f} N, {plant.friction[0]} at both tips, "
          f"dt = {plant.dt * 1e3:.0f} ms")
    hold, relax = torques(2.0, 2.0), torques(0.3, 2.0)
    steps = 0
    while plant.state.t < 1.0 - 1e-12 and not plant.stopped:
        step = plant.step(hold if plant.state.t < 0.3 - 1e-12 else relax)
        steps += 1
        if steps in (1, 300, 301) or step.events or plant.stopped:
            fn, ft = step.forces_surface.T
            modes = [mode.value for mode in step.modes]
            print(f"t = {step.state.t:.3f} s  modes {modes}  normal forces {np.round(fn, 3)} N, "
                  f"tangential {np.round(ft, 3)} N, xi [mm] {np.round(step.xi * 1e3, 2)}")
    print(f"\nstopped: {plant.stopped} after {steps} steps (t = {plant.state.t:.3f} s)")
    print("event log:")
    for ev in plant.events:
        print(f"  t = {ev.time:.3f} s  {ev.contact:8s} {ev.kind:10s} {ev.detail}")
    print(f"maximum constraint drift: {plant.max_constraint_error:.2e} m")
    print(f"object pose at the end: x = {plant.state.X[0]*1e3:.2f} mm, y = {plant.state.X[1]*1e3:.2f} mm, "
          f"beta = {np.degrees(plant.state.X[2]):.2f} deg")


if __name__ == "__main__":
    main()

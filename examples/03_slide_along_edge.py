"""Slide a fingertip along the object while the hand holds it, first still, then on a small ellipse.

Run: python examples/03_slide_along_edge.py
Two fingers hold the paper's rectangle against gravity: finger 2 (right edge) holds it fixed and
finger 1 (left edge) slides. It goes from one end of its feasible interval to the other while the
object stays still, then back while the object moves on a small ellipse. Proposition 3's law runs
(corrected, m = 2, p = 1, friction from the state through P) on the independent full-coordinate
plant.

Why the fingertips differ: with two fingers the contact forces are fixed by the object's motion
(no internal force is left to choose), so whether a slide is possible depends on its direction
(paper Remark 3.3, Figure 3.4). With equal friction on both tips, a side-held block can only let
the finger slide upwards. A smooth sliding tip (μ = 0.05, a PTFE pad) against a rubber holding tip
(μ = 0.8) allows both directions over part of the edge. The example finds that part with
`sliding_feasibility`, intersects it with the planner's envelope (minus a 10 % margin at each
end), and slides over the result.

Prints the slide range, the largest tracking errors, the smallest friction-cone margin of the
holding finger, the plant's event log (empty) and the control step's median time.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from regrasp import Friction

HERE = Path(__file__).resolve().parent
MU = (0.05, 0.8)            # sliding tip, holding tip (mu_s = mu_k each; tip_friction())
XI_HOLD = 0.019             # finger 2's contact: 19 mm below the centre of the right edge
X0 = (0.0, 0.12, 0.0)       # the object's pose (x, y, β) on the first leg
T_LEG = 1.5                 # [s] per slide leg
ELLIPSE = (0.004, 0.002, 2.0)  # a [m], b [m], ω [rad/s] of the object's small ellipse


def tip_friction() -> list[Friction]:
    """The sliding tip's and the holding tip's friction, ``Friction(mu)`` for each of MU."""
    from regrasp import Friction

    return [Friction(mu) for mu in MU]


def slide_range(sc, grasp):
    """The planner's feasible interval at X0 minus 10 % at each end, intersected with the contacts
    where sliding is possible both ways (sliding_feasibility, 0.5 mm grid, pushes of 0.3 to 6 N)."""
    import numpy as np

    from regrasp import FingerEnvelope
    from regrasp.dynamics.internal_force.settings import InternalForceSettings
    from regrasp.dynamics.sliding import sliding_feasibility

    x0, friction = np.array(X0), tip_friction()
    envelope = FingerEnvelope(sc.contacts[0].finger, sc.polygon, 1, geometry="urdf").at(x0)
    lo, hi = max(envelope.feasible, key=lambda iv: iv[1] - iv[0])
    lo, hi = lo + 0.1 * (hi - lo), hi - 0.1 * (hi - lo)
    settings = InternalForceSettings(f_min=0.3, friction_margin=0.05, f_max=6.0)
    both = [x for x in np.arange(lo, hi + 1e-12, 5e-4)
            if all(sliding_feasibility(grasp, x0, [x, XI_HOLD], np.zeros(3), 0, s, friction,
                                       object_mass=sc.polygon.mass,
                                       object_inertia=sc.polygon.inertia, gravity_in_hand=sc.gravity_in_hand,
                                       settings=settings).possible for s in (1, -1))]
    return (lo, hi), (min(both), max(both))


def make_reference(lo, hi):
    import numpy as np

    c, amp, w = 0.5 * (lo + hi), 0.5 * (hi - lo), np.pi / T_LEG
    a, b, om = ELLIPSE

    def reference(t):
        # ξ: lo -> hi on the first leg, hi -> lo on the second (cosine, smooth at the turn)
        xi, xi_d, xi_dd = c - amp * np.cos(w * t), amp * w * np.sin(w * t), amp * w * w * np.cos(w * t)
        pos, vel, acc = np.array(X0), np.zeros(3), np.zeros(3)
        if t > T_LEG:  # the object joins a small ellipse, blended in over 0.5 s (quintic)
            tau = t - T_LEG
            u = min(tau / 0.5, 1.0)
            s, ds, dds = 10 * u**3 - 15 * u**4 + 6 * u**5, (30 * u**2 - 60 * u**3 + 30 * u**4) / 0.5, \
                (60 * u - 180 * u**2 + 120 * u**3) / 0.25
            if tau >= 0.5:
                ds = dds = 0.0
            e = np.array([a * np.sin(om * tau), b * (np.cos(om * tau) - 1.0)])
            de = np.array([a * om * np.cos(om * tau), -b * om * np.sin(om * tau)])
            dde = -om * om * np.array([a * np.sin(om * tau), b * np.cos(om * tau)])
            pos[:2] += s * e
            vel[:2] = ds * e + s * de
            acc[:2] = dds * e + 2 * ds * de + s * dde
        return np.append(pos, xi), np.append(vel, xi_d), np.append(acc, xi_dd)

    return reference


def main() -> None:
    argparse.ArgumentParser(description=__doc__.split("\n\n")[0]).parse_args()
    # (imported after parsing: --help answers at once)
    import numpy as np

    from regrasp import Grasp, Hand, Plant, PlantContact, ReducedModel, load_scenario
    from regrasp.dynamics.control import Gains
    from regrasp.dynamics.laws import Proposition3Controller
    from regrasp.plants.closed_loop import run_closed_loop

    friction = tip_friction()
    sc = load_scenario(HERE / "scenarios" / "paper_trajectory_2.toml")
    hand = Hand([c.finger for c in sc.contacts], gravity_in_hand=sc.gravity_in_hand)
    grasp = Grasp(sc.polygon, [1, 3], ["sliding", "fixed"])
    (env_lo, env_hi), (lo, hi) = slide_range(sc, grasp)
    print("finger 1's feasible interval (planner, urdf geometry) minus 10 %: "
          f"[{env_lo * 1e3:.1f}, {env_hi * 1e3:.1f}] mm")
    print(f"where it can slide both ways (sliding_feasibility): [{lo * 1e3:.1f}, {hi * 1e3:.1f}] mm -> slide range")

    model = ReducedModel(hand, grasp, xi=[lo, XI_HOLD])
    reference = make_reference(lo, hi)
    S0, S0_dot, _ = reference(0.0)
    st = model.state(S0, S0_dot)
    plant = Plant(hand, sc.polygon, [PlantContact(1, "sliding", lo, 1.0), PlantContact(3, "fixed", XI_HOLD)],
                  friction=friction)
    plant.reset(st.q, st.q_dot, S0[:3], S0_dot[:3])
    controller = Proposition3Controller(model, Gains.critically_damped(40.0, 4), friction=friction)
    log = run_closed_loop(plant, controller, reference, 2 * T_LEG)

    err = log.errors
    print(f"\nsimulated {log.times[-1] + plant.dt:.2f} s at dt = {plant.dt * 1e3:.0f} ms; "
          f"xi went {log.S[0, 3] * 1e3:.1f} -> {log.S[:, 3].max() * 1e3:.1f} -> {log.S[-1, 3] * 1e3:.1f} mm")
    print(f"max object error: {np.hypot(err[:, 0], err[:, 1]).max() * 1e6:.1f} um, "
          f"{np.degrees(np.abs(err[:, 2]).max()):.4f} deg")
    print(f"max sliding error: {np.abs(err[:, 3]).max() * 1e6:.1f} um")
    print(f"min cone margin of the holding finger: {log.cone_margins[:, 1].min():.3f} N "
          f"(min normal forces: {log.plant_forces[:, 0, 0].min():.3f} N sliding, "
          f"{log.plant_forces[:, 1, 0].min():.3f} N holding)")
    print("plant event log:", "empty" if not log.events else "")
    for ev in log.events:
        print(f"  t = {ev.time:.3f} s  {ev.contact:8s} {ev.kind:10s} {ev.detail}")
    print(f"max constraint drift: {log.max_constraint_error:.2e} m; "
          f"control step median: {np.median(log.control_seconds) * 1e6:.0f} us")


if __name__ == "__main__":
    main()

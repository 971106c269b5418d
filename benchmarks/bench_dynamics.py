"""Median time of one plant step and of one evaluation of the reduced model (paper §3).

Run: python benchmarks/bench_dynamics.py [--quick] [--json]

* ``plant_step``: one RK4 step of :class:`regrasp.Plant` (4 dynamics evaluations, event checks
  and the coal collision check), the paper's hand holding the rectangle with one sliding contact.
* ``reduced_state``: :meth:`ReducedModel.state` (IK, H, Ḣ Ṡ, Pinocchio M, N, J, J̇q̇).
* ``reduced_forward_dynamics``: :meth:`ReducedModel.forward_dynamics` on that state.
* ``plant_accelerations``: one :meth:`Plant.accelerations` (one dynamics evaluation of the plant).
* ``control_step_qp`` / ``control_step_no_qp``: one call of the fixed-contact law (two fingers, both
  fixed) with and without the internal-force QP (a persistent OSQP solver, warm-started), and
  ``control_step_m3_qp``: Proposition 1 with three fingers (a two-dimensional internal force).
Medians over repeated calls (time.perf_counter), never means.
"""

from __future__ import annotations

import json

import numpy as np
from common import ROOT, median_us, parse_args, sliding_hold

from regrasp import Finger, Grasp, Hand, ReducedModel
from regrasp.dynamics.control import Gains
from regrasp.dynamics.laws import FixedContactController, Proposition1Controller


def main() -> None:
    args, n = parse_args(__doc__, 500)

    setup = sliding_hold()
    sc, hand, model, S, S_dot, st, tau, plant = (setup.scenario, setup.hand, setup.model, setup.S, setup.S_dot,
                                                  setup.state, setup.tau, setup.plant)
    results = {
        "plant_step": median_us(setup.plant_step, n),
        "plant_accelerations": median_us(lambda: plant.accelerations(plant.state, tau), n),
        "reduced_state": median_us(lambda: model.state(S, S_dot), n),
        "reduced_forward_dynamics": median_us(lambda: model.forward_dynamics(st, tau, 0.3), n),
    }
    results["reduced_evaluation"] = results["reduced_state"] + results["reduced_forward_dynamics"]

    fixed = ReducedModel(hand, Grasp(sc.polygon, [1, 3], ["fixed", "fixed"]), xi=[0.0, 0.0])
    X, zero = np.array([0.0, 0.12, 0.0]), np.zeros(3)
    with_qp = FixedContactController(fixed, Gains.critically_damped(20.0, 3), friction=0.5)
    without_qp = FixedContactController(fixed, Gains.critically_damped(20.0, 3), friction=0.5, internal_force=None)
    results["control_step_qp"] = median_us(lambda: with_qp(X, zero, X, zero, zero), n)
    results["control_step_no_qp"] = median_us(lambda: without_qp(X, zero, X, zero, zero), n)
    third = Finger.from_urdf(ROOT / "urdf" / "planar_2r_finger.urdf", base_in_hand=(0.04, -0.02, np.pi / 2),
                             configuration="left", name="finger3")
    hand3 = Hand([*hand.fingers, third], gravity_in_hand=sc.gravity_in_hand)
    three = ReducedModel(hand3, Grasp(sc.polygon, [1, 3, 2], ["sliding", "fixed", "fixed"]), xi=[-0.01, -0.01, 0.02])
    prop1 = Proposition1Controller(three, Gains.critically_damped(20.0, 4), friction=[0.0, 0.5, 0.5])
    S3, S3_dot = np.array([0.0, 0.12, 0.0, -0.01]), np.array([0.0, 0.0, 0.0, 0.01])
    results["control_step_m3_qp"] = median_us(lambda: prop1(S3, S3_dot, S3, S3_dot, np.zeros(4)), n)
    if args.json:
        print(json.dumps({k: {"median_us": v} for k, v in results.items()}))
        return
    print(f"median of {n} calls each (this machine):")
    for key, value in results.items():
        print(f"  {key:26s} {value:9.1f} us")


if __name__ == "__main__":
    main()

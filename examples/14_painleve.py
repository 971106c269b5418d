"""Painlevé's paradox on a sliding finger: why a slide the forces allow can still fail, and the planner's check.

Run: python examples/14_painleve.py [VARIANT] [--spec SPEC] [--unchecked] [--periods P]

Takes variant VARIANT (default 6) of a suite spec (default: examples/suites/default.toml), plans its regrasp schedule
and runs it on the project plant. For every slide it prints the least ratio rho = A_ii(mu_k) / A_ii(0) along the
contact's sliding phase (``regrasp.dynamics.painleve``: how much of the contact's frictionless normal mobility
friction leaves; at 0 the slider's normal force needs infinitely precise torques, below it the contact problem has
no solution or several) and its least normal force. With ``--unchecked`` the planner does not check the slides'
well-posedness (``RegraspSettings(sliding_friction_factor=None)``): on variant 6 finger 1 then slides where rho falls
to 0 and lifts off; with the check (the default, 1.25 x mu_k) its schedule keeps every slider's rho at 0.2 or more.
``docs/derivations.md``, "Sliding contacts and Painlevé", cites it.
"""

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def slide_ratios(result, scenario) -> list[tuple[str, int, float, float, float, float]]:
    """Per sliding phase in the rollout: (contact, direction, start [s], end [s], least rho, least f_n [N])."""
    from regrasp import Hand
    from regrasp.dynamics.painleve import sliding_response, tip_mobility

    hand = Hand([c.finger for c in scenario.contacts])
    edges = [scenario.polygon.edge(c.edge) for c in scenario.contacts]
    mass, inertia = scenario.polygon.mass, scenario.polygon.inertia
    sliding = result.phases == "sliding"
    rows = []
    for i, contact in enumerate(scenario.contacts):
        steps = np.flatnonzero(sliding[:, i])
        for run in np.split(steps, np.flatnonzero(np.diff(steps) > 1) + 1) if steps.size else []:
            direction = int(np.sign(result.xi[run[-1], i] - result.xi[run[0], i])) or 1
            rho = []
            for k in run:
                q, X = result.joint_positions[k], result.poses[k]
                dyn = hand.dynamics(q, np.zeros_like(q))
                c, s = np.cos(X[2]), np.sin(X[2])
                rot = np.array([[c, -s], [s, c]])
                points = hand.tip_positions(q).reshape(-1, 2) - X[:2]
                W = np.array([tip_mobility(dyn.jacobian[2 * j:2 * j + 2, 2 * j:2 * j + 2],
                                           dyn.mass_matrix[2 * j:2 * j + 2, 2 * j:2 * j + 2])
                              for j in range(len(edges))])
                normals = np.array([rot @ e.inward_normal for e in edges])
                tangents = np.array([rot @ e.xi_direction for e in edges])
                ratios = [None] * len(edges)

                def diagonal(r):
                    ratios[i] = r
                    return sliding_response(mass, inertia, points, normals, tangents, W, ratios)[0, 0]
                rho.append(diagonal(direction * contact.friction.kinetic) / diagonal(0.0))
            rows.append((contact.finger.name, direction, float(result.times[run[0]]), float(result.times[run[-1]]),
                         float(min(rho)), float(result.forces_surface[run, i, 0].min())))
    return sorted(rows, key=lambda r: r[2])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("variant", nargs="?", type=int, default=6, help="the suite variant (default 6)")
    parser.add_argument("--spec", default=str(ROOT / "examples" / "suites" / "default.toml"), help="suite spec")
    parser.add_argument("--unchecked", action="store_true", help="plan without the well-posedness check")
    parser.add_argument("--periods", type=float, default=2.0, help="periods to run (default 2)")
    args = parser.parse_args(argv)
    from regrasp import RunSpec
    from regrasp.rollout.build import build_rollout
    from regrasp.schedule import NoScheduleError
    from regrasp.schedule.problem import RegraspSettings, trajectory_period
    from regrasp.suite import draw_variant, load_suite_spec, variant_scenario

    spec = load_suite_spec(args.spec)
    variant = draw_variant(spec, args.variant)
    scenario = variant_scenario(spec, variant)
    print(f"variant {args.variant}: " + ", ".join(f"{k} = {v:.4g}" for k, v in variant.parameters.items()))
    settings = RegraspSettings(sliding_friction_factor=None) if args.unchecked else RegraspSettings()
    print("planning", "without" if args.unchecked else "with", "the well-posedness check ...", flush=True)
    try:
        rollout = build_rollout(scenario, RunSpec(duration=args.periods * trajectory_period(scenario.trajectory)),
                                policy="scheduled", regrasp_settings=settings)
    except NoScheduleError as exc:
        print(f"no schedule ({exc.limit.value}): {exc}")
        return 0
    result = rollout.run()
    print("rollout:", "SUCCESS" if result.success else f"FAILED: {result.failure.kind.value} at "
          f"t = {result.failure.time:.3f} s ({result.failure.reason})")
    print(f"{'contact':>8} {'dir':>4} {'from [s]':>9} {'to [s]':>7} {'least rho':>10} {'least f_n [N]':>14}")
    for name, d, t0, t1, rho, fn in slide_ratios(result, scenario):
        print(f"{name:>8} {'+' if d > 0 else '-':>4} {t0:9.3f} {t1:7.3f} {rho:10.3f} {fn:14.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

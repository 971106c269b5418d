"""Two artifacts of MuJoCo's soft contacts that decide how the scheduled regrasp fares on MuJoCo: a sliding contact
hops, and a held one on a turning object drifts.

Run: python examples/13_mujoco_contact_artifacts.py [--rollouts] [--duration T]

1. *Sliding contacts hop.* A 0.25 mm sphere on two slide joints (mass m, normal and tangential) is pushed onto a
   plane with a constant normal force f_n and held at a sliding speed v by a 1 kHz servo (zero-order hold, as the
   hand's laws are), with no controller in the normal direction at all. A Coulomb contact on a Kelvin-Voigt pad
   would carry f_n at every step. MuJoCo's (elliptic cones, the plant's solimp and impratio) carries it in bursts:
   the table gives the range of the force averaged over each 1 ms step and the number of whole steps in 50 ms
   that carried none, which the contact-health criteria count as a lost contact. The first row is the stuck
   control (v = 0).
2. *Held contacts drift* (``--rollouts``, about a minute): the default scenario's nominal scheduled rollout on
   MuJoCo, for the friction rows' time constant (``solreffriction``) at a normal one (``solref``) of 2 ms: the
   largest slip of a held contact, and the verdict. A short friction time constant holds the contacts but makes
   the sliders chatter off their edges; a long one lets held contacts creep. Then whether the default scenario
   has a schedule whose sliders push with 0.6 N rather than 0.3 N (``RegraspSettings(slider_floor=0.6)``).

``docs/derivations.md``, "MuJoCo's contacts: drift and hops", quotes these tables (``--rollouts --duration 6.283``).
"""

import argparse
import sys

import numpy as np

SPHERE = 2.5e-4  # the plant's default tip radius [m]


def sliding_sphere(time_constant: float, friction_time_constant: float, mass: float, speed: float,
                   normal_force: float, mu: float = 0.5) -> tuple[float, float, int]:
    """(least, largest force [N] averaged over a 1 ms step, steps with no force) over the last 50 ms of 100 ms."""
    import mujoco

    xml = f"""<mujoco><option timestep="1e-4" cone="elliptic" impratio="100" integrator="implicitfast" solver="Newton"
    iterations="100" tolerance="1e-10" gravity="0 0 0"/><worldbody><geom name="plane" type="plane" size="1 1 0.01"/>
    <body name="tip" pos="0 0 {SPHERE}"><joint type="slide" axis="1 0 0"/><joint type="slide" axis="0 0 1"/>
    <geom name="tip" type="sphere" size="{SPHERE}" mass="{mass}" contype="0" conaffinity="0"/></body></worldbody>
    <contact><pair geom1="tip" geom2="plane" condim="3" friction="{mu} {mu} 0 0 0" solref="{time_constant} 1"
    solreffriction="{friction_time_constant} 1" solimp="0.99 0.999 0.0001 0.5 2"/></contact></mujoco>"""
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    substeps, forces, wrench = 10, [], np.zeros(6)
    push = 0.0
    for k in range(1000):
        if k % substeps == 0:  # the servo: friction fed forward, the speed error fed back at 200 rad/s
            push = (mu * normal_force if speed > 0.0 else 0.0) + mass * 200.0 * (speed - data.qvel[0])
        data.qfrc_applied[:] = (push, -normal_force)
        mujoco.mj_step(model, data)
        fn = 0.0
        for c in range(data.ncon):
            mujoco.mj_contactForce(model, data, c, wrench)
            fn += wrench[0]
        forces.append(fn)
    per_step = np.array(forces[-500:]).reshape(-1, substeps).mean(axis=1)
    return float(per_step.min()), float(per_step.max()), int((per_step <= 0.0).sum())


def held_drift(friction_time_constant: float, duration: float) -> tuple[float, str]:
    """(largest held slip [mm], verdict) of the default scenario's nominal rollout on MuJoCo at solref 2 ms."""
    from regrasp import load_scenario
    from regrasp.plants.mujoco.mjcf import MujocoSettings
    from regrasp.plants.spec import PlantSpec
    from regrasp.rollout.build import build_rollout
    from regrasp.rollout.spec import RunSpec

    scenario = load_scenario("examples/scenarios/paper_trajectory_2_three_fingers.toml")
    settings = MujocoSettings(time_constant=2e-3, friction_time_constant=friction_time_constant)
    result = build_rollout(scenario, RunSpec(duration=duration), plant=PlantSpec("mujoco", settings=settings)).run()
    slip = max(h.largest_held_slip for h in result.health)
    verdict = "success" if result.success else f"{result.failure.reason} at {result.failure.time:.3f} s"
    return 1e3 * slip, verdict


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rollouts", action="store_true", help="also the held drift on the default scenario")
    parser.add_argument("--duration", type=float, default=2.0, help="the rollouts' duration [s] (default 2)")
    args = parser.parse_args(argv)
    try:
        import mujoco  # noqa: F401
    except ImportError:
        print("this example needs MuJoCo: pip install 'regrasp[mujoco]'")
        return 0
    print("1. a sliding sphere under constant forces (1 ms steps, the last 50 ms of 100 ms)")
    print("   solref  solreffriction  mass    speed     f_n    force per step [N]  steps with none")
    cases = [(2e-3, 5e-4, 0.05, 0.0, 0.7)]
    for tc, tcf in ((5e-4, 5e-4), (2e-3, 5e-4), (2e-3, 8e-4), (2e-3, 2e-3)):
        for mass, speed, fn in ((0.005, 0.05, 0.7), (0.05, 0.005, 0.7), (0.05, 0.05, 0.7), (0.05, 0.05, 1.5)):
            cases.append((tc, tcf, mass, speed, fn))
    for tc, tcf, mass, speed, fn in cases:
        lo, hi, none = sliding_sphere(tc, tcf, mass, speed, fn)
        print(f"   {tc * 1e3:4.1f} ms  {tcf * 1e3:6.1f} ms     {mass * 1e3:4.0f} g  {speed * 1e3:4.0f} mm/s  "
              f"{fn:4.1f} N  {lo:5.2f} .. {hi:5.2f}        {none:2d} of 50")
    if args.rollouts:
        print(f"\n2. the default scenario's nominal rollout on MuJoCo, solref 2 ms, {args.duration:g} s")
        print("   solreffriction  largest held slip  verdict")
        for tcf in (5e-4, 8e-4, 1e-3, 2e-3):
            slip, verdict = held_drift(tcf, args.duration)
            print(f"   {tcf * 1e3:6.1f} ms      {slip:7.3f} mm         {verdict}")
        from regrasp import load_scenario
        from regrasp.core.exceptions import RegraspError
        from regrasp.schedule.planner import RegraspSettings, plan_regrasps

        scenario = load_scenario("examples/scenarios/paper_trajectory_2_three_fingers.toml")
        try:
            schedule = plan_regrasps(scenario, RegraspSettings(slider_floor=0.6))
            print(f"\n3. sliders pushing with >= 0.6 N: a schedule of {len(schedule.slides)} slides")
        except RegraspError as exc:
            print(f"\n3. sliders pushing with >= 0.6 N: {exc}")
        sys.stdout.flush()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

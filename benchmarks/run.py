"""All benchmarks in one table: medians and the floor each stands on, measured in the same run.

Run: python benchmarks/run.py [--quick] [--json]

Items and their floors:
* control steps (fixed law and Proposition 1, with and without the internal-force QP; compiled, the default):
  floor = the bare compiled kernel call (``regrasp.kernels.control.control_step_into`` with the controller's
  arguments: the reduced terms, the law, the QP's dense solver, no Python around it); and the fixed law with
  the QP on the reference path (``compiled=False`` and the QP on OSQP): floor = the Pinocchio calls one step
  needs (per finger: crba, nonLinearEffects, the tip's frame Jacobian, and forward kinematics + the classical
  acceleration for J̇q̇) plus the bare solve of its persistent, warm-started ``osqp.OSQP`` object;
* one plant step, compiled (the default, :mod:`regrasp.kernels.plant`): floor = the bare kernel call
  (``plant_step_into``: RK4, the end evaluation and the event inputs, no Python around it); and on the
  reference path (``Plant(compiled=False)``): floor = four times those Pinocchio calls (RK4 evaluates the
  dynamics 4 times);
* the planner per time sample (``ideal``: no floor (null); ``urdf``, compiled, the default where the finger's
  shapes have planar footprints (:mod:`regrasp.kernels.envelope`): floor = the bare kernel call
  ``envelope_sample_into``; ``urdf`` on the reference path (``FingerEnvelope(compiled=False)``, coal): no floor);
* one supervisor step (``RegraspSupervisor.step`` minus its control law: the runtime envelopes of
  all fingers at the measured pose, the look-ahead in the plan, the danger test), three fingers of
  ``paper_trajectory_2_three_fingers.toml`` holding still, with the scenario's ``urdf`` envelopes
  and with ``ideal`` ones; floor: one envelope sample per finger (``FingerEnvelope.at``); and with the
  ``urdf`` envelopes followed from step to step (``track_envelopes``, ``EnvelopeTracker``), whose floor
  is the coal distance calls the tracked steps make (bare ``coal.ComputeDistance`` calls; none, so no floor,
  where the envelopes run compiled);
* the regrasp schedule of the three-finger scenario (``plan_regrasps``, default settings): the
  median wall time of whole plans (after one warm-up plan that loads numba's compiled kernels;
  three timed plans, one with ``--quick``), target ≤ 10 s;
* the regrasp schedules of the four- and five-finger scenarios (the decomposition planner): one plan each in a fresh
  process by ``benchmarks/bench_many_fingers.py`` (its wall time and the process's peak memory; four fingers only with
  ``--quick``; that script alone takes medians of three and compares both planners on three fingers), targets four
  fingers ≤ 60 s and ≤ 4 GiB, five ≤ 3 min;
* the rollout of paper trajectory 2 with the palm finger (``paper_trajectory_2_three_fingers.toml``,
  two periods at 1 kHz, or until it fails): real-time factor = simulated time / wall time, with compiled
  stretches (the default) and on the reference path (every step through the supervisor), with
  recording off and on (a ``RolloutRecorder`` writing an .rrd to a temporary directory, logging every step,
  and every 10th step: ``regrasp simulate --rrd``'s default ``--decimate 10``); and 2 s of it with
  each policy (scheduled, paper, none), recording off;
* one step inside a compiled stretch (:mod:`regrasp.rollout.stretch`: the supervisor's continuous work, the control law
  and the plant step in :func:`regrasp.kernels.stretch.stretch_into`), per step of 8-step calls on states
  captured from the rollout below; floor = the bare control and plant kernels at the same state;
* a study's throughput (``run_study``, 240 runs of 2 s, one schedule planned beforehand): simulated seconds per
  wall second per worker with 1 and 2 worker processes, and the speed-up of 2 over 1.
Medians of repeated calls (time.perf_counter); the Pinocchio floors time batches of 1000 calls.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin
from common import ROOT, median_us, parse_args, sliding_hold

import regrasp.envelope.evaluator as envelope_module
from regrasp import (
    FingerEnvelope,
    Grasp,
    Hand,
    ReducedModel,
    RolloutRecorder,
    RunSpec,
    build_rollout,
    load_scenario,
    plan_regrasps,
    run_study,
)
from regrasp.dynamics.control import Gains
from regrasp.dynamics.internal_force.solver import InternalForceSolver
from regrasp.dynamics.laws import FixedContactController, Proposition1Controller
from regrasp.kernels import FINGER_TERMS, control_step_into, envelope_sample_into, output_size, plant_step_into
from regrasp.plants.simulation import sense
from regrasp.supervisor.settings import MonitorSettings, PaperSettings, SupervisorSettings

THREE = ROOT / "examples" / "scenarios" / "paper_trajectory_2_three_fingers.toml"


def control_kernel_us(controller, args, n: int) -> float:
    """The bare compiled control step (``control_step_into``) with ``controller``'s arguments [µs]."""
    head, tail, _, size = controller.compiled_arguments
    rows, out = np.array(args, dtype=float), np.empty(size)
    return median_us(lambda: control_step_into(*head, rows[0], rows[1], rows[2], rows[3], rows[4], *tail, out), n)


def plant_kernel_us(plant, n: int) -> float:
    """Median of the bare compiled plant step (:func:`regrasp.kernels.plant.plant_step_into`) at the plant's state."""
    m = plant.hand.m
    args = (*plant.kernel.arguments(plant.state, plant.contacts, np.zeros(plant.hand.nq)), np.empty(output_size(m)),
            np.empty(m, dtype=FINGER_TERMS), np.empty(m, np.bool_), np.empty((m, 7)))
    return median_us(lambda: plant_step_into(*args), n)


def supervisor_step_us(geometry: str, n: int, track: bool = False) -> tuple[float, float]:
    """Median of the supervisor's own time per step and its floor. Three fingers at t = 0 on the
    middles of their feasible sets; ``regrasp=False``, so each step evaluates the envelopes, the
    look-ahead and the danger test but starts no slide. Floor: one envelope sample per finger at the
    same pose (``FingerEnvelope.at``); with ``track`` (``EnvelopeTracker``), the collision queries
    the tracked steps made, each at the cost of one bare call: ``tip_is_free`` where the envelopes run
    compiled, else ``coal.ComputeDistance``."""
    sc = load_scenario(THREE)
    settings = SupervisorSettings(monitor=MonitorSettings(geometry=geometry, track=track),
                                  paper=PaperSettings(regrasp=False))
    rollout = build_rollout(sc, RunSpec(duration=0.01, xi0=[-0.0125, 0.0125, 0.0]), settings=settings, policy="paper")
    sup, plant = rollout.supervisor, rollout.plant
    meas = sense(plant, None)
    times = []
    for _ in range(n + 1):
        times.append(sup.step(meas, plant.dt).supervisor_seconds)
    if not track:
        floor = sum(median_us(lambda env=env: env.at(meas.X, meas.t), n) for env in sup.monitor.envelopes)
        return float(np.median(times[1:]) * 1e6), floor
    if all(env.compiled for env in sup.monitor.envelopes):
        return float(np.median(times[1:]) * 1e6), compiled_queries_us(sup, meas, plant.dt, n)
    before = sum(env.checker.queries for env in sup.monitor.envelopes)  # the coal queries of a few more steps
    for _ in range(n):
        sup.step(meas, plant.dt)
    calls = sum(env.checker.queries for env in sup.monitor.envelopes) - before
    # one bare coal distance query: the distal link's first shape against the object, 1 cm apart
    checker = sup.monitor.envelopes[0].checker
    shape = next(s for s in checker.shapes if s.link == 1)
    distance = coal.ComputeDistance(shape.geometry, checker.object_geometry)
    placement, apart = coal.Transform3s(), coal.Transform3s(np.eye(3), np.array([0.0, 0.01 + 0.1, 0.0]))
    request, result = coal.DistanceRequest(), coal.DistanceResult()
    bare = batch_us(lambda: distance(placement, apart, request, result), 100)
    return float(np.median(times[1:]) * 1e6), calls / n * bare


def compiled_queries_us(sup, meas, dt: float, n: int) -> float:
    """The compiled collision queries (``tip_is_free`` calls) of ``n`` more tracked supervisor steps, per step, each at
    the cost of one bare call [µs]."""
    calls, inner = [0], envelope_module.tip_is_free

    def counted(*args):
        calls[0] += 1
        return inner(*args)

    envelope_module.tip_is_free = counted
    try:
        for _ in range(n):
            sup.step(meas, dt)
    finally:
        envelope_module.tip_is_free = inner
    env = sup.monitor.envelopes[0]
    par, shapes, vertices, normals = env.kernel_arguments(meas.X)[:4]
    x, y, beta = meas.X.tolist()
    lo, hi = env.at(meas.X).feasible[0]
    s = 0.5 * (lo + hi) + env.line(meas.X).s0  # (the middle of the feasible set, in line coordinates)
    nearest = np.empty(2)
    bare = batch_us(lambda: inner(par, shapes, vertices, normals, x, y, beta, s, nearest), 100)
    return calls[0] / n * bare


def stretch_step_us(n: int) -> dict:
    """One step inside a compiled stretch: the arguments of the three-finger rollout's stretches (each 8-step
    call's, captured as the rollout calls the kernel, once with the fixed law and once with two sliders), re-run
    from copies; per step. Floor: the bare control and plant kernels on the same states."""
    import regrasp.rollout.stretch as stretch_module

    captured = {}
    kernel = stretch_module.stretch_into

    def copied(value):
        """``value`` with every array in it copied (the kernel's bundles are (named) tuples of arrays)."""
        if isinstance(value, np.ndarray):
            return value.copy()
        if isinstance(value, tuple):
            items = [copied(v) for v in value]
            return type(value)(*items) if hasattr(value, "_fields") else tuple(items)
        return value

    def capture(*args):  # (settings, state, times, desired, the participants' bundles, ...)
        fixed = bool(args[0]["fixed_law"])
        if fixed not in captured and args[2].size >= 8:
            captured[fixed] = [copied(a) for a in args]
        return kernel(*args)

    stretch_module.stretch_into = capture
    try:
        build_rollout(load_scenario(THREE), RunSpec(duration=1.2)).run()
    finally:
        stretch_module.stretch_into = kernel
    per_step = []
    for args in captured.values():
        def call(args=args):
            fresh = [copied(a) for a in args]
            fresh[2], fresh[3] = args[2][:8], args[3][:8]  # (the first 8 steps' times and desired states)
            start = time.perf_counter()
            kernel(*fresh)
            return (time.perf_counter() - start) / 8
        per_step.append(float(np.median([call() for _ in range(max(20, n // 10))])) * 1e6)
    return {"median_us": float(np.mean(per_step)), "floor_us": None, "fixed_law_us": per_step[0],
            "sliding_us": per_step[-1]}


def rollout_realtime(quick: bool) -> dict:
    """Real-time factors of the three-finger rollout of paper trajectory 2 (the scheduled policy, one
    schedule planned for both), recording off and on."""
    sc = load_scenario(THREE)
    duration = 0.2 if quick else None
    first = build_rollout(sc, RunSpec(duration=duration))
    off = first.run()
    stretched = first.stretches.steps / off.steps
    reference = build_rollout(sc, RunSpec(duration=duration), schedule=first.schedule).run(compiled_stretches=False)
    on = {}
    with tempfile.TemporaryDirectory() as tmp:
        for decimation in (1, 10):  # every step, and ``regrasp simulate --rrd``'s default (every 10th)
            rollout = build_rollout(sc, RunSpec(duration=duration), schedule=first.schedule)
            with RolloutRecorder(rollout.plant, rrd_path=Path(tmp) / f"bench{decimation}.rrd",
                                 decimation=decimation) as recorder:
                on[decimation] = rollout.run(recorder=recorder)
    simulated = off.steps * rollout.plant.dt
    return {"recording_off": off.realtime_factor, "recording_on": on[1].realtime_factor,
            "recording_on_every_10th": on[10].realtime_factor, "reference_path": reference.realtime_factor,
            "steps_in_stretches": stretched,
            "simulated_s": simulated, "requested_s": off.duration,
            "outcome": "success" if off.success else f"failed at {off.failure.time:.3f} s: {off.failure.reason}",
            "slides": sum(off.regrasps.values())}


def rollout_policies(quick: bool) -> dict:
    """Real-time factor of the three-finger rollout (recording off) with each policy: the scheduled one (the
    default), the paper's heuristic and none (a fixed grasp; it fails where the envelopes close)."""
    sc = load_scenario(THREE)
    duration = 0.2 if quick else 2.0
    out = {}
    for policy in ("scheduled", "paper", "none"):
        rollout = build_rollout(sc, RunSpec(duration=duration), policy=policy)
        result = rollout.run()
        out[policy] = {"realtime_factor": result.realtime_factor, "simulated_s": result.steps * rollout.plant.dt,
                       "outcome": "success" if result.success else f"failed at {result.failure.time:.3f} s"}
    return out


def study_throughput(quick: bool) -> dict:
    """A study's throughput, simulated seconds per wall second per worker, with 1 and 2 worker processes
    (the same 24 runs of 2 s, default perturbations, one schedule planned beforehand): over the study's wall
    time (the pool's start-up included, the plan not), and in steady state (over the runs' own loops: what a
    study of thousands of runs approaches)."""
    sc = load_scenario(THREE)
    schedule = plan_regrasps(sc)
    runs, duration = (2, 0.2) if quick else (240, 2.0)
    out = {}
    for workers in (1, 2):
        result = run_study(sc, runs, seed=0, duration=duration, workers=workers, schedule=schedule)
        simulated = sum(r.failure_time if r.failure_time is not None else duration for r in result.runs)
        seconds = result.wall_seconds - result.plan_seconds
        running = sum(r.wall_seconds for r in result.runs)  # the runs' own loops, start-up excluded
        out[f"workers_{workers}"] = {"simulated_s_per_s_per_worker": simulated / seconds / workers,
                                     "steady_simulated_s_per_s_per_worker": simulated / running,
                                     "wall_s": seconds, "simulated_s": simulated}
    one, two = out["workers_1"], out["workers_2"]
    out["speed_up"] = 2 * two["simulated_s_per_s_per_worker"] / one["simulated_s_per_s_per_worker"]
    out["steady_speed_up"] = 2 * two["steady_simulated_s_per_s_per_worker"] / one["steady_simulated_s_per_s_per_worker"]
    return out


def regrasp_plan_seconds(quick: bool) -> dict:
    """Wall time of whole plans of the three-finger scenario's regrasp schedule (after a warm-up)."""
    sc = load_scenario(THREE)
    plan_regrasps(sc)  # warm-up: numba loads (or, on a fresh checkout, compiles) the lattice kernels
    seconds, schedule = [], None
    for _ in range(1 if quick else 3):
        t0 = time.perf_counter()
        schedule = plan_regrasps(sc)
        seconds.append(time.perf_counter() - t0)
    return {"median_s": float(np.median(seconds)), "runs_s": seconds, "slides": len(schedule.slides),
            "slides_lower_bound": schedule.slides_lower_bound, "periodic": schedule.periodic,
            "min_envelope_margin_m": schedule.min_envelope_margin, "min_cone_margin_n": schedule.min_cone_margin}


def many_fingers(quick: bool) -> dict:
    """``benchmarks/bench_many_fingers.py``: four and five fingers planned once each in a fresh process (four only
    with ``quick``)."""
    done = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "bench_many_fingers.py"), "--cases",
                           "quick" if quick else "many", "--repeats", "1", "--json"], capture_output=True, text=True,
                          check=True)
    return json.loads(done.stdout)


def batch_us(fn, batch: int = 1000, repeats: int = 7) -> float:
    """Median over ``repeats`` of the mean time of ``batch`` calls (for sub-microsecond calls)."""
    fn()
    samples = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(batch):
            fn()
        samples.append((time.perf_counter() - t0) / batch)
    return float(np.median(samples) * 1e6)


def pinocchio_floor_us(hand: Hand, quick: bool) -> float:
    """The Pinocchio calls one evaluation of the hand's dynamics needs, summed over the fingers."""
    total = 0.0
    zero = np.zeros(2)
    for f in hand.fingers:
        model, data, fid = f.model, f.model.createData(), f.tip_frame_id
        q, v = np.array([0.3, -1.2]), np.array([0.5, -0.4])
        batch = 100 if quick else 1000

        def jdot(model=model, data=data, q=q, v=v, fid=fid):
            pin.forwardKinematics(model, data, q, v, zero)
            pin.getFrameClassicalAcceleration(model, data, fid, pin.LOCAL_WORLD_ALIGNED)

        total += batch_us(lambda model=model, data=data, q=q: pin.crba(model, data, q), batch)
        total += batch_us(lambda model=model, data=data, q=q, v=v: pin.nonLinearEffects(model, data, q, v), batch)
        total += batch_us(lambda model=model, data=data, q=q, fid=fid: pin.computeFrameJacobian(
            model, data, q, fid, pin.LOCAL_WORLD_ALIGNED), batch)
        total += batch_us(jdot, batch)
    return total


def main() -> None:
    args, n = parse_args(__doc__, 300)

    setup = sliding_hold()
    sc, hand = setup.scenario, setup.hand
    floor_dyn = pinocchio_floor_us(hand, args.quick)

    X, zero3 = np.array([0.0, 0.12, 0.0]), np.zeros(3)
    fixed = ReducedModel(hand, Grasp(sc.polygon, [1, 3], ["fixed", "fixed"]), xi=[0.0, 0.0])
    fixed_qp = FixedContactController(fixed, Gains.critically_damped(20.0, 3), friction=0.5)
    fixed_no = FixedContactController(fixed, Gains.critically_damped(20.0, 3), friction=0.5, internal_force=None)
    out = fixed_qp(X, zero3, X, zero3, zero3)
    assert out.internal is not None and fixed_qp.compiled  # (the compiled step answers)
    # the reference path: the controller's Python and the QP on OSQP; its floor: the bare OSQP solve
    fixed_ref = FixedContactController(fixed, Gains.critically_damped(20.0, 3), friction=0.5, compiled=False)
    fixed_ref.internal_force_solver = InternalForceSolver(fixed_ref.internal_force, compiled=False)
    fixed_ref(X, zero3, X, zero3, zero3)
    (raw_osqp,) = fixed_ref.internal_force_solver.osqp_solvers
    osqp_floor = median_us(lambda: raw_osqp.solve(raise_error=False), n)

    third = hand.fingers[0].with_placement(base_in_hand=(0.04, -0.02, np.pi / 2), configuration="left",
                                           name="finger3")
    hand3 = Hand([*hand.fingers, third], gravity_in_hand=sc.gravity_in_hand)
    three = ReducedModel(hand3, Grasp(sc.polygon, [1, 3, 2], ["sliding", "fixed", "fixed"]), xi=[-0.01, -0.01, 0.02])
    S3, S3d = np.array([0.0, 0.12, 0.0, -0.01]), np.array([0.0, 0.0, 0.0, 0.01])
    slide_qp = Proposition1Controller(three, Gains.critically_damped(20.0, 4), friction=[0.0, 0.5, 0.5])
    slide_no = Proposition1Controller(three, Gains.critically_damped(20.0, 4), friction=[0.0, 0.5, 0.5],
                                      internal_force=None)

    env_ideal = FingerEnvelope(sc.contacts[0].finger, sc.polygon, 1)
    env_urdf = FingerEnvelope(sc.contacts[0].finger, sc.polygon, 1, geometry="urdf")
    env_urdf_ref = FingerEnvelope(sc.contacts[0].finger, sc.polygon, 1, geometry="urdf", compiled=False)
    pose = sc.trajectory.pose(0.3)
    kernel_args = env_urdf.kernel_arguments(pose)

    results = {
        "control_fixed_qp": {"median_us": median_us(lambda: fixed_qp(X, zero3, X, zero3, zero3), n),
                             "floor_us": control_kernel_us(fixed_qp, (X, zero3, X, zero3, zero3), n)},
        "control_fixed_no_qp": {"median_us": median_us(lambda: fixed_no(X, zero3, X, zero3, zero3), n),
                                "floor_us": control_kernel_us(fixed_no, (X, zero3, X, zero3, zero3), n)},
        "control_fixed_qp_reference": {"median_us": median_us(lambda: fixed_ref(X, zero3, X, zero3, zero3), n),
                                       "floor_us": floor_dyn + osqp_floor},
        "control_sliding_m3_qp": {"median_us": median_us(lambda: slide_qp(S3, S3d, S3, S3d, np.zeros(4)), n),
                                  "floor_us": control_kernel_us(slide_qp, (S3, S3d, S3, S3d, np.zeros(4)), n)},
        "control_sliding_m3_no_qp": {"median_us": median_us(lambda: slide_no(S3, S3d, S3, S3d, np.zeros(4)), n),
                                     "floor_us": control_kernel_us(slide_no, (S3, S3d, S3, S3d, np.zeros(4)), n)},
        "plant_step": {"median_us": median_us(setup.plant_step, n), "floor_us": plant_kernel_us(setup.plant, n)},
        "plant_step_reference": {"median_us": median_us(lambda: setup.plant_step(setup.plant_reference), n),
                                 "floor_us": 4 * floor_dyn},
        "planner_sample_ideal": {"median_us": median_us(lambda: env_ideal.at(pose), n), "floor_us": None},
        "planner_sample_urdf": {"median_us": median_us(lambda: env_urdf.at(pose), n),
                                "floor_us": median_us(lambda: envelope_sample_into(*kernel_args), n)},
        "planner_urdf_reference": {"median_us": median_us(lambda: env_urdf_ref.at(pose), max(5, n // 10)),
                                          "floor_us": None},
    }
    for geometry in ("urdf", "ideal"):
        med, floor = supervisor_step_us(geometry, n)
        results[f"supervisor_step_{geometry}"] = {"median_us": med, "floor_us": floor}
    med, floor = supervisor_step_us("urdf", n, track=True)
    results["supervisor_step_urdf_tracked"] = {"median_us": med, "floor_us": floor}
    results["stretch_step"] = stretch_step_us(n)
    results["rollout_realtime_factor"] = rollout_realtime(args.quick)
    results["rollout_policies"] = rollout_policies(args.quick)
    results["study_throughput"] = study_throughput(args.quick)
    results["regrasp_plan"] = regrasp_plan_seconds(args.quick)
    results["many_fingers"] = many_fingers(args.quick)
    if args.json:
        print(json.dumps(results))
        return
    print(f"{'item':28s} {'median [us]':>12s} {'floor [us]':>11s} {'ratio':>7s}")
    for key, value in results.items():
        if key in ("rollout_realtime_factor", "regrasp_plan", "rollout_policies", "study_throughput", "many_fingers"):
            continue
        med, floor = value["median_us"], value["floor_us"]
        ratio = f"{med / floor:6.1f}x" if floor else "     -"
        floor_s = f"{floor:11.1f}" if floor else f"{'-':>11s}"
        print(f"{key:28s} {med:12.1f} {floor_s} {ratio:>7s}")
    rt = results["rollout_realtime_factor"]
    print(f"rollout real-time factor      {rt['recording_off']:6.2f}x recording off, {rt['recording_on']:6.2f}x on "
          f"(every step), {rt['recording_on_every_10th']:6.2f}x on (every 10th) ({rt['simulated_s']:.3f} of "
          f"{rt['requested_s']:.3f} s simulated; {rt['outcome']}; {rt['steps_in_stretches']:.1%} of the steps in "
          f"compiled stretches); reference path {rt['reference_path']:.2f}x")
    for policy, value in results["rollout_policies"].items():
        print(f"rollout, {policy:9s} policy      {value['realtime_factor']:6.2f}x real time "
              f"({value['simulated_s']:.3f} s simulated; {value['outcome']})")
    st = results["study_throughput"]
    one, two = st["workers_1"], st["workers_2"]
    print(f"study throughput              {one['simulated_s_per_s_per_worker']:6.2f} simulated s per s per worker "
          f"with 1 worker, {two['simulated_s_per_s_per_worker']:6.2f} with 2 ({st['speed_up']:.2f}x the "
          f"throughput); steady state {one['steady_simulated_s_per_s_per_worker']:.2f} and "
          f"{two['steady_simulated_s_per_s_per_worker']:.2f} ({st['steady_speed_up']:.2f}x)")
    rp = results["regrasp_plan"]
    print(f"regrasp schedule, three fingers  {rp['median_s']:6.2f} s median of {len(rp['runs_s'])} plans "
          f"({rp['slides']} slides per period, fewest possible {rp['slides_lower_bound']}; target <= 10 s)")
    for value in results["many_fingers"].values():
        target = "<= 60 s, <= 4096 MiB" if value["fingers"] == 4 else "<= 180 s"
        print(f"regrasp schedule, {value['fingers']} fingers   {value['median_s']:6.2f} s, peak "
              f"{value['median_peak_mib']:.0f} MiB ({value['slides']} slides per period; {value['planner']} planner, "
              f"a fresh process; target {target})")
    print(f"(Pinocchio floor of one 2-finger dynamics evaluation: {floor_dyn:.1f} us; "
          f"persistent OSQP solve of the 2-finger QP: {osqp_floor:.1f} us; supervisor floors: one "
          f"envelope sample per finger; tracked: its coal calls)")


if __name__ == "__main__":
    main()

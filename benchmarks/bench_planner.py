r"""Benchmark: wall time of one finger's envelope at one object pose (one "time sample").

What is measured
----------------
The scenario is ``examples/scenarios/paper_trajectory_2.toml`` (both fingers, each on its own
edge). For a fixed set of sample times, uniformly spaced over one period of the trajectory
(``t_k = t_start + k T / n``, k = 0..n-1, so the periodic end point is not counted twice), we time
with :func:`time.perf_counter` one call that produces one finger's feasible set at one pose:

1. ``ideal`` -- ``FingerEnvelope(finger, polygon, edge, geometry="ideal").at(pose, t)``
   (closed form, links are segments);
2. ``urdf`` -- the same with ``geometry="urdf"`` (URDF collision shapes against the object
   with coal; grid + bisection, interval ends accurate to <= 1e-4 of the edge length);
3. ``brute_force`` -- a dense sampler of the same accuracy written here: ξ on a uniform grid
   over the edge's ξ range with spacing 1e-4 x edge length (10001 points); for each point the
   tip's hand-frame position, a skip if it lies outside the reachable annulus, the finger's IK
   (``finger.inverse_kinematics``), the reachability test (the elbow,
   ``finger.joint_positions_in_hand(q)[1]``, must not be in the open interior half-plane of
   the edge) and the link--object collision test with the same
   ``UrdfCollisionChecker(finger, polygon, tip_clearance)`` the ``urdf`` mode uses
   (``checker.collides(q, pose)``); the feasible intervals are the runs of feasible grid
   points.

The envelopes are built once per finger (outside the timing), as the planner does. Each
(finger, time) call is warmed up once, then timed ``repeats`` times; we report the MEDIAN (and
25th/75th percentiles) over all timed calls together with the number of calls -- never means.
Brute force is slow, so it gets fewer timed calls: by default the same 24 times with 3 repeats
(instead of 20), with ``--quick`` only 4 of the times (every 6th) with 1 repeat. It is not
warmed up separately (the ``urdf`` pass already warmed up the checker and the IK).

Correctness check: on every brute-force sample the brute-force intervals must agree with the
``urdf`` intervals (same number of intervals, every end within 2 grid steps); otherwise the
discrepancy is printed and the script exits with status 1 (timing different answers would be
meaningless).

A separate, untimed profiling pass counts the ``urdf`` mode's posture queries per sample (one
``checker.links_collide`` per grid or bisection point) and the links among them that coal had to
evaluate (one ``coal.distance`` per shape of the link; the others were certified free by the
checker's distance certificate), and how much of the sample's time those coal evaluations take.

Run (from any directory)::

    python benchmarks/bench_planner.py            # default: < 3 min on a 2-core machine
    python benchmarks/bench_planner.py --quick    # CI smoke run, < 20 s
    python benchmarks/bench_planner.py --json     # one JSON document on stdout

Exit status: 0 on success, 1 if brute force and ``urdf`` disagree.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

from regrasp.core.planar import rotation
from regrasp.envelope.finger_envelope import FingerEnvelope
from regrasp.model.collision import UrdfCollisionChecker
from regrasp.model.scenario import load_scenario

REPO_ROOT = Path(__file__).resolve().parent.parent
SCENARIO = REPO_ROOT / "examples" / "scenarios" / "paper_trajectory_2.toml"

#: Brute-force grid spacing as a fraction of the edge length (1e-4 -> 10001 points).
GRID_FRACTION = 1e-4
#: Allowed disagreement between brute-force and urdf interval ends, in grid steps.
AGREE_STEPS = 2.0


# ---------------------------------------------------------------------- brute force
class BruteForceEnvelope:
    """Dense-grid feasible set of one finger on one edge (see the module docstring)."""

    def __init__(self, finger, polygon, edge_index: int, tip_clearance: float):
        self.finger = finger
        self.edge = polygon.edge(edge_index)
        self.checker = UrdfCollisionChecker(finger, polygon, tip_clearance)
        lo, hi = self.edge.xi_range
        self.n_points = int(round(1.0 / GRID_FRACTION)) + 1
        self.xi = np.linspace(lo, hi, self.n_points)
        self.step = (hi - lo) / (self.n_points - 1)
        self.inner, self.outer = finger.reach
        self.o1 = finger.joint1_in_hand
        self.collision_checks = 0  # collides() calls in the last at()

    def at(self, pose: np.ndarray) -> tuple[tuple[float, float], ...]:
        """Feasible ξ-intervals [m] at object pose ``(x, y, beta)`` in the hand frame."""
        finger, checker, xi = self.finger, self.checker, self.xi
        rot = rotation(pose[2])
        # Tip positions in the hand frame for every grid point (vectorised; cheap).
        tips = pose[:2] + (self.edge.xi_origin + xi[:, None] * self.edge.xi_direction) @ rot.T
        normal = rot @ self.edge.inward_normal          # inward normal in the hand frame
        on_line = tips[0]                               # a point of the edge's line
        dist = np.hypot(tips[:, 0] - self.o1[0], tips[:, 1] - self.o1[1])
        slack = 1e-12 * self.outer
        in_annulus = (dist >= self.inner - slack) & (dist <= self.outer + slack)
        feasible = np.zeros(self.n_points, dtype=bool)
        checks = 0
        for k in np.flatnonzero(in_annulus):
            q = finger.inverse_kinematics(tips[k])
            elbow = finger.joint_positions_in_hand(q)[1]
            if float(normal @ (elbow - on_line)) > 0.0:   # elbow inside the object's side
                continue
            checks += 1
            feasible[k] = not checker.collides(q, pose)
        self.collision_checks = checks
        return runs_to_intervals(xi, feasible)


def runs_to_intervals(xi: np.ndarray, mask: np.ndarray) -> tuple[tuple[float, float], ...]:
    """Closed intervals [xi[first], xi[last]] of the runs of True in ``mask``.

    Single isolated points (zero length) are dropped, as the envelope drops them.
    """
    padded = np.concatenate(([False], mask, [False])).astype(np.int8)
    edges = np.diff(padded)
    starts = np.flatnonzero(edges == 1)
    ends = np.flatnonzero(edges == -1) - 1
    return tuple((float(xi[a]), float(xi[b])) for a, b in zip(starts, ends) if b > a)


def compare(brute, urdf, step: float) -> tuple[bool, float]:
    """(agree, largest end difference in grid steps); intervals must pair up one to one."""
    if len(brute) != len(urdf):
        return False, math.inf
    worst = 0.0
    for (bl, bh), (ul, uh) in zip(brute, urdf):
        worst = max(worst, abs(bl - ul) / step, abs(bh - uh) / step)
    return worst <= AGREE_STEPS, worst


# ---------------------------------------------------------------------- helpers
def stats_us(durations: list[float]) -> dict:
    arr = np.asarray(durations) * 1e6
    return {
        "median_us": float(np.median(arr)),
        "p25_us": float(np.percentile(arr, 25)),
        "p75_us": float(np.percentile(arr, 75)),
        "n": int(arr.size),
    }


def time_calls(fn, items, repeats: int) -> list[float]:
    """Warm up each item once, then time ``fn(item)`` ``repeats`` times per item."""
    for item in items:
        fn(item)
    out = []
    for _ in range(repeats):
        for item in items:
            t0 = time.perf_counter()
            fn(item)
            out.append(time.perf_counter() - t0)
    return out


def fmt_iv(ivs) -> str:
    return "[" + ", ".join(f"({lo * 1e3:+.4f}, {hi * 1e3:+.4f})" for lo, hi in ivs) + "] mm"


def log(msg: str, quiet: bool) -> None:
    if not quiet:
        print(msg, flush=True)


def microbench(fn, n: int = 2000) -> float:
    """Median wall time [s] of ``fn()`` over ``n`` calls."""
    out = []
    for _ in range(n):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return float(np.median(out))


def profile_urdf(envs, samples) -> dict:
    """Untimed pass: posture queries and coal link evaluations inside the urdf mode's at().

    The urdf mode asks ``checker.links_collide`` once per grid or bisection point (a "posture
    query"); that calls coal only for the links its certificate cannot clear
    (``checker._link_distance``: one coal.distance per shape of the link).
    """
    per_sample = []
    for env, _ in envs:
        checker = env.checker
        counters = {"queries": 0, "links": 0, "t_links": 0.0}
        orig_query, orig_link = checker.links_collide, checker._link_distance

        def query(*args, _f=orig_query, _c=counters):
            _c["queries"] += 1
            return _f(*args)

        def link(*args, _f=orig_link, _c=counters):
            t0 = time.perf_counter()
            try:
                return _f(*args)
            finally:
                _c["links"] += 1
                _c["t_links"] += time.perf_counter() - t0

        checker.links_collide, checker._link_distance = query, link  # instance attributes only
        try:
            for t, pose in samples:
                counters.update(queries=0, links=0, t_links=0.0)
                t0 = time.perf_counter()
                env.at(pose, t)
                total = time.perf_counter() - t0
                per_sample.append((counters["queries"], counters["links"], counters["t_links"] / total))
        finally:
            del checker.links_collide, checker._link_distance
    arr = np.array(per_sample, dtype=float)
    # One coal.distance call and one collides() call in isolation, for scale.
    env, finger = envs[0]
    checker = env.checker
    t, pose = samples[len(samples) // 2]
    sample = env.at(pose, t)
    lo, hi = sample.feasible[0] if sample.feasible else sample.edge_range
    q = finger.inverse_kinematics(env.tip_at(pose, 0.5 * (lo + hi)))
    import coal  # noqa: PLC0415
    import pinocchio as pin  # noqa: PLC0415

    from regrasp.core.planar import se3_from_planar  # noqa: PLC0415

    pin.forwardKinematics(finger.model, finger.data, q)
    shape = checker.shapes[0]
    placement = finger.data.oMi[shape.link + 1] * shape.placement_in_joint
    obj = se3_from_planar(pose)
    req = coal.DistanceRequest()
    req.enable_signed_distance = True
    res = coal.DistanceResult()

    def one_distance():
        res.clear()
        coal.distance(shape.geometry, placement, checker.object_geometry, obj, req, res)

    return {
        "posture_queries_per_sample_median": float(np.median(arr[:, 0])),
        "posture_queries_per_sample_range": [int(arr[:, 0].min()), int(arr[:, 0].max())],
        "coal_link_evaluations_per_sample_median": float(np.median(arr[:, 1])),
        "coal_link_evaluations_per_sample_range": [int(arr[:, 1].min()), int(arr[:, 1].max())],
        "share_in_coal_link_evaluations_median": float(np.median(arr[:, 2])),
        "collides_call_us": microbench(lambda: checker.collides(q, pose)) * 1e6,
        "coal_distance_call_us": microbench(one_distance) * 1e6,
        "samples": int(arr.shape[0]),
    }


# ---------------------------------------------------------------------- main
def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="CI smoke run (< 20 s)")
    parser.add_argument("--json", action="store_true", help="print one JSON document on stdout")
    args = parser.parse_args(argv)
    quiet = args.json

    n_times = 24
    repeats = 3 if args.quick else 20
    brute_every = 6 if args.quick else 1    # brute force on every k-th time: 4 (quick) or all 24 times
    brute_repeats = 1 if args.quick else 3

    t_wall = time.perf_counter()
    scenario = load_scenario(SCENARIO)
    traj = scenario.trajectory
    times = traj.t_start + traj.duration * np.arange(n_times) / n_times
    poses = traj.pose(times)
    samples = list(zip(times.tolist(), poses))
    brute_idx = list(range(0, n_times, brute_every))

    ideal_envs, urdf_envs, brute_envs = [], [], []
    for c in scenario.contacts:
        ideal_envs.append((FingerEnvelope(c.finger, scenario.polygon, c.edge, geometry="ideal"), c.finger))
        u = FingerEnvelope(c.finger, scenario.polygon, c.edge, geometry="urdf", tip_clearance=c.tip_clearance)
        urdf_envs.append((u, c.finger))
        brute_envs.append(BruteForceEnvelope(c.finger, scenario.polygon, c.edge, u.tip_clearance))

    log(f"scenario: {scenario.name} ({SCENARIO.relative_to(REPO_ROOT)}), fingers: "
        f"{', '.join(c.finger.name for c in scenario.contacts)}", quiet)
    log(f"sample times: {n_times} uniformly over [{traj.t_start:.4g}, {traj.t_end:.4g}) s; "
        f"ideal/urdf: {repeats} repeats each; brute force: {len(brute_idx)} times x "
        f"{brute_repeats} repeat ({'--quick' if args.quick else 'default'} mode)", quiet)

    # 1. ideal, 2. urdf: items are (envelope, t, pose)
    results = {}
    urdf_feasible = {}
    for mode, envs in (("ideal", ideal_envs), ("urdf", urdf_envs)):
        items = [(fi, env, t, pose) for fi, (env, _) in enumerate(envs) for t, pose in samples]
        durations = time_calls(lambda it: it[1].at(it[3], it[2]), items, repeats)
        results[mode] = stats_us(durations)
        if mode == "urdf":
            for fi, env, t, pose in items:
                urdf_feasible[(fi, t)] = env.at(pose, t).feasible
        log(f"  timed {mode}: median {results[mode]['median_us']:.1f} us over {results[mode]['n']} calls", quiet)

    # 3. brute force (no separate warm-up: the urdf pass warmed up the checker and the IK)
    brute_durations, checks, brute_checks_per_sample = [], [], []
    all_ok = True
    for fi, benv in enumerate(brute_envs):
        for k in brute_idx:
            t, pose = samples[k]
            this = []
            for _ in range(brute_repeats):
                t0 = time.perf_counter()
                ivs = benv.at(pose)
                this.append(time.perf_counter() - t0)
            brute_durations += this
            brute_checks_per_sample.append(benv.collision_checks)
            ref = urdf_feasible[(fi, t)]
            ok, worst = compare(ivs, ref, benv.step)
            all_ok &= ok
            checks.append({"finger": benv.finger.name, "t": t, "ok": ok, "max_diff_steps": worst,
                           "brute_force": [list(iv) for iv in ivs], "urdf": [list(iv) for iv in ref]})
            log(f"  brute force {benv.finger.name} t={t:.4f} s: {np.median(this):.3f} s "
                f"({benv.collision_checks} collides() calls), "
                f"{'agrees' if ok else 'DISAGREES'} (max end diff {worst:.2f} grid steps)", quiet)
            if not ok:
                print(f"DISCREPANCY {benv.finger.name} t={t:.6f} s (grid step {benv.step * 1e3:.4f} mm, "
                      f"allowed {AGREE_STEPS:g} steps):\n  brute force {fmt_iv(ivs)}\n  urdf        {fmt_iv(ref)}",
                      file=sys.stderr, flush=True)
    results["brute_force"] = stats_us(brute_durations)
    results["brute_force"].update({
        "grid_points": brute_envs[0].n_points,
        "grid_step_fraction_of_edge": GRID_FRACTION,
        "collides_calls_per_sample_median": float(np.median(brute_checks_per_sample)),
        "times_per_finger": len(brute_idx),
        "repeats": brute_repeats,
    })

    prof = profile_urdf(urdf_envs, samples)
    results["urdf"].update({k: v for k, v in prof.items() if k != "samples"})
    results["ideal"]["repeats"] = results["urdf"]["repeats"] = repeats

    med = {k: results[k]["median_us"] for k in ("ideal", "urdf", "brute_force")}
    results["ratios"] = {
        "brute_over_urdf": med["brute_force"] / med["urdf"],
        "brute_over_ideal": med["brute_force"] / med["ideal"],
        "urdf_over_ideal": med["urdf"] / med["ideal"],
    }
    max_steps = max((c["max_diff_steps"] for c in checks), default=0.0)
    results["check"] = {"ok": bool(all_ok), "samples": len(checks), "max_diff_steps": max_steps,
                        "allowed_steps": AGREE_STEPS,
                        "failures": [c for c in checks if not c["ok"]]}
    results["config"] = {
        "scenario": scenario.name, "quick": bool(args.quick), "fingers": len(scenario.contacts),
        "times": n_times, "brute_force_times": len(brute_idx),
        "machine": f"{platform.machine()}, {os.cpu_count()} CPUs, Python {platform.python_version()}",
        "wall_s": time.perf_counter() - t_wall,
    }

    if args.json:
        print(json.dumps(results, indent=2))
    else:
        r = results
        nf = len(scenario.contacts)
        print()
        print(f"Median wall time of one finger's envelope at one object pose ({scenario.name}, {nf} fingers)")
        print(f"{'mode':<12} {'median':>12} {'p25':>12} {'p75':>12} {'calls':>7}   notes")
        notes = {
            "ideal": f"{n_times} times x {nf} fingers x {repeats} repeats",
            "urdf": f"{n_times} times x {nf} fingers x {repeats} repeats",
            "brute_force": f"{len(brute_idx)} times x {nf} fingers x {brute_repeats} repeat(s), "
                           f"{r['brute_force']['grid_points']} grid points",
        }
        for mode in ("ideal", "urdf", "brute_force"):
            s = r[mode]
            print(f"{mode:<12} {s['median_us']:>9.1f} us {s['p25_us']:>9.1f} us {s['p75_us']:>9.1f} us "
                  f"{s['n']:>7}   {notes[mode]}")
        print()
        print("Ratios of medians:  brute/urdf = {brute_over_urdf:.0f}x   brute/ideal = {brute_over_ideal:.0f}x   "
              "urdf/ideal = {urdf_over_ideal:.1f}x".format(**r["ratios"]))
        print()
        u = r["urdf"]
        print(f"urdf mode, per sample (median over {prof['samples']} samples): "
              f"{u['posture_queries_per_sample_median']:.0f} posture queries "
              f"(range {u['posture_queries_per_sample_range'][0]}-{u['posture_queries_per_sample_range'][1]}), "
              f"of which coal evaluated {u['coal_link_evaluations_per_sample_median']:.0f} links "
              f"(range {u['coal_link_evaluations_per_sample_range'][0]}-"
              f"{u['coal_link_evaluations_per_sample_range'][1]}; the others were certified free)")
        print(f"  share of at() time in coal link evaluations (transform + coal.distance): "
              f"{100 * u['share_in_coal_link_evaluations_median']:.0f} %")
        print(f"  one collides() call (public API, both links): {u['collides_call_us']:.1f} us; "
              f"one coal.distance: {u['coal_distance_call_us']:.2f} us")
        print(f"brute force: median {r['brute_force']['collides_calls_per_sample_median']:.0f} collides() "
              f"calls per sample (reachable grid points on the edge)")
        print()
        print(f"check: brute force vs urdf on {len(checks)} samples: "
              f"{'OK' if all_ok else 'FAILED'}, max end difference {max_steps:.2f} grid steps "
              f"(allowed {AGREE_STEPS:g}; grid step = {GRID_FRACTION:g} x edge length)")
        print(f"machine: {r['config']['machine']}; total wall time {r['config']['wall_s']:.1f} s")
    if not all_ok:
        print("ERROR: brute force and urdf intervals disagree beyond "
              f"{AGREE_STEPS:g} grid steps (see DISCREPANCY above); timings are not comparable.",
              file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The regrasp planner's joint torque limits (``regrasp.schedule.torque``, ``force_polytope.torque_excess``, the
lattice's necessary condition, the verification and the diagnosis).

* The torque map (w, J·n, J·t) of each contact equals the reduced model's τ = M(H S̈ + Ḣ Ṡ) + N + Jᵀ f, with
  fixed contacts and with a sliding one (its ξ̇ and ξ̈), at the three-finger scenario's states.
* ``torque_excess`` equals an independent linear program written here (hand-frame forces, Newton–Euler, the
  reduced model's joint torques).
* Too small a limit: no schedule, and the error names the torque limit, the finger, the joint and the time; the
  shipped 5 N m limits cut nothing (the default plan is the one without limits).
* The verification finds a schedule planned without limits violating a smaller one, naming the joint.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
import scipy.optimize

from regrasp import Grasp, NoScheduleError, ReducedModel, RegraspSettings, load_scenario, plan_regrasps
from regrasp.schedule.force_polytope import ForceLimits, torque_excess
from regrasp.schedule.planner import verify
from regrasp.schedule.problem import build_problem
from regrasp.schedule.schedule import ScheduleLimit
from regrasp.schedule.torque import TorqueModel

ROOT = Path(__file__).resolve().parents[2]
SCENARIO = ROOT / "examples" / "scenarios" / "paper_trajectory_2_three_fingers.toml"
XI = np.array([-0.012, 0.012, -0.001])  # the schedule's start, about
TIMES = np.array([0.1, 0.8, 2.5])


def scenario(effort=None):
    sc = load_scenario(SCENARIO)
    if effort is None:
        return sc
    contacts = tuple(dataclasses.replace(c, finger=c.finger.with_placement(effort_limit=effort)) for c in sc.contacts)
    return dataclasses.replace(sc, contacts=contacts)


def reference(sc, t: float, modes, xi_dot=0.0, xi_ddot=0.0):
    """The reduced model at time t with contacts at XI (``modes``; a sliding one at ξ̇, ξ̈): its state, w = M q̈ + N
    and the surface frames."""
    model = ReducedModel(TorqueModel(sc).hand, Grasp(sc.polygon, [c.edge for c in sc.contacts], modes), XI)
    smp = sc.trajectory.sample(t)
    p = model.grasp.p
    S = np.concatenate([smp.pose, XI[list(model.grasp.sliding)]])
    st = model.state(S, np.concatenate([smp.velocity, [xi_dot] * p]))
    q_ddot = st.H @ np.concatenate([smp.acceleration, [xi_ddot] * p]) + st.H_dot_S_dot
    return st, st.hand.mass_matrix @ q_ddot + st.hand.nonlinear, model.grasp.surface_frames(smp.pose)


@pytest.mark.parametrize("sliding", [None, 0, 2])
def test_the_torque_map_equals_the_reduced_models_torques(sliding):
    sc = scenario()
    model = TorqueModel(sc)
    rng = np.random.default_rng(4)
    modes = ["sliding" if i == sliding else "fixed" for i in range(3)]
    xi_dot, xi_ddot = (0.04, -3.0) if sliding is not None else (0.0, 0.0)
    for t in TIMES:
        st, w, frames = reference(sc, t, modes, xi_dot, xi_ddot)
        smp = sc.trajectory.sample(np.array([t]))
        for i in range(3):
            rate = (xi_dot, xi_ddot) if i == sliding else (0.0, 0.0)
            got = model.contact(i, smp.pose, smp.velocity, smp.acceleration, XI[None, i:i + 1], *rate)
            force = rng.uniform([0.2, -0.5], [3.0, 0.5])  # (λ, τ)
            J = st.hand.jacobian[2 * i:2 * i + 2, 2 * i:2 * i + 2]
            expected = w[2 * i:2 * i + 2] + J.T @ (frames[i] @ force)
            np.testing.assert_allclose(got.at(*force)[0, 0], expected, rtol=0, atol=1e-10)
            assert got.reachable.all()


def test_torque_excess_equals_an_independent_lp():
    sc = scenario(effort=[0.2, 0.1])
    problem_limits = ForceLimits(0.2, 20.0, 0.2)
    model = TorqueModel(sc)
    geometry = build_geometry(sc)
    mu = [f.static for f in sc.friction]
    for t in TIMES:
        st, w, frames = reference(sc, t, ["fixed"] * 3)
        smp = sc.trajectory.sample(np.array([t]))
        maps = np.empty((3, 2, 3))
        for i in range(3):
            c = model.contact(i, smp.pose, smp.velocity, smp.acceleration, XI[None, i:i + 1])
            maps[i] = np.stack([c.wrench[0, 0], c.normal[0, 0], c.tangential[0, 0]], axis=-1)
        got = torque_excess(geometry, smp.pose[0, 2], smp.acceleration[0], XI, [None] * 3, mu, problem_limits, maps,
                            model.effort)
        # the LP written here: variables (f (6), t), hand frame
        rows_eq, rhs_eq, rows_ub, rhs_ub = [], [], [], []
        F = sc.polygon.mass * (smp.acceleration[0, :2] - sc.gravity_in_hand)
        for axis in range(2):
            row = np.zeros(7)
            row[axis:6:2] = 1.0
            rows_eq.append(row)
            rhs_eq.append(F[axis])
        row = np.zeros(7)
        for i, (k, x) in enumerate(zip([c.edge for c in sc.contacts], XI)):
            c_, s_ = np.cos(smp.pose[0, 2]), np.sin(smp.pose[0, 2])
            r = np.array([[c_, -s_], [s_, c_]]) @ sc.polygon.edge(k).point(x)
            row[2 * i], row[2 * i + 1] = -r[1], r[0]
        rows_eq.append(row)
        rhs_eq.append(sc.polygon.inertia * smp.acceleration[0, 2])
        for i in range(3):
            n, tt = frames[i][:, 0], frames[i][:, 1]
            for vec, lo in ((n, 0.2), (-n, -20.0), (mu[i] * n - tt, 0.2), (mu[i] * n + tt, 0.2)):
                row = np.zeros(7)
                row[2 * i:2 * i + 2] = -vec
                rows_ub.append(row)
                rhs_ub.append(-lo)
            J = st.hand.jacobian[2 * i:2 * i + 2, 2 * i:2 * i + 2]
            for j in range(2):
                for sign in (1.0, -1.0):  # sign (w + J_jᵀ f) - t <= e
                    row = np.zeros(7)
                    row[2 * i:2 * i + 2], row[6] = sign * J[:, j], -1.0
                    rows_ub.append(row)
                    rhs_ub.append(model.effort[i, j] - sign * w[2 * i + j])
        lp = scipy.optimize.linprog(np.eye(7)[6], A_ub=np.array(rows_ub), b_ub=rhs_ub, A_eq=np.array(rows_eq),
                                    b_eq=rhs_eq, bounds=[(None, None)] * 7, method="highs")
        assert lp.status == 0
        assert got.excess == pytest.approx(lp.x[6], abs=1e-8)
        assert got.contact in (0, 1, 2) and got.joint in (0, 1)
        assert got.torque == pytest.approx(model.effort[got.contact, got.joint] + got.excess)


def build_geometry(sc):
    from regrasp.schedule.force_polytope import ForceGeometry
    return ForceGeometry.of(sc.polygon, [c.edge for c in sc.contacts], mass=sc.polygon.mass,
                            inertia=sc.polygon.inertia, gravity=sc.gravity_in_hand)


def test_too_small_a_torque_limit_has_no_schedule_and_the_planner_says_which_joint():
    with pytest.raises(NoScheduleError) as info:
        plan_regrasps(scenario(effort=0.02))
    error = info.value
    assert error.limit is ScheduleLimit.TORQUE and error.to_json_dict()["limit"] == "torque"
    assert len(error.contacts) == 1 and error.contacts[0] in ("finger1", "finger2", "palm")
    text = str(error)
    assert f"{error.contacts[0]} keeps its joint" in text and "torque limit of 0.0200 N m" in text
    assert "at t = 0.000 s" in text and "needs at least" in text


def test_the_shipped_limits_cut_nothing_and_the_verification_checks_a_smaller_one():
    settings = RegraspSettings()
    shipped = build_problem(scenario(), settings, start_time=1.45, t_end=1.75)
    assert shipped.torque.limited and shipped.free_tables is None  # (5 N m: far above what the task needs)
    schedule = plan_regrasps(scenario(), settings, start_time=1.45, t_end=1.75)
    violations, _ = verify(shipped, schedule, settings.verify_substeps)
    assert violations == []
    limited = build_problem(scenario(effort=[0.08, 0.08]), settings, start_time=1.45, t_end=1.75)
    violations, _ = verify(limited, schedule, settings.verify_substeps)
    torque = [v for v in violations if v[1].startswith("torque limit")]
    assert torque and all(f"{limited.names[i]} joint" in what for _, what, i in torque)
    assert "its limit is 0.0800 N m" in torque[0][1]

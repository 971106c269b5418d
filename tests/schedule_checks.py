"""The independent checks of a regrasp schedule (tests/schedule/test_planner.py's module docstring), shared by the
planner's tests on polygons and on curves."""

from __future__ import annotations

import numpy as np

from factories import force_lp
from regrasp.envelope.finger_envelope import FingerEnvelope
from regrasp.schedule.force_polytope import ForceLimits
from regrasp.schedule.planner import RegraspSettings


def check_schedule(scenario, schedule, settings: RegraspSettings) -> dict:
    """The independent checks of the module docstring; returns the smallest margins they saw."""
    traj = scenario.trajectory
    step = settings.time_step
    n = int(round((schedule.t_end - schedule.t_start) / step * 4))
    times = schedule.t_start + (np.arange(n) + 0.5) * (schedule.t_end - schedule.t_start) / n
    at = schedule.at(times)
    sample = traj.sample(times)
    envelopes = [FingerEnvelope(c.finger, scenario.polygon, c.edge, geometry=scenario.geometry,
                                tip_clearance=c.tip_clearance) for c in scenario.contacts]
    near = getattr(scenario.polygon.edge(scenario.contacts[0].edge), "curved", False)  # (ξ unwrapped on a curve)
    env_min = min(env.at(pose, float(t), **({"near": float(x)} if near else {})).margin(float(x))
                  for j, (t, pose) in enumerate(zip(times, sample.pose)) for env, x in zip(envelopes, at.xi[j]))
    assert env_min >= settings.envelope_margin - 1e-9
    limits = ForceLimits(settings.f_min, settings.f_max, settings.cone_margin, friction_margin=settings.friction_margin)
    friction = [c.friction for c in scenario.contacts]
    mu_s = [f.static for f in friction]
    edges = [c.edge for c in scenario.contacts]
    for j in range(len(times)):
        ratios = [None if d == 0 else d * f.kinetic for d, f in zip(at.direction[j], friction)]
        assert force_lp(scenario.polygon, edges, sample.pose[j], sample.acceleration[j], at.xi[j], ratios, mu_s,
                        limits, scenario.gravity_in_hand), f"no force system at t = {times[j]:.4f} s"
    # break-away as the slide starts: the contacts that start together primed together past their static edges
    # (mu_s + prime_overshoot, the executor's priming), the held ones inside the cones the executor's internal force
    # keeps as its last resort (friction_margin; f_min, no floors, no cone margin in newtons: its target)
    breakaway = ForceLimits(settings.f_min, settings.f_max, 0.0, friction_margin=settings.friction_margin)
    for s in schedule.slides:
        t = s.start
        start = schedule.at(t)
        moving = schedule.at(t + 1e-6)
        together = {o.contact for o in schedule.slides if abs(o.start - t) < 1e-9}
        ratios = [None if d == 0 else d * (f.static + settings.prime_overshoot if i in together else f.kinetic)
                  for i, (d, f) in enumerate(zip(moving.direction, friction))]
        smp = traj.sample(t)
        assert force_lp(scenario.polygon, edges, smp.pose, smp.acceleration, start.xi, ratios, mu_s, breakaway,
                        scenario.gravity_in_hand), f"{s.name} cannot break away at t = {t:.4f} s"
    # the profiles
    fine = np.linspace(schedule.t_start, schedule.t_end, 40001)
    prof = schedule.at(fine)
    dt = fine[1] - fine[0]
    assert np.abs(prof.xi_dot).max() <= settings.max_slide_speed * (1 + 1e-9)
    assert np.abs(prof.xi_ddot).max() <= settings.max_slide_acceleration * (1 + 1e-9)
    np.testing.assert_allclose(np.gradient(prof.xi, dt, axis=0)[1:-1], prof.xi_dot[1:-1],
                               atol=settings.max_slide_acceleration * dt * 2)
    m = len(edges)
    assert np.count_nonzero(prof.direction, axis=1).max() <= min(m - 1, 2 * m - 3)
    for s in schedule.slides:
        assert schedule.at(s.start).xi_dot[s.contact] == 0.0 and schedule.at(s.end).xi_dot[s.contact] == 0.0
        assert np.sign(s.end_xi - s.start_xi) == s.direction
    if schedule.periodic:
        np.testing.assert_allclose(schedule.at(schedule.t_end).xi, schedule.at(schedule.t_start).xi, atol=1e-12)
        assert np.all(schedule.at(schedule.t_start).xi_dot == 0.0)
    return {"envelope": env_min}

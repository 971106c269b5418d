"""The slide executor on synthetic measurements: its phases, its laws and its cone edges.

The measurements are made up by the test (no plant): the executor's decisions and the forces its
laws predict are checked against what the phases ask for.
"""

import math
from dataclasses import fields
from pathlib import Path

import numpy as np
import pytest

from regrasp import Hand, load_scenario
from regrasp.core.contact import ContactMode, Friction
from regrasp.core.events import EventKind
from regrasp.core.exceptions import InvalidParameterError
from regrasp.core.measurement import Measurement
from regrasp.dynamics.grasp import Grasp
from regrasp.dynamics.internal_force.problem import InternalForceInfeasibleError
from regrasp.dynamics.internal_force.settings import InternalForceSettings
from regrasp.supervisor.executor import SlideExecutor
from regrasp.supervisor.fallbacks import FEEDBACK_FRACTIONS, FLOOR_BISECTIONS, FLOOR_FRACTIONS
from regrasp.supervisor.settings import ExecutorSettings, SupervisorSettings
from regrasp.supervisor.types import ContactPhase, SlideOrder

SCENARIOS = Path(__file__).resolve().parents[2] / "examples" / "scenarios"


SC = load_scenario(SCENARIOS / "paper_trajectory_2_three_fingers.toml")
XI = np.array([-0.014, 0.014, -0.001])


def executor(friction=None, **settings) -> SlideExecutor:
    hand = Hand([c.finger for c in SC.contacts], gravity_in_hand=SC.gravity_in_hand)
    grasp = Grasp(SC.polygon, [c.edge for c in SC.contacts], [ContactMode.FIXED] * 3)
    return SlideExecutor(hand, grasp, XI, SC.friction if friction is None else friction, object_mass=SC.polygon.mass,
                         object_inertia=SC.polygon.inertia, settings=ExecutorSettings(**settings))


def meas(t, xi=XI, xi_dot=(0.0, 0.0, 0.0), sliding=(False, False, False), normal=None, tangential=(0.0, 0.0, 0.0)):
    pose = SC.trajectory.pose(t)
    return Measurement(t, pose, SC.trajectory.velocity(t), np.array(xi, float), np.array(xi_dot, float),
                       np.array(sliding), np.array(tangential, float), None if normal is None else np.array(normal))


def command(ex, t, m, out):
    return ex.command(m, SC.trajectory.sample(t), 1e-3, out)


def test_two_slides_prime_on_their_cone_edges_then_slide_on_their_kinetic_edges():
    ex = executor()
    out = []
    t = 0.8
    for i, d in ((0, 1), (1, -1)):
        ex.start(SlideOrder(i, d, 0.0, reference=lambda t, i=i: (XI[i], 0.0, 0.0)), meas(t), out)
    assert [e.kind for e in out] == [EventKind.PRIME, EventKind.PRIME]
    control, law, reference, aborted = command(ex, t, meas(t), out)
    assert law == "fixed contacts (cone edge)" and not aborted and np.isnan(reference).all()
    (fn1, ft1), (fn2, ft2) = control.contact_forces_surface[:2]
    assert ft1 == pytest.approx(0.55 * fn1, rel=1e-9) and ft2 == pytest.approx(-0.55 * fn2, rel=1e-9)
    # both sensed slipping: both slide, Proposition 3 with p = 2
    m = meas(t + 1e-3, xi_dot=(0.001, -0.001, 0.0), sliding=(True, True, False))
    ex.advance(m, out)
    assert ex.phases[:2] == [ContactPhase.SLIDING, ContactPhase.SLIDING]
    control, law, reference, _ = command(ex, t + 1e-3, m, out)
    assert law == "Proposition 3" and reference[:2].tolist() == XI[:2].tolist() and math.isnan(reference[2])
    (fn1, ft1), (fn2, ft2), (fn3, ft3) = control.contact_forces_surface
    assert ft1 == pytest.approx(0.5 * fn1, rel=1e-9) and ft2 == pytest.approx(-0.5 * fn2, rel=1e-9)
    assert abs(ft3) < 0.5 * fn3  # the palm inside its cone


def test_a_slide_arrives_settles_inside_its_kinetic_cone_and_counts_once_fixed():
    ex = executor()
    out = []
    ex.start(SlideOrder(0, 1, -0.010), meas(0.0), out)  # a filtered slide (no reference)
    ex.advance(meas(0.001, sliding=(True, False, False), xi_dot=(0.001, 0, 0)), out)
    assert ex.phases[0] is ContactPhase.SLIDING
    arrived = meas(0.2, xi=(-0.0101, XI[1], XI[2]), xi_dot=(0.001, 0, 0), sliding=(True, False, False))
    (end,) = ex.advance(arrived, out)
    assert end.kind is EventKind.ARRIVED and ex.phases[0] is ContactPhase.SETTLING and ex.regrasps[0] == 0
    control, law, _, _ = command(ex, 0.2, arrived, out)
    fn, ft = control.contact_forces_surface[0]
    assert law == "fixed contacts (cone edge)" and ft == pytest.approx(0.45 * fn, rel=1e-9)  # μ_k - 0.05
    ex.advance(meas(0.201, xi=(-0.0101, XI[1], XI[2])), out)
    assert ex.phases[0] is ContactPhase.FIXED and ex.regrasps[0] == 1 and out[-1].kind is EventKind.SETTLED


def test_a_planned_slide_that_sticks_on_the_way_is_primed_again():
    ex = executor(max_reprimes=1)
    out = []
    order = SlideOrder(0, 1, 0.010, reference=lambda t: (-0.014 + 0.05 * t, 0.05, 0.0), planned_start=0.0,
                       planned_end=0.5)
    ex.start(order, meas(0.0), out)
    ex.advance(meas(0.001, sliding=(True, False, False), xi_dot=(0.01, 0, 0)), out)
    assert ex.advance(meas(0.1, xi=(-0.012, XI[1], XI[2])), out) == []  # stuck: primed again
    stuck, prime = out[-2:]
    assert ex.phases[0] is ContactPhase.PRIMING and stuck.kind is EventKind.STUCK and prime.kind is EventKind.PRIME
    assert stuck.values["reprime"] == prime.values["reprime"] == 1
    ex.advance(meas(0.101, sliding=(True, False, False), xi_dot=(0.01, 0, 0)), out)
    (end,) = ex.advance(meas(0.2, xi=(-0.009, XI[1], XI[2])), out)  # stuck again: the last re-prime is used
    assert end.kind is EventKind.STUCK and ex.phases[0] is ContactPhase.FIXED


def test_each_repriming_starts_its_overshoot_higher():
    """``reprime_overshoot_step``: a planned slide stuck on its way is primed again from μ_s + prime_overshoot + its
    re-primings so far times the step (at most ``prime_overshoot_max``), where the first priming started from μ_s +
    prime_overshoot; the priming's own ramp then grows it towards the maximum over ``prime_time``."""
    ex = executor(max_reprimes=3, prime_overshoot=0.01, prime_overshoot_max=0.1, reprime_overshoot_step=0.04,
                  prime_time=0.04)
    out = []
    mu_s = SC.contacts[0].friction.static
    order = SlideOrder(0, 1, 0.010, reference=lambda t: (-0.014 + 0.05 * t, 0.05, 0.0), planned_start=0.0,
                       planned_end=0.5)

    def ratio(t, m):
        fn, ft = command(ex, t, m, out)[0].contact_forces_surface[0]
        return ft / fn

    ex.start(order, meas(0.0), out)
    assert ratio(0.0, meas(0.0)) == pytest.approx(mu_s + 0.01, rel=1e-9)
    t = 0.0
    for reprimes, expected in ((1, 0.05), (2, 0.09), (3, 0.1)):
        ex.advance(meas(t + 0.001, sliding=(True, False, False), xi_dot=(0.01, 0, 0)), out)  # slides ...
        assert ex.phases[0] is ContactPhase.SLIDING
        t += 0.05
        stuck = meas(t, xi=(-0.013, XI[1], XI[2]))
        assert ex.advance(stuck, out) == [] and ex.phases[0] is ContactPhase.PRIMING  # ... sticks: primed again
        assert out[-1].values["reprime"] == reprimes
        assert ratio(t, stuck) == pytest.approx(mu_s + expected, rel=1e-9)


def test_the_sliders_kinetic_friction_is_estimated_from_the_sensed_forces():
    ex = executor(friction_filter_time=0.01)
    out = []
    ex.start(SlideOrder(0, 1, 0.0, reference=lambda t: (-0.014, 0.0, 0.0)), meas(0.0), out)
    for k in range(1, 60):  # the plant's μ_k is 0.6 (the model's: 0.5)
        m = meas(k * 1e-3, sliding=(True, False, False), xi_dot=(0.01, 0, 0), normal=(1.0, 1.0, 1.0),
                 tangential=(0.6, 0.0, 0.0))
        ex.advance(m, out)
    control, law, _, _ = command(ex, 0.06, m, out)
    fn, ft = control.contact_forces_surface[0]
    assert law == "Proposition 3" and ft == pytest.approx(0.6 * fn, rel=1e-9)  # on the estimated kinetic edge


def test_the_first_friction_estimate_is_the_ratio_the_contact_broke_away_at():
    """Sensed slipping at the end of its priming, the slider's law starts on the kinetic edge of the force ratio
    the sensor read when it broke away (0.58 here, against the model's 0.5), not on the model's."""
    ex = executor(friction_filter_time=0.01, breakaway_estimate=True)
    out = []
    ex.start(SlideOrder(0, 1, 0.0, reference=lambda t: (-0.014, 0.0, 0.0)), meas(0.0), out)
    m = meas(0.001, sliding=(True, False, False), xi_dot=(0.0, 0, 0), normal=(1.0, 1.0, 1.0),
             tangential=(0.58, 0.0, 0.0))
    ex.advance(m, out)
    control, law, _, _ = command(ex, 0.001, m, out)
    fn, ft = control.contact_forces_surface[0]
    assert law == "Proposition 3" and ft == pytest.approx(0.58 * fn, rel=1e-9)


@pytest.mark.parametrize("broke_away_at", [0.50, 0.61])
def test_the_first_friction_estimate_is_no_less_than_the_largest_ratio_the_primed_contact_held(broke_away_at):
    """A compliant contact's friction builds up over its first slipping step: primed, it held 0.56 of its load
    (the plant's μ_s, 12 % above the model's 0.5), then broke away reading 0.50. The sliding law starts on the
    edge of 0.56, what the contact held, not 0.50 (the slider would stick again within a step); a break-away
    read above what it held (0.61) is kept."""
    ex = executor(friction_filter_time=0.01, breakaway_estimate=True)
    out = []
    ex.start(SlideOrder(0, 1, 0.0, reference=lambda t: (-0.014, 0.0, 0.0)), meas(0.0), out)
    for k, ratio in enumerate((0.52, 0.56, 0.54), start=1):  # held, primed (not sliding)
        ex.advance(meas(k * 1e-3, normal=(1.0, 1.0, 1.0), tangential=(ratio, 0.0, 0.0)), out)
        assert ex.phases[0] is ContactPhase.PRIMING
    ex.advance(meas(0.001, sliding=(False, False, False), normal=(0.01, 1.0, 1.0), tangential=(0.009, 0, 0)), out)
    m = meas(0.004, sliding=(True, False, False), normal=(1.0, 1.0, 1.0), tangential=(broke_away_at, 0.0, 0.0))
    ex.advance(m, out)
    control, law, _, _ = command(ex, 0.004, m, out)
    fn, ft = control.contact_forces_surface[0]
    assert law == "Proposition 3" and ft == pytest.approx(max(0.56, broke_away_at) * fn, rel=1e-9)


def test_with_a_start_speed_the_priming_lasts_until_the_contact_moves_the_right_way():
    ex = executor(start_speed=1e-3)
    out = []
    ex.start(SlideOrder(0, -1, -0.02), meas(0.0), out)
    for xi_dot in (0.0, 0.002, -0.0005):  # broke away, but not moving down yet (or moving up)
        ex.advance(meas(0.001, sliding=(True, False, False), xi_dot=(xi_dot, 0, 0)), out)
        assert ex.phases[0] is ContactPhase.PRIMING
    ex.advance(meas(0.002, sliding=(True, False, False), xi_dot=(-0.0015, 0, 0)), out)
    assert ex.phases[0] is ContactPhase.SLIDING and out[-1].kind is EventKind.SLIDE


def test_a_settling_contact_keeps_a_margin_in_newtons_on_a_light_touch():
    """f_n = 0.25 N: the 0.05 undershoot would leave 0.0125 N; settle_margin = 0.05 N asks for μ_k f_n - 0.05 N."""
    ex = executor(settle_margin=0.05)
    out = []
    ex.start(SlideOrder(0, 1, -0.010), meas(0.0), out)
    ex.advance(meas(0.001, sliding=(True, False, False), xi_dot=(0.001, 0, 0)), out)
    arrived = meas(0.2, xi=(-0.0101, XI[1], XI[2]), xi_dot=(0.001, 0, 0), sliding=(True, False, False),
                   normal=(0.25, 1.0, 1.0), tangential=(0.125, 0.0, 0.0))
    ex.advance(arrived, out)
    control, law, _, _ = command(ex, 0.2, arrived, out)
    fn, ft = control.contact_forces_surface[0]
    assert law == "fixed contacts (cone edge)" and ft == pytest.approx((0.5 - 0.05 / 0.25) * fn, rel=1e-9)
    heavy = executor(settle_margin=0.05)  # f_n = 2 N: the undershoot's 0.1 N is the larger margin
    heavy.start(SlideOrder(0, 1, -0.010), meas(0.0), out)
    heavy.advance(meas(0.001, sliding=(True, False, False), xi_dot=(0.001, 0, 0)), out)
    heavy.advance(meas(0.2, xi=(-0.0101, XI[1], XI[2]), xi_dot=(0.001, 0, 0), sliding=(True, False, False),
                       normal=(2.0, 1.0, 1.0), tangential=(1.0, 0.0, 0.0)), out)
    fn, ft = command(heavy, 0.2, arrived, out)[0].contact_forces_surface[0]
    assert ft == pytest.approx(0.45 * fn, rel=1e-9)


def test_with_an_actuation_delay_a_stuck_slide_settles_until_the_torques_in_flight_are_its_own():
    ex = executor(actuation_delay=1)
    out = []
    ex.start(SlideOrder(0, 1, -0.010), meas(0.0), out)
    ex.advance(meas(0.001, sliding=(True, False, False), xi_dot=(0.001, 0, 0)), out)
    still = meas(0.2, xi=(-0.0101, XI[1], XI[2]))  # arrived and already stuck
    (end,) = ex.advance(still, out)
    assert end.kind is EventKind.ARRIVED and ex.phases[0] is ContactPhase.SETTLING
    control, law, _, _ = command(ex, 0.2, still, out)
    assert law == "fixed contacts"  # stuck: its own static cone, no cone edge
    ex.advance(meas(0.201, xi=(-0.0101, XI[1], XI[2]), sliding=(True, False, False)), out)  # the last
    assert ex.phases[0] is ContactPhase.SETTLING  # sliding law's torque broke it away: still the slide's
    ex.advance(meas(0.202, xi=(-0.0101, XI[1], XI[2])), out)
    assert ex.phases[0] is ContactPhase.SETTLING  # stuck for one step: one torque in flight was not its own
    ex.advance(meas(0.203, xi=(-0.0101, XI[1], XI[2])), out)
    assert ex.phases[0] is ContactPhase.FIXED and ex.regrasps[0] == 1


def test_an_infeasible_slide_is_aborted_and_the_contact_held():
    # a priming that asks finger 1 for |f_t| = 3.5 f_n: no squeeze balances that with the others in their cones
    ex = executor(prime_overshoot=3.0, prime_overshoot_max=3.0,
                  internal_force=InternalForceSettings(f_min=0.2, f_max=5.0))
    out = []
    ex.start(SlideOrder(0, 1, 0.0), meas(0.8), out)
    control, law, _, aborted = command(ex, 0.8, meas(0.8), out)
    (end,) = aborted
    assert end.kind is EventKind.SLIDE_ABORTED and law == "fixed contacts" and ex.phases[0] is ContactPhase.FIXED
    assert np.isfinite(control.tau).all() and ex.regrasps[0] == 0


def test_orders_and_settings_are_checked():
    ex = executor()
    ex.start(SlideOrder(0, 1, 0.0), meas(0.0), [])
    with pytest.raises(InvalidParameterError):
        ex.start(SlideOrder(0, 1, 0.0), meas(0.0), [])  # not fixed
    for bad in (dict(integral=2.0), dict(prime_overshoot_max=0.01), dict(max_reprimes=-1), dict(slide_omega=0.0),
                dict(settle_margin=-0.1), dict(actuation_delay=-1), dict(actuation_delay=0.5), dict(start_speed=-1e-3),
                dict(start_speed=math.nan)):
        with pytest.raises(InvalidParameterError):
            ExecutorSettings(**bad)


def test_held_contacts_follow_the_sensed_positions_past_the_resolution():
    """A fingertip that rolls moves along its edge while held: the laws' model follows it once it has moved more
    than ``hold_resolution`` (and never a contact being slid, nor with None)."""
    out = []
    for resolution, drift, follows in ((2e-6, 1e-5, True), (2e-6, 1e-6, False), (None, 1e-5, False)):
        ex = executor(hold_resolution=resolution)
        xi = XI + np.array([drift, -drift, drift])
        ex.advance(meas(0.1, xi=xi), out)
        np.testing.assert_array_equal(ex.xi, xi if follows else XI)
    ex = executor()
    ex.start(SlideOrder(0, 1, 0.0), meas(0.0), out)
    ex.advance(meas(0.001, xi=XI + 1e-5), out)  # contact 0 is being primed: its position is set by its phases
    assert ex.phases[0] is ContactPhase.PRIMING and ex.xi[0] == XI[0] and ex.xi[1] == XI[1] + 1e-5


def test_spherical_tips_add_their_couple_to_every_laws_torque():
    from regrasp.model.sphere_tip import sphere_tip_torque

    t = 0.8
    point = command(executor(), t, meas(t), [])[0]
    sphere = command(executor(tip_radius=5e-4), t, meas(t), [])[0]
    beta = SC.trajectory.pose(t)[2]
    rot = np.array([[math.cos(beta), -math.sin(beta)], [math.sin(beta), math.cos(beta)]])
    normals = [rot @ SC.polygon.edge(c.edge).inward_normal for c in SC.contacts]
    np.testing.assert_allclose(sphere.contact_forces, point.contact_forces, rtol=0, atol=1e-12)
    np.testing.assert_allclose(sphere.tau - point.tau, sphere_tip_torque(normals, point.contact_forces, 5e-4),
                               rtol=0, atol=1e-12)
    assert np.abs(sphere.tau - point.tau).max() > 1e-5


def test_held_positions_follow_a_noisy_sensor_through_the_filter_and_rarely_rebuild_the_law():
    """A held contact sensed 0.3 mm from where the model holds it, with 0.2 mm of noise: filtered (20 ms) at a
    0.1 mm resolution the model moves there in a few steps and then stays; unfiltered at 2 um it moves every step."""
    rng = np.random.default_rng(4)
    truth = XI + np.array([3e-4, 0.0, 0.0])
    readings = [truth + rng.normal(0.0, 2e-4, 3) for _ in range(300)]
    for settings, most_moves in ((dict(hold_filter_time=0.02, hold_resolution=1e-4), 10),
                                 (dict(hold_filter_time=None, hold_resolution=2e-6), None)):
        ex = executor(**settings)
        moves, last = 0, ex.xi.copy()
        for k, xi in enumerate(readings):
            ex.advance(meas(k * 1e-3, xi=xi), [])
            moves += not np.array_equal(ex.xi, last)
            last = ex.xi.copy()
        if most_moves is None:
            assert moves > 250  # the noise moves the model at nearly every step
        else:
            assert moves <= most_moves
            np.testing.assert_allclose(ex.xi, truth, rtol=0, atol=1.5e-4)  # (the filtered noise: 0.03 mm)


def test_floors_load_the_sliders_the_holders_while_one_slides_and_a_contact_the_reflex_caught():
    """The executor's floors (``slider_floor``, ``holder_preload``, the reflex): what each contact must push with in
    the laws at each phase, and the laws' predicted forces at or above them."""
    ex = executor(slider_floor=0.35, holder_preload=0.3, reflex_below=0.1, reflex_floor=0.45, reflex_time=0.01,
                  internal_force=InternalForceSettings(f_min=0.2))
    out = []
    assert ex.floors() == (0.0, 0.0, 0.0)
    control, *_ = command(ex, 0.8, meas(0.8), out)
    assert control.contact_forces_surface[:, 0].min() >= 0.2 - 1e-6
    ex.start(SlideOrder(0, 1, 0.0, reference=lambda t: (XI[0], 0.0, 0.0)), meas(0.8), out)
    assert ex.floors() == (0.35, 0.3, 0.3)  # (priming: the slider's floor; the holders pre-loaded)
    control, *_ = command(ex, 0.8, meas(0.8), out)
    normal = control.contact_forces_surface[:, 0]
    assert normal[0] >= 0.35 - 1e-6 and normal[1:].min() >= 0.3 - 1e-6
    # the palm sensed at 0.05 N: its reflex lasts 10 ms
    low = meas(0.801, xi_dot=(0.001, 0.0, 0.0), sliding=(True, False, False), normal=(0.4, 0.4, 0.05))
    ex.advance(low, out)
    control, *_ = command(ex, 0.801, low, out)
    assert ex.floors() == (0.35, 0.3, 0.45) and control.contact_forces_surface[2, 0] >= 0.45 - 1e-6
    ok = meas(0.812, xi_dot=(0.001, 0.0, 0.0), sliding=(True, False, False), normal=(0.4, 0.4, 0.4))
    ex.advance(ok, out)
    command(ex, 0.812, ok, out)
    assert ex.floors() == (0.35, 0.3, 0.3)


def test_floors_no_squeeze_can_meet_give_way_to_f_min():
    """A floor is a preference; the internal force's f_min is the limit: where no squeeze meets the floors, the law
    runs without them (and says nothing), where f_min itself is met."""
    ex = executor(slider_floor=15.0, holder_preload=15.0, internal_force=InternalForceSettings(f_min=0.2, f_max=16.0))
    out = []
    ex.start(SlideOrder(0, 1, 0.0, reference=lambda t: (XI[0], 0.0, 0.0)), meas(0.8), out)
    control, law, _, aborted = command(ex, 0.8, meas(0.8), out)
    assert not aborted and law == "fixed contacts (cone edge)"
    assert 0.2 - 1e-6 <= control.contact_forces_surface[:, 0].min() < 15.0


@pytest.mark.parametrize("bad", [dict(slider_floor=-0.1), dict(holder_preload=math.nan), dict(reflex_below="0.1"),
                                 dict(reflex_floor=25.0, internal_force=InternalForceSettings(f_max=20.0)),
                                 dict(reflex_time=0.0)])
def test_floor_settings_refuse_bad_values(bad):
    with pytest.raises(InvalidParameterError):
        ExecutorSettings(**bad)


def test_floors_no_squeeze_can_meet_are_kept_in_part_where_the_forces_allow():
    """Between the floors and f_min: a step whose forces cannot meet the floors keeps the largest fraction of them
    that they can, to 1/2^``FLOOR_BISECTIONS`` (a slider dragging harder than the model's μ caps the squeeze)."""
    assert FLOOR_FRACTIONS == (1.0, 0.0)
    ex = executor(slider_floor=0.21, holder_preload=0.7, internal_force=InternalForceSettings(f_min=0.2, f_max=16.0))
    ex.start(SlideOrder(0, 1, 0.0, reference=lambda t: (XI[0], 0.0, 0.0)), meas(0.8), [])
    control, law, _, aborted = command(ex, 0.8, meas(0.8), [])
    holders = control.contact_forces_surface[1:, 0]
    assert not aborted and holders.min() < 0.7
    # the largest fraction (f_min alone: 0.235 N): a pre-load one bisection step above what was kept is not met
    # either, and one a step below is met whole
    kept = (holders.min() - 0.2) / (0.7 - 0.2)
    assert kept > 0.5
    step = 0.5**FLOOR_BISECTIONS
    for shift, met in ((step, False), (-step, True)):
        preload = 0.2 + (kept + shift) * (0.7 - 0.2)  # (and the same fraction of the slider's floor)
        other = executor(slider_floor=0.2 + (kept + shift) * (0.21 - 0.2), holder_preload=preload,
                         internal_force=InternalForceSettings(f_min=0.2, f_max=16.0))
        other.start(SlideOrder(0, 1, 0.0, reference=lambda t: (XI[0], 0.0, 0.0)), meas(0.8), [])
        loads = command(other, 0.8, meas(0.8), [])[0].contact_forces_surface[1:, 0]
        assert bool(loads.min() >= preload - 1e-6) == met


def test_floors_are_never_kept_by_taking_the_holders_fallback_friction_margin():
    """A holder pre-load of 1 N no force meets within the friction margin 0.1 but one meets within the fallback 0:
    the step keeps the whole margin at every held contact and gives up floors instead (kept above f_min where the
    margin allows); with the fallback margin the palm would sit on its cone's edge (ratio 0.499 of μ_s 0.5)."""
    margin = 0.1
    ex = executor(slider_floor=0.21, holder_preload=1.0, internal_force=InternalForceSettings(
        f_min=0.2, f_max=16.0, friction_margin=margin, fallback_friction_margin=0.0))
    ex.start(SlideOrder(0, 1, 0.0, reference=lambda t: (XI[0], 0.0, 0.0)), meas(0.8), [])
    control, _, _, aborted = command(ex, 0.8, meas(0.8), [])
    forces = control.contact_forces_surface[1:]
    ratios = np.abs(forces[:, 1]) / forces[:, 0]
    assert not aborted and forces[:, 0].max() < 1.0  # the pre-load is not met whole
    assert np.all(ratios <= np.array([f.static for f in SC.friction[1:]]) - margin + 1e-6)
    assert forces[:, 0].min() > 0.2 + 0.1  # some of the floors kept, not f_min alone


def _robust_without_floors(**changes) -> dict:
    """The robust executor's settings with no floors and no reflex: the internal force's f_min alone."""
    settings = SupervisorSettings.robust().executor
    values = {f.name: getattr(settings, f.name) for f in fields(settings)}
    return values | dict(slider_floor=0.0, holder_preload=0.0, reflex_below=0.0) | changes


def _sliding_at(ex, mu, steps=30, t=0.8):
    """Two slides (finger 1 up, finger 2 down from XI) run ``steps`` control steps, the plant's friction ratio ``mu``
    sensed at both; the last measurement's time."""
    out = []
    for i, d in ((0, 1), (1, -1)):
        ex.start(SlideOrder(i, d, XI[i], reference=lambda t, i=i: (XI[i], 0.0, 0.0)), meas(t), out)
    for k in range(1, steps + 1):
        m = meas(t + 1e-3 * k, xi_dot=(0.005, -0.005, 0.0), sliding=(True, True, False), normal=(0.3, 0.3, 1.0),
                 tangential=(mu * 0.3, -mu * 0.3, 0.0))
        command(ex, m.t, m, out)
        ex.advance(m, out)
    return t + 1e-3 * steps


def test_a_correction_no_forces_can_give_is_scaled_down_not_the_slide_aborted():
    """Where the cones cannot give the feedback's correction (an object turned by sliders dragging harder than the
    model's μ), the step keeps the planned motion and as much of the correction as ``FEEDBACK_FRACTIONS`` allow."""
    assert FEEDBACK_FRACTIONS[0] == 1.0 and FEEDBACK_FRACTIONS[-1] == 0.0
    ex = executor(friction=[Friction(0.5, 0.5)] * 3, **_robust_without_floors())
    t = _sliding_at(ex, mu=0.7) + 1e-3
    turned = 0.4  # [rad] of orientation error
    m = meas(t, xi_dot=(0.005, -0.005, 0.0), sliding=(True, True, False), normal=(0.3, 0.3, 1.0),
             tangential=(0.21, -0.21, 0.0))
    m = Measurement(m.t, m.X + np.array([0.0, 0.0, turned]), m.V, m.xi, m.xi_dot, m.sliding, m.tangential_force,
                    m.normal_force)
    S = np.concatenate([m.X, m.xi[:2]])
    S_dot = np.concatenate([m.V, m.xi_dot[:2]])
    full = (np.concatenate([SC.trajectory.pose(t), XI[:2]]), np.concatenate([SC.trajectory.velocity(t), [0.0, 0.0]]),
            np.concatenate([SC.trajectory.acceleration(t), [0.0, 0.0]]))
    with pytest.raises(InternalForceInfeasibleError):  # the whole correction: no forces
        ex.law()(S, S_dot, *full)
    out = []
    control, law, _, aborted = command(ex, t, m, out)
    assert law == "Proposition 3" and not aborted and not any(e.kind is EventKind.SLIDE_ABORTED for e in out)
    fraction = control.error[2] / -turned  # (the integral adds one step's error: 1 + 0.3 · 20 rad/s · 1 ms)
    assert 0.0 < fraction < 1.0
    (fn1, ft1), (fn2, ft2), (fn3, ft3) = control.contact_forces_surface
    assert min(fn1, fn2, fn3) >= 0.2 - 1e-6 and abs(ft3) <= 0.5 * fn3  # f_min everywhere, the palm in its cone
    assert ft1 == pytest.approx(0.7 * fn1, rel=1e-9) and ft2 == pytest.approx(-0.7 * fn2, rel=1e-9)


def test_settling_contacts_whose_cone_edges_leave_no_forces_get_the_plain_fixed_law():
    """Two aborted slides settling, one of them sensed moving against its slide: their kinetic edges leave no forces
    (the run once ended there, a control failure); the law holds them with their static cones instead."""
    ex = executor(friction=[Friction(0.5, 0.5)] * 3, **_robust_without_floors())
    t = _sliding_at(ex, mu=0.7, steps=40) + 0.01
    m = meas(t, xi_dot=(0.005, 0.005, 0.0), sliding=(True, True, False), normal=(0.3, 0.3, 1.0),
             tangential=(0.21, -0.21, 0.0))
    out = []
    ex.abort(m, out, "for the test")
    assert ex.phases[:2] == [ContactPhase.SETTLING] * 2
    S_d = (SC.trajectory.pose(t), SC.trajectory.velocity(t), SC.trajectory.acceleration(t))
    with pytest.raises(InternalForceInfeasibleError):  # on the settling edges, even without feedback
        ex.law()(m.X, m.V, m.X, m.V, S_d[2])
    control, law, _, _ = command(ex, t, m, out)
    assert law == "fixed contacts"
    fn, ft = control.contact_forces_surface.T
    assert fn.min() >= 0.2 - 1e-6 and (np.abs(ft) <= 0.5 * fn + 1e-9).all()


def test_a_priming_keeps_each_holders_load_of_the_step_before_and_releases_it_over_the_handover_time():
    """The handover hold (``handover_time``): at the priming the least squeeze drops (with the hold off, a contact's
    predicted load falls in one step); with it on, every contact keeps its load of the step before, released
    linearly, and the laws' forces stay at or above it."""
    settings = dict(slider_floor=0.3, holder_preload=0.3, internal_force=InternalForceSettings(f_min=0.2))
    drops = {}
    for time in (0.0, 0.03):
        ex = executor(handover_time=time, **settings)
        out = []
        before, *_ = command(ex, 0.8, meas(0.8), out)
        loads = before.contact_forces_surface[:, 0].copy()
        ex.start(SlideOrder(2, -1, -0.01, reference=lambda t: (XI[2], 0.0, 0.0)), meas(0.801), out)  # (the palm's
        # load falls 0.05 N in a step without the hold)
        after, *_ = command(ex, 0.801, meas(0.801), out)
        drops[time] = float(np.max(loads - after.contact_forces_surface[:, 0]))
        if time:
            assert ex.floors() == pytest.approx(tuple(np.maximum(np.minimum(loads, 2.0), (0.3, 0.3, 0.3))))
            assert (after.contact_forces_surface[:, 0] >= loads - 1e-6).all()
            later, *_ = command(ex, 0.816, meas(0.816), out)  # (half-way: half the loads, or the usual floors)
            half = np.maximum(0.5 * np.minimum(loads, 2.0), 0.3)
            assert ex.floors() == pytest.approx(tuple(half))
            assert (later.contact_forces_surface[:, 0] >= half - 1e-6).all()
            assert ex.stretch_view() is None  # (a hold runs on the reference path)
    assert drops[0.0] > 0.04 and drops[0.03] <= 1e-6


def test_the_handover_load_is_checked_against_f_max_only_when_the_hold_is_on():
    limited = InternalForceSettings(f_max=1.5)
    assert ExecutorSettings(internal_force=limited).handover_load_max == 2.0  # (no hold: nothing to check)
    with pytest.raises(InvalidParameterError, match="handover_load_max"):
        ExecutorSettings(internal_force=limited, handover_time=0.03)
    ExecutorSettings(internal_force=limited, handover_time=0.03, handover_load_max=1.0)

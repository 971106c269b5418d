"""The project plant on curved objects (``regrasp.core.curves``): a disc, a rounded box, an ellipse and a
support-function curve held by the three fingers of ``examples/scenarios/paper_trajectory_2_three_fingers.toml``
(finger 1 on the left, finger 2 on the right, the palm finger underneath), the object at (0, 0.12) m.

* Constraints: tips placed by inverse kinematics on c(ξ_i), zero velocity, a balanced squeeze (finger 1 pushes
  slightly more along its tangent than kinetic friction holds, so it slides; finger 2 balances its drag; the palm
  carries the rest of the weight). Over 200 steps of 1 ms each fixed tip stays at its object point and the slider
  on the curve (|δ|), to 1e-9 m, measured here from forward kinematics and the curve's own projection; the slider's
  ξ changes (on the rounded box it slides off a corner's arc onto the flat side, across the curvature's jump).
* Energy: the energy change equals the integrated work of the torques, the damping and friction, friction
  dissipates μ_k ∫ λ ξ̇ dt.
* The sliding row's curvature term: the plant's ψ̈ for given accelerations against a finite difference of
  ψ = -δ along the quadratic trajectory with those accelerations (δ from the curve's projection), and ξ̇ likewise.
* Polygons are unchanged; errors are typed; pads, separation, gap and surface forces on curves.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

import coal
import numpy as np
import pytest

from regrasp import Friction, Hand, Plant, PlantContact, load_scenario
from regrasp.core.contact import ContactMode
from regrasp.core.curves import Disc, Ellipse, RoundedPolygon, SupportCurve, rounded
from regrasp.core.exceptions import InvalidParameterError, UnknownEdgeError
from regrasp.core.pad import Pad
from regrasp.core.polygon import ConvexPolygon

ROOT = Path(__file__).resolve().parents[3]
SCENARIO = ROOT / "examples" / "scenarios" / "paper_trajectory_2_three_fingers.toml"
X0 = np.array([0.0, 0.12, 0.0])
MU = 0.3  # the slider's kinetic coefficient (the holders': 1.0)
MODES = ("sliding", "fixed", "fixed")
STEPS = 200


@functools.lru_cache(maxsize=None)
def scenario():
    return load_scenario(SCENARIO)


def make_hand(gravity=(0.0, -9.81), damping=True) -> Hand:
    return Hand([c.finger for c in scenario().contacts], gravity_in_hand=gravity, damping=damping)


def rot(beta: float) -> np.ndarray:
    c, s = math.cos(beta), math.sin(beta)
    return np.array([[c, -s], [s, c]])


@functools.lru_cache(maxsize=None)
def curve(name: str):
    if name == "disc":
        return Disc(0.05, mass=0.08)
    if name == "ellipse":
        return Ellipse(0.05, 0.035, mass=0.08)
    if name == "support":
        return SupportCurve.centred([0.045, 0.0, 0.004, 0.002], [0.0, 0.001, 0.0], mass=0.08)
    return RoundedPolygon(ConvexPolygon.rectangle(0.1, 0.04, mass=1.0).vertices, 0.012, mass=0.08)


def grip(obj) -> list[float]:
    """ξ of the three grip points (object frame): left (on the rounded box: on its lower-left corner's arc, 0.3 mm
    before it meets the left side), right, bottom."""
    xi = [float(obj.project(np.array([p]))[0][0]) for p in ([-0.06, 0.0], [0.06, 0.0], [0.0, -0.06])]
    if isinstance(obj, RoundedPolygon):
        kink = next(lo for kind, k, lo, _ in obj.piece_ranges() if (kind, k) == ("edge", 1))
        xi[0] = kink - 3e-4
        assert obj.piece(xi[0])[0] == "arc"
    return xi


def start(obj, modes=MODES, xi=None, X=X0, hand=None, friction=(Friction(MU), Friction(1.0), Friction(1.0)),
          **kw) -> Plant:
    """A plant with the tips on c(ξ_i) (inverse kinematics) at pose X, at rest."""
    hand = make_hand() if hand is None else hand
    xi = grip(obj) if xi is None else xi
    tips = np.array([X[:2] + rot(X[2]) @ obj.local(x).point for x in xi])
    q = hand.inverse_kinematics(tips)
    plant = Plant(hand, obj, [PlantContact(0, m, x, 1.0) for m, x in zip(modes, xi)], friction=list(friction), **kw)
    plant.reset(q, np.zeros(hand.nq), X, np.zeros(3))
    return plant


def cross(a, b) -> float:
    return float(a[0] * b[1] - a[1] * b[0])


def squeeze(plant: Plant, surplus: float = 0.004, normal: float = 1.0) -> np.ndarray:
    """Torques: gravity compensation plus tip forces on the object along each contact's surface frame at its
    current ξ: finger 1 pushes ``normal`` [N] and (μ_k ``normal`` + ``surplus``) along its tangent, finger 2
    ``normal``; finger 2's tangential force and the palm's two components balance the object's wrench with the
    slider's kinetic force n + μ_k t and the weight (so the object stays nearly still and the slider slides)."""
    st, obj, hand = plant.state, plant.polygon, plant.hand
    (c1, c2, c3), (n1, n2, n3), (t1, t2, t3) = zip(*((p.point, p.normal, p.tangent) for p in (
        obj.local(plant.contact_xi(st, i)[0]) for i in range(3))))
    R = rot(st.X[2])
    known = normal * (n1 + MU * t1) + normal * n2 + R.T @ (obj.mass * plant.hand.gravity_in_hand)
    lhs = np.array([[t2[0], n3[0], t3[0]], [t2[1], n3[1], t3[1]], [cross(c2, t2), cross(c3, n3), cross(c3, t3)]])
    a, b, c = np.linalg.solve(lhs, -np.array([*known, cross(c1, normal * (n1 + MU * t1)) + cross(c2, normal * n2)]))
    forces = np.concatenate([R @ (normal * n1 + (MU * normal + surplus) * t1), R @ (normal * n2 + a * t2),
                             R @ (b * n3 + c * t3)])
    return hand.jacobian(st.q).T @ forces + hand.dynamics(st.q, np.zeros(hand.nq)).nonlinear


def violations(plant: Plant, xi0) -> np.ndarray:
    """Each contact's violation [m] from forward kinematics: a fixed tip's distance from its object point, a
    slider's |δ| (the curve's projection)."""
    st, obj = plant.state, plant.polygon
    tips = plant.hand.tip_positions(st.q).reshape(-1, 2)
    R = rot(st.X[2])
    out = []
    for i, c in enumerate(plant.contacts):
        if c.mode is ContactMode.FIXED:
            out.append(np.linalg.norm(tips[i] - st.X[:2] - R @ obj.local(xi0[i]).point))
        else:
            out.append(abs(obj.project(np.array([R.T @ (tips[i] - st.X[:2])]))[1][0]))
    return np.array(out)


@functools.lru_cache(maxsize=None)
def slide(name: str) -> dict:
    """The squeezed slide of the module docstring on ``name``, recorded."""
    obj = curve(name)
    plant = start(obj, contact_events=False, stop_on=())
    xi0 = grip(obj)
    E0 = plant.energy()
    out = {"xi": [], "xi_dot": [], "err": [], "own": [], "forces": [], "events": [], "torque": 0.0, "pieces": set()}
    for _ in range(STEPS):
        q0 = plant.state.q.copy()
        tau = squeeze(plant)
        step = plant.step(tau)
        out["torque"] += float(tau @ (plant.state.q - q0))
        for key, value in (("xi", step.xi), ("xi_dot", step.xi_dot), ("err", step.constraint_error),
                           ("own", violations(plant, xi0)), ("forces", step.forces_surface)):
            out[key].append(value)
        out["events"] += list(step.events)
        if isinstance(obj, RoundedPolygon):
            out["pieces"].add(obj.piece(step.xi[0]))
    out.update({key: np.array(out[key]) for key in ("xi", "xi_dot", "err", "own", "forces")})
    out.update(plant=plant, E0=E0, xi0=xi0)
    return out


# ---------------------------------------------------------------------------- 1. constraints
@pytest.mark.parametrize("name", ["disc", "rounded", "ellipse", "support"])
def test_the_tips_stay_on_the_curve_while_one_slides(name):
    run = slide(name)
    plant = run["plant"]
    assert run["err"].max() <= 1e-9 and plant.max_constraint_error <= 1e-9, run["err"].max()
    assert run["own"].max() <= 1e-9, run["own"].max(axis=0)
    assert [e.kind for e in run["events"]] == []  # no collision, no singular finger
    assert [c.mode for c in plant.contacts] == list(MODES)
    xi = run["xi"]
    assert np.ptp(xi[:, 0]) > 5e-4  # it slides ...
    assert (run["xi_dot"][:, 0] > 0).all()  # ... one way (up the left side, +t)
    np.testing.assert_allclose(xi[:, 1:], np.tile(run["xi0"][1:], (STEPS, 1)), atol=1e-9)  # the holders hold
    assert np.abs(np.diff(xi[:, 0])).max() < 1e-4  # ξ continuous (the disc's starts < 0: no wrap to [0, P))
    if name == "rounded":  # from the corner's arc onto the left side, across the jump of curvature
        assert run["pieces"] == {("arc", 2), ("edge", 1)}


# ---------------------------------------------------------------------------- 2. energy
@pytest.mark.parametrize("name", ["disc", "rounded", "ellipse", "support"])
def test_energy_change_is_the_work_of_torques_damping_and_friction(name):
    run = slide(name)
    plant = run["plant"]
    st = plant.state
    balance = plant.energy() - run["E0"] - (st.torque_work + st.damping_work + st.contact_work)
    assert abs(balance) < 1e-6 * abs(st.contact_work), balance / st.contact_work
    assert st.torque_work == pytest.approx(run["torque"], rel=1e-9)  # τ constant over a step: Σ τ·Δq
    assert st.contact_work < 0.0 and st.damping_work < 0.0
    # friction dissipates μ_k ∫ λ ξ̇ dt (trapezoids of the recorded normal forces and slip rates)
    lam, rate = run["forces"][:, 0, 0], run["xi_dot"][:, 0]
    assert run["forces"][:, 0, 1] == pytest.approx(MU * lam, rel=1e-12)
    dissipated = MU * float(np.sum(0.5 * (lam[1:] * rate[:-1] + lam[1:] * rate[1:]))) * plant.dt
    assert -st.contact_work == pytest.approx(dissipated, rel=1e-2)


# ---------------------------------------------------------------------------- 3. the curvature term
@pytest.mark.parametrize("name", ["disc", "rounded", "ellipse"])
def test_the_sliding_row_is_the_second_derivative_of_the_signed_distance(name):
    """All three contacts sliding, random velocities and accelerations: the row applied to (q̈, Ẍ) plus its drift
    (the right-hand side at α = 0) is ψ̈ of ψ = -δ along q(h) = q + q̇h + q̈h²/2, X(h) likewise (Richardson
    extrapolated central differences); ξ̇ is the difference quotient of the foot's ξ."""
    obj = curve(name)
    rng = np.random.default_rng(7)
    hand = make_hand()
    xi = grip(obj)
    if name == "rounded":  # on the arc's middle
        xi[0] = obj.project(np.array([[-0.088, 0.058]]))[0][0]
        assert obj.piece(xi[0])[0] == "arc"
    X = np.array([0.003, 0.121, 0.1])
    lifts = (0.0, 1e-3, -5e-4)  # tips a little off the curve: δ ≠ 0
    tips = np.array([X[:2] + rot(X[2]) @ (obj.local(x).point - d * obj.local(x).normal) for x, d in zip(xi, lifts)])
    q = hand.inverse_kinematics(tips)
    v, V = rng.normal(size=6) * 2.0, rng.normal(size=3) * [0.2, 0.2, 3.0]
    qdd, Xdd = rng.normal(size=6) * 20.0, rng.normal(size=3) * [2.0, 2.0, 30.0]
    plant = Plant(hand, obj, [PlantContact(0, "sliding", x) for x in xi], friction=0.0, baumgarte=0.0,
                  collision_check=False)
    plant.reset(q, v, X, V)
    eq = plant.equations
    rows, rhs, _ = eq.rows(eq.pin_pass(plant.state.q, plant.state.v), eq.specs(plant.contacts), X.tolist(),
                           V.tolist())
    tip_acc = hand.jacobian(q) @ qdd
    psi_dd = np.array([d[1] * tip_acc[2 * d[0]] + d[2] * tip_acc[2 * d[0] + 1] + np.dot(d[3:], Xdd) - b
                       for d, b in zip(rows, rhs)])

    def feet(h):
        qh, Xh = q + v * h + 0.5 * qdd * h * h, X + V * h + 0.5 * Xdd * h * h
        t = hand.tip_positions(qh).reshape(-1, 2)
        return np.array([obj.project_floats(*(rot(Xh[2]).T @ (t[i] - Xh[:2])), xi[i]) for i in range(3)])

    def second(h):
        return -(feet(h)[:, 1] - 2 * feet(0.0)[:, 1] + feet(-h)[:, 1]) / h ** 2

    h = 5e-4
    fd = (4 * second(h / 2) - second(h)) / 3
    np.testing.assert_allclose(psi_dd, fd, rtol=0, atol=2e-8)  # (measured: 1.4e-9 at most, on values of 1 to 7)
    # the curvature term κ (T·u)² / (1 + κδ) that a straight edge's row lacks is far above that tolerance
    rel = [plant.contact_xi(plant.state, i) for i in range(3)]
    kappa = np.array([obj.local(x).curvature for x, _ in rel])
    delta = feet(0.0)[:, 1]
    term = kappa * (np.array([r[1] for r in rel]) * (1 + kappa * delta)) ** 2 / (1 + kappa * delta)
    assert term.max() > 0.1
    xi_dot = (4 * (feet(h / 4)[:, 0] - feet(-h / 4)[:, 0]) / (h / 2) - (feet(h / 2)[:, 0] - feet(-h / 2)[:, 0]) / h) / 3
    np.testing.assert_allclose([r[1] for r in rel], xi_dot, rtol=0, atol=1e-9)


# ---------------------------------------------------------------------------- 4. polygons unchanged
def _polygon_run(polygon: ConvexPolygon, compiled: bool) -> list[np.ndarray]:
    hand = Hand([c.finger for c in scenario().contacts[:2]], gravity_in_hand=(0.0, -9.81), damping=True)
    q = hand.inverse_kinematics(np.array([[-0.05, 0.121], [0.05, 0.119]]))
    plant = Plant(hand, polygon, [PlantContact(1, "sliding", 0.001), PlantContact(3, "fixed", 0.001)],
                  friction=[Friction(0.5, 0.3), Friction(0.8, 0.6)], compiled=compiled, stop_on=())
    plant.reset(q, np.zeros(4), X0, np.zeros(3))
    out = []
    for k in range(60):
        force = np.array([0.6 + 0.3 * np.sin(k / 30), 0.2 * np.cos(k / 20), -0.6, 0.5 * np.sin(k / 50)])
        step = plant.step(hand.jacobian(plant.state.q).T @ force)
        out += [step.state.flat(), step.forces_surface, step.xi, step.xi_dot, step.gap]
    assert plant.equations.curve is None and plant.kinks is None
    return out


@pytest.mark.parametrize("compiled", [False, True])
def test_a_polygon_plant_steps_bitwise_as_before(compiled):
    """``rounded(vertices, 0)`` is the polygon itself: the plant takes the polygon path, bitwise (the curve
    branches sit beside it; the suite's polygon tests hold the rest)."""
    box = ConvexPolygon.rectangle(0.1, 0.04, mass=0.08)
    same = rounded(box.vertices, 0.0, mass=0.08)
    assert type(same) is ConvexPolygon
    for a, b in zip(_polygon_run(box, compiled), _polygon_run(same, compiled)):
        assert a.tobytes() == b.tobytes()


# ---------------------------------------------------------------------------- 5. errors and validation
def test_a_curved_object_refuses_the_compiled_kernel_and_other_faces():
    obj = curve("disc")
    with pytest.raises(InvalidParameterError, match="curved object"):
        start(obj, compiled=True)
    assert not start(obj, compiled=None).compiled
    with pytest.raises(UnknownEdgeError):
        start(obj, xi=grip(obj)).reset(np.zeros(6), np.zeros(6), X0, np.zeros(3),
                                       contacts=[PlantContact(1, "fixed", 0.0)] * 3)
    plant = start(obj, modes=("fixed",) * 3, xi=[g + 7 * obj.perimeter for g in grip(obj)])  # any finite ξ
    assert plant.constraint_error(plant.state) < 1e-12
    with pytest.raises(InvalidParameterError):
        plant.kernel.contact_records(plant.contacts)  # the kernel has straight edges only


def test_collision_shapes_of_curves():
    """The links are checked against the curve's own coal shape: the disc's exact cylinder; an ellipse's hull has
    too many vertices for coal at the curve's tolerance and falls back to a coarser circumscribed polygon."""
    assert isinstance(start(curve("disc")).checkers[0].object_geometry, coal.Cylinder)
    plant = start(curve("ellipse"))
    assert plant.checkers is not None
    assert [e.kind for e in plant.step(squeeze(plant)).events] == []


# ---------------------------------------------------------------------------- 6. reports and events on curves
def test_gap_surface_forces_and_separation_on_a_disc():
    """Every contact's forces are in its foot's frame (normal along the inward radius); pulling finger 2 away
    separates it (and unloads the palm, which lets go too), and a separated contact's gap is its tip's distance
    from the disc, |p_o| - r."""
    obj = curve("disc")
    plant = start(obj, friction=(1.0, 1.0, 1.0), modes=("fixed",) * 3, stop_on=())
    tau = squeeze(plant, surplus=-MU)  # (no slide)
    st = plant.state
    tips = plant.hand.tip_positions(st.q).reshape(-1, 2)
    _, _, forces = plant.accelerations(st, tau)
    surface = plant.surface_forces(st, forces)
    for i in range(3):
        inward = (st.X[:2] - tips[i]) / np.linalg.norm(st.X[:2] - tips[i])
        own = [forces[i] @ inward, forces[i] @ np.array([-inward[1], inward[0]])]
        assert surface[i] == pytest.approx(own, abs=1e-12) and surface[i][0] > 0.1
    pull = plant.hand.jacobian(st.q).T @ np.array([0, 0, 3.0, 0, 0, 0])  # finger 2 pulled right
    step = plant.step(tau + pull)
    assert [(e.kind, e.contact) for e in step.events] == [("separation", "finger2"), ("separation", "palm")]
    for _ in range(5):
        step = plant.step(tau + pull)
    st = step.state
    tips = plant.hand.tip_positions(st.q).reshape(-1, 2)
    np.testing.assert_allclose(step.gap[1:], np.linalg.norm(tips[1:] - st.X[:2], axis=1) - obj.radius, atol=1e-12)
    assert step.gap[0] == 0.0 and step.gap[1] > 5e-4
    assert step.forces_surface[1:] == pytest.approx(np.zeros((2, 2)), abs=1e-15)


def test_a_slip_then_a_slide_round_the_disc_never_leaves_its_edge():
    """A fixed contact pushed tangentially beyond μ_s slips, then slides (its ξ followed, no left_edge event)."""
    obj = curve("disc")
    plant = start(obj, modes=("fixed",) * 3, friction=(0.2, 1.0, 1.0), stop_on=())
    events = []
    for _ in range(100):
        events += [(e.kind, e.contact) for e in plant.step(squeeze(plant, surplus=0.3)).events]
    assert events[0] == ("slip", "finger1") and ("left_edge", "finger1") not in events
    assert plant.contacts[0].mode is ContactMode.SLIDING
    assert plant.contacts[0].xi == pytest.approx(plant.contact_xi(plant.state, 0)[0], abs=1e-15)
    assert plant.max_constraint_error < 1e-8  # (a fast slide: some 0.1 m/s)


def test_pads_on_a_curve_push_along_the_foots_normal():
    """With pads: each pad's depth is -δ + δ_0 (the tip's signed distance from the disc) and a slider's force is
    k δ + c δ̇ along the foot's normal plus μ_k times that along its tangent; a short squeeze keeps all three."""
    obj = curve("disc")
    pad = Pad(stiffness=2e3, damping=5.0, preload=0.5)
    plant = start(obj, pad=pad, stop_on=())
    for _ in range(20):
        step = plant.step(squeeze(plant))
    assert [c.mode for c in plant.contacts] == list(MODES)
    st, eq = plant.state, plant.equations
    fingers = eq.pin_pass(st.q, st.v)
    tips = plant.hand.tip_positions(st.q).reshape(-1, 2)
    depth = {i: d for i, d, *_ in eq.depths(eq.specs(plant.contacts), st.X.tolist(), st.V.tolist(), fingers)}
    for i in range(3):
        assert depth[i] == pytest.approx(obj.radius - np.linalg.norm(tips[i] - st.X[:2]) + pad.preload_depth,
                                         abs=1e-12)
    _, _, forces = plant.accelerations(st, squeeze(plant))
    fn, ft = plant.surface_forces(st, forces)[0]
    assert ft == pytest.approx(MU * fn, rel=1e-12) and fn > 0
    assert np.isfinite(step.state.flat()).all() and step.gap.max() < 0

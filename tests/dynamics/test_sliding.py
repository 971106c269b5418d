"""When can a contact slide? ``regrasp.dynamics.sliding.sliding_feasibility`` (paper Remark 3.3).

The oracle here is written from the physics, not from the library's matrices: contact points,
surface frames and the grasp matrix are rebuilt from the polygon's edge data (inward normal,
ξ direction, ξ origin) and the pose; the object's equation is
:math:`\\sum_i f_i = m(a - g)`, :math:`\\sum_i r_i \\times f_i = I\\alpha`, and a contact j sliding in
direction s has :math:`t_j \\cdot f_j = s\\mu_{k,j}\\, n_j \\cdot f_j` (the fingertip drags the object
along its sliding direction, with its kinetic coefficient) while the fixed contacts stay inside
their static cones, :math:`|t_i \\cdot f_i| \\le (\\mu_{s,i} - \\text{margin})\\, n_i \\cdot f_i`.

* m = 2: those four equations fix f; the slide is possible iff every normal force ≥ f_min and
  the fixed contact is inside its (margin-reduced) cone. Checked on seeded random poses,
  contact positions, gravity vectors, accelerations, directions, μ (scalar and per contact; half
  the cases with μ_k < μ_s) and margins, on the paper's rectangle and on random convex polygons.
* m = 3: possible ⇔ an LP (HiGHS) that maximises the smallest constraint slack finds a positive
  one; when possible, the library's forces are checked against the equations and constraints
  and against the least-norm force distribution found by enumerating active sets.
* Figure 3.4: the paper's rectangle held against gravity by its two side fingers, finger 2
  7.5 mm above the centre and finger 1 7.5 mm below: finger 1 can slide up, not down; the
  closed loop on the full-coordinate plant agrees.
* μ_s ≠ μ_k: a hold where the slide is possible only with the slider at μ_k and the holder's cone
  at μ_s (closed form), and the supervisor's ``edge_mu``.
"""

from __future__ import annotations

import functools
import itertools
from pathlib import Path

import numpy as np
import pytest
import scipy.optimize

from factories import random_polygon
from regrasp import Friction, Grasp, Hand, Plant, PlantContact, ReducedModel, load_scenario
from regrasp.core.exceptions import InvalidParameterError
from regrasp.dynamics.control import Gains
from regrasp.dynamics.internal_force.settings import InternalForceSettings
from regrasp.dynamics.internal_force.solver import InternalForceSolver
from regrasp.dynamics.laws import Proposition3Controller
from regrasp.dynamics.sliding import SlideFeasibility, sliding_feasibility
from regrasp.plants.closed_loop import run_closed_loop

ROOT = Path(__file__).resolve().parents[2]
SCENARIO = ROOT / "examples" / "scenarios" / "paper_trajectory_2.toml"
G0 = 9.81
AMBIGUOUS = 1e-6  # [N]: cases this close to the feasibility boundary are not judged


@functools.lru_cache(maxsize=None)
def scenario():
    return load_scenario(SCENARIO)


def rectangle():
    return scenario().polygon


# ---------------------------------------------------------------------------- own geometry
def rot(beta: float) -> np.ndarray:
    c, s = np.cos(beta), np.sin(beta)
    return np.array([[c, -s], [s, c]])


def contact_geometry(polygon, edges, pose, xi):
    """Per contact: lever arm r_i (hand frame, from the centre of mass), inward normal n_i and ξ
    direction t_i (hand frame), from the edges' data only."""
    R = rot(pose[2])
    r, n, t = [], [], []
    for k, x in zip(edges, xi):
        e = polygon.edge(k)
        r.append(R @ (np.asarray(e.xi_origin) + x * np.asarray(e.xi_direction)))
        n.append(R @ np.asarray(e.inward_normal))
        t.append(R @ np.asarray(e.xi_direction))
    return np.array(r), np.array(n), np.array(t)


def object_equation(r):
    """(3, 2m): f -> (Σ f_i, Σ r_i × f_i)."""
    m = len(r)
    E = np.zeros((3, 2 * m))
    for i in range(m):
        E[0, 2 * i] = E[1, 2 * i + 1] = 1.0
        E[2, 2 * i], E[2, 2 * i + 1] = -r[i][1], r[i][0]
    return E


def slide_system(polygon, edges, pose, xi, acc, gravity, mass, inertia, j, s, mu):
    """[object equation; friction law of contact j] f = [m(a - g), I α; 0]."""
    r, n, t = contact_geometry(polygon, edges, pose, xi)
    m = len(edges)
    row = np.zeros(2 * m)
    row[2 * j:2 * j + 2] = t[j] - s * mu[j] * n[j]
    system = np.vstack([object_equation(r), row])
    rhs = np.array([mass * (acc[0] - gravity[0]), mass * (acc[1] - gravity[1]), inertia * acc[2], 0.0])
    return system, rhs, n, t


def surface_of(forces, n, t):
    forces = np.asarray(forces).reshape(len(n), 2)
    return np.stack([[n[i] @ forces[i], t[i] @ forces[i]] for i in range(len(n))])


def slacks(surface, j, mu, f_min, margin):
    """Slack of every constraint (>= 0: holds): n_i >= f_min for all, fixed cones for i != j."""
    out = []
    for i, (fn, ft) in enumerate(surface):
        out.append(fn - f_min)
        if i != j:
            out.append((mu[i] - margin) * fn - abs(ft))
    return np.array(out)


def call(polygon, edges, pose, xi, acc, j, s, mu, gravity, mass, inertia, settings=None) -> SlideFeasibility:
    kwargs = {} if settings is None else {"settings": settings}
    grasp = Grasp(polygon, edges, ["fixed"] * len(edges))  # modes are ignored by the predicate
    return sliding_feasibility(grasp, pose, xi, acc, j, s, mu, object_mass=mass, object_inertia=inertia,
                               gravity_in_hand=gravity, **kwargs)


# ---------------------------------------------------------------------------- random cases
def random_slide_case(seed: int, m: int):
    rng = np.random.default_rng(seed)
    if rng.random() < 0.7:
        polygon = rectangle()
        mass, inertia = polygon.mass, polygon.inertia
        # mostly the paper's grasps (opposite sides, plus the bottom for m = 3), sometimes any edges
        edges = list(rng.permutation(4)[:m]) if rng.random() < 0.3 else [[1, 3, 2], [0, 2, 1]][seed % 2][:m]
    else:
        polygon = random_polygon(rng, rng.uniform(0.05, 0.2))
        edges = list(rng.permutation(polygon.n_vertices)[:m])
        mass, inertia = rng.uniform(0.02, 0.5), rng.uniform(1e-5, 1e-3)
    edges = [int(e) for e in edges]
    xi = np.array([rng.uniform(*polygon.edge(k).xi_range) for k in edges])
    pose = np.array([rng.uniform(-0.1, 0.1), rng.uniform(0.0, 0.2), rng.uniform(-np.pi, np.pi)])
    angle = rng.uniform(-np.pi, np.pi)
    gravity = rng.uniform(0.0, 1.2) * G0 * np.array([np.cos(angle), np.sin(angle)])
    acc = np.concatenate([rng.uniform(-3.0, 3.0, 2), [rng.uniform(-30.0, 30.0)]]) * rng.choice([0.0, 0.3, 1.0])
    j = int(rng.integers(m))
    s = float(rng.choice([-1.0, 1.0]))
    mu = rng.uniform(0.1, 1.2, m) if rng.random() < 0.5 else np.full(m, rng.uniform(0.1, 1.2))
    mu_arg = list(mu) if rng.random() < 0.5 or len(set(mu)) > 1 else float(mu[0])
    if rng.random() < 0.6:
        settings, f_min, margin = None, 0.0, 0.0  # the default: bare physics
    else:
        f_min, margin = rng.uniform(0.0, 0.5), rng.uniform(0.0, 0.08)
        settings = InternalForceSettings(f_min=f_min, friction_margin=margin)
    # half the cases: kinetic coefficients 30 to 100 % of the static ones (mu); the friction law of the
    # slider uses its μ_k, the fixed contacts' cones their μ_s
    kinetic = mu * rng.uniform(0.3, 1.0, m) if rng.random() < 0.5 else mu.copy()
    friction = mu_arg if np.array_equal(kinetic, mu) else [Friction(a, b) for a, b in zip(mu, kinetic)]
    return dict(polygon=polygon, edges=edges, pose=pose, xi=xi, acc=acc, j=j, s=s, mu=mu, kinetic=kinetic,
                friction=friction, gravity=gravity, mass=mass, inertia=inertia, settings=settings, f_min=f_min,
                margin=margin)


def run(case) -> SlideFeasibility:
    c = case
    return call(c["polygon"], c["edges"], c["pose"], c["xi"], c["acc"], c["j"], c["s"], c["friction"], c["gravity"],
                c["mass"], c["inertia"], c["settings"])


def system_of(case):
    c = case
    return slide_system(c["polygon"], c["edges"], c["pose"], c["xi"], c["acc"], c["gravity"], c["mass"],
                        c["inertia"], c["j"], c["s"], c["kinetic"])


def two_finger_verdict(case):
    """(my possible, my surface forces, smallest slack) for m = 2, or None if the system is singular."""
    system, rhs, n, t = system_of(case)
    if np.linalg.cond(system) > 1e8:
        return None
    f = np.linalg.solve(system, rhs)
    surface = surface_of(f, n, t)
    sl = slacks(surface, case["j"], case["mu"], case["f_min"], case["margin"])
    return bool(np.all(sl >= 0.0)), surface, float(sl.min())


TWO_FINGER_SEEDS = range(300)


def test_two_finger_slide_matches_the_square_system():
    """m = 2: the library's verdict and forces equal the unique solution of the 4 x 4 system."""
    outcomes = {True: 0, False: 0}
    judged = 0
    for seed in TWO_FINGER_SEEDS:
        case = random_slide_case(seed, 2)
        mine = two_finger_verdict(case)
        if mine is None:
            continue
        possible, surface, worst = mine
        result = run(case)
        scale = max(1.0, np.abs(surface).max())
        np.testing.assert_allclose(result.forces_surface, surface, rtol=0, atol=1e-9 * scale, err_msg=f"seed {seed}")
        np.testing.assert_allclose(result.normal_forces, surface[:, 0], rtol=0, atol=1e-9 * scale)
        # μ_s at the fixed contact, μ_k at the slider
        margin_mu = np.where(np.arange(2) == case["j"], case["kinetic"], case["mu"])
        np.testing.assert_allclose(result.cone_margins, margin_mu * surface[:, 0] - np.abs(surface[:, 1]),
                                   rtol=0, atol=1e-9 * scale)
        assert result.contact == case["j"] and result.direction == case["s"]
        if abs(worst) < AMBIGUOUS * scale:
            continue  # on the boundary: either verdict is right
        judged += 1
        assert result.possible == possible, (seed, surface, worst, result.reason)
        outcomes[possible] += 1
        if possible:
            assert result.reason is None
            assert abs(result.cone_margins[case["j"]]) <= 1e-9 * scale  # on the cone edge
        else:
            assert result.reason
            if surface[:, 0].min() < 0.0:
                assert "pull" in result.reason, (seed, result.reason)
            elif surface[:, 0].min() < case["f_min"]:
                assert "f_min" in result.reason, (seed, result.reason)
            else:
                assert "slip" in result.reason, (seed, result.reason)
    assert judged >= 250
    assert outcomes[True] >= 25 and outcomes[False] >= 25, outcomes


def test_two_finger_per_contact_mu_uses_each_contacts_coefficient():
    """The sliding contact uses its own μ in the friction law, the fixed one its own in the cone:
    swapping the coefficients changes the answer as the square system says."""
    polygon = rectangle()
    pose, xi = [0.0, 0.12, 0.0], [-0.0075, -0.0075]
    for mu in ([0.3, 0.3], [0.3, 0.9], [0.9, 0.3], [0.05, 0.6]):
        case = dict(polygon=polygon, edges=[1, 3], pose=np.array(pose), xi=np.array(xi), acc=np.zeros(3), j=0,
                    s=1.0, mu=np.array(mu), kinetic=np.array(mu), friction=mu, gravity=np.array([0.0, -G0]),
                    mass=polygon.mass, inertia=polygon.inertia, settings=None, f_min=0.0, margin=0.0)
        possible, surface, _ = two_finger_verdict(case)
        result = run(case)
        assert result.possible == possible, mu
        np.testing.assert_allclose(result.forces_surface, surface, rtol=0, atol=1e-9)
        # the sliding contact is exactly on its own cone edge
        assert result.forces_surface[0, 1] == pytest.approx(mu[0] * result.forces_surface[0, 0], abs=1e-12)


def test_a_slide_needs_the_slider_at_mu_k_and_the_holder_inside_mu_s():
    """Hand computation (the rectangle held at its vertical sides, no acceleration, x = ±0.05 m):
    finger 1 at height y1 = 0 slides up (t1 = +y) carrying t·f = μ_k N, finger 2 (fixed) at
    y2 = -7.5 mm. Forces balance with N1 = N2 = N, μ_k N - F2 = m g (F2 = t2·f2, finger 2's force
    along its ξ, t2 = -y) and moments -0.05 μ_k N - y1 N - 0.05 F2 + y2 N = 0, so
    N = 0.05 m g / (0.1 μ_k - (y2 - y1)) and finger 2 needs |F2| / N = 20 (y2 - y1) - μ_k in magnitude
    = 0.15 + μ_k. With μ_s = 0.6, μ_k = 0.3 on both tips: 0.45 <= 0.6, possible. Mixing them up fails
    both ways: the slider at μ_s needs 0.75 > 0.6, the holder's cone at μ_k allows 0.3 < 0.45. And
    ``edge_mu`` = μ_s + 0.05 (the supervisor's priming) needs 0.8: impossible, the holder would slip."""
    polygon = rectangle()
    weight = polygon.mass * G0
    grasp = Grasp(polygon, [1, 3], ["fixed", "fixed"])
    pose, xi = [0.0, 0.12, 0.0], [0.0, 0.0075]  # finger 2's ξ points down: ξ = 7.5 mm is y2 = -7.5 mm
    d = -0.0075

    def ask(friction, **kw):
        return sliding_feasibility(grasp, pose, xi, np.zeros(3), 0, 1.0, friction, object_mass=polygon.mass,
                                   object_inertia=polygon.inertia, gravity_in_hand=(0.0, -G0), **kw)

    def forces(mu_edge):
        n = 0.05 * weight / (0.1 * mu_edge - d)
        return n, np.array([[n, mu_edge * n], [n, mu_edge * n - weight]])  # F2 = μ N - m g

    result = ask(Friction(0.6, 0.3))
    n, expected = forces(0.3)
    assert result.possible and result.reason is None
    np.testing.assert_allclose(result.forces_surface, expected, rtol=1e-12, atol=1e-12)
    assert abs(result.forces_surface[1, 1]) / n == pytest.approx(0.45, rel=1e-12)
    # cone margins: μ_k at the slider (on its edge), μ_s at the holder
    np.testing.assert_allclose(result.cone_margins, [0.0, 0.6 * n - 0.45 * n], rtol=0, atol=1e-12)
    # the same tips with one coefficient: neither 0.3 nor 0.6 allows the slide
    for mu, why in ((0.3, "slip"), (0.6, "slip")):
        other = ask(mu)
        assert not other.possible and why in other.reason, (mu, other.reason)
    # the same slide asked at the priming's ratio μ_s + 0.05 = 0.65
    primed = ask(Friction(0.6, 0.3), edge_mu=0.65)
    n, expected = forces(0.65)
    assert not primed.possible and "fixed contact 1 would slip" in primed.reason
    np.testing.assert_allclose(primed.forces_surface, expected, rtol=1e-12, atol=1e-12)
    assert primed.cone_margins[0] == pytest.approx((0.3 - 0.65) * n, rel=1e-12)  # past its kinetic edge
    for bad in (-0.1, float("nan"), float("inf")):
        with pytest.raises(InvalidParameterError):
            ask(Friction(0.6, 0.3), edge_mu=bad)


# ---------------------------------------------------------------------------- m = 3
def max_slack(case):
    """max σ (<= 1) s.t. the slide's equations hold and every constraint has slack >= σ (LP)."""
    system, rhs, n, t = system_of(case)
    m, j, mu = 3, case["j"], case["mu"]
    rows = []  # a . f >= σ + lo  ->  -a . f + σ <= -lo
    for i in range(m):
        a = np.zeros(2 * m)
        a[2 * i:2 * i + 2] = n[i]
        rows.append((a, case["f_min"]))
        if i != j:
            for sgn in (1.0, -1.0):
                a = np.zeros(2 * m)
                a[2 * i:2 * i + 2] = (mu[i] - case["margin"]) * n[i] - sgn * t[i]
                rows.append((a, 0.0))
    A_ub = np.array([np.concatenate([-a, [1.0]]) for a, _ in rows])
    b_ub = np.array([-lo for _, lo in rows])
    A_eq = np.hstack([system, np.zeros((4, 1))])
    cost = np.zeros(2 * m + 1)
    cost[-1] = -1.0
    res = scipy.optimize.linprog(cost, A_ub=A_ub, b_ub=b_ub, A_eq=A_eq, b_eq=rhs,
                                 bounds=[(None, None)] * (2 * m) + [(None, 1.0)], method="highs")
    assert res.status == 0, res.message
    return float(res.x[-1]), rows, system, rhs


def least_norm_forces(rows, system, rhs):
    """Least-norm f with system f = rhs and every row a . f >= lo, by active-set enumeration
    (the optimum is the least-norm point of the equalities plus <= dim null(system) active rows)."""
    k = system.shape[1] - np.linalg.matrix_rank(system)
    scale = max(1.0, np.abs(rhs).max())
    best = None
    for r in range(k + 1):
        for subset in itertools.combinations(range(len(rows)), r):
            E = np.vstack([system] + [rows[i][0] for i in subset])
            b = np.concatenate([rhs, [rows[i][1] for i in subset]])
            f = np.linalg.lstsq(E, b, rcond=None)[0]
            if np.linalg.norm(E @ f - b) > 1e-9 * scale:
                continue
            if all(a @ f >= lo - 1e-10 * scale for a, lo in rows):
                if best is None or np.linalg.norm(f) < np.linalg.norm(best):
                    best = f
    return best


THREE_FINGER_SEEDS = range(10_000, 10_060)


def test_three_finger_slide_matches_a_brute_force_search():
    outcomes = {True: 0, False: 0}
    gaps = []
    for seed in THREE_FINGER_SEEDS:
        case = random_slide_case(seed, 3)
        sigma, rows, system, rhs = max_slack(case)
        result = run(case)
        _, _, n, t = system_of(case)
        scale = max(1.0, np.abs(rhs).max())
        if abs(sigma) < AMBIGUOUS * scale:
            continue
        possible = sigma > 0
        assert result.possible == possible, (seed, sigma, result.reason)
        outcomes[possible] += 1
        if not possible:
            assert result.reason and "squeeze" in result.reason, (seed, result.reason)
            # reported forces: the least-norm ones that move the object as asked (equations only)
            f_ls = np.linalg.lstsq(system, rhs, rcond=None)[0]
            np.testing.assert_allclose(result.forces_surface, surface_of(f_ls, n, t), rtol=0, atol=1e-9 * scale)
            continue
        assert result.reason is None
        f = np.concatenate([n_t_inverse(result.forces_surface[i], n[i], t[i]) for i in range(3)])
        np.testing.assert_allclose(system @ f, rhs, rtol=0, atol=1e-8 * scale)  # object equation + edge
        sl = slacks(result.forces_surface, case["j"], case["mu"], case["f_min"], case["margin"])
        assert sl.min() >= -1e-7 * scale, (seed, sl)
        assert abs(result.cone_margins[case["j"]]) <= 1e-8 * scale
        best = least_norm_forces(rows, system, rhs)
        assert best is not None
        gap = (np.linalg.norm(f) - np.linalg.norm(best)) / np.linalg.norm(best)
        gaps.append(gap)
        assert abs(gap) <= 1e-6, (seed, gap)
    assert sum(outcomes.values()) >= 30, outcomes
    assert outcomes[True] >= 8 and outcomes[False] >= 8, outcomes



def test_persistent_solver_gives_the_one_shot_verdicts():
    """``solver=``: the same QP on a persistent OSQP object; same verdicts and forces on the random
    cases of both sizes, and a solver with other settings is refused."""
    compared = 0
    for seed in THREE_FINGER_SEEDS:
        c = random_slide_case(seed, 3)
        one_shot = run(c)
        settings = c["settings"] or InternalForceSettings(f_min=0.0, friction_margin=0.0)  # the predicate's default
        grasp = Grasp(c["polygon"], c["edges"], ["fixed"] * 3)
        fast = sliding_feasibility(grasp, c["pose"], c["xi"], c["acc"], c["j"], c["s"], c["friction"],
                                   object_mass=c["mass"], object_inertia=c["inertia"], gravity_in_hand=c["gravity"],
                                   settings=settings, solver=InternalForceSolver(settings))
        assert fast.possible == one_shot.possible, seed
        scale = max(1.0, np.abs(one_shot.forces_surface).max())
        np.testing.assert_allclose(fast.forces_surface, one_shot.forces_surface, rtol=0, atol=1e-6 * scale)
        compared += 1
    assert compared == len(THREE_FINGER_SEEDS)
    with pytest.raises(InvalidParameterError, match="solver"):
        sliding_feasibility(grasp, c["pose"], c["xi"], c["acc"], c["j"], c["s"], c["friction"], object_mass=c["mass"],
                            object_inertia=c["inertia"], settings=InternalForceSettings(f_min=1.0),
                            solver=InternalForceSolver(InternalForceSettings(f_min=2.0)))

def n_t_inverse(surface_force, n, t):
    """Hand-frame force from its (normal, tangential) components."""
    return surface_force[0] * n + surface_force[1] * t


# ---------------------------------------------------------------------------- Figure 3.4
XI0 = -0.0075  # finger 1: 7.5 mm below the centre (ξ up); finger 2: 7.5 mm above (ξ down)
MU = 0.3


def figure_3_4(direction):
    polygon = rectangle()
    return call(polygon, [1, 3], [0.0, 0.12, 0.0], [XI0, XI0], [0.0, 0.0, 0.0], 0, direction, MU,
                (0.0, -G0), polygon.mass, polygon.inertia)


def test_figure_3_4_slide_up_possible_down_impossible():
    """Hand computation: n1 = n2 = n; moments about the centre give the fixed finger's upward
    force f2y = (s - 1) μ n; the weight gives s μ n + f2y = m g. Up (s = +1): n = m g / μ,
    finger 2 carries nothing tangentially. Down (s = -1): n = -m g / (3 μ) < 0, a pull."""
    weight = rectangle().mass * G0
    up = figure_3_4(+1)
    assert up.possible and up.reason is None
    n = weight / MU
    np.testing.assert_allclose(up.forces_surface, [[n, MU * n], [n, 0.0]], rtol=0, atol=1e-12)
    down = figure_3_4(-1)
    assert not down.possible
    n = -weight / (3 * MU)
    # finger 2's ξ points down: its upward force f2y = -2 μ n is the tangential component t2 = 2 μ n
    np.testing.assert_allclose(down.forces_surface, [[n, -MU * n], [n, 2 * MU * n]], rtol=0, atol=1e-12)
    assert "pull" in down.reason


def closed_loop_slide(v0: float):
    """Proposition 3 on the plant: hold the object still, slide finger 1 at v0 for 0.3 s."""
    polygon = rectangle()
    hand = Hand([c.finger for c in scenario().contacts], gravity_in_hand=(0.0, -G0))
    model = ReducedModel(hand, Grasp(polygon, [1, 3], ["sliding", "fixed"]), xi=[XI0, XI0])
    controller = Proposition3Controller(model, Gains.critically_damped(20.0, 4), friction=MU)
    sign = float(np.sign(v0))
    plant = Plant(hand, polygon, [PlantContact(1, "sliding", XI0, sign), PlantContact(3, "fixed", XI0)], friction=MU)
    S = np.array([0.0, 0.12, 0.0, XI0])
    S_dot = np.array([0.0, 0.0, 0.0, v0])
    st = model.state(S, S_dot)
    plant.reset(st.q, st.q_dot, S[:3], S_dot[:3])

    def reference(t):
        return np.array([0.0, 0.12, 0.0, XI0 + v0 * t]), np.array([0.0, 0.0, 0.0, v0]), np.zeros(4)

    return run_closed_loop(plant, controller, reference, 0.3)


def test_figure_3_4_plant_slides_up():
    log = closed_loop_slide(+0.005)
    assert log.events == ()
    assert not log.stopped
    assert len(log.times) == 300
    err = np.abs(log.errors).max(axis=0)
    assert err[3] < 1e-4, err  # ξ [m]
    assert err[0] < 1e-4 and err[1] < 1e-4, err  # object position [m]
    assert err[2] < 1e-3, err  # object orientation [rad]
    # the plant's forces at the start are the predicate's; both contacts keep pushing throughout
    # and the fixed one stays inside its cone
    np.testing.assert_allclose(log.plant_forces[0], figure_3_4(+1).forces_surface, rtol=1e-6, atol=1e-9)
    assert log.plant_forces[:, :, 0].min() > 0.0
    assert log.cone_margins[:, 1].min() > 0.0
    assert log.S[-1, 3] == pytest.approx(XI0 + 0.005 * log.times[-1], abs=1e-4)


def test_figure_3_4_plant_cannot_slide_down():
    log = closed_loop_slide(-0.005)
    kinds = {e.kind for e in log.events}
    assert kinds & {"separation", "slip"}, log.events
    # what breaks the grasp is the pull the predicate predicted
    np.testing.assert_allclose(log.plant_forces[0], figure_3_4(-1).forces_surface, rtol=1e-6, atol=1e-9)
    assert log.plant_forces[0, :, 0].max() < 0.0


def test_figure_3_4_png(tmp_path):
    """The Figure 3.4 reproduction as a picture: both panels drawn from the predicate's verdicts."""
    import numpy as np

    from regrasp import Grasp, load_scenario
    from regrasp.dynamics.plotting import plot_slide_feasibility
    from regrasp.dynamics.sliding import sliding_feasibility

    root = __import__("pathlib").Path(__file__).resolve().parents[2]
    sc = load_scenario(root / "examples" / "scenarios" / "paper_trajectory_2.toml")
    pose, xi = np.array([0.0, 0.12, 0.0]), np.array([-0.0075, -0.0075])
    grasp = Grasp(sc.polygon, [1, 3], ["fixed", "fixed"])
    results = [sliding_feasibility(grasp, pose, xi, np.zeros(3), 0, d, 0.3, object_mass=sc.polygon.mass,
                                   object_inertia=sc.polygon.inertia) for d in (1, -1)]
    assert [r.possible for r in results] == [True, False]
    path = plot_slide_feasibility(sc.polygon, pose, [c.finger for c in sc.contacts], grasp.points(pose, xi), [1, 3],
                                  [0.3, 0.3], results, tmp_path / "figure_3_4.png")
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 20_000


def test_two_equal_friction_fingers_cannot_slide_with_gravity_along_trajectory_2():
    """A consequence of Remark 3.3 that the regrasp issue depends on: holding the paper's rectangle at
    its vertical sides with one μ on both tips, no finger can ever slide in the direction of gravity
    (the holder would have to carry the weight plus the slider's drag, mg + μλ, with only μλ of
    friction), at any time of trajectory 2, any contact positions and any μ; while the envelope of
    trajectory 2 makes every finger move both up and down within each period."""
    import numpy as np

    from regrasp import Grasp, load_scenario, plan_scenario
    from regrasp.dynamics.sliding import sliding_feasibility

    root = __import__("pathlib").Path(__file__).resolve().parents[2]
    sc = load_scenario(root / "examples" / "scenarios" / "paper_trajectory_2.toml")
    grasp = Grasp(sc.polygon, [1, 3], ["fixed", "fixed"])
    traj = sc.trajectory
    grid = np.linspace(-0.019, 0.019, 5)
    for gravity, with_g in (((0.0, -9.81), (-1, +1)), ((0.0, 9.81), (+1, -1))):  # ξ points up on edge 1, down on edge 3
        for mu in (0.3, 0.8, 1.2):
            for t in np.linspace(0.0, traj.t_end, 9):
                for x1 in grid:
                    for x2 in grid:
                        for i in (0, 1):
                            r = sliding_feasibility(grasp, traj.pose(t), [x1, x2], traj.acceleration(t), i, with_g[i],
                                                    mu, object_mass=sc.polygon.mass, object_inertia=sc.polygon.inertia,
                                                    gravity_in_hand=gravity)
                            assert not r.possible
    # ... but each finger's envelope needs moves of >= 10 mm both ways within a period
    plan = plan_scenario(sc, samples=201)
    for f in plan.fingers:
        lo = np.array([s.feasible[0][0] for s in f.samples])
        hi = np.array([s.feasible[-1][1] for s in f.samples])
        rise = max(lo[j] - hi[i] for i in range(len(lo)) for j in range(i + 1, len(lo)))
        fall = max(lo[i] - hi[j] for i in range(len(lo)) for j in range(i + 1, len(lo)))
        assert rise > 0.009 and fall > 0.009

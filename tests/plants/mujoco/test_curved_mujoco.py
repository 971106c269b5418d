"""The MuJoCo plant on curved objects (:mod:`regrasp.core.curves`; :mod:`regrasp.plants.mujoco.curve_mesh`,
:mod:`regrasp.plants.sphere_sensing`): a disc, a rounded box and an ellipse between two fingers of
``urdf/planar_2r_finger.urdf``.

The model compiles with the curve as ``hull`` and its erosion by r − contact_depth as ``object`` (cylinders for the
disc, meshes within their sagitta otherwise); tips placed on the curve by inverse kinematics start touching at
contact_depth, where the plant measures them; constant squeeze torques hold each object; a finger pushed past its
friction cone slides across ξ = 0 (= P) on the disc with a continuous ξ whose rate is the finite difference of ξ and
whose slip is MuJoCo's own relative velocity of the material points at the contact; ξ̇ is dξ/dt to 1e-6 along a
prescribed smooth motion off the curve; and a tip larger than the curve's smallest radius of curvature is refused.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from curved_hands import ARC0, CASES, DISC, FINGERS, HAND, in_hand, polygon_distance, rotation

mujoco = pytest.importorskip("mujoco")

from regrasp import PlantContact  # noqa: E402
from regrasp.core.contact import Friction  # noqa: E402
from regrasp.core.curves import Disc, Ellipse  # noqa: E402
from regrasp.core.events import EventKind  # noqa: E402
from regrasp.core.exceptions import InvalidParameterError  # noqa: E402
from regrasp.model.scenario import scenario_from_document  # noqa: E402
from regrasp.plants.mujoco.curve_mesh import MESH_SAGITTA  # noqa: E402
from regrasp.plants.mujoco.mjcf import MujocoSettings, build_mjcf, scenario_to_mjcf  # noqa: E402
from regrasp.plants.mujoco.plant import MujocoPlant  # noqa: E402
from regrasp.plants.project.state import PlantState  # noqa: E402

ROOT = Path(__file__).resolve().parents[3]
SETTINGS = MujocoSettings()
R_TIP, DEPTH = SETTINGS.tip_radius, SETTINGS.contact_depth
_ARC0 = ARC0


def placed(curve, X, xis, **kwargs):
    """A plant whose tips are put on the curve's points at ξ (object at X) by inverse kinematics, at rest."""
    plant = MujocoPlant(HAND, curve, [PlantContact(0, "fixed", xi) for xi in xis], **kwargs)
    q = np.concatenate([f.inverse_kinematics(in_hand(X, curve.local(xi).point)) for f, xi in zip(FINGERS, xis)])
    plant.reset(q, np.zeros(4), np.array(X), np.zeros(3))
    return plant


def squeeze(curve, st, xis, normal: float, tangential=(0.0, 0.0)) -> np.ndarray:
    """Joint torques Jᵀf with f = normal · N + tangential · T at each contact's ξ (hand frame): the fingers push so."""
    rot = rotation(st.X[2])
    out = []
    for i, finger in enumerate(FINGERS):
        sp = curve.local(xis[i])
        force = normal * (rot @ sp.normal) + tangential[i] * (rot @ sp.tangent)
        out.append(finger.tip_jacobian(st.q[2 * i:2 * i + 2]).T @ force)
    return np.concatenate(out)


def tip_contacts(plant) -> dict[int, int]:
    """Finger -> index of its tip's contact in ``plant.data`` (mj_forward'ed)."""
    model, data = plant.model, plant.data
    tips = {model.geom(g).id: i for i, g in enumerate(plant.mjcf.tip_geoms)}
    obj = model.geom(plant.mjcf.object_geom).id
    out = {}
    for j in range(data.ncon):
        g1, g2 = data.contact.geom[j]
        if g1 in tips and g2 == obj:
            out[tips[g1]] = j
    return out


# ---------------------------------------------------------------------------- the model
@pytest.mark.parametrize("name", CASES)
def test_the_model_has_the_curve_and_its_erosion(name):
    """Disc: cylinders of R and R − r + depth. Others: meshes whose vertices lie on the curve (``hull``) and on its
    parallel curve r − depth inside (``object``), within single precision, and whose chords stay within the
    sagitta: every point of a dense sampling of the curve is that close to the hull's polygon."""
    curve, X, _, _ = CASES[name]
    built = build_mjcf(FINGERS, curve, [Friction(0.5)] * 2)
    model = built.spec.compile()
    data = mujoco.MjData(model)
    for joint, x in zip(built.object_joints, X):
        data.qpos[model.joint(joint).qposadr[0]] = x
    mujoco.mj_kinematics(model, data)
    assert model.body("object").mass[0] == pytest.approx(curve.mass)
    assert model.body("object").inertia[2] == pytest.approx(curve.inertia)
    if isinstance(curve, Disc):
        assert built.sagitta == (0.0, 0.0)
        for geom, radius in (("hull", curve.radius), ("object", curve.radius - R_TIP + DEPTH)):
            g = model.geom(geom)
            assert g.type[0] == mujoco.mjtGeom.mjGEOM_CYLINDER and g.size[0] == pytest.approx(radius, abs=1e-15)
        return
    assert 0.0 < max(built.sagitta) <= MESH_SAGITTA
    back = rotation(X[2]).T
    for geom, depth in (("hull", 0.0), ("object", R_TIP - DEPTH)):
        g = model.geom(geom)
        assert g.type[0] == mujoco.mjtGeom.mjGEOM_MESH
        mesh = model.mesh(g.dataid[0])
        local = model.mesh_vert[mesh.vertadr[0]:mesh.vertadr[0] + mesh.vertnum[0]].astype(float)
        world = local @ data.geom_xmat[g.id].reshape(3, 3).T + data.geom_xpos[g.id]
        pts = (world[:, :2] - X[:2]) @ back.T  # object frame
        xi, delta = curve.project(pts)
        np.testing.assert_allclose(delta, -depth, atol=1e-8)  # (single-precision vertices)
        if geom == "hull":
            order = np.argsort(xi % curve.perimeter)[::2]  # (each point twice: the prism's two faces)
            dense_xi = np.linspace(0.0, curve.perimeter, 20000, endpoint=False)
            gap = polygon_distance(pts[order], xi[order] % curve.perimeter, curve.points(dense_xi), dense_xi)
            assert gap.max() <= built.sagitta[1] + 1e-8
            print(f"{name}: {len(order)} hull points, sagitta {built.sagitta[1]:.3g} m, the curve at most "
                  f"{gap.max():.3g} m from the hull")


def test_a_curved_scenario_writes_mjcf_that_loads_back():
    document = tomllib.loads((ROOT / "examples" / "scenarios" / "paper_trajectory_2.toml").read_text())
    document["object"] = {"shape": "disc", "radius": 0.04, "mass": 0.1}
    for finger in document["fingers"]:
        finger["edge"] = 0
    scenario = scenario_from_document(document, ROOT / "examples" / "scenarios" / "disc.toml")
    model = mujoco.MjModel.from_xml_string(scenario_to_mjcf(scenario))
    assert model.npair == 2 and model.geom("hull").size[0] == pytest.approx(0.04)


def test_a_tip_larger_than_the_smallest_radius_of_curvature_is_refused():
    thin = Ellipse(0.05, 0.005, mass=0.05)  # radius of curvature b²/a = 0.5 mm at the ends of the major axis
    for radius in (1e-3, 5.02e-4):
        with pytest.raises(InvalidParameterError, match=r"tip_radius.*smallest radius of curvature \(0\.0005 m\)"):
            build_mjcf(FINGERS, thin, [Friction(0.5)] * 2, settings=MujocoSettings(tip_radius=radius))
    with pytest.raises(InvalidParameterError, match="tip_radius"):
        MujocoPlant(HAND, thin, [PlantContact(0, "fixed")] * 2, settings=MujocoSettings(tip_radius=1e-3))


# ---------------------------------------------------------------------------- placed tips
@pytest.mark.parametrize("name", CASES)
def test_tips_placed_on_the_curve_touch_at_the_contact_depth_and_measure_their_xi(name):
    curve, X, _, xis = CASES[name]
    plant = placed(curve, X, xis)
    contacts = tip_contacts(plant)
    assert sorted(contacts) == [0, 1]
    links = [plant.model.geom(n).id for ls in plant.mjcf.link_geoms for n, _ in ls]
    assert not any(g in links for g in plant.data.contact.geom[:plant.data.ncon].ravel())
    # the mesh's chords bring its surface up to its sagitta closer to the tip than the curve's erosion is
    tol = 1e-12 if isinstance(curve, Disc) else plant.mjcf.sagitta[0] + 1e-8
    depths = [-plant.data.contact.dist[contacts[i]] for i in range(2)]
    np.testing.assert_allclose(depths, DEPTH, atol=tol)
    measured = [plant.contacts[i].xi for i in range(2)]  # (measured at reset, continued from the placed ξ)
    np.testing.assert_allclose(measured, xis, rtol=0.0, atol=1e-9)
    step = plant.step(np.zeros(4))  # and the plant reports the same (the tips barely moved in 1 ms)
    np.testing.assert_allclose(step.xi, xis, atol=1e-6)
    assert plant.constraint_error(plant.state) < 1e-5
    print(f"{name}: depths {depths} m, xi error {np.subtract(measured, xis).tolist()} m")


# ---------------------------------------------------------------------------- holding
@pytest.mark.parametrize("name", CASES)
def test_constant_squeeze_torques_hold_the_object(name):
    """Gravity off; each finger pushes 2 N along the normal at its contact, with the torques of the start held
    throughout. (A two-finger squeeze with constant torques is an unstable equilibrium of the rolling mode, the
    object turning between the tips: a mesh's facet normals, up to √(2 s κ) off the curve's, seed it, and the
    ellipse turns by about 0.02 rad in 0.2 s; every contact still carries its force and none slips.)"""
    curve, X, xis, _ = CASES[name]
    plant = placed(curve, X, xis)
    tau = squeeze(curve, plant.state, xis, 2.0)
    normal = []
    for _ in range(200):
        step = plant.step(tau)
        assert not step.events and all(m.value == "fixed" for m in step.modes)
        normal.append(step.forces_surface[:, 0])
        assert abs(step.forces_surface[:, 1]).max() < 0.05
    normal = np.array(normal)
    moved = plant.state.X - np.array(X)
    print(f"{name}: normal forces {normal.min():.4f}..{normal.max():.4f} N, object moved {moved.tolist()}, "
          f"xi moved {(step.xi - np.array(xis)).tolist()} m")
    assert normal.min() > 1.9 and normal.max() < 2.1
    assert np.abs(moved[:2]).max() < 1e-4 and abs(moved[2]) < 0.05
    assert np.abs(step.xi - np.array(xis)).max() < 2e-5


# ---------------------------------------------------------------------------- sliding
@pytest.fixture(scope="module")
def disc_slide():
    """Finger 1 starts 2 mm before the disc's top (ξ = P − 2 mm, its left side: the disc is turned by 90°) and
    pushes 2 N along the normal and 1.05 N along t, past μ f_n = 1 N, so it slides up across ξ = P; finger 2 only
    pushes. The object is heavy (5 kg, 0.05 kg m²) so that the finger, not the disc, moves. Control step = MuJoCo's
    step, so that ξ can be compared with ξ̇ step by step. Each step: (ξ, ξ̇, slip, step), and the slip's check
    against MuJoCo's contact velocity where the tip touches at the step's end."""
    period = DISC.perimeter
    X = np.array([0.0, 0.12, math.pi / 2])
    xis = [period - 0.002, 0.5 * period]
    plant = placed(DISC, X, xis, object_mass=5.0, object_inertia=0.05, dt=1e-4)
    rows, checks = [], []
    xi = list(xis)
    for _ in range(450):
        step = plant.step(squeeze(DISC, plant.state, xi, 2.0, (1.05, 0.0)))
        xi = step.xi.tolist()
        rows.append((step.state.t, step.xi[0], step.xi_dot[0], step.slip[0], step))
        contact = tip_contacts(plant).get(0)
        if contact is not None:  # the slip velocity now, from the measurement, against MuJoCo's
            checks.append((instant_slip(plant, step), mujoco_slip(plant, contact)))
    return plant, rows, checks


def instant_slip(plant, step) -> float:
    r"""s = (1 + κδ) ξ̇ + r φ̇ (:mod:`regrasp.plants.sphere_sensing`), φ̇ = ω_tip − ω."""
    vel = np.empty(6)
    mujoco.mj_objectVelocity(plant.model, plant.data, mujoco.mjtObj.mjOBJ_SITE, plant.model.site(
        plant.mjcf.tip_sites[0]).id, vel, 0)
    kappa = DISC.local_floats(step.xi[0])[4]
    return (1.0 + kappa * step.gap[0]) * step.xi_dot[0] + R_TIP * (vel[2] - step.state.V[2])


def mujoco_slip(plant, contact: int) -> float:
    """The tip's material point's velocity relative to the object's at MuJoCo's contact, along the curve's T there:
    MuJoCo's constraint velocity (the object's point relative to the tip's: geom 2 less geom 1), negated."""
    data = plant.data
    con = data.contact[contact]
    adr = con.efc_address
    frame = con.frame.reshape(3, 3)
    relative = data.efc_vel[adr + 1] * frame[1] + data.efc_vel[adr + 2] * frame[2]  # (elliptic: rows n, t1, t2)
    normal = frame[0, :2]  # (from geom 1, the tip, into geom 2, the object: the inward normal N)
    return -float(relative[:2] @ np.array([-normal[1], normal[0]]))


def test_a_finger_pushed_past_its_cone_slides_across_xi_zero_continuously(disc_slide):
    plant, rows, _ = disc_slide
    period = DISC.perimeter
    t, xi, xi_dot, slip = (np.array([r[k] for r in rows]) for k in range(4))
    steps = np.diff(xi)
    print(f"disc slide: xi - P from {xi[0] - period:.6f} to {xi[-1] - period:.6f} m in {t[-1]:.3f} s, largest step "
          f"{np.abs(steps).max():.3g} m, xi_dot up to {xi_dot.max():.3f} m/s")
    assert xi[0] < period < xi[-1] and xi[-1] - period > 1e-3  # across the top, and ξ stays above P (no wrap to 0)
    assert np.abs(steps).max() < 1e-4 and steps.min() > -1e-6  # continuous (at most 0.1 mm per 0.1 ms), upwards
    events = [e for r in rows for e in r[4].events]
    assert events and events[0].kind is EventKind.SLIP and events[0].contact == "finger1"
    assert rows[-1][4].modes[0].value == "sliding" and not plant.stopped
    assert np.all(slip[5:] > 0.0)


def test_the_sliding_xi_dot_is_the_finite_difference_of_xi(disc_slide):
    """One MuJoCo step per control step, semi-implicit: q_{k+1} = q_k + h v_{k+1}, so (ξ_{k+1} − ξ_k)/h is ξ̇ at
    the step's end up to the kinematics' curvature over the step (h |v| / l ≈ 1e-4)."""
    _, rows, _ = disc_slide
    t, xi, xi_dot = (np.array([r[k] for r in rows]) for k in range(3))
    moving = xi_dot[1:] > 0.02
    difference = np.diff(xi) / np.diff(t)
    rel = np.abs(difference - xi_dot[1:])[moving] / xi_dot[1:][moving]
    print(f"disc slide: |finite difference - xi_dot| / xi_dot median {np.median(rel):.3g}, max {rel.max():.3g} "
          f"over {moving.sum()} steps")
    assert moving.sum() > 300 and np.median(rel) < 1e-4 and rel.max() < 1e-3


def test_the_slip_is_the_relative_velocity_of_the_material_points_at_the_contact(disc_slide):
    _, _, checks = disc_slide
    ours, theirs = np.array(checks).T
    err = np.abs(ours - theirs)
    print(f"disc slide: slip (1 + kappa delta) xi_dot + r phi_dot against MuJoCo's contact velocity at {len(ours)} "
          f"steps: largest difference {err.max():.3g} m/s of up to {np.abs(theirs).max():.3g} m/s")
    # (r φ̇ is up to 1.3e-3 m/s here and the (1 + κδ) stretch 1e-5 m/s: without it the difference is 1.4e-5 m/s;
    # what is left is MuJoCo's contact point, half the 1 µm depth nearer the centre than r)
    assert len(ours) > 100 and err.max() < 1e-5


# ---------------------------------------------------------------------------- ξ̇ along a prescribed motion
@pytest.mark.parametrize("name", ["disc", "ellipse", "box"])
def test_xi_dot_is_the_time_derivative_of_xi_off_the_curve(name):
    """Tip 1 follows p_o(t) = c(ξ(t)) − δ(t) n(ξ(t)) (δ = 2 to 3 mm outside, ξ(t) = ξ₀ + 0.02 t crossing the curve's
    ξ = P on the disc and the ellipse) while the object translates and turns: the plant measures ξ(t) and δ(t), and
    ξ̇ = tᵀRᵀu / (1 + κδ) is both 0.02 m/s and the central difference of its ξ to 1e-6 (1 + κδ is 1.06 on the
    disc: leaving it out is off by 6 %)."""
    curve, X0, _, xis = CASES[name]
    period = curve.perimeter
    start = period - 0.004 if name != "box" else xis[0]
    plant = placed(curve, X0, (start, xis[1]))

    def motion(t: float):
        X = np.array(X0) + np.array([0.01 * t, -0.02 * t, 0.3 * t])
        sp = curve.local(start + 0.02 * t)
        return X, in_hand(X, sp.point - (0.002 + 0.01 * t) * sp.normal)

    def state(t: float, h: float = 1e-6) -> PlantState:
        X, p = motion(t)
        q1 = FINGERS[0].inverse_kinematics(p)
        v1 = np.linalg.solve(FINGERS[0].tip_jacobian(q1), (motion(t + h)[1] - motion(t - h)[1]) / (2.0 * h))
        q = np.concatenate([q1, plant.state.q[2:]])
        v = np.concatenate([v1, np.zeros(2)])
        return PlantState(t, q, v, X, np.array([0.01, -0.02, 0.3]))

    h, worst, worst_fd = 1e-5, 0.0, 0.0
    for t in np.linspace(0.0, 0.4, 9):
        xi, rate = plant.contact_xi(state(t), 0)
        assert xi == pytest.approx(start + 0.02 * t, abs=1e-10)  # continued: above P once past it
        assert plant.constraint_error(state(t)) == pytest.approx(0.002 + 0.01 * t, abs=1e-10)
        difference = (plant.contact_xi(state(t + h), 0)[0] - plant.contact_xi(state(t - h), 0)[0]) / (2.0 * h)
        worst, worst_fd = max(worst, abs(rate / 0.02 - 1.0)), max(worst_fd, abs(rate / difference - 1.0))
    print(f"{name}: xi_dot relative error {worst:.3g} (against 0.02 m/s), {worst_fd:.3g} (against the central "
          f"difference of the measured xi)")
    assert worst < 1e-6 and worst_fd < 1e-6


def test_surface_forces_on_a_curve_are_in_the_frame_at_the_contacts_xi():
    curve, X, xis, _ = CASES["ellipse"]
    plant = placed(curve, X, xis)
    st = plant.state
    _, _, forces = plant.accelerations(st, squeeze(curve, st, xis, 2.0))
    surface = plant.surface_forces(st, forces)
    rot = rotation(st.X[2])
    for i, xi in enumerate(xis):
        sp = curve.local(plant.contact_xi(st, i)[0])
        np.testing.assert_allclose(surface[i], [forces[i] @ (rot @ sp.normal), forces[i] @ (rot @ sp.tangent)],
                                   atol=1e-12)
    assert surface[:, 0].min() > 0.0

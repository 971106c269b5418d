"""A scenario as a MuJoCo model (:mod:`regrasp.plants.mujoco.mjcf`): the fingers are the URDFs as Pinocchio reads them
(masses, centres of mass, inertias, damping, hinge axes, the tip's forward kinematics at random postures, so the link
lengths and base placements), the object a planar body with the polygon's mass, inertia and shape, the tips' prism
eroded by the tip radius; the MJCF text loads back; bad settings are typed errors."""

import math
from pathlib import Path

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

from field_checks import field_tests, fields_of  # noqa: E402
from regrasp import load_scenario  # noqa: E402
from regrasp.core.exceptions import InvalidParameterError  # noqa: E402
from regrasp.plants.mujoco.mjcf import MujocoSettings, build_mjcf, eroded_vertices, scenario_to_mjcf  # noqa: E402

SC3 = load_scenario(Path(__file__).resolve().parents[3] / "examples" / "scenarios"
                    / "paper_trajectory_2_three_fingers.toml")
R_TIP = MujocoSettings().tip_radius


def compiled(sc):
    built = build_mjcf([c.finger for c in sc.contacts], sc.polygon, sc.friction, gravity_in_hand=sc.gravity_in_hand,
                       tip_clearance=[c.tip_clearance for c in sc.contacts])
    return built, built.spec.compile()


def test_the_fingers_are_the_urdfs_as_pinocchio_reads_them():
    built, model = compiled(SC3)
    data = mujoco.MjData(model)
    rng = np.random.default_rng(3)
    for finger, joints, site in zip([c.finger for c in SC3.contacts], built.finger_joints, built.tip_sites):
        pm = finger.model
        for k, name in enumerate(joints):
            j = model.joint(name)
            body = model.body(j.bodyid[0])
            inertia = pm.inertias[k + 1]
            assert body.mass[0] == pytest.approx(inertia.mass, rel=1e-12)
            np.testing.assert_allclose(body.ipos, inertia.lever, atol=1e-12)  # centre of mass, joint frame
            rot = np.zeros(9)
            mujoco.mju_quat2Mat(rot, body.iquat)
            rot = rot.reshape(3, 3)
            np.testing.assert_allclose(rot @ np.diag(body.inertia) @ rot.T, inertia.inertia, atol=1e-12)
            assert model.dof_damping[j.dofadr[0]] == pytest.approx(pm.damping[k], rel=1e-12)
            np.testing.assert_allclose(model.jnt_axis[j.id], [0.0, 0.0, 1.0])
            assert model.jnt_type[j.id] == mujoco.mjtJoint.mjJNT_HINGE and not model.jnt_limited[j.id]
        # the tip's forward kinematics (link lengths and base placement together) at random postures
        for _ in range(5):
            q = rng.uniform(-math.pi, math.pi, 2)
            for k, name in enumerate(joints):
                data.qpos[model.joint(name).qposadr[0]] = q[k]
            mujoco.mj_kinematics(model, data)
            np.testing.assert_allclose(data.site_xpos[model.site(site).id, :2], finger.forward_kinematics(q),
                                       atol=1e-12)
        l1, l2 = finger.link_lengths
        link2 = model.body(model.joint(joints[1]).bodyid[0])
        assert np.linalg.norm(link2.pos) == pytest.approx(l1, rel=1e-12)
        assert np.linalg.norm(model.body(model.site(site).bodyid[0]).pos) == pytest.approx(l2, rel=1e-12)
        assert model.geom(built.tip_geoms[0]).size[0] == pytest.approx(R_TIP)


def test_the_object_is_a_planar_body_with_the_polygons_mass_and_shape():
    built, model = compiled(SC3)
    data = mujoco.MjData(model)
    kinds = [model.jnt_type[model.joint(n).id] for n in built.object_joints]
    assert kinds == [mujoco.mjtJoint.mjJNT_SLIDE, mujoco.mjtJoint.mjJNT_SLIDE, mujoco.mjtJoint.mjJNT_HINGE]
    np.testing.assert_allclose([model.jnt_axis[model.joint(n).id] for n in built.object_joints], np.eye(3))
    body = model.body("object")
    assert body.mass[0] == pytest.approx(SC3.polygon.mass) and body.inertia[2] == pytest.approx(SC3.polygon.inertia)
    np.testing.assert_allclose(model.opt.gravity, [*SC3.gravity_in_hand, 0.0])
    X = np.array([0.01, 0.13, 0.3])
    for n, x in zip(built.object_joints, X):
        data.qpos[model.joint(n).qposadr[0]] = x
    mujoco.mj_kinematics(model, data)
    for geom, vertices in (("hull", SC3.polygon.vertices),
                           ("object", eroded_vertices(SC3.polygon, R_TIP - MujocoSettings().contact_depth))):
        g = model.geom(geom)
        mesh = model.mesh(g.dataid[0])
        local = model.mesh_vert[mesh.vertadr[0]:mesh.vertadr[0] + mesh.vertnum[0]]
        world = local @ data.geom_xmat[g.id].reshape(3, 3).T + data.geom_xpos[g.id]
        expected = SC3.polygon.vertices_in(X) if geom == "hull" else (
            vertices @ np.array([[math.cos(X[2]), math.sin(X[2])], [-math.sin(X[2]), math.cos(X[2])]]) + X[:2])
        for v in expected:  # every polygon vertex is a prism vertex (MuJoCo stores mesh vertices in single precision)
            assert np.min(np.linalg.norm(world[:, :2] - v, axis=1)) < 1e-8


def test_erosion_moves_every_edge_by_the_distance():
    poly = SC3.polygon
    for d in (2.5e-4, -1e-3):
        v = eroded_vertices(poly, d)
        for k, e in enumerate(poly.edges):  # both ends of eroded edge k lie d inside edge k's line
            for p in (v[k], v[(k + 1) % len(v)]):
                assert (p - e.start) @ e.inward_normal == pytest.approx(d, abs=1e-15)
    with pytest.raises(InvalidParameterError, match="survives the erosion"):
        eroded_vertices(poly, 0.03)


def test_the_mjcf_text_loads_back():
    text = scenario_to_mjcf(SC3)
    model = mujoco.MjModel.from_xml_string(text)
    assert model.nbody == compiled(SC3)[1].nbody and model.npair == 3



@pytest.mark.parametrize("kwargs", [dict(tip_radius=-1e-4), dict(timestep=1e-4, time_constant=1e-4),
                                    dict(timestep=1e-4, friction_time_constant=1.5e-4),
                                    dict(solimp=(0.9, 0.8, 1e-3, 0.5, 2)), dict(integrator="verlet"),
                                    dict(erode="yes"), dict(contact_depth=math.nan)])
def test_bad_mujoco_settings_are_typed_errors(kwargs):
    with pytest.raises(InvalidParameterError):
        MujocoSettings(**kwargs)


TABLE = fields_of(MujocoSettings(), {
    "pos": ("tip_radius", "timestep", "time_constant", "friction_time_constant", "damping_ratio", "impratio",
            "tolerance", "object_thickness"),
    "nonneg": ("contact_depth",), "count0": ("noslip_iterations",), "count1": ("iterations",), "flag": ("erode",),
    "choice": ("integrator",), "other": ("solimp",)},
    optional=("friction_time_constant",), good={"friction_time_constant": 5e-4},
    choices={"integrator": ("euler", "implicit", "implicitfast", "rk4")})

test_each_field_refuses_bad_values, test_each_field_refuses_generated_bad_values = field_tests(TABLE)


def test_solimp_is_stored_as_a_tuple_of_floats():
    assert MujocoSettings(solimp=[0.9, 0.95, 1e-3, 0.5, 2]).solimp == (0.9, 0.95, 1e-3, 0.5, 2.0)


def test_the_friction_rows_time_constant_follows_the_normal_rows_unless_given():
    """None: 0.4 of the normal rows' time constant, within [0.5 ms, the normal rows']; the MJCF carries it."""
    assert MujocoSettings(time_constant=2.5e-4).friction_rows_time_constant == 2.5e-4
    assert MujocoSettings(time_constant=1e-3).friction_rows_time_constant == 5e-4
    assert MujocoSettings(time_constant=2e-3).friction_rows_time_constant == pytest.approx(8e-4)
    assert MujocoSettings(time_constant=2e-3, friction_time_constant=3e-4).friction_rows_time_constant == 3e-4
    model = mujoco.MjModel.from_xml_string(scenario_to_mjcf(SC3, MujocoSettings(time_constant=2e-3)))
    tips = [k for k in range(model.npair) if "tip_object" in model.pair(k).name]
    assert tips and all(model.pair_solref[k][0] == pytest.approx(2e-3) for k in tips)
    assert all(model.pair_solreffriction[k][0] == pytest.approx(8e-4) for k in tips)

"""Recordings and figures of rollouts on curved objects (:mod:`regrasp.core.curves`).

The set-up is the project plant's curved one (``tests/plants/project/test_curved_plant.py``): the three fingers of
``paper_trajectory_2_three_fingers.toml`` hold a disc, an ellipse or a rounded box at (0, 0.12) m, finger 1
sliding under a squeeze, the others fixed; a few 1 ms steps are recorded without a supervisor (the recorder
measures ξ and the envelopes) and one supervised step from given values.

What is checked, against the curve itself (its projection ``project_floats``): the outline (the scene's at every
step, the static one, and the float64 one the recorder draws from: every point on the curve, every chord within
0.05 mm of it), each contact's cone and force drawn in the surface frame at the contact's ξ, ξ continuous (a
contact started a perimeter further stays there), each feasible interval drawn along the curve at its slot's
distance outside it, from one end of the interval (or of its danger zone) to the other; and ``plot_frames``' outline.
Logged scene points are float32 millimetres: "on the curve" is within 1e-9 m plus their rounding (:data:`F32`).
"""

from __future__ import annotations

import functools
import math
import shutil
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from rerun.chunk import RrdReader

from recordings import read
from regrasp import Friction, Hand, Plant, PlantContact, load_scenario
from regrasp.core.curves import Disc, Ellipse, RoundedPolygon
from regrasp.core.intervals import danger_zones
from regrasp.core.polygon import ConvexPolygon
from regrasp.rollout import plots
from regrasp.rollout.recording.outline import CHORD_ERROR, closed_outline, curve_path, outline_size
from regrasp.rollout.recording.recorder import RolloutRecorder
from regrasp.rollout.recording.scene import ENVELOPE_GAP
from regrasp.supervisor.types import ContactPhase

pytestmark = pytest.mark.filterwarnings("error::rerun.error_utils.RerunWarning")

ROOT = Path(__file__).resolve().parents[2]
X0 = np.array([0.0, 0.12, 0.0])
MU = 0.3
STEPS = 12
FORCE_SCALE = 10.0  # [mm/N], the recorder's default
#: The rounding of a logged float32 coordinate below 256 mm, as a distance [m].
F32 = float(np.spacing(np.float32(256.0))) / 1000.0
TOL = 1e-9 + F32


@functools.lru_cache(maxsize=None)
def scenario():
    return load_scenario(ROOT / "examples" / "scenarios" / "paper_trajectory_2_three_fingers.toml")


@functools.lru_cache(maxsize=None)
def curve(name: str):
    if name == "disc":
        return Disc(0.05, mass=0.08)
    if name == "ellipse":
        return Ellipse(0.05, 0.035, mass=0.08)
    return RoundedPolygon(ConvexPolygon.rectangle(0.1, 0.04, mass=1.0).vertices, 0.012, mass=0.08)


def rot(beta: float) -> np.ndarray:
    c, s = math.cos(beta), math.sin(beta)
    return np.array([[c, -s], [s, c]])


def grip(obj) -> list[float]:
    """ξ of the left, right and bottom grip points."""
    return [float(obj.project(np.array([p]))[0][0]) for p in ([-0.06, 0.0], [0.06, 0.0], [0.0, -0.06])]


def start(obj, xi: list[float]) -> Plant:
    """Finger 1 sliding, the others fixed, the tips on c(ξ_i) by inverse kinematics, at rest at X0."""
    hand = Hand([c.finger for c in scenario().contacts], gravity_in_hand=(0.0, -9.81))
    q = hand.inverse_kinematics(np.array([X0[:2] + rot(X0[2]) @ obj.local(x).point for x in xi]))
    plant = Plant(hand, obj, [PlantContact(0, m, x, 1.0) for m, x in zip(("sliding", "fixed", "fixed"), xi)],
                  friction=[Friction(MU), Friction(1.0), Friction(1.0)], contact_events=False, stop_on=())
    plant.reset(q, np.zeros(hand.nq), X0, np.zeros(3))
    return plant


def cross(a, b) -> float:
    return float(a[0] * b[1] - a[1] * b[0])


def squeeze(plant: Plant) -> np.ndarray:
    """Torques: finger 1 pushes 1 N along its normal and a little more than μ_k along its tangent (it slides),
    finger 2 and the palm balance the object's wrench; gravity compensated."""
    st, obj, hand = plant.state, plant.polygon, plant.hand
    (c1, c2, c3), (n1, n2, n3), (t1, t2, t3) = zip(*((p.point, p.normal, p.tangent) for p in (
        obj.local(plant.contact_xi(st, i)[0]) for i in range(3))))
    R = rot(st.X[2])
    known = (n1 + MU * t1) + n2 + R.T @ (obj.mass * hand.gravity_in_hand)
    lhs = np.array([[t2[0], n3[0], t3[0]], [t2[1], n3[1], t3[1]], [cross(c2, t2), cross(c3, n3), cross(c3, t3)]])
    a, b, c = np.linalg.solve(lhs, -np.array([*known, cross(c1, n1 + MU * t1) + cross(c2, n2)]))
    forces = np.concatenate([R @ (n1 + (MU + 0.004) * t1), R @ (n2 + a * t2), R @ (b * n3 + c * t3)])
    return hand.jacobian(st.q).T @ forces + hand.dynamics(st.q, np.zeros(hand.nq)).nonlinear


def rerun_cli() -> list[str]:
    exe = Path(sys.executable).with_name("rerun")
    if exe.exists():
        return [str(exe)]
    found = shutil.which("rerun")
    return [found] if found else [sys.executable, "-m", "rerun"]


def verify(path: Path) -> None:
    proc = subprocess.run([*rerun_cli(), "rrd", "verify", str(path)], capture_output=True, text=True, timeout=120,
                          check=False)
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0 and "verified without error" in out, out


def to_object(points_mm, X) -> np.ndarray:
    """Scene points [mm, y flipped] -> object frame [m] at pose X."""
    p = np.asarray(points_mm, dtype=float).reshape(-1, 2) * np.array([1e-3, -1e-3])
    return (p - X[:2]) @ rot(X[2])


def feet(obj, points, near=None) -> np.ndarray:
    """(ξ, signed distance) [m] of each point (object frame) on the curve."""
    return np.array([obj.project_floats(float(x), float(y), near) for x, y in points]).reshape(-1, 2)


def static_outline(path: Path) -> np.ndarray:
    for chunk in RrdReader(path).stream().to_chunks():
        if chunk.entity_path.lstrip("/") == "model/object/outline":
            return np.array(chunk.to_record_batch().column("LineStrips2D:strips").to_pylist()[0][0])
    raise AssertionError("no model/object/outline")


def recorded(name: str, tmp: Path) -> tuple:
    """A recording of STEPS squeezed steps on ``name`` (finger 1 started one perimeter further: ξ + P), the poses
    logged and the start's ξ."""
    obj = curve(name)
    xi0 = grip(obj)
    xi0[0] += obj.perimeter  # (the same point: its ξ must stay this representative)
    plant = start(obj, xi0)
    path = tmp / f"{name}.rrd"
    poses = [plant.state.X.copy()]
    with RolloutRecorder(plant, rrd_path=path) as rec:
        rec.log_step(plant, None)
        for _ in range(STEPS):
            step = plant.step(squeeze(plant))
            rec.log_step(plant, None, plant_step=step)
            poses.append(plant.state.X.copy())
    return path, poses, xi0, rec


@pytest.mark.parametrize("name", ["disc", "ellipse", "rounded"])
def test_a_curved_rollout_records_the_curve_its_contacts_frames_and_envelopes(name, tmp_path):
    obj = curve(name)
    path, poses, xi0, rec = recorded(name, tmp_path)
    verify(path)
    assert rec.steps_logged == STEPS + 1
    rows, static, _, _ = read(path)
    m = 3
    xi = np.array([[rows[f"plots/xi/{k}"]["Scalars:scalars"][s][0] for k in ("finger1", "finger2", "palm")]
                   for s in range(STEPS + 1)]) * 1e-3  # [m], float64
    bands = [np.array(rows[f"plots/xi/{k}"]["Scalars:scalars"], dtype=float) * 1e-3
             for k in ("finger1", "finger2", "palm")]  # (steps, 7): ξ, ξ_d, lo, hi, lo zone, hi zone, planned

    # ξ: the tips' feet, continuous, the representative each contact started at (finger 1: a perimeter on)
    assert np.allclose(xi[0], xi0, rtol=0.0, atol=1e-9)
    assert np.abs(np.diff(xi, axis=0)).max() < 1e-3 and xi[-1, 0] > obj.perimeter
    assert abs(xi[-1, 0] - xi[0, 0]) > 1e-7  # (finger 1 slid)

    # the outline the recorder draws from (float64): on the curve, its chords within 0.05 mm of it
    closed = closed_outline(obj)
    n = outline_size(obj)
    assert closed.shape == (n + 1, 2) and np.array_equal(closed[0], closed[-1])
    assert np.abs(feet(obj, closed)[:, 1]).max() <= 1e-9
    assert np.abs(feet(obj, 0.5 * (closed[1:] + closed[:-1]))[:, 1]).max() <= CHORD_ERROR
    # the static outline (object frame) and the scene's at every step: on the curve
    assert np.abs(feet(obj, to_object(static_outline(path), np.zeros(3)))[:, 1]).max() <= TOL
    assert "model/object/outline" in static
    for s, X in enumerate(poses):
        strip, = rows["scene/object"]["LineStrips2D:strips"][s]
        assert len(strip) == n + 1
        assert np.abs(feet(obj, to_object(strip, X))[:, 1]).max() <= TOL, s

    forces = np.array(rows["plots/force"]["Scalars:scalars"], dtype=float)
    for s, X in enumerate(poses):
        R = rot(X[2])
        normals = np.array([R @ obj.local(x).normal for x in xi[s]])
        tangents = np.stack([-normals[:, 1], normals[:, 0]], axis=1)
        # each cone's axis is the inward normal at the contact's ξ (rays [mm]: tip + L a, tip, tip + L b)
        cones = np.array(rows["scene/contacts/cones"]["LineStrips2D:strips"][s]) * np.array([1e-3, -1e-3])
        axes = (cones[:, 0] - cones[:, 1]) + (cones[:, 2] - cones[:, 1])
        axes /= np.linalg.norm(axes, axis=1)[:, None]
        assert np.abs(axes - normals).max() < 1e-5, s
        # each force arrow is f_n n + f_t t in that frame
        if s:
            vectors = np.array(rows["scene/contacts/forces"]["Arrows2D:vectors"][s]) * np.array([1.0, -1.0])
            expected = (forces[s, :m, None] * normals + forces[s, m:2 * m, None] * tangents) * FORCE_SCALE
            assert np.abs(vectors - expected).max() < 1e-3, s  # [mm]
        # the tips (joints' third dots) are on the curve at their ξ
        tips = np.array(rows["scene/joints"]["Points2D:positions"][s]).reshape(m, 3, 2)[:, 2]
        on = np.array([obj.project_floats(*p, x) for p, x in zip(to_object(tips, X), xi[s])])
        assert np.abs(on[:, 0] - xi[s]).max() < 1e-6 and np.abs(on[:, 1]).max() < 1e-6

    # the envelopes: each interval's safe part along the curve, 3 mm (1 + slot) outside it, finger i in slot i
    P = obj.perimeter
    for s, X in enumerate(poses):
        safe = [to_object(p, X) for p in rows["scene/envelope/safe"]["LineStrips2D:strips"][s]]
        danger = [to_object(p, X) for p in rows["scene/envelope/danger"]["LineStrips2D:strips"][s]]
        assert safe and len(danger) % 2 == 0
        spans = []
        for strip in safe + danger:
            foot = feet(obj, strip)  # (ξ in [0, P))
            offset = float(np.median(foot[:, 1]))
            slot = round(offset / ENVELOPE_GAP) - 1
            assert slot in (0, 1, 2) and np.abs(foot[:, 1] - ENVELOPE_GAP * (1 + slot)).max() <= 2e-7, (s, slot)
            assert all(math.remainder(d, P) > 0 for d in np.diff(foot[:, 0]))  # along ξ, growing
            mid = feet(obj, 0.5 * (strip[1:] + strip[:-1]))[:, 1]  # each chord within 0.05 mm of its arc
            assert np.all(ENVELOPE_GAP * (1 + slot) - mid <= CHORD_ERROR + 2e-7)
            spans.append((slot, foot[0, 0], foot[-1, 0]))
        for i in range(m):  # finger i's band: its safe part and its two danger zones, in slot i
            _, _, lo, hi, lo_zone, hi_zone, _ = bands[i][s]
            for a, b in ((lo_zone, hi_zone), (lo, lo_zone), (hi_zone, hi)):  # (ξ of the strips: modulo P)
                assert any(k == i and abs(math.remainder(u - a, P)) < 1e-6 and abs(math.remainder(v - b, P)) < 1e-6
                           for k, u, v in spans), (s, i, a, b)


def test_a_supervised_step_on_a_curve_draws_each_contact_at_its_own_xi(tmp_path):
    """A supervised step's row draws each contact's frame at the step's ξ (not the tips': given here) and the
    envelopes given, each finger's intervals in its slot."""
    obj = curve("ellipse")
    xi0 = grip(obj)
    plant = start(obj, xi0)
    st = plant.state
    given = np.array(xi0) + np.array([0.01, -0.015, 0.02])
    feasible = [[(x - 0.02, x + 0.03)] for x in given]
    path = tmp_path / "supervised.rrd"
    with RolloutRecorder(plant, rrd_path=path) as rec:
        rec.log_stretch_step(1, 1e-3, st.X, st.q, st.X, np.ones((3, 2)), np.ones((3, 2)), np.ones((3, 2)), feasible,
                             [ContactPhase.SLIDING, ContactPhase.FIXED, ContactPhase.FIXED], given, np.zeros(4),
                             np.zeros(3), np.zeros(3), np.array([iv[0] for iv in feasible]), np.full(3, np.nan),
                             np.full(3, np.nan))
    verify(path)
    rows, _, _, _ = read(path)
    cones = np.array(rows["scene/contacts/cones"]["LineStrips2D:strips"][0]) * np.array([1e-3, -1e-3])
    axes = (cones[:, 0] - cones[:, 1]) + (cones[:, 2] - cones[:, 1])
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    assert np.abs(axes - [rot(st.X[2]) @ obj.local(x).normal for x in given]).max() < 1e-5
    safe = rows["scene/envelope/safe"]["LineStrips2D:strips"][0]
    assert len(safe) == 3
    for i, (strip, x) in enumerate(zip(safe, given)):
        foot = feet(obj, to_object(strip, st.X), x)
        (_, a), (b, _) = danger_zones(*feasible[i][0])  # (the safe part: between the default danger zones)
        assert np.abs(foot[:, 1] - ENVELOPE_GAP * (1 + i)).max() <= 2e-7
        assert abs(foot[0, 0] - a) < 1e-6 and abs(foot[-1, 0] - b) < 1e-6
        arc = curve_path(obj, a, b, ENVELOPE_GAP * (1 + i))
        assert len(strip) == len(arc) and np.abs(to_object(strip, st.X) - arc).max() <= TOL


def frames_result(X: np.ndarray) -> SimpleNamespace:
    """What ``plot_frames`` reads of a rollout's result: 4 steps at pose X, two fingers holding."""
    n = 4
    return SimpleNamespace(steps=n, poses=np.tile(X, (n, 1)), times=np.arange(n) * 1e-3,
                           joint_positions=np.tile([1.2, 0.8, 1.9, -0.8], (n, 1)),
                           phases=np.array([["fixed", "sliding"]] * n, dtype=object), names=("finger1", "finger2"),
                           failure=None, success=True, simulated_seconds=n * 1e-3, policy="scheduled")


@pytest.fixture()
def figures(monkeypatch):
    made = []
    monkeypatch.setattr(plots, "save_figure", lambda fig, path, layout=True: made.append(fig) or Path(path))
    yield made
    import matplotlib.pyplot as plt

    for fig in made:  # (kept open for the test to read; closed after it, as save_figure would)
        plt.close(fig)


@pytest.mark.parametrize("name", ["disc", "rounded"])
def test_plot_frames_draws_a_curved_objects_outline(name, figures, tmp_path):
    sc = load_scenario(ROOT / "examples" / "scenarios" / "paper_trajectory_2.toml")
    hand = Hand([c.finger for c in sc.contacts], gravity_in_hand=sc.gravity_in_hand)
    obj, X = curve(name), np.array([0.005, 0.17, 0.3])
    plots.plot_frames(frames_result(X), hand, obj, tmp_path / "frames.png", scenario=sc, frames=2)
    for ax in figures[0].axes[:2]:
        outline = np.asarray(ax.patches[0].get_xy()) / 1000.0  # [mm] -> [m], hand frame, closed
        assert len(outline) == outline_size(obj) + 1
        local = (outline - X[:2]) @ rot(X[2])
        assert np.abs(feet(obj, local)[:, 1]).max() <= 1e-9


def test_plot_frames_draws_a_polygon_by_its_vertices(figures, tmp_path):
    sc = load_scenario(ROOT / "examples" / "scenarios" / "paper_trajectory_2.toml")
    hand = Hand([c.finger for c in sc.contacts], gravity_in_hand=sc.gravity_in_hand)
    X = np.array([0.005, 0.17, 0.3])
    plots.plot_frames(frames_result(X), hand, sc.polygon, tmp_path / "frames.png", frames=2)
    verts = sc.polygon.vertices_in(X) * 1000.0
    assert np.array_equal(np.asarray(figures[0].axes[0].patches[0].get_xy()), np.vstack([verts, verts[:1]]))

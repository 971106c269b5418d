"""The scenario's ``[object]`` table: polygons, rounded polygons and curved objects, and errors that name the key."""

import tomllib
from pathlib import Path

import numpy as np
import pytest

from regrasp import ScenarioError
from regrasp.core.curves import Disc, Ellipse, RoundedPolygon, SupportCurve
from regrasp.core.polygon import ConvexPolygon
from regrasp.model.scenario import scenario_from_document

ROOT = Path(__file__).resolve().parents[2]
URDF = ROOT / "urdf" / "planar_2r_finger.urdf"


def document(object_table: str, edges=(1, 3)) -> dict:
    fingers = "".join(f"""
[[fingers]]
name = "f{i}"
urdf = "{URDF}"
base = [{x}, 0.0, 1.5707963267948966]
configuration = "{side}"
{'' if edge is None else f'edge = {edge}'}
""" for i, (x, side, edge) in enumerate(zip((-0.05, 0.05), ("left", "right"), edges)))
    return tomllib.loads(f"""
name = "t"
[object]
{object_table}
[trajectory]
type = "ellipse"
cx = 0.0
cy = 0.12
a = 0.01
b = 0.01
omega = 2.0
{fingers}""")


def load(object_table: str, edges=(1, 3)):
    return scenario_from_document(document(object_table, edges), ROOT / "t.toml")


def test_each_shape_loads_with_its_mass_properties():
    disc = load('shape = "disc"\nradius = 0.05\nmass = 0.2', edges=(None, 0)).polygon
    assert isinstance(disc, Disc) and disc.radius == 0.05 and disc.inertia == pytest.approx(0.5 * 0.2 * 0.05 ** 2)
    ellipse = load('shape = "ellipse"\na = 0.06\nb = 0.04\ndensity = 10.0', edges=(0, 0)).polygon
    assert isinstance(ellipse, Ellipse) and ellipse.mass == pytest.approx(10.0 * np.pi * 0.06 * 0.04)
    box = load("width = 0.1\nheight = 0.06\ncorner_radius = 0.01\nmass = 0.08", edges=(0, 0)).polygon
    assert isinstance(box, RoundedPolygon) and box.radius == 0.01 and box.mass == 0.08
    curve = load('shape = "support"\ncosines = [0.05, 0.0, 0.004]\nsines = [0.0, 0.002]\nmass = 0.1',
                 edges=(0, 0)).polygon
    assert isinstance(curve, SupportCurve) and np.linalg.norm(curve.centroid) < 1e-12


def test_corner_radius_zero_is_the_polygon_exactly():
    plain = load("width = 0.1\nheight = 0.04\nmass = 0.08").polygon
    zero = load("width = 0.1\nheight = 0.04\ncorner_radius = 0.0\nmass = 0.08").polygon
    assert type(zero) is ConvexPolygon
    assert np.array_equal(plain.vertices, zero.vertices) and (plain.mass, plain.inertia) == (zero.mass, zero.inertia)
    verts = "vertices = [[0.05, 0.02], [-0.05, 0.02], [-0.05, -0.02], [0.05, -0.02]]"
    assert type(load(f"{verts}\ncorner_radius = 0.0\nmass = 0.08").polygon) is ConvexPolygon
    assert type(load(f"{verts}\ncorner_radius = 0.005\nmass = 0.08", edges=(0, 0)).polygon) is RoundedPolygon


@pytest.mark.parametrize("table,edges,key,words", [
    ('shape = "disc"\nradius = -0.05\nmass = 0.2', (0, 0), "object.radius", "> 0"),
    ('shape = "disc"\nmass = 0.2', (0, 0), "object.radius", "required"),
    ('shape = "blob"\nmass = 0.2', (0, 0), "object.shape", "one of"),
    ('shape = "disc"\nradius = 0.05\nwidth = 0.1\nmass = 0.2', (0, 0), "object.width", "unknown key"),
    ("width = 0.1\nheight = 0.04\ncorner_radius = 0.03\nmass = 0.08", (0, 0), "object.corner_radius",
     "largest corner radius"),
    ("width = 0.1\nheight = 0.04\ncorner_radius = -0.01\nmass = 0.08", (0, 0), "object.corner_radius", ">= 0"),
    ('shape = "support"\ncosines = [0.05, 0.0, 0.02]\nsines = [0.0, 0.0]\nmass = 0.1', (0, 0), "object.cosines",
     "not convex"),
    ('shape = "disc"\nradius = 0.05\nmass = 0.2', (0, 1), "fingers[1].edge", "one face"),
])
def test_bad_object_tables_name_the_key(table, edges, key, words):
    with pytest.raises(ScenarioError) as info:
        load(table, edges)
    assert info.value.key == key and words in str(info.value)

"""The ``[object]`` table of a scenario file: a convex polygon (``vertices``, or ``width`` and ``height``), rounded
at its corners by ``corner_radius`` [m] (0, the default: the polygon itself), or a curved object by ``shape``:
``"disc"`` (``radius``), ``"ellipse"`` (``a``, ``b``: semi-axes along x and y) or ``"support"`` (a support
function's Fourier coefficients ``cosines`` = a_0..a_K and ``sines`` = b_1..b_K [m], translated so that its
centroid is the origin). Mass properties: ``mass`` and ``inertia``, ``mass`` alone or ``density``
(:mod:`regrasp.core.curves`, :class:`~regrasp.core.polygon.ConvexPolygon`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any, TypeAlias

from ..core.curves import CurvedObject, Disc, Ellipse, SupportCurve, rounded
from ..core.exceptions import ScenarioError
from ..core.polygon import ConvexPolygon
from .toml_table import TableReader, wrap_errors

__all__ = ["SHAPES", "SceneObject", "read_object"]

#: An object a scenario can hold: a convex polygon or a curved object.
SceneObject: TypeAlias = ConvexPolygon | CurvedObject
#: The ``shape`` key's values.
SHAPES = ("polygon", "disc", "ellipse", "support")


def read_object(path: Path, table: Any) -> SceneObject:
    """The object of a scenario's ``[object]`` table (module docstring); a ScenarioError names a bad key."""
    if not isinstance(table, dict):
        raise ScenarioError(path, "object", "expected a table [object]")
    r = TableReader(path, table, "object.")
    shape = r.string("shape", "polygon", choices=SHAPES)
    masses = {"mass": r.number("mass", None), "inertia": r.number("inertia", None),
              "density": r.number("density", None)}
    if shape == "disc":
        radius = r.number("radius")
        obj = wrap_errors(r, "radius", lambda: Disc(radius, **masses))
    elif shape == "ellipse":
        a, b = r.number("a"), r.number("b")
        obj = wrap_errors(r, "a", lambda: Ellipse(a, b, **masses))
    elif shape == "support":
        cosines, sines = r.array("cosines", (-1,)), r.array("sines", (-1,))
        obj = wrap_errors(r, "cosines", lambda: SupportCurve.centred(cosines, sines, **masses))
    else:
        corner = r.number("corner_radius", 0.0)
        if r.has("vertices"):
            vertices = r.array("vertices", (-1, 2))
            key = "vertices"
        elif r.has("width") or r.has("height"):
            width, height = r.number("width"), r.number("height")
            key = "width"
            if corner == 0.0:  # the rectangle exactly as before (its own validation and vertex order)
                obj = wrap_errors(r, "width", lambda: ConvexPolygon.rectangle(width, height, **masses))
                r.finish()
                return obj
            vertices = wrap_errors(r, "width", lambda: ConvexPolygon.rectangle(width, height, mass=1.0).vertices)
        else:
            raise r.fail("vertices", "expected 'vertices' (a list of [x, y]) or 'width' and 'height'")
        if corner < 0.0:
            raise r.fail("corner_radius", f"expected a corner radius >= 0 [m], got {corner!r}")
        obj = wrap_errors(r, "corner_radius" if corner else key, lambda: rounded(vertices, corner, **masses))
    r.finish()
    return obj

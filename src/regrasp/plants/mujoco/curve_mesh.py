r"""A curved object's two prisms for the MuJoCo plant (:mod:`regrasp.plants.mujoco.mjcf`): the curve (``hull``, the
links touch it) and the curve **eroded by d = r − contact_depth** (``object``, the tips touch it).

**The eroded curve** is the inner parallel curve :math:`e(\xi) = c(\xi) + d\,n(\xi)` (n the unit inward normal).
With :math:`c' = t` and :math:`n' = -\kappa t`, :math:`e' = (1 - d\kappa)\,t`: it shares the curve's normals and
tangents, and its curvature is :math:`\kappa / (1 - d\kappa)`. It is a smooth convex curve exactly while
:math:`d\kappa < 1` everywhere, i.e. d below the curve's smallest radius of curvature :math:`1/\max\kappa` (else it
folds back into a swallowtail): :func:`check_erosion` samples κ and refuses a tip radius past it. A sphere of radius
r touching the eroded curve at :math:`e(\xi)` has its centre at :math:`e(\xi) - r\,n(\xi) = c(\xi) -
\text{depth}\;n(\xi)`, and on the curve itself, :math:`c(\xi)`, once it sinks ``contact_depth`` in: the point-contact
model's tip position (the normal is the curve's there).

**Discs** are exact: MuJoCo cylinders of radius R (``hull``) and R − d (``object``). **Other curves** are convex
meshes of points on the (parallel) curve, extruded along z; MuJoCo collides a mesh as its convex hull, which is the
inscribed polygon of those points. Its error is the chords' sagitta: the points are spaced by
:math:`h = \sqrt{4 s / \kappa_d}` (a chord of an arc of curvature κ and length h stands :math:`\kappa h^2/8` off
it: half the budget s), from κ sampled on a grid with each cell's neighbours' largest value, then every chord's
largest distance to the curve is measured at interior points and a chord past s is halved until none is:
:func:`curve_points` returns the largest measured distance, and :func:`add_curve_prism` asserts it below
:data:`MESH_SAGITTA`. A contact's normal is its facet's, within half a chord's turn, :math:`\sqrt{2 s \kappa}`, of the
curve's (2 mrad at s = 0.05 µm, κ = 33 /m).
"""

from __future__ import annotations

import math

import numpy as np

from ...core.curves import CurvedObject, Disc
from ...core.exceptions import InvalidParameterError

__all__ = ["CURVATURE_SAMPLES", "MESH_SAGITTA", "add_curve_prism", "check_erosion", "curvature_table", "curve_points",
           "smallest_radius_of_curvature"]

#: The largest chord error (sagitta) [m] of a curve's mesh: far below the contacts' 1 µm depth, so a tip placed on
#: the curve starts that deep within 10 %, and above the single-precision rounding of MuJoCo's mesh vertices (a few
#: nm on a hand-sized object).
MESH_SAGITTA = 1e-7
#: Samples of the curvature over one perimeter (the erosion check and the mesh's spacing).
CURVATURE_SAMPLES = 4096
#: Interior points per chord where its distance to the curve is measured.
_CHORD_PROBES = 3
#: The longest chord [-] (times the perimeter), also on a straight part.
_LONGEST_CHORD = 1.0 / 32.0


def curvature_table(curve: CurvedObject) -> np.ndarray:
    """κ [1/m] at :data:`CURVATURE_SAMPLES` evenly spaced ξ over one perimeter, from ξ = 0."""
    xi = np.linspace(0.0, curve.perimeter, CURVATURE_SAMPLES, endpoint=False)
    return np.array([curve.local_floats(float(x))[4] for x in xi])


def smallest_radius_of_curvature(curve: CurvedObject, curvature: np.ndarray | None = None) -> float:
    """The curve's smallest radius of curvature 1/max κ [m] (κ sampled at :data:`CURVATURE_SAMPLES` points, or
    ``curvature``, :func:`curvature_table`; a disc's radius exactly; inf for a curve sampled flat everywhere)."""
    if isinstance(curve, Disc):
        return curve.radius
    kappa = float(np.max(curvature_table(curve) if curvature is None else curvature))
    return 1.0 / kappa if kappa > 0.0 else math.inf


def check_erosion(curve: CurvedObject, distance: float, tip_radius: float,
                  curvature: np.ndarray | None = None) -> float:
    """Raise :class:`~regrasp.core.exceptions.InvalidParameterError` (naming ``tip_radius``) unless the curve eroded
    by ``distance`` [m] (its tip radius less the contact's depth; negative: grown) is smooth and convex: ``distance``
    below its smallest radius of curvature, which is returned [m] (``curvature``: :func:`curvature_table`, if
    known)."""
    rho = smallest_radius_of_curvature(curve, curvature)
    if distance > 0.0 and not distance < rho:
        raise InvalidParameterError("tip_radius", tip_radius, f"a tip radius whose erosion of the object "
                                    f"({distance:.6g} m, the radius less contact_depth) is below the curve's "
                                    f"smallest radius of curvature ({rho:.6g} m): eroded by more, the curve "
                                    "folds over itself (not convex, not smooth)")
    return rho


def _step(kappa: float, sagitta: float, longest: float) -> float:
    return longest if kappa <= 0.0 else min(longest, math.sqrt(4.0 * sagitta / kappa))


def curve_points(curve: CurvedObject, offset: float, sagitta: float = MESH_SAGITTA,
                 curvature: np.ndarray | None = None) -> tuple[np.ndarray, float]:
    r"""Points (k, 2) [m] of the parallel curve :math:`c + \mathrm{offset}\,n` (object frame, clockwise from ξ = 0)
    whose chords stay within ``sagitta`` [m] of it (module docstring), and the largest chord distance measured [m].
    ``offset`` must be below the smallest radius of curvature (:func:`check_erosion`); ``curvature``: κ [1/m] at
    :data:`CURVATURE_SAMPLES` evenly spaced ξ from 0 (:func:`curvature_table`), if known."""
    period = curve.perimeter
    kappa = curvature_table(curve) if curvature is None else curvature
    kd = kappa / (1.0 - offset * kappa)  # the parallel curve's curvature
    # each cell's (from sample j to j + 1) bound: the largest of the samples around it
    cell_bound = np.maximum.reduce([np.roll(kd, s) for s in (1, 0, -1, -2)])
    cell = period / CURVATURE_SAMPLES
    longest = _LONGEST_CHORD * period

    def bound(a: float, b: float) -> float:
        j0, j1 = int(math.floor(a / cell)), int(math.floor(b / cell))
        return float(np.max(cell_bound[np.arange(j0, j1 + 1) % CURVATURE_SAMPLES]))

    breaks = [0.0]
    x = 0.0
    while x < period:
        h = _step(bound(x, x), sagitta, longest)
        for _ in range(60):  # shrink until the curvature over the whole step allows it
            h_new = _step(bound(x, x + h), sagitta, longest)
            if h_new >= h:
                break
            h = h_new
        x = min(x + h, period)
        if period - x < 1e-3 * h:
            x = period
        breaks.append(x)

    cache: dict[float, tuple[float, float]] = {}

    def point(xi: float) -> tuple[float, float]:
        if xi not in cache:
            cx, cy, nx, ny, _ = curve.local_floats(xi)
            cache[xi] = (cx + offset * nx, cy + offset * ny)
        return cache[xi]

    def deviation(a: float, b: float) -> float:
        (ax, ay), (bx, by) = point(a), point(b)
        dx, dy = bx - ax, by - ay
        length = math.hypot(dx, dy)
        ox, oy = -dy / length, dx / length  # the chord's outward normal (the curve runs clockwise)
        probes = (point(a + (b - a) * k / (_CHORD_PROBES + 1)) for k in range(1, _CHORD_PROBES + 1))
        return max(abs((px - ax) * ox + (py - ay) * oy) for px, py in probes)

    kept, worst = [], 0.0
    pending = list(zip(breaks[:-1], breaks[1:]))[::-1]
    while pending:
        a, b = pending.pop()
        dev = deviation(a, b)
        if dev > sagitta and b - a > 1e-9 * period:
            m = 0.5 * (a + b)
            pending.extend(((m, b), (a, m)))
            continue
        kept.append(a)
        worst = max(worst, dev)
    return np.array([point(xi) for xi in kept]), worst


def add_curve_prism(mujoco: object, spec: object, body: object, name: str, curve: CurvedObject, offset: float,
                    thickness: float, conaffinity: int, curvature: np.ndarray | None = None) -> float:
    """Add to ``body`` the geom ``name``: the curve's parallel curve at ``offset`` [m] inwards (0: the curve) extruded
    to ``thickness`` [m] along z, a cylinder for a disc and a convex mesh otherwise (module docstring; ``curvature``:
    :func:`curvature_table`, if known); returns its chord error [m] (0 for a cylinder).

    Raises:
        AssertionError: the mesh's measured chord error exceeds :data:`MESH_SAGITTA` (never: the sampling halves
            chords until it does not).
    """
    half = 0.5 * thickness
    if isinstance(curve, Disc):
        body.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[curve.radius - offset, half, 0.0],
                      contype=0, conaffinity=conaffinity, density=0.0, mass=0.0, group=0)
        return 0.0
    points, sagitta = curve_points(curve, offset, curvature=curvature)
    assert sagitta <= MESH_SAGITTA, f"the {name} mesh's chord error {sagitta:.3g} m exceeds {MESH_SAGITTA:g} m"
    spec.add_mesh(name=name + "_mesh", uservert=[float(c) for x, y in points for c in (x, y, -half, x, y, half)],
                  inertia=mujoco.mjtMeshInertia.mjMESH_INERTIA_CONVEX)
    body.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=name + "_mesh", contype=0,
                  conaffinity=conaffinity, density=0.0, mass=0.0, group=0)
    return sagitta

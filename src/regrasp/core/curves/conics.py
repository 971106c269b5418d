r"""Discs and ellipses (object frame, centre of mass at the origin; ξ as in :mod:`regrasp.core.curves.base`).

**Disc** of radius r: with :math:`\varphi = \pi/2 - \xi / r`,
:math:`c = r(\cos\varphi, \sin\varphi)`, :math:`n = -(\cos\varphi, \sin\varphi)`, :math:`\kappa = 1/r`,
:math:`P = 2\pi r`; uniform: :math:`A = \pi r^2`, :math:`I = m r^2 / 2`.

**Ellipse** with semi-axes a (along x) and b (along y), :math:`c(u) = (a\cos u, b\sin u)`. With
:math:`F(u) = \int_0^u \sqrt{a^2\sin^2 s + b^2\cos^2 s}\,ds = b\,E(u \mid 1 - a^2/b^2)` (the incomplete elliptic
integral of the second kind, ``scipy.special.ellipeinc``), :math:`\xi(u) = F(\pi/2) - F(u)` (ξ = 0 at the top,
growing clockwise as u falls), :math:`P = 4 F(\pi/2)`,
:math:`n = -(b\cos u, a\sin u) / F'(u)`, :math:`\kappa = a b / F'(u)^3`; u(ξ) by Newton's method kept in the
bracket :math:`F' \in [\min(a, b), \max(a, b)]` gives. Uniform: :math:`A = \pi a b`,
:math:`I = m (a^2 + b^2) / 4`.
"""

from __future__ import annotations

import math

import coal
import numpy as np
from scipy.special import ellipeinc

from ..exceptions import CurveError
from ..validation import as_finite_float, as_positive_float
from .base import CurvedObject, bracketed_root, uniform_mass_properties

__all__ = ["Disc", "Ellipse"]

#: The largest radius or semi-axis [m] (a hand's object); the smallest is a micrometre.
MAX_LENGTH, MIN_LENGTH = 1e3, 1e-6
#: An ellipse's largest ratio of its semi-axes [-] (thinner is a segment: its ends' curvature overflows).
MAX_ASPECT = 1e3


def _length(name: str, value: float) -> float:
    out = as_positive_float(name, value)
    if not MIN_LENGTH <= out <= MAX_LENGTH:
        raise CurveError(f"{name} = {out:g} m: expected a length in [{MIN_LENGTH:g}, {MAX_LENGTH:g}] m",
                         parameter=name, value=value)
    return out


class Disc(CurvedObject):
    """A disc of ``radius`` [m] centred on the origin; mass properties as in
    :func:`~regrasp.core.curves.base.uniform_mass_properties` (``mass`` alone: uniform)."""

    def __init__(self, radius: float, *, mass: float | None = None, inertia: float | None = None,
                 density: float | None = None):
        self.radius = _length("radius", radius)
        self.mass, self.inertia = uniform_mass_properties(
            "disc", self._moments(), 2.0 * self.radius, mass=mass, inertia=inertia, density=density,
            centring_hint="a disc is centred")

    def __repr__(self) -> str:
        return f"Disc(radius={self.radius:g}, mass={self.mass:g}, inertia={self.inertia:g})"

    @property
    def label(self) -> str:
        """``"disc, r = 40 mm"``."""
        return f"disc, r = {self.radius * 1e3:.4g} mm"

    @property
    def perimeter(self) -> float:
        """2πr [m]."""
        return 2.0 * math.pi * self.radius

    def _local_floats(self, xi: float) -> tuple[float, float, float, float, float]:
        r = self.radius
        phi = 0.5 * math.pi - xi / r
        c, s = math.cos(phi), math.sin(phi)
        return r * c, r * s, -c, -s, 1.0 / r

    def _moments(self) -> tuple[float, np.ndarray, float]:
        r = self.radius
        return math.pi * r * r, np.zeros(2), 0.5 * math.pi * r ** 4

    def project_floats(self, px: float, py: float, near: float | None = None) -> tuple[float, float]:
        """Closed form: ξ = r(π/2 - atan2(p_y, p_x)), δ = |p| - r (the centre projects to ξ = 0 or ``near``)."""
        r = self.radius
        xi = r * (0.5 * math.pi - math.atan2(py, px)) if (px or py) else (0.0 if near is None else float(near))
        xi = xi % self.perimeter if near is None else near + math.remainder(xi - near, self.perimeter)
        return xi, math.hypot(px, py) - r

    def to_coal(self, half_thickness: float) -> coal.CollisionGeometry:
        """A coal cylinder of the disc's radius, z in ``[-h, h]`` [m] (exact)."""
        h = as_positive_float("half_thickness", half_thickness)
        return coal.Cylinder(self.radius, 2.0 * h)


class Ellipse(CurvedObject):
    """An ellipse with semi-axes ``a`` (along x) and ``b`` (along y) [m] centred on the origin; mass properties as
    for :class:`Disc`."""

    def __init__(self, a: float, b: float, *, mass: float | None = None, inertia: float | None = None,
                 density: float | None = None):
        self.a, self.b = _length("a", a), _length("b", b)
        if max(self.a, self.b) > MAX_ASPECT * min(self.a, self.b):
            raise CurveError(f"semi-axes {self.a:g} and {self.b:g} m: expected a ratio of at most {MAX_ASPECT:g}",
                             parameter="b", value=b)
        self._m = 1.0 - (self.a / self.b) ** 2
        self._quarter = self._arc(0.5 * math.pi)
        self.mass, self.inertia = uniform_mass_properties(
            "ellipse", self._moments(), 2.0 * max(self.a, self.b), mass=mass, inertia=inertia, density=density,
            centring_hint="an ellipse is centred")

    def __repr__(self) -> str:
        return f"Ellipse(a={self.a:g}, b={self.b:g}, mass={self.mass:g}, inertia={self.inertia:g})"

    @property
    def label(self) -> str:
        """``"ellipse, 50 x 30 mm semi-axes"``."""
        return f"ellipse, {self.a * 1e3:.4g} x {self.b * 1e3:.4g} mm semi-axes"

    def _arc(self, u: float) -> float:
        """F(u) [m], the arc length from u = 0 (the +x end) counter-clockwise to u."""
        return self.b * float(ellipeinc(u, self._m))

    def _speed(self, u: float) -> float:
        return math.hypot(self.a * math.sin(u), self.b * math.cos(u))

    def parameter(self, xi: float) -> float:
        """The ellipse's angle u [rad] of ξ [m] (a finite float): :math:`F(u) = F(\\pi/2) - \\xi`."""
        xi = as_finite_float("xi", xi)
        return self._parameter(xi)

    def _parameter(self, xi: float) -> float:
        target = self._quarter - xi
        lo_speed, hi_speed = min(self.a, self.b), max(self.a, self.b)
        lo, hi = (target / hi_speed, target / lo_speed) if target >= 0.0 else (target / lo_speed, target / hi_speed)
        u0 = target * 2.0 * math.pi / self.perimeter
        return bracketed_root(lambda u: (self._arc(u) - target, self._speed(u)), lo, hi, u0,
                               1e-15 * max(1.0, abs(u0)))

    @property
    def perimeter(self) -> float:
        """4 F(π/2) [m]."""
        return 4.0 * self._quarter

    def _local_floats(self, xi: float) -> tuple[float, float, float, float, float]:
        u = self._parameter(xi)
        c, s = math.cos(u), math.sin(u)
        speed = math.hypot(self.a * s, self.b * c)
        return self.a * c, self.b * s, -self.b * c / speed, -self.a * s / speed, self.a * self.b / speed ** 3

    def _moments(self) -> tuple[float, np.ndarray, float]:
        a, b = self.a, self.b
        area = math.pi * a * b
        return area, np.zeros(2), 0.25 * area * (a * a + b * b)

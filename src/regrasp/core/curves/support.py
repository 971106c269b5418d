r"""A smooth convex curve given by its support function, a finite Fourier series.

For the outward normal :math:`u(\theta) = (\cos\theta, \sin\theta)` the support function
:math:`h(\theta) = \max_{x} x \cdot u` is

.. math:: h(\theta) = a_0 + \sum_{k=1}^{K} a_k \cos k\theta + b_k \sin k\theta .

The boundary point with that normal is :math:`x(\theta) = h\,u + h'\,u^\perp` (:math:`u^\perp = du/d\theta`), the
radius of curvature :math:`\rho = h + h''` (> 0 everywhere for a smooth strictly convex curve: checked, with a
certificate, below), so :math:`dx/d\theta = \rho\, u^\perp`, the curvature is :math:`\kappa = 1/\rho` and the
arc length from θ = 0 is, in closed form,

.. math:: S(\theta) = a_0\theta + \sum_{k \ge 2} \frac{1 - k^2}{k}\left(a_k \sin k\theta - b_k(\cos k\theta - 1)\right),

with perimeter :math:`P = 2\pi a_0`. ξ (clockwise, :mod:`regrasp.core.curves.base`) is
:math:`\xi = S(\pi/2) - S(\theta)`, zero at the top (θ = π/2); the inward normal is :math:`n = -u`. θ(ξ) by
Newton's method kept in the bracket :math:`|S(\theta) - a_0\theta| \le B = \sum_k |1-k^2|(|a_k| + 2|b_k|)/k`
gives. The k = 1 terms translate the curve by :math:`(a_1, b_1)`: :meth:`SupportCurve.centred` chooses them so
that the centroid is the origin. Second moments by the trapezoidal rule in θ, exact for these trigonometric
polynomials.

**Convexity certificate.** ρ is sampled on N points; :math:`|\rho'| \le L = \sum_k |1 - k^2|\, k\,
\sqrt{a_k^2 + b_k^2}`, so :math:`\min \rho \ge \min_j \rho(\theta_j) - L\pi/N`; N doubles until that bound is
positive (convex) or a sample is not (not convex, :class:`~regrasp.core.exceptions.CurveError` at that θ).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from ..exceptions import CurveError
from ..validation import as_finite_array
from .base import CurvedObject, bracketed_root, uniform_mass_properties

__all__ = ["SupportCurve"]

#: The most samples of ρ the convexity certificate takes before it calls a curve too close to a corner.
_MAX_CERTIFICATE_SAMPLES = 1 << 20


class SupportCurve(CurvedObject):
    r"""The convex curve of support function :math:`h(\theta) = \sum_k a_k \cos k\theta + b_k \sin k\theta` (module
    docstring): ``cosines`` = :math:`(a_0, a_1, \dots, a_K)` [m], ``sines`` = :math:`(b_1, \dots, b_K)` [m]; mass
    properties as :func:`~regrasp.core.curves.base.uniform_mass_properties`.

    Raises:
        CurveError: :math:`a_0 \le 0`, or the radius of curvature is not positive somewhere (``where``: the
            outward normal's angle θ [rad]).
    """

    def __init__(self, cosines: ArrayLike, sines: ArrayLike, *, mass: float | None = None,
                 inertia: float | None = None, density: float | None = None):
        a = as_finite_array("cosines", cosines, (-1,))
        b = as_finite_array("sines", sines, (-1,))
        if a.size < 1 or b.size != a.size - 1:
            raise CurveError(f"{a.size} cosines and {b.size} sines: expected a_0..a_K and b_1..b_K (K sines)",
                             parameter="sines", value=sines)
        if not a[0] > 0.0:
            raise CurveError(f"a_0 = {a[0]:g} m: expected the mean radius a_0 > 0", parameter="cosines", value=cosines)
        self.cosines, self.sines = a.copy(), np.concatenate([[0.0], b])
        self.cosines.setflags(write=False)
        self.sines.setflags(write=False)
        self._k = np.arange(a.size, dtype=float)
        self._a0 = float(a[0])
        #: (k, a_k, b_k) for k >= 0 as floats (h's series; S's and ρ's skip their zero terms)
        self._terms = [(float(k), float(ak), float(bk)) for k, ak, bk in zip(self._k, self.cosines, self.sines)]
        self._certify()
        self._quarter = self._arc_and_rho(0.5 * math.pi)[0]
        k2 = self._k[2:]
        self._bound = float(np.sum(np.abs(1.0 - k2 ** 2) * (np.abs(a[2:]) + 2.0 * np.abs(b[1:])) / k2))
        self.mass, self.inertia = uniform_mass_properties(
            "curve", self._moments(), 2.0 * float(np.sum(np.abs(a)) + np.sum(np.abs(b))), mass=mass, inertia=inertia,
            density=density, centring_hint="SupportCurve.centred() sets a_1 and b_1 so that it is")

    def __repr__(self) -> str:
        return f"SupportCurve(K={self.cosines.size - 1}, mass={self.mass:g}, inertia={self.inertia:g})"

    @property
    def label(self) -> str:
        """``"support-function curve, K = 4"``."""
        return f"support-function curve, K = {self.cosines.size - 1}"

    @classmethod
    def centred(cls, cosines: ArrayLike, sines: ArrayLike, **mass_properties: float | None) -> "SupportCurve":
        """The curve of these coefficients translated (its a_1, b_1 changed) so that its centroid is the origin."""
        a = np.array(as_finite_array("cosines", cosines, (-1,)), dtype=float)
        b = np.array(as_finite_array("sines", sines, (-1,)), dtype=float)
        if a.size < 2:
            a, b = np.concatenate([a, np.zeros(2 - a.size)]), np.concatenate([b, np.zeros(1 - b.size)])
        centroid = cls(a, b, mass=1.0, inertia=1.0).centroid
        a[1] -= centroid[0]
        b[0] -= centroid[1]
        return cls(a, b, **mass_properties)

    # ------------------------------------------------------------------ the series
    def _series(self, theta: float) -> tuple[float, float, float]:
        """(h, h', h'') at θ [rad] (plain floats: K is small and numpy's per-call cost would dominate)."""
        h = dh = ddh = 0.0
        for k, a, b in self._terms:
            c, s = math.cos(k * theta), math.sin(k * theta)
            h += a * c + b * s
            dh += k * (b * c - a * s)
            ddh -= k * k * (a * c + b * s)
        return h, dh, ddh

    def _arc_and_rho(self, theta: float) -> tuple[float, float]:
        """(S(θ) [m], ρ(θ) = h + h'' [m])."""
        arc, rho = self._a0 * theta, 0.0
        for k, a, b in self._terms:
            c, s = math.cos(k * theta), math.sin(k * theta)
            factor = 1.0 - k * k
            rho += factor * (a * c + b * s)
            if k > 1:
                arc += factor / k * (a * s - b * (c - 1.0))
        return arc, rho

    def _certify(self) -> None:
        k, a, b = self._k, self.cosines, self.sines
        lipschitz = float(np.sum(np.abs(1.0 - k * k) * k * np.hypot(a, b)))
        n = 256
        while n <= _MAX_CERTIFICATE_SAMPLES:
            theta = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
            kt = np.outer(theta, k)
            rho = (np.cos(kt) @ (a * (1.0 - k * k))) + (np.sin(kt) @ (b * (1.0 - k * k)))
            j = int(np.argmin(rho))
            if rho[j] <= 0.0:
                raise CurveError(f"the radius of curvature h + h'' is {rho[j]:.4g} m at the outward normal angle "
                                 f"θ = {theta[j]:.4f} rad: the curve is not convex there (expected > 0 everywhere)",
                                 parameter="cosines", value=self.cosines.tolist(), where=float(theta[j]))
            if rho[j] - lipschitz * math.pi / n > 0.0:
                return
            n *= 2
        raise CurveError("the radius of curvature comes within rounding of 0: the curve has a corner (use a "
                         "RoundedPolygon)", parameter="cosines", value=self.cosines.tolist())

    def normal_angle(self, xi: float) -> float:
        """The outward normal's angle θ [rad] at ξ [m] (a float): :math:`S(\\theta) = S(\\pi/2) - \\xi`."""
        target = self._quarter - float(xi)
        a0 = self._a0

        def residual(theta: float) -> tuple[float, float]:
            arc, rho = self._arc_and_rho(theta)
            return arc - target, rho

        return bracketed_root(residual,
                              (target - self._bound) / a0 - 1e-12, (target + self._bound) / a0 + 1e-12,
                              target / a0, 1e-15 * max(1.0, abs(target / a0)))

    @property
    def perimeter(self) -> float:
        """2π a_0 [m]."""
        return 2.0 * math.pi * float(self.cosines[0])

    def _local_floats(self, xi: float) -> tuple[float, float, float, float, float]:
        theta = self.normal_angle(xi)
        h, dh, ddh = self._series(theta)
        c, s = math.cos(theta), math.sin(theta)
        return h * c - dh * s, h * s + dh * c, -c, -s, 1.0 / (h + ddh)

    def _moments(self) -> tuple[float, np.ndarray, float]:
        n = 8 * self.cosines.size + 64
        theta = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
        rows = np.array([self._series(t) for t in theta])
        h, dh, ddh = rows[:, 0], rows[:, 1], rows[:, 2]
        c, s = np.cos(theta), np.sin(theta)
        x, y = h * c - dh * s, h * s + dh * c
        rho = h + ddh
        tx, ty = -s * rho, c * rho  # dx/dθ, counter-clockwise
        w = 2.0 * math.pi / n
        area = 0.5 * w * float(np.sum(x * ty - y * tx))
        centroid = np.array([0.5 * w * float(np.sum(x * x * ty)), -0.5 * w * float(np.sum(y * y * tx))]) / area
        polar = w * float(np.sum(x ** 3 * ty - y ** 3 * tx)) / 3.0
        return area, centroid, polar

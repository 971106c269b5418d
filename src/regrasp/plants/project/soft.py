r"""The project plant's equations with compliant normal contacts (:class:`PadEquations`): a
:class:`~regrasp.core.pad.Pad` on every fingertip, on the reference path only.

**What remains of the constraints.** With a pad a touching contact's normal is not a constraint but the pad's
force (:mod:`regrasp.core.pad`): with :math:`r_i = p_i - x_o`, :math:`n_i = R n^o`, :math:`t_i = R t^o`,

.. math::

    \delta_i = n_i\cdot r_i - e + \delta_0, \qquad
    \dot\delta_i = \omega\, (n_i\times r_i) + n_i\cdot(\dot p_i - v_o), \qquad
    f_{n,i} = \max(0, k\delta_i + c\dot\delta_i)\ (\delta_i > 0), \ 0\ \text{else}.

* ``FIXED``: one bilateral row along the edge's tangent, the tip's material point does not move along the edge
  (it may move along the normal): :math:`\chi_i = t_i\cdot r_i - (t^o\cdot o + \xi_i) = 0`, i.e. the tip's ξ stays
  the contact's; its multiplier :math:`\lambda_t` is the tangential force (on the object, along :math:`t_i`). The
  row is the rigid plant's sliding row with t for n (so its second derivative and Baumgarte terms are those);
  the force on the object is :math:`f_{n,i} n_i + \lambda_t t_i`.
* ``SLIDING``: no row; the force on the object is the explicit :math:`f_{n,i}(n_i + \mu_k s_i t_i)` (on the tip,
  friction :math:`-\mu_k s_i f_{n,i} t_i` opposes its sliding).
* ``SEPARATED``: nothing.

**On a curved object** (:mod:`regrasp.plants.project.curve`) the pad's depth is minus the tip's signed distance
from the curve plus :math:`\delta_0`, along the foot's normal: a sliding contact's :math:`\delta_i` and
:math:`\dot\delta_i` are the rigid sliding constraint's :math:`\psi + \delta_0` and :math:`\dot\psi` at the
foot, its force :math:`f_{n,i}(N + \mu_k s_i T)`; a fixed contact's tangential row keeps the tip on the curve's
normal line through :math:`c(\xi_i)`, where the depth along that normal is exactly :math:`-\delta + \delta_0`, so
it is the formulas above with the tangent line at :math:`c(\xi_i)` for the edge.

The explicit forces F enter as known generalized forces, :math:`\tau - N - J_i^T F_i` on finger i and
:math:`(\sum F_i, \sum r_i\times F_i)` on the object; the tangential rows' multipliers then come from the same
Delassus system as the rigid plant's (:meth:`PlantEquations.multipliers`), whose right-hand side now also carries
the object's free angular acceleration :math:`\sum r_i\times F_i / I` (the rigid plant's has none).

**Substeps.** The pad makes the equations stiff: the plant integrates a control step of dt in
:meth:`PadEquations.substeps` RK4 steps, as many as :meth:`~regrasp.core.pad.Pad.substeps_for` asks for the
largest row sum of the touching contacts' mobility matrix :math:`W_{ij} = n_i\cdot\Lambda_i^{-1}
(n_j + \mu_j s_j t_j)\delta_{ij} + (n_i\cdot u_j)/m_o + (r_i\times n_i)(r_j\times u_j)/I` (:math:`u_j` the
direction of contact j's pad force, :math:`\Lambda_i^{-1} = J_iM_i^{-1}J_i^T`), an upper bound (Gershgorin) on
:math:`kW`'s eigenvalues; the tangential rows only take mobility away.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from ...core.contact import ContactMode
from ...core.curves import CurvedObject
from ...core.exceptions import InvalidParameterError
from ...core.pad import Pad
from ...core.polygon import ConvexPolygon
from ...model.hand import Hand
from .curve import CURVE_SLIDING, curve_depth, curve_specs
from .equations import PlantEquations
from .state import PlantContact

__all__ = ["PadEquations"]

_MODE_FIXED, _MODE_SLIDING, _MODE_SEPARATED = ContactMode.FIXED, ContactMode.SLIDING, ContactMode.SEPARATED


def tangent_rows(specs: tuple) -> list[tuple]:
    """The bilateral rows of pad ``specs`` (:meth:`PadEquations.specs`): each fixed contact's tangential row, in the
    form of the rigid plant's sliding row ``(i, SLIDING, t_x, t_y, offset, 0)`` (no friction in its column)."""
    return [(spec[0], _MODE_SLIDING, spec[6], spec[7], spec[8], 0.0) for spec in specs if spec[1] is _MODE_FIXED]


class PadEquations(PlantEquations):
    """The plant's equations with a ``pad`` on every fingertip (module docstring); the other arguments are
    :class:`~regrasp.plants.project.equations.PlantEquations`'."""

    def __init__(self, hand: Hand, polygon: ConvexPolygon | CurvedObject, kinetic: Sequence[float], mass: float,
                 inertia: float, alpha: float, pad: Pad):
        super().__init__(hand, polygon, kinetic, mass, inertia, alpha)
        if not isinstance(pad, Pad):
            raise InvalidParameterError("pad", pad, "a Pad (regrasp.core.pad)")
        self.pad = pad
        self.stiffness, self.damping_rate, self.depth0 = pad.stiffness, pad.damping, pad.preload_depth
        #: The RK4 steps the last :meth:`integrate` took.
        self.last_substeps = 0

    def specs(self, contacts: Sequence[PlantContact]) -> tuple[tuple, ...]:
        """The touching contacts as floats: ``(i, mode, n_x, n_y, e - δ_0, μ_k s)`` (the edge's normal, object frame;
        s = 0 for a fixed contact), a fixed one followed by ``t_x, t_y, t·o + ξ`` (its tangential row); on a curve
        :func:`~regrasp.plants.project.curve.curve_specs`' with the pad's preload depth."""
        if self.curve is not None:
            return curve_specs(self.curve, contacts, self.kinetic, self.depth0)
        out, kinetic = [], self.kinetic
        for i, c in enumerate(contacts):
            mode = c.mode
            if mode is _MODE_SEPARATED:
                continue
            if mode is not _MODE_FIXED and mode is not _MODE_SLIDING:
                raise InvalidParameterError("mode", mode, "a ContactMode member (PlantContact converts strings)")
            g = self.edge(c.edge)
            if mode is _MODE_FIXED:
                out.append((i, _MODE_FIXED, g.nx, g.ny, g.offset - self.depth0, 0.0,
                            g.tx, g.ty, g.tx * g.ox + g.ty * g.oy + c.xi))
            else:
                out.append((i, _MODE_SLIDING, g.nx, g.ny, g.offset - self.depth0, kinetic[i] * c.sign))
        return tuple(out)

    @staticmethod
    def violations(specs: tuple, X: list, tips: list) -> float:
        """Largest violation [m] of the fixed contacts' tangential rows at pose X with tips (floats)."""
        return PlantEquations.violations(tuple(tangent_rows(specs)), X, tips)

    def rows(self, fingers: list[tuple], specs: tuple, X: list, V: list, free: list | None = None,
             gravity: tuple | list = (0.0, 0.0)) -> tuple[list, list, list]:
        """:meth:`PlantEquations.rows` of the fixed contacts' tangential rows (the object's free angular acceleration
        is the caller's to subtract)."""
        return super().rows(fingers, tuple(tangent_rows(specs)), X, V, free, gravity)

    def depths(self, specs: tuple, X: list, V: list, fingers: list[tuple]) -> list[tuple]:
        r"""Per touching contact ``(i, δ, δ̇, n_x, n_y, r_x, r_y)``: its pad's penetration [m] and rate [m/s], its
        normal (hand frame) and the tip relative to the object's centre [m] (module docstring)."""
        x, y, beta = X
        vx, vy, w = V
        c, s = math.cos(beta), math.sin(beta)
        out = []
        for spec in specs:
            if spec[1] is CURVE_SLIDING:
                out.append(curve_depth(spec, fingers[spec[0]], x, y, c, s, V))
                continue
            i, _, ux, uy, offset = spec[:5]
            px, py, pvx, pvy = fingers[i][11:15]
            rx, ry = px - x, py - y
            nx, ny = c * ux - s * uy, s * ux + c * uy
            out.append((i, nx * rx + ny * ry - offset, w * (nx * ry - ny * rx) + nx * (pvx - vx) + ny * (pvy - vy),
                        nx, ny, rx, ry))
        return out

    def pad_forces(self, specs: tuple, X: list, V: list, fingers: list[tuple]) -> list[list[float]]:
        """Each finger's explicit contact force on the object [N] (hand frame): its pad's normal force, and a
        slider's kinetic friction."""
        k, c = self.stiffness, self.damping_rate
        out = [[0.0, 0.0] for _ in fingers]
        for spec, (i, depth, rate, nx, ny, _, _) in zip(specs, self.depths(specs, X, V, fingers)):
            if depth > 0.0:
                fn = k * depth + c * rate
                if fn > 0.0:
                    mus = spec[5]
                    out[i] = [fn * (nx - mus * ny), fn * (ny + mus * nx)]
        return out

    def solve(self, fingers: list[tuple], specs: tuple, X: list, V: list, tau: tuple) -> tuple[list, list, list]:
        """(q̈, Ẍ, forces) as lists of floats: forces (fx, fy) per finger on the object (pad, friction and the
        tangential rows' multipliers)."""
        gravity = self.hand.gravity_in_hand.tolist()
        explicit = self.pad_forces(specs, X, V, fingers)
        fx_sum = fy_sum = moment = 0.0
        free = []  # per finger: the tip's acceleration at q̈ = M^-1 (τ - N - J^T F), and τ - N - J^T F
        for i, f in enumerate(fingers):
            fx, fy = explicit[i]
            if fx or fy:
                rx, ry = f[11] - X[0], f[12] - X[1]
                fx_sum, fy_sum, moment = fx_sum + fx, fy_sum + fy, moment + rx * fy - ry * fx
            r0 = tau[2 * i] - f[3] - (f[5] * fx + f[7] * fy)
            r1 = tau[2 * i + 1] - f[4] - (f[6] * fx + f[8] * fy)
            u0, u1 = f[15] * r0 + f[16] * r1, f[16] * r0 + f[17] * r1
            free.append((f[5] * u0 + f[6] * u1, f[7] * u0 + f[8] * u1, r0, r1))
        a_obj = [gravity[0] + fx_sum / self.mass, gravity[1] + fy_sum / self.mass, moment / self.inertia]
        rows, rhs, cols = self.rows(fingers, specs, X, V, free, a_obj[:2])
        if rows:
            rhs = [b - row[5] * a_obj[2] for b, row in zip(rhs, rows)]
            tip_sum, obj = self.multipliers(fingers, rows, cols, rhs)
        else:
            tip_sum, obj = [[0.0, 0.0] for _ in fingers], (0.0, 0.0, 0.0)
        qdd, forces = [], []
        for (fx, fy), (ex, ey), f, (_, _, r0, r1) in zip(tip_sum, explicit, fingers, free):
            r0, r1 = r0 - (f[5] * fx + f[7] * fy), r1 - (f[6] * fx + f[8] * fy)
            qdd += (f[15] * r0 + f[16] * r1, f[16] * r0 + f[17] * r1)
            forces.append([fx + ex, fy + ey])
        return qdd, [a_obj[0] + obj[0] / self.mass, a_obj[1] + obj[1] / self.mass,
                     a_obj[2] + obj[2] / self.inertia], forces

    def mobility(self, specs: tuple, X: list, V: list, fingers: list[tuple]) -> float:
        r"""The largest row sum [1/kg] of the touching contacts' mobility matrix (module docstring; 0: none)."""
        im, ii = 1.0 / self.mass, 1.0 / self.inertia
        contacts = []
        for spec, (i, _, _, nx, ny, rx, ry) in zip(specs, self.depths(specs, X, V, fingers)):
            mus = spec[5]
            ux, uy = nx - mus * ny, ny + mus * nx
            contacts.append((i, nx, ny, ux, uy, rx * ny - ry * nx, rx * uy - ry * ux))
        worst = 0.0
        for i, nx, ny, _, _, mn, _ in contacts:
            total = 0.0
            for j, _, _, ux, uy, _, mu in contacts:
                w = (nx * ux + ny * uy) * im + mn * mu * ii
                if i == j:
                    l00, l01, l11 = fingers[i][18:21]
                    w += nx * (l00 * ux + l01 * uy) + ny * (l01 * ux + l11 * uy)
                total += abs(w)
            worst = max(worst, total)
        return worst

    def substeps(self, specs: tuple, X: list, V: list, fingers: list[tuple], dt: float) -> int:
        """RK4 steps for a control step of ``dt`` [s] from the state (X, V, ``fingers``): module docstring."""
        return self.pad.substeps_for(dt, self.mobility(specs, X, V, fingers))

    def integrate(self, y: list, k1: list, forces: list, fingers: list[tuple], tau: tuple, specs: tuple,
                  dt: float) -> tuple[list, list]:
        r"""The flat state y (:meth:`evaluate`'s) after a control step of ``dt`` [s] at torques ``tau``: RK4 in
        :meth:`substeps` steps, the first from ``k1`` (y's derivative), ``forces`` and the dynamics ``fingers`` at
        y; and the contact forces averaged over the step [N] (per finger, on the object, hand frame), each substep's
        by RK4's weights, :math:`rac{1}{dt}\int f\,dt` to RK4's order."""
        n = self.hand.nq
        count = self.substeps(specs, y[2 * n:2 * n + 3], y[2 * n + 3:2 * n + 6], fingers, dt)
        h = dt / count
        half = h / 2
        mean = [[0.0, 0.0] for _ in fingers]
        for step in range(count):
            if step:
                k1, forces, _ = self.evaluate(y, tau, specs)
            k2, f2, _ = self.evaluate([a + half * b for a, b in zip(y, k1)], tau, specs)
            k3, f3, _ = self.evaluate([a + half * b for a, b in zip(y, k2)], tau, specs)
            k4, f4, _ = self.evaluate([a + h * b for a, b in zip(y, k3)], tau, specs)
            y = [a + h * ((b1 + 2 * b2 + 2 * b3 + b4) / 6.0) for a, b1, b2, b3, b4 in zip(y, k1, k2, k3, k4)]
            for total, a, b, c, d in zip(mean, forces, f2, f3, f4):
                total[0] += (a[0] + 2 * b[0] + 2 * c[0] + d[0]) / (6.0 * count)
                total[1] += (a[1] + 2 * b[1] + 2 * c[1] + d[1]) / (6.0 * count)
        self.last_substeps = count
        return y, mean

    def pad_energy(self, specs: tuple, X: list, V: list, fingers: list[tuple]) -> float:
        r"""The touching pads' elastic energy [J], :math:`\sum_i k\delta_{i+}^2/2`."""
        return sum(self.pad.energy(depth) for _, depth, *_ in self.depths(specs, X, V, fingers))

r"""The project plant's equations of motion on the reference path, in plain floats (:class:`PlantEquations`).

**Coordinates.** Joint positions q (2m) and the object pose X = (x_o, β), with velocities v and V = (v_o, ω).
Contact i joins the tip :math:`p_i(q)` to the object:

* ``FIXED``: the tip stays at the object point :math:`c_i` (object frame):
  :math:`\phi_i = p_i - x_o - R(\beta) c_i = 0` (two rows); the force on the object
  :math:`f_i = \lambda_i \in \mathbb R^2` is a multiplier;
* ``SLIDING``: the tip stays on the edge's line :math:`\{c : n^o\cdot c = e\}`:
  :math:`\psi_i = n_i \cdot (p_i - x_o) - e = 0` with :math:`n_i = R n^o` (one row); the force
  on the object is :math:`f_i = \lambda_{n}(n_i + \mu_k s_i t_i)`: Coulomb friction of magnitude
  :math:`\mu_k\lambda_n` (the kinetic coefficient), opposing the tip's sliding velocity relative
  to the object (:math:`s_i` is the sign of that velocity along :math:`t_i`);
* ``SEPARATED``: no constraint, no force.

On a curved object (:mod:`regrasp.core.curves`) a fixed contact's point is the curve's :math:`c(\xi_i)` and a
sliding contact's line is the tangent at its tip's foot, re-evaluated at every evaluation, with a curvature term
in its second derivative (:mod:`regrasp.plants.project.curve`).

**Equations.** :math:`M\ddot q + N = \tau - \sum_i J_i^T f_i`,
:math:`M_o \ddot X = f_g + \sum_i (f_i,\ (p_i - x_o)\times f_i)`, and every constraint's second
derivative, Baumgarte-stabilised: :math:`\ddot\phi + 2\alpha\dot\phi + \alpha^2\phi = 0`. One
linear solve per evaluation gives (q̈, Ẍ, λ): M is block diagonal (the fingers' 2x2 blocks and
the object's), so the multipliers come from the Delassus system :math:`C M^{-1} W \lambda = b -
C M^{-1}(\tau - N, f_g)` (one row per constraint, in plain floats), then the accelerations.

The plant (:class:`~regrasp.plants.project.plant.Plant`) integrates them with RK4; the compiled kernel
(:mod:`regrasp.kernels.plant`) is the same arithmetic, checked against this path.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from ...core.contact import ContactMode
from ...core.curves import CurvedObject
from ...core.exceptions import InvalidParameterError
from ...core.polygon import ConvexPolygon
from ...core.scalar import solve_small
from ...model.hand import Hand
from .curve import CURVE_SLIDING, curve_specs, curve_violation, foot, sliding_row
from .state import EdgeGeometry, PlantContact, PlantState, edge_geometry

__all__ = ["PlantEquations"]

# the members as module constants for the hot paths (``ContactMode.FIXED`` is a class-attribute
# lookup through the enum's metaclass, ~0.3 us; a global is ~20 ns); compared with ``is``
_MODE_FIXED, _MODE_SLIDING, _MODE_SEPARATED = ContactMode.FIXED, ContactMode.SLIDING, ContactMode.SEPARATED
_LWA = pin.LOCAL_WORLD_ALIGNED


class PlantEquations:
    """The plant's equations (module docstring) for a hand, an object of ``mass`` [kg] and ``inertia`` [kg m²],
    the contacts' kinetic coefficients ``kinetic`` [-] and the Baumgarte ``alpha`` [1/s]; the plant's own
    Pinocchio data on the hand's model of all fingers (their gravity and link masses). ``polygon``: the object's
    geometry, a :class:`~regrasp.core.polygon.ConvexPolygon` or a :class:`~regrasp.core.curves.CurvedObject`."""

    def __init__(self, hand: Hand, polygon: ConvexPolygon | CurvedObject, kinetic: Sequence[float], mass: float,
                 inertia: float, alpha: float):
        self.hand, self.polygon = hand, polygon
        #: The object if it is curved (:mod:`regrasp.plants.project.curve`), else None (a polygon).
        self.curve = polygon if isinstance(polygon, CurvedObject) else None
        self.kinetic = list(kinetic)
        self.mass, self.inertia, self.alpha = mass, inertia, alpha
        self._pin_data = (hand.pinocchio_model, hand.pinocchio_model.createData())
        # per finger: its tip frame in that model, its joints' damping and joint 1's axis
        self._pin = [(tip, *np.asarray(model.damping, dtype=float).tolist(),
                      *model.jointPlacements[1].translation[:2].tolist())
                     for model, tip in zip(hand.finger_models, hand.tip_frame_ids)]
        #: Each finger's joint 1 axis (x, y) [m] in the hand frame.
        self.joint1_axes = [entry[3:5] for entry in self._pin]
        #: Each joint's damping [N m s/rad], and zeros for a hand without damping.
        self.damping = tuple(d for entry in self._pin for d in entry[1:3])
        self.no_damping = (0.0,) * hand.nq
        self._edges: dict[int, EdgeGeometry] = {}

    def edge(self, k: int) -> EdgeGeometry:
        """Edge ``k``'s constants as floats (object frame), cached."""
        geo = self._edges.get(k)
        if geo is None:
            geo = self._edges[k] = edge_geometry(self.polygon, k)
        return geo

    def tip(self, st: PlantState, i: int) -> tuple[np.ndarray, np.ndarray]:
        """Finger i's tip position [m] and velocity [m/s] (hand frame) at state ``st``."""
        f = self.hand.fingers[i]
        qi, vi = st.q[2 * i:2 * i + 2], st.v[2 * i:2 * i + 2]
        tip = f.forward_kinematics(qi)
        return tip, f.tip_jacobian(qi) @ vi

    def gap(self, st: PlantState, i: int, edge: int, near: float | None = None) -> float:
        """Tip i's distance [m] from edge ``edge``'s line at state ``st``: positive outside the object (a curve's:
        its signed distance from the curve; ``near``: the contact's last ξ [m], where its foot is sought)."""
        if self.curve is not None:
            return foot(self.curve, st.X.tolist(), self.tip(st, i)[0].tolist(), near).delta
        g = self.edge(edge)
        tip = self.tip(st, i)[0].tolist()
        X = st.X.tolist()
        c, s = math.cos(X[2]), math.sin(X[2])
        rx, ry = tip[0] - X[0], tip[1] - X[1]
        return g.offset - (g.nx * (c * rx + s * ry) + g.ny * (c * ry - s * rx))

    def specs(self, contacts: Sequence[PlantContact]) -> tuple[tuple, ...]:
        """The active contacts as floats (a tuple): ``(i, FIXED, c_x, c_y)`` (the contact point,
        object frame) or ``(i, SLIDING, n_x, n_y, n·ξ-origin, μ_k s)`` (the edge's normal); on a curve
        :func:`~regrasp.plants.project.curve.curve_specs`'."""
        if self.curve is not None:
            return curve_specs(self.curve, contacts, self.kinetic)
        out, kinetic = [], self.kinetic
        for i, c in enumerate(contacts):
            mode = c.mode
            if mode is _MODE_FIXED:
                g = self.edge(c.edge)
                out.append((i, _MODE_FIXED, g.ox + c.xi * g.tx, g.oy + c.xi * g.ty))
            elif mode is _MODE_SLIDING:
                g = self.edge(c.edge)
                out.append((i, _MODE_SLIDING, g.nx, g.ny, g.offset, kinetic[i] * c.sign))
            elif mode is not _MODE_SEPARATED:  # e.g. a string assigned to a contact's mode after construction
                raise InvalidParameterError("mode", mode, "a ContactMode member (PlantContact converts strings)")
        return tuple(out)

    @staticmethod
    def violations(specs: tuple, X: list, tips: list) -> float:
        """Largest violation of the constraints ``specs`` at pose X with tips (floats)."""
        c, s = math.cos(X[2]), math.sin(X[2])
        worst = 0.0
        for spec in specs:
            i = spec[0]
            rx, ry = tips[i][0] - X[0], tips[i][1] - X[1]
            if spec[1] is _MODE_FIXED:
                ex, ey = rx - (c * spec[2] - s * spec[3]), ry - (s * spec[2] + c * spec[3])
                err = math.sqrt(ex * ex + ey * ey)
            elif spec[1] is CURVE_SLIDING:
                err = curve_violation(spec, c, s, rx, ry)
            else:
                err = abs((c * spec[2] - s * spec[3]) * rx + (s * spec[2] + c * spec[3]) * ry - spec[4])
            worst = max(worst, err)
        return worst

    def pin_pass(self, q: np.ndarray, v: np.ndarray) -> list[tuple]:
        r"""Per finger at (q, v), as floats: M (0-2: m00, m01, m11), N (3-4: Coriolis, gravity,
        damping), the tip Jacobian J (5-8: j00, j01, j10, j11), J̇q̇ (9-10), the tip p (11-12) and
        its velocity J q̇ (13-14), :math:`M^{-1}` (15-17: i00, i01, i11), :math:`J M^{-1} J^T`
        (18-20: l00, l01, l11).

        One ``computeAllTerms`` (M, N) of the whole hand and one ``getFrameJacobian`` per finger, on the
        plant's own Pinocchio data. The finger is a planar chain of revolute joints about z (validated by
        :class:`~regrasp.model.finger.Finger`), so J's columns are :math:`e_z \times (p - o_1)` and
        :math:`e_z \times (p - o_2)` (joint axes :math:`o_1` fixed, :math:`o_2` the elbow): p follows
        from :math:`o_1`, and :math:`\dot J\dot q = -\dot q_1^2 (o_2 - o_1) - (\dot q_1 + \dot q_2)^2
        (p - o_2)`, the tip's acceleration at :math:`\ddot q = 0` (Pinocchio's classical
        acceleration; ``tests/plants/project/test_plant.py`` checks both against :meth:`Hand.dynamics`)."""
        damped = self.hand.damping_enabled
        model, data = self._pin_data
        pin.computeAllTerms(model, data, q, v)
        mass, nle, vel = data.M.tolist(), data.nle.tolist(), v.tolist()  # (M's upper triangle: crba's)
        out = []
        for i, (fid, d0, d1, ox, oy) in enumerate(self._pin):
            r = 2 * i
            m00, m01, m11 = mass[r][r], mass[r][r + 1], mass[r + 1][r + 1]
            n0, n1 = nle[r], nle[r + 1]
            v0, v1 = vel[r], vel[r + 1]
            if damped:
                n0 += d0 * v0
                n1 += d1 * v1
            (j00, j01), (j10, j11) = pin.getFrameJacobian(model, data, fid, _LWA)[:2, r:r + 2].tolist()
            w1, w2 = v0 * v0, (v0 + v1) * (v0 + v1)
            det = m00 * m11 - m01 * m01
            i00, i01, i11 = m11 / det, -m01 / det, m00 / det
            k00, k01 = j00 * i00 + j01 * i01, j00 * i01 + j01 * i11  # J M^-1
            k10, k11 = j10 * i00 + j11 * i01, j10 * i01 + j11 * i11
            out.append((m00, m01, m11, n0, n1, j00, j01, j10, j11,
                        -w1 * (j10 - j11) - w2 * j11, w2 * j01 - w1 * (j01 - j00), ox + j10, oy - j00,
                        j00 * v0 + j01 * v1, j10 * v0 + j11 * v1, i00, i01, i11,
                        k00 * j00 + k01 * j01, k00 * j10 + k01 * j11, k10 * j10 + k11 * j11))
        return out

    def rows(self, fingers: list[tuple], specs: tuple, X: list, V: list, free: list | None = None,
             gravity: tuple | list = (0.0, 0.0)) -> tuple[list, list, list]:
        r"""Per active contact, its constraint rows ``(i, d_x, d_y, c_0, c_1, c_2)`` (the row acting
        on (q̈, Ẍ) is :math:`(d^T J_i, c)`), their right-hand sides, and its force columns
        ``(i, f_x, f_y, o_0, o_1, o_2)`` (a unit multiplier is the force f on the object at the tip:
        :math:`-J_i^T f` on finger i, o = (f, r × f) on the object).

        The right-hand side is the Baumgarte one, b, less the rows applied to the free accelerations
        (:math:`C M^{-1}(\tau - N, f_g)`): ``free`` gives each finger's free tip acceleration
        :math:`J M^{-1}(\tau - N)` (None: zero), ``gravity`` the object's."""
        x, y, beta = X
        vx, vy, w = V
        g0, g1 = gravity
        c, s = math.cos(beta), math.sin(beta)
        alpha2, alpha_sq, w_sq = 2 * self.alpha, self.alpha**2, w**2
        rows, rhs, cols = [], [], []
        for spec in specs:
            i, kind, ux, uy = spec[:4]
            jax, jay, px, py, pvx, pvy = fingers[i][9:15]
            fax, fay = (0.0, 0.0) if free is None else free[i][:2]
            rx, ry = px - x, py - y
            if kind is _MODE_FIXED:
                rcx, rcy = c * ux - s * uy, s * ux + c * uy
                rows += ((i, 1.0, 0.0, -1.0, 0.0, rcy), (i, 0.0, 1.0, 0.0, -1.0, -rcx))
                rhs += (-jax - w_sq * rcx - alpha2 * (pvx - vx + w * rcy) - alpha_sq * (rx - rcx) - (fax - g0),
                        -jay - w_sq * rcy - alpha2 * (pvy - vy - w * rcx) - alpha_sq * (ry - rcy) - (fay - g1))
                cols += ((i, 1.0, 0.0, 1.0, 0.0, -ry), (i, 0.0, 1.0, 0.0, 1.0, rx))
            elif kind is CURVE_SLIDING:
                row, b, col = sliding_row(spec, fingers[i], rx, ry, c, s, V, (fax - g0, fay - g1), self.alpha)
                rows.append(row)
                rhs.append(b)
                cols.append(col)
            else:
                nx, ny = c * ux - s * uy, s * ux + c * uy
                nr, tr = nx * rx + ny * ry, nx * ry - ny * rx
                rvx, rvy = pvx - vx, pvy - vy
                psi_dot = w * tr + (nx * rvx + ny * rvy)
                drift = -w_sq * nr + 2 * w * (nx * rvy - ny * rvx) + (nx * jax + ny * jay)
                rows.append((i, nx, ny, -nx, -ny, tr))
                rhs.append(-drift - alpha2 * psi_dot - alpha_sq * (nr - spec[4]) - (nx * (fax - g0) + ny * (fay - g1)))
                fx, fy = nx - spec[5] * ny, ny + spec[5] * nx
                cols.append((i, fx, fy, fx, fy, rx * fy - ry * fx))
        return rows, rhs, cols

    def multipliers(self, fingers: list[tuple], rows: list, cols: list, rhs: list) -> tuple[list, tuple]:
        r"""Solve :math:`C M^{-1} W \lambda = rhs` (the Delassus form of the KKT system: M is block
        diagonal) and return :math:`\sum f\lambda` per finger and :math:`\sum o\lambda`."""
        im, ii = 1.0 / self.mass, 1.0 / self.inertia
        a = []
        for ri, dx, dy, c0, c1, c2 in rows:
            l00, l01, l11 = fingers[ri][18:21]
            ux, uy = dx * l00 + dy * l01, dx * l01 + dy * l11
            c0, c1, c2 = c0 * im, c1 * im, c2 * ii
            a.append([c0 * o0 + c1 * o1 + c2 * o2 - (ux * fx + uy * fy if ri == ci else 0.0)
                      for ci, fx, fy, o0, o1, o2 in cols])
        tip_sum = [[0.0, 0.0] for _ in fingers]
        s0 = s1 = s2 = 0.0
        for value, (i, fx, fy, o0, o1, o2) in zip(solve_small(a, rhs), cols):
            f = tip_sum[i]
            f[0] += fx * value
            f[1] += fy * value
            s0 += o0 * value
            s1 += o1 * value
            s2 += o2 * value
        return tip_sum, (s0, s1, s2)

    def solve(self, fingers: list[tuple], specs: tuple, X: list, V: list, tau: tuple) -> tuple[list, list, list]:
        """(q̈, Ẍ, forces) as lists of floats: forces (fx, fy) per finger on the object."""
        gravity = self.hand.gravity_in_hand.tolist()
        free = []  # per finger: the tip's acceleration at q̈ = M^-1 (τ - N), and τ - N
        for i, f in enumerate(fingers):
            r0, r1 = tau[2 * i] - f[3], tau[2 * i + 1] - f[4]
            u0, u1 = f[15] * r0 + f[16] * r1, f[16] * r0 + f[17] * r1
            free.append((f[5] * u0 + f[6] * u1, f[7] * u0 + f[8] * u1, r0, r1))
        rows, rhs, cols = self.rows(fingers, specs, X, V, free, gravity)
        if rows:
            forces, obj = self.multipliers(fingers, rows, cols, rhs)
        else:
            forces, obj = [[0.0, 0.0] for _ in fingers], (0.0, 0.0, 0.0)
        qdd = []
        for (fx, fy), f, (_, _, r0, r1) in zip(forces, fingers, free):
            r0, r1 = r0 - (f[5] * fx + f[7] * fy), r1 - (f[6] * fx + f[8] * fy)
            qdd += (f[15] * r0 + f[16] * r1, f[16] * r0 + f[17] * r1)
        return qdd, [gravity[0] + obj[0] / self.mass, gravity[1] + obj[1] / self.mass, obj[2] / self.inertia], forces

    def project_velocities(self, st: PlantState, contacts: Sequence[PlantContact]) -> float:
        """Remove the velocity that violates the active constraints (a plastic sticking impulse):
        the mass-weighted projection of (q̇, V) onto C (q̇, V) = 0. Returns the kinetic energy [J]
        it removes (negative), which is friction's doing and is booked as contact work."""
        fingers = self.pin_pass(st.q, st.v)
        X, V = st.X.tolist(), st.V.tolist()
        rows, _, _ = self.rows(fingers, self.specs(contacts), X, V)
        if not rows:
            return 0.0
        # z_new = z - M^-1 C^T μ with C M^-1 C^T μ = C z: columns (d, -c) in multipliers' form
        cols = [(i, dx, dy, -c0, -c1, -c2) for i, dx, dy, c0, c1, c2 in rows]
        rhs = [-(dx * fingers[i][13] + dy * fingers[i][14] + c0 * V[0] + c1 * V[1] + c2 * V[2])
               for i, dx, dy, c0, c1, c2 in rows]
        tip_sum, obj_sum = self.multipliers(fingers, rows, cols, rhs)
        v_old, v_new, energy = st.v.tolist(), [], 0.0
        for i, f in enumerate(fingers):
            m00, m01, m11, _, _, j00, j01, j10, j11 = f[:9]
            fx, fy = tip_sum[i]
            r0, r1 = -(j00 * fx + j10 * fy), -(j01 * fx + j11 * fy)
            w0, w1 = v_old[2 * i:2 * i + 2]
            u0, u1 = w0 + (f[15] * r0 + f[16] * r1), w1 + (f[16] * r0 + f[17] * r1)
            energy += m00 * (u0 * u0 - w0 * w0) + 2 * m01 * (u0 * u1 - w0 * w1) + m11 * (u1 * u1 - w1 * w1)
            v_new += [u0, u1]
        scale = (1.0 / self.mass, 1.0 / self.mass, 1.0 / self.inertia)
        V_new = [V[k] + obj_sum[k] * scale[k] for k in range(3)]
        weights = (self.mass, self.mass, self.inertia)
        energy += sum(wk * (a * a - b * b) for wk, a, b in zip(weights, V_new, V))
        st.v, st.V = np.array(v_new), np.array(V_new)
        return 0.5 * energy

    def evaluate(self, y: list, tau: tuple, specs: tuple, q: np.ndarray | None = None, v: np.ndarray | None = None,
                 fingers: list[tuple] | None = None) -> tuple[list, list, list[tuple]]:
        """dy/dt of the flat state y = (q, v, X, V, works) (a list of floats), the contact forces
        (per finger) and the fingers' dynamics (:meth:`pin_pass`, or ``fingers`` if known);
        ``q``, ``v``: y's as arrays."""
        n = self.hand.nq
        vel, X, V = y[n:2 * n], y[2 * n:2 * n + 3], y[2 * n + 3:2 * n + 6]
        if fingers is None:
            if q is None:
                qv = np.array(y[:2 * n])
                q, v = qv[:n], qv[n:]
            fingers = self.pin_pass(q, v)
        qdd, Xdd, forces = self.solve(fingers, specs, X, V, tau)
        # the powers of the torques, of the damping and of the contact forces (on the object at its
        # material point, minus on the tips)
        torque = damp = power = 0.0
        damping = self.damping if self.hand.damping_enabled else self.no_damping
        for i, ((fx, fy), f) in enumerate(zip(forces, fingers)):
            u0, u1 = vel[2 * i], vel[2 * i + 1]
            torque += tau[2 * i] * u0 + tau[2 * i + 1] * u1
            damp -= damping[2 * i] * u0 * u0 + damping[2 * i + 1] * u1 * u1
            if fx or fy:
                rx, ry = f[11] - X[0], f[12] - X[1]
                power += fx * (V[0] - V[2] * ry - f[13]) + fy * (V[1] + V[2] * rx - f[14])
        return [*vel, *qdd, *V, *Xdd, torque, damp, power], forces, fingers

r"""An independent simulator of the hand and the object in full coordinates.

It shares with :mod:`regrasp.reduced` only primitive models: the fingers' Pinocchio
dynamics (M, N, J, J̇q̇ through :class:`~regrasp.hand.Hand`), the object's geometry and
inertia, and μ. It never uses H, G, G_f, P or eq. (3.2.11), so a controller that works
on the plant works on physics, not on its own model.

**Coordinates.** Joint positions q (2m) and the object pose X = (x_o, β), with velocities
v and V = (v_o, ω). Contact i joins the tip :math:`p_i(q)` to the object:

* ``fixed``: the tip stays at the object point :math:`c_i` (object frame):
  :math:`\phi_i = p_i - x_o - R(\beta) c_i = 0` (two rows); the force on the object
  :math:`f_i = \lambda_i \in \mathbb R^2` is a multiplier;
* ``sliding``: the tip stays on the edge's line :math:`\{c : n^o\cdot c = e\}`:
  :math:`\psi_i = n_i \cdot (p_i - x_o) - e = 0` with :math:`n_i = R n^o` (one row); the force
  on the object is :math:`f_i = \lambda_{n}(n_i + \mu s_i t_i)`: Coulomb friction of magnitude
  :math:`\mu\lambda_n`, opposing the tip's sliding velocity relative to the object
  (:math:`s_i` is the sign of that velocity along :math:`t_i`);
* ``separated``: no constraint, no force.

**Equations.** :math:`M\ddot q + N = \tau - \sum_i J_i^T f_i`,
:math:`M_o \ddot X = f_g + \sum_i (f_i,\ (p_i - x_o)\times f_i)`, and every constraint's second
derivative, Baumgarte-stabilised: :math:`\ddot\phi + 2\alpha\dot\phi + \alpha^2\phi = 0`. One
linear solve per evaluation gives (q̈, Ẍ, λ).

**Integration.** Classical Runge–Kutta (RK4) with a fixed step (default 1 ms); the contact
modes and friction directions are frozen during a step. The work of the joint torques, of
the joint damping and of the contact forces (friction) are integrated alongside, for
energy-balance checks.

**Events** (checked after every step, reported with time, contact and detail):
``separation`` (a normal force < 0; the contact is released), ``slip`` (a fixed contact's
force leaves its friction cone; it becomes sliding in the direction of the tangential
force), ``stick`` (a sliding contact's relative velocity reverses while the fixed-contact
force would be inside the cone; it becomes fixed, otherwise it keeps sliding the other
way), ``left_edge`` (a contact's ξ leaves its edge), ``collision`` (a link penetrates the
object, coal and the URDF geometry), ``singular`` (a finger's Jacobian condition number
exceeds the hand's threshold). Kinds in ``stop_on`` stop the simulation.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from .collision import UrdfCollisionChecker, default_tip_clearance
from .exceptions import InvalidParameterError
from .hand import Hand
from .planar import perp, rotation
from .polygon import ConvexPolygon
from .validation import as_finite_array, as_friction_coefficients, as_positive_float

__all__ = ["Plant", "PlantContact", "PlantEvent", "PlantState", "PlantStep"]

_MODES = ("fixed", "sliding", "separated")


@dataclass
class PlantContact:
    """One contact's mode and parameters (mutable: the plant switches modes on events).

    Attributes:
        edge: Edge index on the object.
        mode: ``"fixed"``, ``"sliding"`` or ``"separated"``.
        xi: For a fixed contact, its position ξ [m] on the edge (object-fixed).
        sign: For a sliding contact, the sliding direction s = ±1 along the edge's ξ.
    """

    edge: int
    mode: str
    xi: float = 0.0
    sign: float = 1.0


@dataclass(frozen=True)
class PlantEvent:
    """Something the plant detected.

    Attributes:
        time: [s].
        contact: Finger name.
        kind: ``separation``, ``slip``, ``stick``, ``left_edge``, ``collision`` or ``singular``.
        detail: Human-readable numbers.
    """

    time: float
    contact: str
    kind: str
    detail: str


@dataclass
class PlantState:
    """The plant's continuous state and its integrated work terms."""

    t: float
    q: np.ndarray
    v: np.ndarray
    X: np.ndarray
    V: np.ndarray
    torque_work: float = 0.0
    damping_work: float = 0.0
    contact_work: float = 0.0

    def copy(self) -> "PlantState":
        return PlantState(self.t, self.q.copy(), self.v.copy(), self.X.copy(), self.V.copy(),
                          self.torque_work, self.damping_work, self.contact_work)


@dataclass(frozen=True)
class PlantStep:
    """What one plant step produced.

    Attributes:
        state: The state after the step.
        forces_surface: Each contact's force on the object in its surface frame
            (normal, tangential) [N], at the step's start; zeros when separated.
        xi: Each contact's ξ [m] after the step.
        xi_dot: Each contact's relative tangential velocity ξ̇ [m/s] after the step.
        modes: Contact modes during the step.
        constraint_error: Largest constraint violation [m] after the step.
        events: Events detected after the step.
    """

    state: PlantState
    forces_surface: np.ndarray
    xi: np.ndarray
    xi_dot: np.ndarray
    modes: tuple[str, ...]
    constraint_error: float
    events: tuple[PlantEvent, ...] = field(default_factory=tuple)


class Plant:
    r"""Full-coordinate hand–object simulator with fixed and sliding contacts.

    Args:
        hand: The fingers (its gravity is the plant's gravity; it may differ from the
            controller's hand, e.g. other link masses).
        polygon: The object (geometry; inertia unless overridden).
        contacts: One :class:`PlantContact` per finger.
        mu: Coulomb friction coefficient [-], one for all contacts or one per contact.
        object_mass, object_inertia: Override the polygon's [kg], [kg m^2].
        dt: Time step [s].
        baumgarte: α [1/s] of the constraint stabilisation.
        collision_check: Check link–object collisions with coal after every step.
        tip_clearance: Tip clearance [m] for the collision check (see :mod:`regrasp.collision`);
            default: :func:`~regrasp.collision.default_tip_clearance`.
        stop_on: Event kinds that stop the simulation.
        contact_events: Detect separation, slip and stick and switch modes. With False the
            contacts are ideal bilateral constraints whose modes never change (for checking
            the integrator's energy conservation, e.g. a torque-free motion, which pulls on
            the contacts).
    """

    def __init__(
        self,
        hand: Hand,
        polygon: ConvexPolygon,
        contacts: Sequence[PlantContact],
        *,
        mu: float = 0.0,
        object_mass: float | None = None,
        object_inertia: float | None = None,
        dt: float = 1e-3,
        baumgarte: float = 50.0,
        collision_check: bool = True,
        tip_clearance: float | None = None,
        stop_on: Sequence[str] = ("separation", "left_edge", "collision", "singular"),
        contact_events: bool = True,
    ):
        if len(contacts) != hand.m:
            raise InvalidParameterError("contacts", contacts, f"one contact per finger ({hand.m})")
        self.hand = hand
        self.polygon = polygon
        self.contacts = self._copy_contacts(contacts)
        self.mu = as_friction_coefficients(mu, hand.m)
        self.mass = as_positive_float("object_mass", polygon.mass if object_mass is None else object_mass)
        self.inertia = as_positive_float("object_inertia",
                                         polygon.inertia if object_inertia is None else object_inertia)
        self.dt = as_positive_float("dt", dt)
        self.alpha = as_positive_float("baumgarte", baumgarte, allow_zero=True)
        self.stop_on = frozenset(stop_on)
        self.contact_events = bool(contact_events)
        self.checkers = None
        if collision_check:
            self.checkers = []
            for f in hand.fingers:
                clearance = default_tip_clearance(f) if tip_clearance is None else tip_clearance
                self.checkers.append(UrdfCollisionChecker(f, polygon, clearance))
        self.state: PlantState | None = None
        self.events: list[PlantEvent] = []
        self.stopped = False
        self.max_constraint_error = 0.0

    # ------------------------------------------------------------------ set-up
    def reset(self, q, v, X, V, t: float = 0.0, contacts: Sequence[PlantContact] | None = None) -> PlantState:
        """Set the state (q, v [rad, rad/s], X = (x, y, β), V = (vx, vy, ω)) and clear the event log.

        Contact modes persist across resets (events change them); pass ``contacts`` to set them anew.
        """
        n = self.hand.nq
        if contacts is not None:
            if len(contacts) != self.hand.m:
                raise InvalidParameterError("contacts", contacts, f"one contact per finger ({self.hand.m})")
            self.contacts = self._copy_contacts(contacts)
        self.state = PlantState(float(t), as_finite_array("q", q, (n,)).copy(), as_finite_array("v", v, (n,)).copy(),
                                as_finite_array("X", X, (3,)).copy(), as_finite_array("V", V, (3,)).copy())
        self.events = []
        self.stopped = False
        self.max_constraint_error = self.constraint_error(self.state)
        return self.state

    def _copy_contacts(self, contacts: Sequence[PlantContact]) -> list[PlantContact]:
        out = [PlantContact(c.edge, c.mode, float(c.xi), float(c.sign)) for c in contacts]
        for c in out:
            if c.mode not in _MODES:
                raise InvalidParameterError("mode", c.mode, "'fixed', 'sliding' or 'separated'")
            self.polygon.edge(c.edge)
            if c.sign not in (-1.0, 1.0):
                raise InvalidParameterError("sign", c.sign, "+1 or -1")
        return out

    # ------------------------------------------------------------------ geometry
    def _edge(self, c: PlantContact):
        return self.polygon.edge(c.edge)

    def contact_xi(self, st: PlantState, i: int, tip=None, tip_vel=None) -> tuple[float, float]:
        """ξ [m] of tip i's projection on its edge's line, and its relative velocity ξ̇ [m/s]
        (``tip``/``tip_vel``: the tip's position and velocity if already known)."""
        e = self._edge(self.contacts[i])
        rot = rotation(st.X[2])
        if tip is None:
            tip, tip_vel = self._tip(st, i)
        rel = rot.T @ (tip - st.X[:2])
        xi = float(e.xi_direction @ (rel - e.xi_origin))
        # velocity of the tip relative to the object, in object coordinates
        point_vel = st.V[:2] + st.V[2] * perp(tip - st.X[:2])
        xi_dot = float(e.xi_direction @ (rot.T @ (tip_vel - point_vel)))
        return xi, xi_dot

    def _tip(self, st: PlantState, i: int):
        f = self.hand.fingers[i]
        qi, vi = st.q[2 * i:2 * i + 2], st.v[2 * i:2 * i + 2]
        tip = f.forward_kinematics(qi)
        return tip, f.tip_jacobian(qi) @ vi

    def constraint_error(self, st: PlantState, tips=None) -> float:
        """Largest violation [m] of the active contact constraints (``tips``: (m, 2) if known)."""
        rot = rotation(st.X[2])
        worst = 0.0
        for i, c in enumerate(self.contacts):
            if c.mode == "separated":
                continue
            e = self._edge(c)
            tip = self._tip(st, i)[0] if tips is None else tips[i]
            if c.mode == "fixed":
                err = np.linalg.norm(tip - st.X[:2] - rot @ e.point(c.xi))
            else:
                err = abs((rot @ e.inward_normal) @ (tip - st.X[:2]) - e.inward_normal @ e.xi_origin)
            worst = max(worst, float(err))
        return worst

    # ------------------------------------------------------------------ dynamics
    def _force_column(self, sl: slice, J: np.ndarray, r: np.ndarray, d: np.ndarray) -> np.ndarray:
        """Generalized force (fingers, object) of a unit force ``d`` on the object at lever arm ``r``,
        applied by finger joints ``sl``: -Jᵀd on the finger, (d, r × d) on the object."""
        n = self.hand.nq
        col = np.zeros(n + 3)
        col[sl] = -J.T @ d
        col[n:n + 2] = d
        col[n + 2] = r[0] * d[1] - r[1] * d[0]
        return col

    def _rows(self, st: PlantState, dyn, contacts):
        """Per active contact: force columns W (generalized force per multiplier), constraint
        rows C (acting on (q̈, Ẍ) or, at velocity level, on (q̇, V)), right-hand sides b, owners."""
        n = self.hand.nq
        rot = rotation(st.X[2])
        omega = st.V[2]
        w_cols, c_rows, b, owners = [], [], [], []
        for i, c in enumerate(contacts):
            if c.mode == "separated":
                continue
            e = self.polygon.edge(c.edge)
            sl = slice(2 * i, 2 * i + 2)
            J = dyn.jacobian[sl, sl]
            tip = dyn.tips[i]
            tip_vel = dyn.tip_velocities[i]
            jdv = dyn.jacobian_dot_v[sl]
            r = tip - st.X[:2]
            if c.mode == "fixed":
                rc = rot @ e.point(c.xi)
                phi = tip - st.X[:2] - rc
                phi_dot = tip_vel - st.V[:2] - omega * perp(rc)
                for k in range(2):
                    w_cols.append(self._force_column(sl, J, r, np.eye(2)[k]))
                    row = np.zeros(n + 3)
                    row[sl] = J[k]
                    row[n + k] = -1.0
                    row[n + 2] = -perp(rc)[k]
                    c_rows.append(row)
                    b.append(-jdv[k] - omega**2 * rc[k] - 2 * self.alpha * phi_dot[k] - self.alpha**2 * phi[k])
                    owners.append((i, k))
            else:
                normal = rot @ e.inward_normal
                tangent = perp(normal)
                offset = e.inward_normal @ e.xi_origin
                psi = normal @ r - offset
                psi_dot = omega * (perp(normal) @ r) + normal @ (tip_vel - st.V[:2])
                w_cols.append(self._force_column(sl, J, r, normal + self.mu[i] * c.sign * tangent))
                row = np.zeros(n + 3)
                row[sl] = normal @ J
                row[n:n + 2] = -normal
                row[n + 2] = perp(normal) @ r
                c_rows.append(row)
                drift = (-omega**2 * (normal @ r) + 2 * omega * (perp(normal) @ (tip_vel - st.V[:2]))
                         + normal @ jdv)
                b.append(-drift - 2 * self.alpha * psi_dot - self.alpha**2 * psi)
                owners.append((i, "n"))
        return w_cols, c_rows, b, owners

    def _full_mass(self, dyn) -> np.ndarray:
        n = self.hand.nq
        mass = np.zeros((n + 3, n + 3))
        mass[:n, :n] = dyn.mass_matrix
        mass[n:, n:] = np.diag([self.mass, self.mass, self.inertia])
        return mass

    def accelerations(self, st: PlantState, tau, modes=None):
        """(q̈, Ẍ, forces) at state ``st`` for torques ``tau``: ``forces`` (m, 2) are the contact
        forces on the object in the hand frame (zeros for separated contacts)."""
        tau = as_finite_array("tau", tau, (self.hand.nq,))
        return self._accelerations(st, tau, modes)[:3]

    def _accelerations(self, st: PlantState, tau: np.ndarray, modes=None):
        contacts = self.contacts if modes is None else modes
        dyn = self.hand._dynamics(st.q.reshape(-1, 2), st.v.reshape(-1, 2))
        n, m = self.hand.nq, self.hand.m
        rot = rotation(st.X[2])
        w_cols, c_rows, b, owners = self._rows(st, dyn, contacts)
        k = len(w_cols)
        g = self.hand.gravity_in_hand
        rhs_dyn = np.concatenate([tau - dyn.nonlinear, [self.mass * g[0], self.mass * g[1], 0.0]])
        kkt = np.zeros((n + 3 + k, n + 3 + k))
        kkt[:n + 3, :n + 3] = self._full_mass(dyn)
        if k:
            kkt[:n + 3, n + 3:] = -np.array(w_cols).T
            kkt[n + 3:, :n + 3] = np.array(c_rows)
        sol = np.linalg.solve(kkt, np.concatenate([rhs_dyn, b]))
        acc, lam = sol[:n + 3], sol[n + 3:]
        forces = np.zeros((m, 2))
        for (i, kind), value in zip(owners, lam):
            if kind == "n":
                c = contacts[i]
                normal = rot @ self.polygon.edge(c.edge).inward_normal
                forces[i] = value * (normal + self.mu[i] * c.sign * perp(normal))
            else:
                forces[i, kind] = value
        return acc[:n], acc[n:], forces, dyn

    def _project_velocities(self, st: PlantState) -> float:
        """Remove the velocity that violates the active constraints (a plastic sticking impulse):
        the mass-weighted projection of (q̇, V) onto C (q̇, V) = 0. Returns the kinetic energy [J]
        it removes (negative), which is friction's doing and is booked as contact work."""
        dyn = self.hand.dynamics(st.q, st.v)
        _, c_rows, _, _ = self._rows(st, dyn, self.contacts)
        if not c_rows:
            return 0.0
        n = self.hand.nq
        C = np.array(c_rows)
        mass = self._full_mass(dyn)
        z = np.concatenate([st.v, st.V])
        k = C.shape[0]
        kkt = np.zeros((n + 3 + k, n + 3 + k))
        kkt[:n + 3, :n + 3] = mass
        kkt[:n + 3, n + 3:] = C.T
        kkt[n + 3:, :n + 3] = C
        z_new = np.linalg.solve(kkt, np.concatenate([mass @ z, np.zeros(k)]))[:n + 3]
        delta = 0.5 * (z_new @ mass @ z_new - z @ mass @ z)
        st.v, st.V = z_new[:n].copy(), z_new[n:].copy()
        return float(delta)

    def _derivative(self, st: PlantState, tau):
        qdd, Xdd, forces, dyn = self._accelerations(st, tau)
        damping = self.hand.damping
        # net power of the contact forces: on the object at its material point, minus on the tips
        power = 0.0
        for i in range(self.hand.m):
            if not forces[i].any():
                continue
            tip, tip_vel = dyn.tips[i], dyn.tip_velocities[i]
            point_vel = st.V[:2] + st.V[2] * perp(tip - st.X[:2])
            power += forces[i] @ (point_vel - tip_vel)
        return (st.v, qdd, st.V, Xdd, float(tau @ st.v), float(-(damping * st.v) @ st.v), float(power)), forces

    @staticmethod
    def _advance(st: PlantState, deriv, h: float) -> PlantState:
        dq, dv, dX, dV, pt, pd, pc = deriv
        return PlantState(st.t + h, st.q + h * dq, st.v + h * dv, st.X + h * dX, st.V + h * dV,
                          st.torque_work + h * pt, st.damping_work + h * pd, st.contact_work + h * pc)

    # ------------------------------------------------------------------ stepping
    def surface_forces(self, st: PlantState, forces: np.ndarray) -> np.ndarray:
        """Contact forces (m, 2) in each contact's surface frame (normal, tangential)."""
        rot = rotation(st.X[2])
        out = np.zeros_like(forces)
        for i, c in enumerate(self.contacts):
            e = self._edge(c)
            out[i] = (rot @ np.column_stack([e.inward_normal, e.xi_direction])).T @ forces[i]
        return out

    def step(self, tau) -> PlantStep:
        """Advance one time step with constant joint torques ``tau`` [N m] (RK4)."""
        if self.state is None:
            raise InvalidParameterError("state", None, "a state: call reset() first")
        if self.stopped:
            raise InvalidParameterError("plant", "stopped", "a running plant (it stopped on an event)")
        tau = as_finite_array("tau", tau, (self.hand.nq,))
        st, h = self.state, self.dt
        k1, forces0 = self._derivative(st, tau)
        k2, _ = self._derivative(self._advance(st, k1, h / 2), tau)
        k3, _ = self._derivative(self._advance(st, k2, h / 2), tau)
        k4, _ = self._derivative(self._advance(st, k3, h), tau)
        avg = tuple((a + 2 * b2 + 2 * c + d) / 6.0 for a, b2, c, d in zip(k1, k2, k3, k4))
        new = self._advance(st, avg, h)
        self.state = new
        modes = tuple(c.mode for c in self.contacts)
        surface = self.surface_forces(st, forces0)
        dyn = self.hand._dynamics(new.q.reshape(-1, 2), new.v.reshape(-1, 2))
        err = self.constraint_error(new, dyn.tips)
        self.max_constraint_error = max(self.max_constraint_error, err)
        events = self._events(new, tau, dyn)
        xis = np.array([self.contact_xi(new, i, dyn.tips[i], dyn.tip_velocities[i]) for i in range(self.hand.m)])
        return PlantStep(new, surface, xis[:, 0], xis[:, 1], modes, err, tuple(events))

    def _event(self, t, i, kind, detail, out):
        ev = PlantEvent(t, self.hand.fingers[i].name, kind, detail)
        out.append(ev)
        self.events.append(ev)
        if kind in self.stop_on:
            self.stopped = True

    def _events(self, st: PlantState, tau, dyn) -> list[PlantEvent]:
        out: list[PlantEvent] = []
        forces = self._accelerations(st, tau)[2]
        surface = self.surface_forces(st, forces)
        for i, c in enumerate(self.contacts):
            if c.mode == "separated":
                continue
            xi, xi_dot = self.contact_xi(st, i, dyn.tips[i], dyn.tip_velocities[i])
            if self.contact_events:
                self._switch_mode(st, tau, i, surface[i], xi, xi_dot, out)
                if c.mode == "separated":
                    continue
            lo, hi = self._edge(c).xi_range
            if not lo <= xi <= hi:
                self._event(st.t, i, "left_edge", f"xi = {xi:.5g} m outside [{lo:.5g}, {hi:.5g}]", out)
        jac = dyn.jacobian
        for i in range(self.hand.m):
            cond = np.linalg.cond(jac[2 * i:2 * i + 2, 2 * i:2 * i + 2])
            if not cond <= self.hand.singular_threshold:
                self._event(st.t, i, "singular", f"Jacobian condition number {cond:.3g}", out)
        if self.checkers is not None:
            for i, checker in enumerate(self.checkers):
                dist = checker.signed_distances(st.q[2 * i:2 * i + 2], st.X)
                if dist.size and dist.min() < 0.0:
                    self._event(st.t, i, "collision", f"link penetrates the object by {-dist.min():.3g} m", out)
        return out

    def _switch_mode(self, st: PlantState, tau, i: int, force_surface, xi: float, xi_dot: float, out) -> None:
        """Separation, slip and stick of contact i (module docstring)."""
        c = self.contacts[i]
        fn, ft = force_surface
        tol = 1e-9
        if fn < -tol:
            self._event(st.t, i, "separation", f"normal force {fn:.4g} N < 0", out)
            c.mode = "separated"
        elif c.mode == "fixed" and abs(ft) > self.mu[i] * fn + tol * max(1.0, abs(fn)):
            self._event(st.t, i, "slip", f"|f_t| = {abs(ft):.4g} N > mu f_n = {self.mu[i] * fn:.4g} N", out)
            c.mode, c.sign = "sliding", float(np.sign(ft) or 1.0)
        elif c.mode == "sliding" and xi_dot * c.sign <= 0.0:
            trial = [PlantContact(o.edge, o.mode, o.xi, o.sign) for o in self.contacts]
            trial[i] = PlantContact(c.edge, "fixed", xi, c.sign)
            _, _, f_fixed = self.accelerations(st, tau, modes=trial)
            fn2, ft2 = self.surface_forces(st, f_fixed)[i]
            if fn2 >= 0.0 and abs(ft2) <= self.mu[i] * fn2:
                self._event(st.t, i, "stick", f"xi_dot = {xi_dot:.3g} m/s crossed zero; force inside the cone", out)
                c.mode, c.xi = "fixed", xi
                st.contact_work += self._project_velocities(st)
            else:
                c.sign = -c.sign

    def energy(self, st: PlantState | None = None) -> float:
        """Kinetic + gravitational potential energy [J] of fingers and object."""
        st = self.state if st is None else st
        g = self.hand.gravity_in_hand
        kin = self.hand.kinetic_energy(st.q, st.v) + 0.5 * (self.mass * st.V[:2] @ st.V[:2] + self.inertia * st.V[2] ** 2)
        pot = self.hand.potential_energy(st.q) - self.mass * g @ st.X[:2]
        return float(kin + pot)

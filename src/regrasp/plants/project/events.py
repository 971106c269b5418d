r"""The project plant's events (:class:`PlantEvents`), checked after every step and reported with time, contact
and detail:

* ``separation``: a normal force < 0; the contact is released;
* ``slip``: a fixed contact's force leaves its static friction cone, :math:`|f_t| > \mu_s f_n`; it becomes sliding
  in the direction of the tangential force, carrying :math:`\mu_k f_n` from the next step on;
* ``stick``: a sliding contact's relative velocity reverses while the fixed-contact force would be inside the static
  cone, :math:`|f_t| \le \mu_s f_n`; it becomes fixed (otherwise it keeps sliding the other way);
* ``left_edge``: a contact's ξ leaves its edge;
* ``collision``: a link penetrates the object (coal and the URDF geometry; a certificate per finger skips coal while
  no link can have reached the object, :meth:`PlantEvents.collisions`);
* ``singular``: a finger's Jacobian condition number exceeds the hand's threshold.

Kinds in the plant's ``stop_on`` stop it. On a curved object (:mod:`regrasp.plants.project.curve`) the forces are
in each tip's foot's surface frame, ``left_edge`` never fires, a sliding or separated contact's ξ follows its foot
after every check, and the links are checked against the curve's own coal shape.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import coal
import numpy as np

from ...core.contact import ContactMode, Friction, cone_margin
from ...core.curves import CurvedObject
from ...core.events import Event
from ...core.polygon import ConvexPolygon
from ...kernels.finger import condition_2x2
from ...model.collision import UrdfCollisionChecker, default_tip_clearance
from ...model.hand import Hand
from .curve import collision_object, curve_contact_xi, foot
from .equations import PlantEquations
from .state import EdgeGeometry, PlantContact, PlantLog, PlantState, contact_xi, surface_force

__all__ = ["Accelerations", "PlantEvents"]

#: A plant's (q̈, Ẍ, contact forces) at a state for torques [N m] with given contacts' modes.
Accelerations = Callable[[PlantState, np.ndarray, Sequence[PlantContact]], tuple[np.ndarray, np.ndarray, np.ndarray]]

_MODE_FIXED, _MODE_SLIDING, _MODE_SEPARATED = ContactMode.FIXED, ContactMode.SLIDING, ContactMode.SEPARATED


def link_reach(shape: object) -> float:
    """Largest distance [m] of a point of a link shape from its joint (inf for unknown shapes)."""
    geom = shape.geometry
    if isinstance(geom, coal.Cylinder):
        extent = math.hypot(geom.radius, geom.halfLength)
    elif isinstance(geom, coal.Capsule):
        extent = geom.radius + geom.halfLength
    elif isinstance(geom, coal.Box):
        extent = float(np.linalg.norm(geom.halfSide))
    elif isinstance(geom, coal.Sphere):
        extent = geom.radius
    else:
        return math.inf
    return float(np.linalg.norm(shape.placement_in_joint.translation)) + extent


class PlantEvents:
    """Detects the events of a plant (module docstring) of ``hand`` and ``polygon`` with ``friction`` per contact and
    ``equations``: the contacts switch modes here (with ``contact_events``) and ``log`` records the events.
    ``collision_check``: check the links against the object with coal (``tip_clearance`` [m] per finger, None:
    :func:`~regrasp.model.collision.default_tip_clearance`)."""

    def __init__(self, hand: Hand, polygon: ConvexPolygon | CurvedObject, friction: Sequence[Friction],
                 equations: PlantEquations, log: PlantLog, *, contact_events: bool, collision_check: bool,
                 tip_clearance: float | None):
        m = hand.m
        self.hand, self.equations, self.log, self.contact_events = hand, equations, log, contact_events
        self.static = [f.static for f in friction]
        #: Each finger's coal checker, or None (no collision check).
        self.checkers: list[UrdfCollisionChecker] | None = None
        #: Per finger and link, the largest distance [m] of a point of its shapes from its joint (m, 2).
        self.link_radii = np.zeros((m, 2))
        #: Per finger, the posture and distance budgets within which its links are known free (a NaN row: none).
        self.certificates = np.full((m, 9), np.nan)
        if collision_check:
            self.checkers = []
            polygon = collision_object(polygon)
            for f in hand.fingers:
                clearance = default_tip_clearance(f) if tip_clearance is None else tip_clearance
                self.checkers.append(UrdfCollisionChecker(f, polygon, clearance))
            self.link_radii = np.array([tuple(max((link_reach(s) for s in checker.shapes if s.link == k), default=0.0)
                                              for k in (0, 1)) for checker in self.checkers], dtype=float)

    def detect(self, st: PlantState, tau: tuple, forces: list, fingers: list[tuple], contacts: list[PlantContact],
               accelerations: Accelerations) -> tuple[list[Event], list]:
        """Events at the step's end ``st`` given the contact forces and the fingers' dynamics there, for ``contacts``
        (switched here); and every contact's (ξ, ξ̇) after them. ``accelerations``: the plant's (the stick test asks
        it for the forces with the contact fixed)."""
        equations = self.equations
        out: list[Event] = []
        V0 = st.V
        X = st.X.tolist()
        c, s = math.cos(X[2]), math.sin(X[2])
        curve = equations.curve
        if curve is None:
            geometry = [equations.edge(ct.edge) for ct in contacts]
        else:  # the tangent lines at the tips' feet
            feet = [foot(curve, X, f[11:13], ct.xi) for ct, f in zip(contacts, fingers)]
            geometry = [ft.line for ft in feet]

        def xis():
            V = st.V.tolist()
            if curve is not None:
                return [curve_contact_xi(ft, X, V, c, s, f[11:13], f[13:15]) for ft, f in zip(feet, fingers)]
            return [contact_xi(g, X, V, c, s, f[11:13], f[13:15]) for g, f in zip(geometry, fingers)]

        current = xis()
        for i, ct in enumerate(contacts):
            if ct.mode is _MODE_SEPARATED:
                continue
            if st.V is not V0:  # a stick before changed the velocities
                current = xis()
            xi, xi_dot = current[i]
            if self.contact_events:
                if curve is None:
                    force = surface_force(equations.edge(ct.edge), c, s, forces[i])
                    self.switch_mode(st, tau, i, force, xi, xi_dot, contacts, accelerations, out)
                else:
                    force = surface_force(geometry[i], c, s, forces[i])
                    self.switch_mode(st, tau, i, force, xi, xi_dot, contacts, accelerations, out, geometry[i])
                if ct.mode is _MODE_SEPARATED:
                    continue
            g = geometry[i]
            if not g.lo <= xi <= g.hi:
                self.log.add(st.t, i, "left_edge", f"xi = {xi:.5g} m outside [{g.lo:.5g}, {g.hi:.5g}]", out, xi=xi)
        for i, f in enumerate(fingers):
            cond = condition_2x2(*f[5:9])
            if not cond <= self.hand.singular_threshold:
                self.log.add(st.t, i, "singular", f"Jacobian condition number {cond:.3g}", out)
        if self.checkers is not None:
            # the elbows: p - o_2 = (j11, -j01)
            self.collisions(st, [(f[11] - f[8], f[12] + f[6]) for f in fingers], out)
        final = current if st.V is V0 else xis()
        if curve is not None:  # a sliding or separated contact's ξ follows its foot (a fixed one's is its point)
            for ct, (xi, _) in zip(contacts, final):
                if ct.mode is not _MODE_FIXED:
                    ct.xi = xi
        return out, final

    def collisions(self, st: PlantState, elbows: list, out: list[Event]) -> None:
        r"""Collision events from coal's signed distances of each finger's link shapes.

        Coal is skipped for a finger whose links cannot have reached the object since coal last
        found them free: a distance is 1-Lipschitz in a rigid motion, and a point of link k's
        shapes moves relative to the object by at most :math:`|\Delta r_k| + |\Delta\theta_k| R_k`
        (:math:`r_k`: the link's joint in the object frame, :math:`\theta_k`: its direction
        relative to the object, :math:`R_k`: the largest distance of a point of its shapes from
        the joint). The link is free while that stays below its last distance, less 0.1 % and
        10 µm (far above coal's tolerance): coal's verdict there would be the same. ``elbows``: each
        finger's joint 2 axis (hand frame)."""
        equations = self.equations
        x, y, beta = st.X.tolist()
        c, s = math.cos(beta), math.sin(beta)
        q = st.q.tolist()
        for i in range(len(self.checkers)):
            ox, oy = equations.joint1_axes[i]
            ex, ey = elbows[i]
            posture = (q[2 * i], q[2 * i + 1], beta, c * (ox - x) + s * (oy - y), c * (oy - y) - s * (ox - x),
                       c * (ex - x) + s * (ey - y), c * (ey - y) - s * (ex - x))
            cert = self.certificates[i].tolist()
            if not math.isnan(cert[0]):
                q1, q2, b, r1x, r1y, r2x, r2y, budget1, budget2 = cert
                turn1 = abs(posture[0] - q1 - (beta - b))
                turn2 = abs(posture[0] - q1 + posture[1] - q2 - (beta - b))
                radius1, radius2 = self.link_radii[i].tolist()
                if (math.hypot(posture[3] - r1x, posture[4] - r1y) + turn1 * radius1 < budget1
                        and math.hypot(posture[5] - r2x, posture[6] - r2y) + turn2 * radius2 < budget2):
                    continue
            self.coal(st, i, posture, out)

    def coal(self, st: PlantState, i: int, posture: tuple, out: list[Event]) -> None:
        """Finger i's links against the object with coal: a collision event where one penetrates, and the
        finger's new certificate (``posture``: see :meth:`collisions`)."""
        dist, nearest = self.certify(st.q, st.X, i, posture)
        if dist and min(dist) < 0.0:
            link = min(range(2), key=lambda k: nearest[k])
            self.log.add(st.t, i, "collision", f"link {link + 1} penetrates the object by {-min(dist):.3g} m",
                        out, link=link, depth=-min(dist))

    def certify(self, q: np.ndarray, X: np.ndarray, i: int, posture: tuple) -> tuple[list[float], list[float]]:
        """Finger i's links' signed distances to the object (coal) at joints ``q`` (all fingers') and pose ``X``,
        the nearest per link, and the finger's new certificate."""
        dist = self.checkers[i].signed_distances(q[2 * i:2 * i + 2], X).tolist()
        nearest = [math.inf, math.inf]
        for d, shape in zip(dist, self.checkers[i].shapes):
            nearest[shape.link] = min(nearest[shape.link], d)
        self.certificates[i] = (*posture, *(d * (1.0 - 1e-3) - 1e-5 for d in nearest))
        return dist, nearest

    def switch_mode(self, st: PlantState, tau: tuple, i: int, force_surface: tuple[float, float], xi: float,
                    xi_dot: float, contacts: list[PlantContact], accelerations: Accelerations,
                    out: list[Event], line: EdgeGeometry | None = None) -> None:
        """Separation, slip (the static cone) and stick (the static cone) of contact i (module docstring);
        ``line``: the surface frame's line (a curve's tangent at the foot; None: the contact's edge)."""
        c = contacts[i]
        fn, ft = force_surface
        tol = 1e-9
        static = self.static[i]
        if fn < -tol:
            self.log.add(st.t, i, "separation", f"normal force {fn:.4g} N < 0", out, normal_force=fn)
            c.mode = _MODE_SEPARATED
        elif c.mode is _MODE_FIXED and cone_margin(static, fn, ft) < -tol * max(1.0, abs(fn)):
            self.log.add(st.t, i, "slip", f"|f_t| = {abs(ft):.4g} N > mu_s f_n = {static * fn:.4g} N", out,
                        normal_force=fn, tangential_force=ft)
            c.mode, c.sign = _MODE_SLIDING, float(np.sign(ft) or 1.0)
        elif c.mode is _MODE_SLIDING and xi_dot * c.sign <= 0.0:
            trial = [PlantContact(o.edge, o.mode, o.xi, o.sign) for o in contacts]
            trial[i] = PlantContact(c.edge, _MODE_FIXED, xi, c.sign)
            _, _, f_fixed = accelerations(st, np.array(tau), trial)
            fn2, ft2 = surface_force(self.equations.edge(c.edge) if line is None else line, math.cos(st.X[2]),
                                     math.sin(st.X[2]), np.asarray(f_fixed).tolist()[i])
            if fn2 >= 0.0 and cone_margin(static, fn2, ft2) >= 0.0:
                self.log.add(st.t, i, "stick", f"xi_dot = {xi_dot:.3g} m/s crossed zero; force inside the static cone",
                            out, xi=xi)
                c.mode, c.xi = _MODE_FIXED, xi
                st.contact_work += self.equations.project_velocities(st, contacts)
            else:
                c.sign = -c.sign

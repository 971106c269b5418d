r"""An independent simulator of the hand and the object in full coordinates.

It shares with :mod:`regrasp.dynamics.reduced` only primitive models: the fingers' Pinocchio models
(the :class:`~regrasp.model.hand.Hand`'s, with their gravity and link masses; the plant evaluates M,
N, J and J̇q̇ on its own Pinocchio data), the object's geometry and inertia, and the friction
(:class:`~regrasp.core.contact.Friction`, μ_s and μ_k per contact). It never
uses H, G, G_f, P or eq. (3.2.11), so a controller that works on the plant works on physics,
not on its own model.

**Coordinates.** Joint positions q (2m) and the object pose X = (x_o, β), with velocities
v and V = (v_o, ω). Contact i joins the tip :math:`p_i(q)` to the object:

* ``FIXED``: the tip stays at the object point :math:`c_i` (object frame):
  :math:`\phi_i = p_i - x_o - R(\beta) c_i = 0` (two rows); the force on the object
  :math:`f_i = \lambda_i \in \mathbb R^2` is a multiplier;
* ``SLIDING``: the tip stays on the edge's line :math:`\{c : n^o\cdot c = e\}`:
  :math:`\psi_i = n_i \cdot (p_i - x_o) - e = 0` with :math:`n_i = R n^o` (one row); the force
  on the object is :math:`f_i = \lambda_{n}(n_i + \mu_k s_i t_i)`: Coulomb friction of magnitude
  :math:`\mu_k\lambda_n` (the kinetic coefficient), opposing the tip's sliding velocity relative
  to the object (:math:`s_i` is the sign of that velocity along :math:`t_i`);
* ``SEPARATED``: no constraint, no force.

(The modes are :class:`~regrasp.core.contact.ContactMode` members.)

**Equations.** :math:`M\ddot q + N = \tau - \sum_i J_i^T f_i`,
:math:`M_o \ddot X = f_g + \sum_i (f_i,\ (p_i - x_o)\times f_i)`, and every constraint's second
derivative, Baumgarte-stabilised: :math:`\ddot\phi + 2\alpha\dot\phi + \alpha^2\phi = 0`. One
linear solve per evaluation gives (q̈, Ẍ, λ): M is block diagonal (the fingers' 2x2 blocks and
the object's), so the multipliers come from the Delassus system :math:`C M^{-1} W \lambda = b -
C M^{-1}(\tau - N, f_g)` (one row per constraint, in plain floats), then the accelerations.

**Integration.** Classical Runge–Kutta (RK4) with a fixed step (default 1 ms); the contact
modes and friction directions are frozen during a step (the evaluation at a step's end, which
the event checks need, is the next step's first stage when τ and the modes stay). The work of the joint torques, of
the joint damping and of the contact forces (friction) are integrated alongside, for
energy-balance checks.

**Events** (checked after every step, reported with time, contact and detail):
``separation`` (a normal force < 0; the contact is released), ``slip`` (a fixed contact's
force leaves its static friction cone, :math:`|f_t| > \mu_s f_n`; it becomes sliding in the
direction of the tangential force, carrying :math:`\mu_k f_n` from the next step on), ``stick``
(a sliding contact's relative velocity reverses while the fixed-contact force would be inside
the static cone, :math:`|f_t| \le \mu_s f_n`; it becomes fixed, otherwise it keeps sliding the
other way), ``left_edge`` (a contact's ξ leaves its edge), ``collision`` (a link penetrates the
object, coal and the URDF geometry), ``singular`` (a finger's Jacobian condition number
exceeds the hand's threshold). Kinds in ``stop_on`` stop the simulation.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import NamedTuple

import coal
import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ...core.contact import DEFAULT_FRICTION, ContactMode, FrictionLike, as_frictions, as_modes, cone_margin
from ...core.events import Event, EventKind, EventSource
from ...core.exceptions import InvalidParameterError
from ...core.polygon import ConvexPolygon
from ...core.scalar import solve_small as _solve_small
from ...core.validation import (
    as_finite_array,
    as_finite_float,
    as_flag,
    as_inertia,
    as_integer,
    as_mass,
    as_positive_float,
    expect_sequence_of,
    expect_type,
)
from ...kernels import warm_up
from ...kernels.finger import FINGER_TERMS
from ...kernels.finger import condition_2x2 as _condition
from ...kernels.plant import (
    FIXED,
    PLANT_CONTACT,
    PLANT_PARAMETERS,
    SEPARATED,
    SLIDING,
    output_size,
    plant_evaluate,
    plant_step_into,
)
from ...model.collision import UrdfCollisionChecker, default_tip_clearance
from ...model.hand import Hand

__all__ = ["Plant", "PlantContact", "PlantState", "PlantStep"]

# the members as module constants for the hot paths (``ContactMode.FIXED`` is a class-attribute
# lookup through the enum's metaclass, ~0.3 us; a global is ~20 ns); compared with ``is``
_MODE_FIXED, _MODE_SLIDING, _MODE_SEPARATED = ContactMode.FIXED, ContactMode.SLIDING, ContactMode.SEPARATED
_LWA = pin.LOCAL_WORLD_ALIGNED
#: Where the elbow's two fields sit in :data:`~regrasp.kernels.finger.FINGER_TERMS` (the reference layout has none).
_ELBOW = FINGER_TERMS.names.index("ex")


class _EdgeGeometry(NamedTuple):
    """An edge's inward normal n, ξ direction t, ξ origin o, n·o and ξ range (object frame)."""

    nx: float
    ny: float
    tx: float
    ty: float
    ox: float
    oy: float
    offset: float
    lo: float
    hi: float


def _reach(shape) -> float:
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


#: The plant's largest step [s].
MAX_DT = 0.01
_PLANT_KINDS = frozenset(k.value for k in (EventKind.SEPARATION, EventKind.SLIP, EventKind.STICK, EventKind.LEFT_EDGE,
                                           EventKind.COLLISION, EventKind.SINGULAR))


@dataclass
class PlantContact:
    """One contact's mode and parameters (mutable: the plant switches modes on events).

    Attributes:
        edge: Edge index on the object.
        mode: A :class:`~regrasp.core.contact.ContactMode` (its string, ``"fixed"``, ``"sliding"`` or
            ``"separated"``, is converted).
        xi: For a fixed contact, its position ξ [m] on the edge (object-fixed).
        sign: For a sliding contact, the sliding direction s = ±1 along the edge's ξ.
    """

    edge: int
    mode: ContactMode
    xi: float = 0.0
    sign: float = 1.0

    def __post_init__(self) -> None:
        self.edge = as_integer("edge", self.edge)
        self.xi = as_finite_float("xi", self.xi)
        self.sign = as_finite_float("sign", self.sign)
        if type(self.mode) is not ContactMode:
            try:
                self.mode = as_modes((self.mode,))[0]
            except InvalidParameterError:
                raise InvalidParameterError("mode", self.mode, "'fixed', 'sliding' or 'separated'") from None


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
        modes: Contact modes (:class:`~regrasp.core.contact.ContactMode`) during the step.
        constraint_error: Largest constraint violation [m] after the step.
        events: Events detected after the step (:class:`~regrasp.core.events.Event`, source ``PLANT``).
    """

    state: PlantState
    forces_surface: np.ndarray
    xi: np.ndarray
    xi_dot: np.ndarray
    modes: tuple[ContactMode, ...]
    constraint_error: float
    events: tuple[Event, ...] = field(default_factory=tuple)


class Plant:
    r"""Full-coordinate hand–object simulator with fixed and sliding contacts.

    Args:
        hand: The fingers (its gravity is the plant's gravity; it may differ from the
            controller's hand, e.g. other link masses).
        polygon: The object (geometry; inertia unless overridden).
        contacts: One :class:`PlantContact` per finger.
        friction: Coulomb friction: a :class:`~regrasp.core.contact.Friction` (μ_s, μ_k) or a coefficient
            (μ_s = μ_k) [-] for all contacts, or one per contact. A fixed contact slips when
            :math:`|f_t| > \mu_s f_n`; a sliding one carries :math:`\mu_k f_n`.
        object_mass, object_inertia: Override the polygon's [kg], [kg m^2].
        dt: Time step [s].
        baumgarte: α [1/s] of the constraint stabilisation.
        collision_check: Check link–object collisions with coal after every step.
        tip_clearance: Tip clearance [m] for the collision check (see :mod:`regrasp.model.collision`);
            default: :func:`~regrasp.model.collision.default_tip_clearance`.
        stop_on: Event kinds that stop the simulation.
        contact_events: Detect separation, slip and stick and switch modes. With False the
            contacts are ideal bilateral constraints whose modes never change (for checking
            the integrator's energy conservation, e.g. a torque-free motion, which pulls on
            the contacts).
        compiled: Step with the compiled kernel (:mod:`regrasp.kernels.plant`; the same equations,
            ``tests/test_kernels.py`` checks it against this module's reference path). None (default):
            when the hand's kernels agree with Pinocchio (``hand.kernel_parameters``); False: the
            reference path (Pinocchio and plain floats).
    """

    def __init__(
        self,
        hand: Hand,
        polygon: ConvexPolygon,
        contacts: Sequence[PlantContact],
        *,
        friction: FrictionLike = DEFAULT_FRICTION,
        object_mass: float | None = None,
        object_inertia: float | None = None,
        dt: float = 1e-3,
        baumgarte: float = 50.0,
        collision_check: bool = True,
        tip_clearance: float | None = None,
        stop_on: Sequence[str] = ("separation", "left_edge", "collision", "singular"),
        contact_events: bool = True,
        compiled: bool | None = None,
    ):
        expect_type("hand", hand, Hand, "a Hand")
        expect_type("polygon", polygon, ConvexPolygon, "a ConvexPolygon")
        contacts = expect_sequence_of("contacts", contacts, PlantContact, "PlantContact")
        if len(contacts) != hand.m:
            raise InvalidParameterError("contacts", contacts, f"one contact per finger ({hand.m})")
        self.hand = hand
        self.polygon = polygon
        self.contacts = self._copy_contacts(contacts)
        self.friction = as_frictions(friction, hand.m)
        self._static = [f.static for f in self.friction]
        self._kinetic = [f.kinetic for f in self.friction]
        self.mass = as_mass("object_mass", polygon.mass if object_mass is None else object_mass)
        self.inertia = as_inertia("object_inertia",
                                         polygon.inertia if object_inertia is None else object_inertia)
        self.dt = as_positive_float("dt", dt)
        if self.dt > MAX_DT:
            raise InvalidParameterError("dt", dt, f"a step of at most {MAX_DT} s (the explicit integrator and the "
                                        "Baumgarte terms need a fine step)")
        self.alpha = as_positive_float("baumgarte", baumgarte, allow_zero=True)
        if isinstance(stop_on, str) or not all(isinstance(k, str) and k in _PLANT_KINDS for k in stop_on):
            raise InvalidParameterError("stop_on", stop_on, f"a sequence of plant event kinds "
                                        f"({', '.join(sorted(_PLANT_KINDS))})")
        self.stop_on = frozenset(EventKind(k) for k in stop_on)
        self.contact_events = as_flag("contact_events", contact_events)
        self.checkers = None
        if as_flag("collision_check", collision_check):
            self.checkers = []
            for f in hand.fingers:
                clearance = default_tip_clearance(f) if tip_clearance is None else tip_clearance
                self.checkers.append(UrdfCollisionChecker(f, polygon, clearance))
            self._link_radii = [tuple(max((_reach(s) for s in checker.shapes if s.link == k), default=0.0)
                                      for k in (0, 1)) for checker in self.checkers]
            self._link_radii_array = np.array(self._link_radii, dtype=float)
            self._certificates = np.full((hand.m, 9), np.nan)  # per finger (a NaN row: none): see _collisions()
        # the plant's own Pinocchio data on the hand's model of all fingers (their gravity and link masses)
        self._hand_pin = (hand.pinocchio_model, hand.pinocchio_model.createData())
        # per finger: its tip frame in that model, its joints' damping and joint 1's axis
        self._pin = [(tip, *np.asarray(model.damping, dtype=float).tolist(),
                      *model.jointPlacements[1].translation[:2].tolist())
                     for model, tip in zip(hand.finger_models, hand.tip_frame_ids)]
        self._last_key, self._last_evaluation = (None,) * 4, None  # see step()
        self._damping = tuple(d for entry in self._pin for d in entry[1:3])
        self._no_damping = (0.0,) * hand.nq
        self._edge_cache: dict[int, _EdgeGeometry] = {}
        self.state: PlantState | None = None
        self.events: list[Event] = []
        self.stopped = False
        self.max_constraint_error = 0.0
        #: Whether :meth:`step` runs the compiled kernel.
        self.compiled = hand.use_kernels(compiled)
        if self.compiled:
            warm_up()
        self._kernel_contacts: tuple | None = None  # (key, records): see _contact_records()
        self._kernel_plant: tuple | None = None  # (key, record): see _plant_record()
        self._no_certificates, self._no_radii = np.full((hand.m, 9), np.nan), np.zeros((hand.m, 2))
        # the compiled step's outputs: its arrays (fresh each step) and its workspace (read within a step only)
        self._output_size = output_size(hand.m)
        self._no_torques = np.zeros(hand.nq)
        self._workspace = (np.empty(hand.m, dtype=FINGER_TERMS), np.empty(hand.m, np.bool_), np.empty((hand.m, 7)))

    # ------------------------------------------------------------------ set-up
    def reset(self, q: ArrayLike, v: ArrayLike, X: ArrayLike, V: ArrayLike, t: float = 0.0,
              contacts: Sequence[PlantContact] | None = None) -> PlantState:
        """Set the state (q, v [rad, rad/s], X = (x, y, β), V = (vx, vy, ω)) and clear the event log.

        Contact modes persist across resets (events change them); pass ``contacts`` to set them anew.
        """
        n = self.hand.nq
        if contacts is not None:
            if len(contacts) != self.hand.m:
                raise InvalidParameterError("contacts", contacts, f"one contact per finger ({self.hand.m})")
            self.contacts = self._copy_contacts(contacts)
        self.state = PlantState(as_finite_float("t", t), as_finite_array("q", q, (n,)).copy(), as_finite_array("v", v, (n,)).copy(),
                                as_finite_array("X", X, (3,)).copy(), as_finite_array("V", V, (3,)).copy())
        self.events = []
        self.stopped = False
        self.max_constraint_error = self.constraint_error(self.state)
        return self.state

    def _copy_contacts(self, contacts: Sequence[PlantContact]) -> list[PlantContact]:
        if not all(isinstance(c, PlantContact) for c in contacts):
            raise InvalidParameterError("contacts", contacts, "a sequence of PlantContact")
        out = [PlantContact(c.edge, c.mode, as_finite_float("xi", c.xi), as_finite_float("sign", c.sign))
               for c in contacts]
        for c in out:
            lo, hi = self.polygon.edge(c.edge).xi_range
            if c.sign not in (-1.0, 1.0):
                raise InvalidParameterError("sign", c.sign, "+1 or -1")
            if c.mode is ContactMode.FIXED and not lo <= c.xi <= hi:
                raise InvalidParameterError("xi", c.xi, f"a position on edge {c.edge}, in [{lo:.6g}, {hi:.6g}] m")
        return out

    # ------------------------------------------------------------------ geometry
    def _edge_geometry(self, k: int) -> _EdgeGeometry:
        """Edge ``k``'s constants as floats (object frame), cached."""
        geo = self._edge_cache.get(k)
        if geo is None:
            e = self.polygon.edge(k)
            (nx, ny), (tx, ty), (ox, oy) = e.inward_normal.tolist(), e.xi_direction.tolist(), e.xi_origin.tolist()
            geo = _EdgeGeometry(nx, ny, tx, ty, ox, oy, float(e.inward_normal @ e.xi_origin), *e.xi_range)
            self._edge_cache[k] = geo
        return geo

    @staticmethod
    def _xi(g: _EdgeGeometry, X, V, c: float, s: float, tip, tip_vel) -> tuple[float, float]:
        """ξ and ξ̇ of a tip (position, velocity: pairs of floats) on edge ``g`` at pose X, twist V
        (floats), (c, s) = (cos β, sin β)."""
        rx, ry = tip[0] - X[0], tip[1] - X[1]
        xi = g.tx * ((c * rx + s * ry) - g.ox) + g.ty * ((c * ry - s * rx) - g.oy)
        # velocity of the tip relative to the object, in object coordinates
        ux, uy = tip_vel[0] - (V[0] - V[2] * ry), tip_vel[1] - (V[1] + V[2] * rx)
        return xi, g.tx * (c * ux + s * uy) + g.ty * (c * uy - s * ux)

    def contact_xi(self, st: PlantState, i: int, tip: Sequence[float] | np.ndarray | None = None,
                   tip_vel: Sequence[float] | np.ndarray | None = None) -> tuple[float, float]:
        """ξ [m] of tip i's projection on its edge's line, and its relative velocity ξ̇ [m/s]
        (``tip``/``tip_vel``: the tip's position and velocity if already known)."""
        if tip is None:
            tip, tip_vel = self._tip(st, i)
        X = st.X.tolist()
        return self._xi(self._edge_geometry(self.contacts[i].edge), X, st.V.tolist(), math.cos(X[2]), math.sin(X[2]),
                        tip, tip_vel)

    def _tip(self, st: PlantState, i: int):
        f = self.hand.fingers[i]
        qi, vi = st.q[2 * i:2 * i + 2], st.v[2 * i:2 * i + 2]
        tip = f.forward_kinematics(qi)
        return tip, f.tip_jacobian(qi) @ vi

    def _specs(self, contacts) -> tuple[tuple, ...]:
        """The active contacts as floats (a tuple): ``(i, FIXED, c_x, c_y)`` (the contact point,
        object frame) or ``(i, SLIDING, n_x, n_y, n·ξ-origin, μ_k s)`` (the edge's normal)."""
        out, kinetic = [], self._kinetic
        for i, c in enumerate(contacts):
            mode = c.mode
            if mode is _MODE_FIXED:
                g = self._edge_geometry(c.edge)
                out.append((i, _MODE_FIXED, g.ox + c.xi * g.tx, g.oy + c.xi * g.ty))
            elif mode is _MODE_SLIDING:
                g = self._edge_geometry(c.edge)
                out.append((i, _MODE_SLIDING, g.nx, g.ny, g.offset, kinetic[i] * c.sign))
            elif mode is not _MODE_SEPARATED:  # e.g. a string assigned to a contact's mode after construction
                raise InvalidParameterError("mode", mode, "a ContactMode member (PlantContact converts strings)")
        return tuple(out)

    @staticmethod
    def _violations(specs, X, tips) -> float:
        """Largest violation of the constraints ``specs`` at pose X with tips (floats)."""
        c, s = math.cos(X[2]), math.sin(X[2])
        worst = 0.0
        for spec in specs:
            i = spec[0]
            rx, ry = tips[i][0] - X[0], tips[i][1] - X[1]
            if spec[1] is _MODE_FIXED:
                ex, ey = rx - (c * spec[2] - s * spec[3]), ry - (s * spec[2] + c * spec[3])
                err = math.sqrt(ex * ex + ey * ey)
            else:
                err = abs((c * spec[2] - s * spec[3]) * rx + (s * spec[2] + c * spec[3]) * ry - spec[4])
            worst = max(worst, err)
        return worst

    def constraint_error(self, st: PlantState,
                         tips: Sequence[Sequence[float] | np.ndarray | None] | np.ndarray | None = None) -> float:
        """Largest violation [m] of the active contact constraints (``tips``: (m, 2) if known)."""
        if tips is None:
            tips = [self._tip(st, i)[0] if c.mode is not _MODE_SEPARATED else None for i, c in enumerate(self.contacts)]
        return self._violations(self._specs(self.contacts), st.X.tolist(), tips)

    # ------------------------------------------------------------------ dynamics
    def _pin_pass(self, q: np.ndarray, v: np.ndarray) -> list[tuple]:
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
        acceleration; ``tests/test_plant.py`` checks both against :meth:`Hand.dynamics`)."""
        damped = self.hand.damping_enabled
        model, data = self._hand_pin
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

    def _rows(self, fingers, specs, X, V, free=None, gravity=(0.0, 0.0)):
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

    def _multipliers(self, fingers, rows, cols, rhs):
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
        for value, (i, fx, fy, o0, o1, o2) in zip(_solve_small(a, rhs), cols):
            f = tip_sum[i]
            f[0] += fx * value
            f[1] += fy * value
            s0 += o0 * value
            s1 += o1 * value
            s2 += o2 * value
        return tip_sum, (s0, s1, s2)

    def _solve(self, fingers, specs, X, V, tau):
        """(q̈, Ẍ, forces) as lists of floats: forces (fx, fy) per finger on the object."""
        gravity = self.hand.gravity_in_hand.tolist()
        free = []  # per finger: the tip's acceleration at q̈ = M^-1 (τ - N), and τ - N
        for i, f in enumerate(fingers):
            r0, r1 = tau[2 * i] - f[3], tau[2 * i + 1] - f[4]
            u0, u1 = f[15] * r0 + f[16] * r1, f[16] * r0 + f[17] * r1
            free.append((f[5] * u0 + f[6] * u1, f[7] * u0 + f[8] * u1, r0, r1))
        rows, rhs, cols = self._rows(fingers, specs, X, V, free, gravity)
        if rows:
            forces, obj = self._multipliers(fingers, rows, cols, rhs)
        else:
            forces, obj = [[0.0, 0.0] for _ in fingers], (0.0, 0.0, 0.0)
        qdd = []
        for (fx, fy), f, (_, _, r0, r1) in zip(forces, fingers, free):
            r0, r1 = r0 - (f[5] * fx + f[7] * fy), r1 - (f[6] * fx + f[8] * fy)
            qdd += (f[15] * r0 + f[16] * r1, f[16] * r0 + f[17] * r1)
        return qdd, [gravity[0] + obj[0] / self.mass, gravity[1] + obj[1] / self.mass, obj[2] / self.inertia], forces

    def accelerations(self, st: PlantState, tau: ArrayLike,
                      modes: Sequence[PlantContact] | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q̈, Ẍ, forces) at state ``st`` for torques ``tau``: ``forces`` (m, 2) are the contact
        forces on the object in the hand frame (zeros for separated contacts)."""
        if self.compiled:
            n = self.hand.nq
            dy, forces, _ = plant_evaluate(self.hand.kernel_parameters, self._plant_record(),
                                           self._contact_records(self.contacts if modes is None else modes),
                                           self._flat(st), np.array(self._torques(tau)))
            return dy[n:2 * n], dy[2 * n + 3:2 * n + 6], forces
        tau = self._torques(tau)
        fingers = self._pin_pass(st.q, st.v)
        specs = self._specs(self.contacts if modes is None else modes)
        qdd, Xdd, forces = self._solve(fingers, specs, st.X.tolist(), st.V.tolist(), tau)
        return np.array(qdd), np.array(Xdd), np.array(forces)

    def _project_velocities(self, st: PlantState) -> float:
        """Remove the velocity that violates the active constraints (a plastic sticking impulse):
        the mass-weighted projection of (q̇, V) onto C (q̇, V) = 0. Returns the kinetic energy [J]
        it removes (negative), which is friction's doing and is booked as contact work."""
        fingers = self._pin_pass(st.q, st.v)
        X, V = st.X.tolist(), st.V.tolist()
        rows, _, _ = self._rows(fingers, self._specs(self.contacts), X, V)
        if not rows:
            return 0.0
        # z_new = z - M^-1 C^T μ with C M^-1 C^T μ = C z: columns (d, -c) in _multipliers' form
        cols = [(i, dx, dy, -c0, -c1, -c2) for i, dx, dy, c0, c1, c2 in rows]
        rhs = [-(dx * fingers[i][13] + dy * fingers[i][14] + c0 * V[0] + c1 * V[1] + c2 * V[2])
               for i, dx, dy, c0, c1, c2 in rows]
        tip_sum, obj_sum = self._multipliers(fingers, rows, cols, rhs)
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

    def _evaluate(self, y: list, tau: tuple, specs: tuple, q=None, v=None, fingers=None):
        """dy/dt of the flat state y = (q, v, X, V, works) (a list of floats), the contact forces
        (per finger) and the fingers' dynamics (:meth:`_pin_pass`, or ``fingers`` if known);
        ``q``, ``v``: y's as arrays."""
        n = self.hand.nq
        vel, X, V = y[n:2 * n], y[2 * n:2 * n + 3], y[2 * n + 3:2 * n + 6]
        if fingers is None:
            if q is None:
                qv = np.array(y[:2 * n])
                q, v = qv[:n], qv[n:]
            fingers = self._pin_pass(q, v)
        qdd, Xdd, forces = self._solve(fingers, specs, X, V, tau)
        # the powers of the torques, of the damping and of the contact forces (on the object at its
        # material point, minus on the tips)
        torque = damp = power = 0.0
        damping = self._damping if self.hand.damping_enabled else self._no_damping
        for i, ((fx, fy), f) in enumerate(zip(forces, fingers)):
            u0, u1 = vel[2 * i], vel[2 * i + 1]
            torque += tau[2 * i] * u0 + tau[2 * i + 1] * u1
            damp -= damping[2 * i] * u0 * u0 + damping[2 * i + 1] * u1 * u1
            if fx or fy:
                rx, ry = f[11] - X[0], f[12] - X[1]
                power += fx * (V[0] - V[2] * ry - f[13]) + fy * (V[1] + V[2] * rx - f[14])
        return [*vel, *qdd, *V, *Xdd, torque, damp, power], forces, fingers

    # ------------------------------------------------------------------ stepping
    def _surface(self, k: int, c: float, s: float, force) -> tuple[float, float]:
        """A force (fx, fy) at a contact on edge k in its surface frame (normal, tangential) at
        object rotation (c, s) = (cos β, sin β)."""
        g = self._edge_geometry(k)
        fx, fy = force
        return ((c * g.nx - s * g.ny) * fx + (s * g.nx + c * g.ny) * fy,
                (c * g.tx - s * g.ty) * fx + (s * g.tx + c * g.ty) * fy)

    def surface_forces(self, st: PlantState, forces: np.ndarray) -> np.ndarray:
        """Contact forces (m, 2) in each contact's surface frame (normal, tangential)."""
        c, s = math.cos(st.X[2]), math.sin(st.X[2])
        return np.array([self._surface(ct.edge, c, s, f) for ct, f in zip(self.contacts, np.asarray(forces).tolist())])

    def _torques(self, tau) -> tuple:
        """``tau`` validated, as a tuple of floats (a fast path for a finite float64 array)."""
        if isinstance(tau, np.ndarray) and tau.dtype == np.float64 and tau.shape == (self.hand.nq,):
            out = tuple(tau.tolist())
            if all(map(math.isfinite, out)):
                return out
        return tuple(as_finite_array("tau", tau, (self.hand.nq,)).tolist())

    def step(self, tau: ArrayLike) -> PlantStep:
        """Advance one time step with constant joint torques ``tau`` [N m] (RK4)."""
        if self.state is None:
            raise InvalidParameterError("state", None, "a state: call reset() first")
        if self.stopped:
            raise InvalidParameterError("plant", "stopped", "a running plant (it stopped on an event)")
        if self.compiled:
            return self._step_compiled(tau)
        tau = self._torques(tau)
        st, h, n, hand = self.state, self.dt, self.hand.nq, self.hand
        specs = self._specs(self.contacts)
        y = st.q.tolist() + st.v.tolist() + st.X.tolist() + st.V.tolist() + [st.torque_work, st.damping_work,
                                                                           st.contact_work]
        # the event check's evaluation at the last step's end is this step's first stage when the
        # state, τ, the modes and the parameters are the same (its Pinocchio pass, when the state is)
        params = (hand.gravity_in_hand.tobytes(), hand.damping_enabled, self.mass, self.inertia, self.alpha)
        if (y, params) != self._last_key[:2]:
            k1, forces0, _ = self._evaluate(y, tau, specs)
        elif (tau, specs) != self._last_key[2:]:
            k1, forces0, _ = self._evaluate(y, tau, specs, fingers=self._last_evaluation[2])
        else:
            k1, forces0, _ = self._last_evaluation
        half = h / 2
        k2 = self._evaluate([a + half * b for a, b in zip(y, k1)], tau, specs)[0]
        k3 = self._evaluate([a + half * b for a, b in zip(y, k2)], tau, specs)[0]
        k4 = self._evaluate([a + h * b for a, b in zip(y, k3)], tau, specs)[0]
        y = [a + h * ((b1 + 2 * b2 + 2 * b3 + b4) / 6.0) for a, b1, b2, b3, b4 in zip(y, k1, k2, k3, k4)]
        new = PlantState(st.t + h, np.array(y[:n]), np.array(y[n:2 * n]), np.array(y[2 * n:2 * n + 3]),
                         np.array(y[2 * n + 3:2 * n + 6]), *y[2 * n + 6:])
        self.state = new
        modes = tuple(c.mode for c in self.contacts)
        c0, s0 = math.cos(st.X[2]), math.sin(st.X[2])
        surface = np.array([self._surface(c.edge, c0, s0, f) for c, f in zip(self.contacts, forces0)])
        end = self._evaluate(y, tau, specs, new.q, new.v)
        self._last_key, self._last_evaluation = (y, params, tau, specs), end
        fingers = end[2]
        err = self._violations(specs, new.X.tolist(), [f[11:13] for f in fingers])
        self.max_constraint_error = max(self.max_constraint_error, err)
        events, xis = self._events(new, tau, end[1], fingers)
        return PlantStep(new, surface, np.array([x[0] for x in xis]), np.array([x[1] for x in xis]), modes, err,
                         tuple(events))

    # ------------------------------------------------------------------ the compiled path
    @staticmethod
    def _flat(st: PlantState) -> np.ndarray:
        """The kernels' flat state (q, v, X, V, works)."""
        return np.concatenate((st.q, st.v, st.X, st.V, (st.torque_work, st.damping_work, st.contact_work)))

    def _contact_records(self, contacts: Sequence[PlantContact]) -> np.ndarray:
        """``contacts`` as :data:`~regrasp.kernels.plant.PLANT_CONTACT` records (the plant's own, cached)."""
        key = tuple((c.edge, c.mode, c.xi, c.sign) for c in contacts)
        cached = self._kernel_contacts
        if cached is not None and cached[0] == key:
            return cached[1]
        out = np.zeros(len(contacts), dtype=PLANT_CONTACT)
        codes = {_MODE_FIXED: FIXED, _MODE_SLIDING: SLIDING, _MODE_SEPARATED: SEPARATED}
        for i, c in enumerate(contacts):
            if c.mode not in codes:
                raise InvalidParameterError("mode", c.mode, "a ContactMode member (PlantContact converts strings)")
            g = self._edge_geometry(c.edge)
            out[i] = (codes[c.mode], c.xi, c.sign, self._static[i], self._kinetic[i], g.nx, g.ny, g.tx, g.ty, g.ox,
                      g.oy, g.offset, g.lo, g.hi)
        if contacts is self.contacts:
            self._kernel_contacts = (key, out)
        return out

    def _plant_record(self) -> np.ndarray:
        """The plant's constants as a :data:`~regrasp.kernels.plant.PLANT_PARAMETERS` record (cached)."""
        hand = self.hand
        gx, gy = hand.gravity_in_hand.tolist()
        key = (self.mass, self.inertia, gx, gy, self.alpha, hand.damping_enabled, self.dt, self.contact_events,
               hand.singular_threshold)
        if self._kernel_plant is None or self._kernel_plant[0] != key:
            record = np.zeros((), dtype=PLANT_PARAMETERS)
            for name, value in zip(PLANT_PARAMETERS.names, key):
                record[name] = value
            self._kernel_plant = (key, record)
        return self._kernel_plant[1]

    @staticmethod
    def _terms_as_pass(terms: np.ndarray) -> list[tuple]:
        """The kernel's terms in :meth:`_pin_pass`'s layout (for the event logic): :data:`FINGER_TERMS`'s fields
        but the elbow (``ex``, ``ey``), in order."""
        return [t[:_ELBOW] + t[_ELBOW + 2:] for t in terms.tolist()]

    def kernel_arguments(self, tau: ArrayLike) -> tuple:
        """The arguments :meth:`step` passes to :func:`~regrasp.kernels.plant.plant_step_into` (before its outputs)
        at the current state with torques ``tau`` [N m] (benchmarks time the bare kernel with them)."""
        if self.state is None:
            raise InvalidParameterError("state", None, "a state: call reset() first")
        return self._kernel_arguments(np.array(self._torques(tau)))

    def _kernel_arguments(self, tau: np.ndarray) -> tuple:
        checked = self.checkers is not None
        return (self.hand.kernel_parameters, self._plant_record(), self._contact_records(self.contacts),
                self._flat(self.state), tau, self._certificates if checked else self._no_certificates,
                self._link_radii_array if checked else self._no_radii)

    def _step_compiled(self, tau) -> PlantStep:
        """:meth:`step` with the compiled kernel (:func:`~regrasp.kernels.plant.plant_step_into`)."""
        tau = self._torques(tau)
        st, n = self.state, self.hand.nq
        modes = tuple(c.mode for c in self.contacts)
        m, size = self.hand.m, 2 * n + 9
        out = np.empty(self._output_size)  # (one allocation: the step's arrays are views of it)
        terms, needs_coal, posture = self._workspace
        err, attention, any_coal = plant_step_into(*self._kernel_arguments(np.array(tau)), out, terms, needs_coal,
                                                   posture)
        state = PlantState(st.t + self.dt, out[:n], out[n:2 * n], out[2 * n:2 * n + 3], out[2 * n + 3:2 * n + 6],
                           *out[2 * n + 6:size].tolist())
        self.state = state
        self._last_key = (None,) * 4
        if err > self.max_constraint_error:
            self.max_constraint_error = err
        surface = out[size:size + 2 * m].reshape(m, 2)
        xi, xi_dot = out[size + 6 * m:size + 7 * m], out[size + 7 * m:]
        if attention:
            forces = out[size + 2 * m:size + 4 * m].reshape(m, 2)
            events, xis = self._events(state, tau, forces.tolist(), self._terms_as_pass(terms))
            xi, xi_dot = np.array([x[0] for x in xis]), np.array([x[1] for x in xis])
        else:
            events = []
            if any_coal and self.checkers is not None:
                for i in np.flatnonzero(needs_coal).tolist():
                    self._coal(state, i, tuple(posture[i].tolist()), events)
        return PlantStep(state, surface, xi, xi_dot, modes, err, tuple(events))

    # ------------------------------------------------------------------ stretches (regrasp.rollout.stretch)
    def stretch_arguments(self) -> tuple:
        """What :func:`~regrasp.kernels.stretch.stretch_into` steps this plant with: (fingers, plant, contacts,
        the flat state y (a copy), certificates, radii, the step's ``out``, terms, needs_coal, posture)."""
        fingers, plant, contacts, y, _, certificates, radii = self._kernel_arguments(self._no_torques)
        terms, needs_coal, posture = self._workspace
        return (fingers, plant, contacts, y, certificates, radii, np.empty(self._output_size), terms, needs_coal,
                posture)

    def clear_collisions(self, out: np.ndarray, needs_coal: np.ndarray, posture: np.ndarray) -> bool:
        """Whether no link of the fingers ``needs_coal`` penetrates the object at the state ``out`` (a kernel
        step's output), asking coal; their certificates are renewed (as :meth:`step` does). Logs nothing: a
        stretch hands a colliding step to :meth:`step`, which logs it."""
        n = self.hand.nq
        q, X = out[:n], out[2 * n:2 * n + 3]
        clear = True
        for i in np.flatnonzero(needs_coal).tolist():
            dist, _ = self._certify(q, X, i, tuple(posture[i].tolist()))
            clear = clear and not (dist and min(dist) < 0.0)
        return clear

    def take_stretch(self, y: np.ndarray, last_out: np.ndarray, t: float, worst: float,
                     last_error: float) -> PlantStep:
        """Move to the flat state ``y`` at time ``t`` [s] after a stretch whose largest constraint violation was
        ``worst`` [m]; the stretch's last step (``last_out``: its kernel output; ``last_error``: its violation)."""
        n, m = self.hand.nq, self.hand.m
        size = 2 * n + 9
        y = y.copy()
        state = PlantState(t, y[:n], y[n:2 * n], y[2 * n:2 * n + 3], y[2 * n + 3:2 * n + 6], *y[2 * n + 6:].tolist())
        self.state = state
        self._last_key = (None,) * 4
        self.max_constraint_error = max(self.max_constraint_error, worst)
        out = last_out.copy()
        return PlantStep(state, out[size:size + 2 * m].reshape(m, 2), out[size + 6 * m:size + 7 * m],
                         out[size + 7 * m:], tuple(c.mode for c in self.contacts), last_error, ())

    def _event(self, t, i, kind, detail, out, **values):
        ev = Event(t, self.hand.fingers[i].name, EventKind(kind), detail, EventSource.PLANT, values)
        out.append(ev)
        self.events.append(ev)
        if kind in self.stop_on:
            self.stopped = True

    def _events(self, st: PlantState, tau: tuple, forces, fingers):
        """Events at the step's end ``st`` given the contact forces and the fingers' dynamics there;
        and every contact's (ξ, ξ̇) after them."""
        out: list[Event] = []
        V0 = st.V
        X = st.X.tolist()
        c, s = math.cos(X[2]), math.sin(X[2])
        geometry = [self._edge_geometry(ct.edge) for ct in self.contacts]

        def xis():
            V = st.V.tolist()
            return [self._xi(g, X, V, c, s, f[11:13], f[13:15]) for g, f in zip(geometry, fingers)]

        current = xis()
        for i, ct in enumerate(self.contacts):
            if ct.mode is _MODE_SEPARATED:
                continue
            if st.V is not V0:  # a stick before changed the velocities
                current = xis()
            xi, xi_dot = current[i]
            if self.contact_events:
                self._switch_mode(st, tau, i, self._surface(ct.edge, c, s, forces[i]), xi, xi_dot, out)
                if ct.mode is _MODE_SEPARATED:
                    continue
            g = geometry[i]
            if not g.lo <= xi <= g.hi:
                self._event(st.t, i, "left_edge", f"xi = {xi:.5g} m outside [{g.lo:.5g}, {g.hi:.5g}]", out, xi=xi)
        for i, f in enumerate(fingers):
            cond = _condition(*f[5:9])
            if not cond <= self.hand.singular_threshold:
                self._event(st.t, i, "singular", f"Jacobian condition number {cond:.3g}", out)
        if self.checkers is not None:
            # the elbows: p - o_2 = (j11, -j01)
            self._collisions(st, [(f[11] - f[8], f[12] + f[6]) for f in fingers], out)
        return out, (current if st.V is V0 else xis())

    def _collisions(self, st: PlantState, elbows, out: list[Event]) -> None:
        r"""Collision events from coal's signed distances of each finger's link shapes.

        Coal is skipped for a finger whose links cannot have reached the object since coal last
        found them free: a distance is 1-Lipschitz in a rigid motion, and a point of link k's
        shapes moves relative to the object by at most :math:`|\Delta r_k| + |\Delta\theta_k| R_k`
        (:math:`r_k`: the link's joint in the object frame, :math:`\theta_k`: its direction
        relative to the object, :math:`R_k`: the largest distance of a point of its shapes from
        the joint). The link is free while that stays below its last distance, less 0.1 % and
        10 µm (far above coal's tolerance): coal's verdict there would be the same. ``elbows``: each
        finger's joint 2 axis (hand frame)."""
        x, y, beta = st.X.tolist()
        c, s = math.cos(beta), math.sin(beta)
        q = st.q.tolist()
        for i in range(len(self.checkers)):
            ox, oy = self._pin[i][3:5]
            ex, ey = elbows[i]
            posture = (q[2 * i], q[2 * i + 1], beta, c * (ox - x) + s * (oy - y), c * (oy - y) - s * (ox - x),
                       c * (ex - x) + s * (ey - y), c * (ey - y) - s * (ex - x))
            cert = self._certificates[i].tolist()
            if not math.isnan(cert[0]):
                q1, q2, b, r1x, r1y, r2x, r2y, budget1, budget2 = cert
                turn1 = abs(posture[0] - q1 - (beta - b))
                turn2 = abs(posture[0] - q1 + posture[1] - q2 - (beta - b))
                radius1, radius2 = self._link_radii[i]
                if (math.hypot(posture[3] - r1x, posture[4] - r1y) + turn1 * radius1 < budget1
                        and math.hypot(posture[5] - r2x, posture[6] - r2y) + turn2 * radius2 < budget2):
                    continue
            self._coal(st, i, posture, out)

    def _coal(self, st: PlantState, i: int, posture, out: list[Event]) -> None:
        """Finger i's links against the object with coal: a collision event where one penetrates, and the
        finger's new certificate (``posture``: see :meth:`_collisions`)."""
        dist, nearest = self._certify(st.q, st.X, i, posture)
        if dist and min(dist) < 0.0:
            link = min(range(2), key=lambda k: nearest[k])
            self._event(st.t, i, "collision", f"link {link + 1} penetrates the object by {-min(dist):.3g} m",
                        out, link=link, depth=-min(dist))

    def _certify(self, q, X, i: int, posture) -> tuple[list[float], list[float]]:
        """Finger i's links' signed distances to the object (coal) at joints ``q`` (all fingers') and pose ``X``,
        the nearest per link, and the finger's new certificate."""
        dist = self.checkers[i].signed_distances(q[2 * i:2 * i + 2], X).tolist()
        nearest = [math.inf, math.inf]
        for d, shape in zip(dist, self.checkers[i].shapes):
            nearest[shape.link] = min(nearest[shape.link], d)
        self._certificates[i] = (*posture, *(d * (1.0 - 1e-3) - 1e-5 for d in nearest))
        return dist, nearest

    def _switch_mode(self, st: PlantState, tau, i: int, force_surface, xi: float, xi_dot: float, out) -> None:
        """Separation, slip (the static cone) and stick (the static cone) of contact i (module docstring)."""
        c = self.contacts[i]
        fn, ft = force_surface
        tol = 1e-9
        static = self._static[i]
        if fn < -tol:
            self._event(st.t, i, "separation", f"normal force {fn:.4g} N < 0", out, normal_force=fn)
            c.mode = _MODE_SEPARATED
        elif c.mode is _MODE_FIXED and cone_margin(static, fn, ft) < -tol * max(1.0, abs(fn)):
            self._event(st.t, i, "slip", f"|f_t| = {abs(ft):.4g} N > mu_s f_n = {static * fn:.4g} N", out,
                        normal_force=fn, tangential_force=ft)
            c.mode, c.sign = _MODE_SLIDING, float(np.sign(ft) or 1.0)
        elif c.mode is _MODE_SLIDING and xi_dot * c.sign <= 0.0:
            trial = [PlantContact(o.edge, o.mode, o.xi, o.sign) for o in self.contacts]
            trial[i] = PlantContact(c.edge, _MODE_FIXED, xi, c.sign)
            _, _, f_fixed = self.accelerations(st, np.array(tau), modes=trial)
            fn2, ft2 = self.surface_forces(st, f_fixed)[i]
            if fn2 >= 0.0 and cone_margin(static, fn2, ft2) >= 0.0:
                self._event(st.t, i, "stick", f"xi_dot = {xi_dot:.3g} m/s crossed zero; force inside the static cone",
                            out, xi=xi)
                c.mode, c.xi = _MODE_FIXED, xi
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

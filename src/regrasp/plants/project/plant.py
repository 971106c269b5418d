r"""An independent simulator of the hand and the object in full coordinates.

It shares with :mod:`regrasp.dynamics.reduced` only primitive models: the fingers' Pinocchio models
(the :class:`~regrasp.model.hand.Hand`'s, with their gravity and link masses; the plant evaluates M,
N, J and J̇q̇ on its own Pinocchio data), the object's geometry and inertia, and the friction
(:class:`~regrasp.core.contact.Friction`, μ_s and μ_k per contact). It never
uses H, G, G_f, P or eq. (3.2.11), so a controller that works on the plant works on physics,
not on its own model.

**Coordinates and equations**: :mod:`regrasp.plants.project.equations` (the reference path, in plain floats)
and the compiled kernel (:mod:`regrasp.plants.project.compiled`, :mod:`regrasp.kernels.plant`: the same arithmetic).

**Integration.** Classical Runge–Kutta (RK4) with a fixed step (default 1 ms); the contact
modes and friction directions are frozen during a step (the evaluation at a step's end, which
the event checks need, is the next step's first stage when τ and the modes stay). The work of the joint torques, of
the joint damping and of the contact forces (friction) are integrated alongside, for
energy-balance checks.

**Events** (separation, slip, stick, left edge, collision, singular; :mod:`regrasp.plants.project.events`) are
checked after every step; kinds in ``stop_on`` stop the simulation.

**Actuator limits.** The motors saturate: a step applies :math:`\mathrm{clip}(\tau, -e, e)`, e the hand's
:attr:`~regrasp.model.hand.Hand.effort_limit` [N m] (the URDF's ``effort`` or the scenario's), on the reference
path and in the compiled kernel alike. A joint whose commanded torque starts to exceed its limit logs a
``saturation`` event (at the step's start, with the commanded ``torque`` and the ``effort`` [N m] and the
``joint``, 1 or 2), once until it is back within the limit (:mod:`regrasp.plants.saturation`);
:attr:`Plant.saturated` is the last step's mask.

**Compliant contacts.** With a :class:`~regrasp.core.pad.Pad` every fingertip touches through a Kelvin–Voigt pad
(:mod:`regrasp.plants.project.soft`): a touching contact's normal force is the pad's, a fixed contact keeps one
bilateral row along its edge's tangent and a sliding one none (its friction is explicit). Such a plant runs the
reference path only (the compiled kernel has rigid contacts), with RK4 substeps for the pad's stiffness; a touching
contact whose pad ends a step more than ``Pad.separation_gap`` off its edge separates (within it the tip may leave
and touch again, carrying no force while off), :attr:`PlantStep.gap` is each pad's distance from its edge,
:math:`-\delta`, and :attr:`PlantStep.forces_surface` the forces averaged over the step (as the MuJoCo and Drake
plants report them: a pad's force can change within a step).

**Curved objects.** The object may be a :class:`~regrasp.core.curves.CurvedObject` (a disc, an ellipse, a rounded
polygon, a support-function curve): one face (edge 0) whose ξ is the arc length, unbounded
(:mod:`regrasp.plants.project.curve`: a sliding contact follows its tip's foot on the curve). Such a plant runs the
reference path (the compiled kernel has straight edges only); a contact's reported ξ is its foot's, continued from
its last (a sliding or separated contact's :attr:`PlantContact.xi` follows it after every step), its forces are in
the foot's surface frame and ``left_edge`` never fires (a closed curve has no end).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from ...core.contact import DEFAULT_FRICTION, ContactMode, FrictionLike, as_frictions
from ...core.curves import CurvedObject
from ...core.events import Event, EventKind
from ...core.exceptions import InvalidParameterError, PlantStateError, RegraspError
from ...core.pad import Pad
from ...core.polygon import ConvexPolygon
from ...core.validation import (
    as_finite_array,
    as_finite_float,
    as_flag,
    as_inertia,
    as_mass,
    as_positive_float,
    expect_choices,
    expect_sequence_of,
    expect_type,
)
from ...kernels.warm import ROLLOUT, STEP, compiling, warm_up
from ...model.collision import UrdfCollisionChecker
from ...model.hand import Hand
from ..saturation import Saturation
from .compiled import PlantKernel
from .curve import curve_contact_xi, foot
from .equations import PlantEquations
from .events import PlantEvents
from .kinks import kinks, located_step
from .soft import PadEquations
from .state import (
    MAX_DT,
    PLANT_EVENT_KINDS,
    PlantContact,
    PlantLog,
    PlantState,
    PlantStep,
    check_finite_step,
    checked_state,
    contact_xi,
    rigid_contact_report,
    state_magnitudes,
    surface_force,
)

__all__ = ["Plant"]

_MODE_FIXED, _MODE_SEPARATED = ContactMode.FIXED, ContactMode.SEPARATED


class Plant:
    r"""Full-coordinate hand–object simulator with fixed and sliding contacts.

    Args:
        hand: The fingers (its gravity is the plant's gravity; it may differ from the
            controller's hand, e.g. other link masses).
        polygon: The object (geometry; inertia unless overridden): a
            :class:`~regrasp.core.polygon.ConvexPolygon` or a :class:`~regrasp.core.curves.CurvedObject` (module
            docstring).
        contacts: One :class:`PlantContact` per finger.
        friction: Coulomb friction: a :class:`~regrasp.core.contact.Friction` (μ_s, μ_k) or a coefficient
            (μ_s = μ_k) [-] for all contacts, or one per contact (default
            :data:`~regrasp.core.contact.DEFAULT_FRICTION`). A fixed contact slips when
            :math:`|f_t| > \mu_s f_n`; a sliding one carries :math:`\mu_k f_n`.
        object_mass: Overrides the polygon's mass [kg].
        object_inertia: Overrides the polygon's inertia [kg m^2].
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
            ``tests/kernels/test_finger_and_plant.py`` checks it against the reference path). None (default):
            when the hand's kernels agree with Pinocchio (``hand.kernel_parameters``); False: the
            reference path (Pinocchio and plain floats). A plant with a ``pad`` runs the reference path (None
            or False; True is an error): the kernel has rigid contacts only; so does a plant on a curved object
            (the kernel has straight edges only).
        pad: A compliant pad on every fingertip (:class:`~regrasp.core.pad.Pad`; module docstring), or None
            (default): rigid contacts.
    """

    def __init__(
        self,
        hand: Hand,
        polygon: ConvexPolygon | CurvedObject,
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
        pad: Pad | None = None,
    ):

        expect_type("hand", hand, Hand, "a Hand")
        expect_type("polygon", polygon, (ConvexPolygon, CurvedObject),
                    "a ConvexPolygon or a CurvedObject (regrasp.core.curves)")
        contacts = expect_sequence_of("contacts", contacts, PlantContact, "PlantContact")
        if len(contacts) != hand.m:
            raise InvalidParameterError("contacts", contacts, f"one contact per finger ({hand.m})")
        self.hand = hand
        self.polygon = polygon
        self.contacts = self._copy_contacts(contacts)
        self.friction = as_frictions(friction, hand.m)
        mass = as_mass("object_mass", polygon.mass if object_mass is None else object_mass)
        inertia = as_inertia("object_inertia", polygon.inertia if object_inertia is None else object_inertia)
        self.dt = as_positive_float("dt", dt)
        if self.dt > MAX_DT:
            raise InvalidParameterError("dt", dt, f"a step of at most {MAX_DT} s (the explicit integrator and the "
                                        "Baumgarte terms need a fine step)")
        alpha = as_positive_float("baumgarte", baumgarte, allow_zero=True)
        stop_on = expect_choices("stop_on", stop_on, PLANT_EVENT_KINDS, "plant event kinds")
        self.stop_on = frozenset(EventKind(k) for k in stop_on)
        self.contact_events = as_flag("contact_events", contact_events)
        #: The events since the last reset, and whether one stopped the plant.
        self.log = PlantLog([f.name for f in hand.fingers], self.stop_on)
        if isinstance(polygon, CurvedObject):
            if compiled is not None and as_flag("compiled", compiled):
                raise InvalidParameterError("compiled", compiled, "None or False with a curved object (the compiled "
                                            "kernel has straight edges only)")
            compiled = False
        #: Where the object's curvature jumps (a rounded polygon's; :mod:`regrasp.plants.project.kinks`), or None.
        self.kinks = kinks(polygon)
        if pad is not None:
            expect_type("pad", pad, Pad, "a Pad (regrasp.core.pad) or None")
            if compiled is not None and as_flag("compiled", compiled):
                raise InvalidParameterError("compiled", compiled, "None or False with a pad (the compiled kernel "
                                            "has rigid contacts only)")
            compiled = False
        #: The fingertips' compliant pad, or None (rigid contacts).
        self.pad = pad
        kinetic = [f.kinetic for f in self.friction]
        #: The equations of motion (the reference path).
        self.equations = (PlantEquations(hand, polygon, kinetic, mass, inertia, alpha) if pad is None
                          else PadEquations(hand, polygon, kinetic, mass, inertia, alpha, pad))
        #: The event checks after each step (and the links' collision checks).
        self.checks = PlantEvents(hand, polygon, self.friction, self.equations, self.log,
                                  contact_events=self.contact_events,
                                  collision_check=as_flag("collision_check", collision_check),
                                  tip_clearance=tip_clearance)
        #: The compiled path's packing (used when :attr:`compiled`).
        self.kernel = PlantKernel(hand, self.friction, self.equations, self.checks, self.dt, self.contact_events)
        self._last_key, self._last_evaluation = (None,) * 4, None  # see step()
        self.state: PlantState | None = None
        self.max_constraint_error = 0.0
        #: Whether :meth:`step` runs the compiled kernel.
        self.compiled = hand.use_kernels(compiled)
        if self.compiled:
            warm_up(groups=STEP if compiling("stretch") else ROLLOUT)  # (a run decides on its stretches)
        #: The motors' torque limits (module docstring).
        self.saturation = Saturation(hand.effort_limit.tolist())

    @property
    def mass(self) -> float:
        """The object's mass [kg]."""
        return self.equations.mass

    @property
    def inertia(self) -> float:
        """The object's rotational inertia [kg m²]."""
        return self.equations.inertia

    @property
    def alpha(self) -> float:
        """α [1/s] of the constraint stabilisation."""
        return self.equations.alpha

    @property
    def checkers(self) -> list[UrdfCollisionChecker] | None:
        """Each finger's collision checker (coal), or None (no collision check)."""
        return self.checks.checkers

    @property
    def events(self) -> list[Event]:
        """The events since the last reset (:class:`~regrasp.core.events.Event`, source ``PLANT``)."""
        return self.log.events

    @property
    def stopped(self) -> bool:
        """Whether an event of a kind in ``stop_on`` stopped the plant (until the next reset)."""
        return self.log.stopped

    # ------------------------------------------------------------------ set-up
    def reset(self, q: ArrayLike, v: ArrayLike, X: ArrayLike, V: ArrayLike, t: float = 0.0,
              contacts: Sequence[PlantContact] | None = None) -> PlantState:
        """Set the state (q, v [rad, rad/s], X = (x, y, β), V = (vx, vy, ω)) and clear the event log.

        Each entry is finite and within the physical bounds of :func:`~regrasp.plants.project.state.checked_state`.
        Contact modes persist across resets (events change them); pass ``contacts`` to set them anew.
        """
        n = self.hand.nq
        if contacts is not None:
            if len(contacts) != self.hand.m:
                raise InvalidParameterError("contacts", contacts, f"one contact per finger ({self.hand.m})")
            self.contacts = self._copy_contacts(contacts)
        q, v, X, V = checked_state(n, q, v, X, V)
        self.state = PlantState(as_finite_float("t", t), q.copy(), v.copy(), X.copy(), V.copy())
        self.log.clear()
        self.saturation.clear()
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
    def contact_xi(self, st: PlantState, i: int, tip: Sequence[float] | np.ndarray | None = None,
                   tip_vel: Sequence[float] | np.ndarray | None = None) -> tuple[float, float]:
        """ξ [m] of tip i's projection on its edge's line, and its relative velocity ξ̇ [m/s]
        (``tip``/``tip_vel``: the tip's position and velocity if already known); on a curve, its foot's ξ within
        half a perimeter of the contact's :attr:`PlantContact.xi` (module docstring)."""
        if tip is None:
            tip, tip_vel = self.equations.tip(st, i)
        X = st.X.tolist()
        curve = self.equations.curve
        if curve is not None:
            tip, tip_vel = list(tip), list(tip_vel)
            return curve_contact_xi(foot(curve, X, tip, self.contacts[i].xi), X, st.V.tolist(), math.cos(X[2]),
                                    math.sin(X[2]), tip, tip_vel)
        return contact_xi(self.equations.edge(self.contacts[i].edge), X, st.V.tolist(), math.cos(X[2]),
                          math.sin(X[2]), tip, tip_vel)

    def constraint_error(self, st: PlantState,
                         tips: Sequence[Sequence[float] | np.ndarray | None] | np.ndarray | None = None) -> float:
        """Largest violation [m] of the active contact constraints (``tips``: (m, 2) if known)."""
        equations = self.equations
        if tips is None:
            tips = [equations.tip(st, i)[0] if c.mode is not _MODE_SEPARATED else None
                    for i, c in enumerate(self.contacts)]
        return equations.violations(equations.specs(self.contacts), st.X.tolist(), tips)

    # ------------------------------------------------------------------ dynamics
    def accelerations(self, st: PlantState, tau: ArrayLike,
                      modes: Sequence[PlantContact] | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q̈, Ẍ, forces) at state ``st`` for torques ``tau``: ``forces`` (m, 2) are the contact
        forces on the object in the hand frame (zeros for separated contacts)."""
        contacts = self.contacts if modes is None else modes
        tau = self.saturation.clip(self.torques(tau))[0]
        if self.compiled:
            return self.kernel.accelerations(st, tau, contacts)
        equations = self.equations
        fingers = equations.pin_pass(st.q, st.v)
        qdd, Xdd, forces = equations.solve(fingers, equations.specs(contacts), st.X.tolist(), st.V.tolist(), tau)
        return np.array(qdd), np.array(Xdd), np.array(forces)

    def surface_forces(self, st: PlantState, forces: np.ndarray) -> np.ndarray:
        """Contact forces (m, 2) in each contact's surface frame (normal, tangential)."""
        c, s = math.cos(st.X[2]), math.sin(st.X[2])
        if self.equations.curve is not None:
            return self.curve_surface_forces(st.X.tolist(), [self.equations.tip(st, i)[0].tolist()
                                                             for i in range(self.hand.m)], c, s, forces)
        edge = self.equations.edge
        return np.array([surface_force(edge(ct.edge), c, s, f)
                         for ct, f in zip(self.contacts, np.asarray(forces).tolist())])

    def torques(self, tau: ArrayLike) -> tuple[float, ...]:
        """``tau`` [N m] checked, as a tuple of floats (a fast path for a finite float64 array)."""
        if isinstance(tau, np.ndarray) and tau.dtype == np.float64 and tau.shape == (self.hand.nq,):
            out = tuple(tau.tolist())
            if all(map(math.isfinite, out)):
                return out
        return tuple(as_finite_array("tau", tau, (self.hand.nq,)).tolist())

    @property
    def saturated(self) -> tuple[bool, ...]:
        """Which joints' commanded torques the last step clipped to their limits (2m; module docstring)."""
        return self.saturation.saturated

    def step(self, tau: ArrayLike) -> PlantStep:
        """Advance one time step with constant joint torques ``tau`` [N m] (RK4), saturated at the joints' limits
        (module docstring). A state the equations cannot step from (singular, or overflowing: a run that diverged)
        raises :class:`~regrasp.core.exceptions.PlantStateError`, the plant left at that state."""
        if self.state is None:
            raise InvalidParameterError("state", None, "a state: call reset() first")
        if self.stopped:
            raise InvalidParameterError("plant", "stopped", "a running plant (it stopped on an event)")
        commanded = self.torques(tau)
        tau, saturated = self.saturation.clip(commanded)
        saturation: list[Event] = []
        for i, detail, values in self.saturation.onsets(commanded, saturated):  # (at the step's start)
            self.log.add(self.state.t, i, EventKind.SATURATION, detail, saturation, **values)
        start = self.state
        try:
            return self._advance(tau, saturation)
        except RegraspError:
            raise
        except (np.linalg.LinAlgError, ArithmeticError, ValueError) as exc:  # (the solves, math's overflows)
            self.adopt(start, 0.0)
            raise PlantStateError(start.t, f"its equations failed ({type(exc).__name__}: {exc}) at "
                                  f"{state_magnitudes(start)}") from exc

    def _advance(self, tau: tuple[float, ...], saturation: list[Event]) -> PlantStep:
        """:meth:`step`'s integration and event checks, with the saturation events ``saturation``."""
        if self.compiled:
            step = self.kernel.step(self.state, self.contacts, tau, self.accelerations)
            self.adopt(step.state, step.constraint_error)
            return dataclasses.replace(step, events=(*saturation, *step.events)) if saturation else step
        st, h, n, hand = self.state, self.dt, self.hand.nq, self.hand
        equations = self.equations
        specs = equations.specs(self.contacts)
        y = st.q.tolist() + st.v.tolist() + st.X.tolist() + st.V.tolist() + [st.torque_work, st.damping_work,
                                                                           st.contact_work]
        # the event check's evaluation at the last step's end is this step's first stage when the
        # state, τ, the modes and the parameters are the same (its Pinocchio pass, when the state is)
        params = (hand.gravity_in_hand.tobytes(), hand.damping_enabled, self.mass, self.inertia, self.alpha)
        if (y, params) != self._last_key[:2]:
            k1, forces0, fingers0 = equations.evaluate(y, tau, specs)
        elif (tau, specs) != self._last_key[2:]:
            k1, forces0, fingers0 = equations.evaluate(y, tau, specs, fingers=self._last_evaluation[2])
        else:
            k1, forces0, fingers0 = self._last_evaluation
        if self.pad is not None:
            y, forces0 = equations.integrate(y, k1, forces0, fingers0, tau, specs, h)
        elif self.kinks is not None:  # split at a jump of the curvature
            y = located_step(equations, self.kinks, y, k1, [f[11:13] for f in fingers0], tau, specs, h)
        else:
            half = h / 2
            k2 = equations.evaluate([a + half * b for a, b in zip(y, k1)], tau, specs)[0]
            k3 = equations.evaluate([a + half * b for a, b in zip(y, k2)], tau, specs)[0]
            k4 = equations.evaluate([a + h * b for a, b in zip(y, k3)], tau, specs)[0]
            y = [a + h * ((b1 + 2 * b2 + 2 * b3 + b4) / 6.0) for a, b1, b2, b3, b4 in zip(y, k1, k2, k3, k4)]
        check_finite_step(st, y)
        new = PlantState(st.t + h, np.array(y[:n]), np.array(y[n:2 * n]), np.array(y[2 * n:2 * n + 3]),
                         np.array(y[2 * n + 3:2 * n + 6]), *y[2 * n + 6:])
        self.state = new
        modes = tuple(c.mode for c in self.contacts)
        beta = st.X[2] if self.pad is None else 0.5 * (st.X[2] + y[2 * n + 2])  # (a pad's: the step's mean force)
        c0, s0 = math.cos(beta), math.sin(beta)
        if equations.curve is None:
            surface = np.array([surface_force(equations.edge(c.edge), c0, s0, f)
                                for c, f in zip(self.contacts, forces0)])
        else:  # (the feet at the step's start)
            surface = self.curve_surface_forces(st.X.tolist(), [f[11:13] for f in fingers0], c0, s0, forces0)
        end = equations.evaluate(y, tau, specs, new.q, new.v)
        self._last_key, self._last_evaluation = (y, params, tau, specs), end
        fingers = end[2]
        err = equations.violations(specs, new.X.tolist(), [f[11:13] for f in fingers])
        self.max_constraint_error = max(self.max_constraint_error, err)
        released = self.release_pads(new, specs, fingers) if self.pad is not None else []
        events, xis = self.checks.detect(new, tau, end[1], fingers, self.contacts, self.accelerations)
        events = released + events
        xi_dot = np.array([x[1] for x in xis])
        gap, slip = rigid_contact_report(modes, xi_dot, h, self.separated_gap)
        if self.pad is not None:
            depth0 = self.pad.preload_depth
            gap = np.array([self.separated_gap(i) - depth0 for i in range(self.hand.m)])
        return PlantStep(new, surface, np.array([x[0] for x in xis]), xi_dot, modes, err, gap, slip,
                         (*saturation, *events))

    def release_pads(self, st: PlantState, specs: tuple, fingers: list[tuple]) -> list[Event]:
        """With a pad and contact events: separate each touching contact whose pad is more than
        ``Pad.separation_gap`` off its edge at ``st`` (a ``separation`` event; module docstring)."""
        out: list[Event] = []
        if not self.contact_events:
            return out
        for i, depth, *_ in self.equations.depths(specs, st.X.tolist(), st.V.tolist(), fingers):
            if -depth > self.pad.separation_gap:
                self.log.add(st.t, i, "separation", f"the pad is {-depth * 1e6:.3g} um off its edge", out, gap=-depth)
                self.contacts[i].mode = _MODE_SEPARATED
        return out

    def pad_energy(self, st: PlantState | None = None) -> float:
        """The touching pads' elastic energy [J] (0 without a pad)."""
        st = self.state if st is None else st
        if self.pad is None:
            return 0.0
        equations = self.equations
        X, V = st.X.tolist(), st.V.tolist()
        return equations.pad_energy(equations.specs(self.contacts), X, V, equations.pin_pass(st.q, st.v))

    def separated_gap(self, i: int) -> float:
        """Contact i's tip's distance from its edge now [m] (positive outside)."""
        if self.equations.curve is not None:
            return self.equations.gap(self.state, i, 0, self.contacts[i].xi)
        return self.equations.gap(self.state, i, self.contacts[i].edge)

    def curve_surface_forces(self, X: list, tips: Sequence[Sequence[float]], c: float, s: float,
                             forces: Sequence[Sequence[float]] | np.ndarray) -> np.ndarray:
        """On a curved object: forces (m, 2) [N] (hand frame) in the surface frames (normal, tangential) of the
        tips' feet at pose X with tips ``tips`` (floats), the object turned by (c, s) = (cos β, sin β)."""
        curve = self.equations.curve
        return np.array([surface_force(foot(curve, X, tip, ct.xi).line, c, s, list(f))
                         for ct, tip, f in zip(self.contacts, tips, np.asarray(forces).tolist())])

    def adopt(self, state: PlantState, constraint_error: float) -> None:
        """Move to ``state``, reached by a compiled step or stretch whose largest constraint violation was
        ``constraint_error`` [m] (:class:`~regrasp.plants.project.compiled.PlantKernel`)."""
        self.state = state
        self._last_key = (None,) * 4
        self.max_constraint_error = max(self.max_constraint_error, constraint_error)

    def energy(self, st: PlantState | None = None) -> float:
        """Kinetic + gravitational potential energy [J] of fingers and object."""
        st = self.state if st is None else st
        g = self.hand.gravity_in_hand
        kin = self.hand.kinetic_energy(st.q, st.v) + 0.5 * (self.mass * st.V[:2] @ st.V[:2]
                                                            + self.inertia * st.V[2] ** 2)
        pot = self.hand.potential_energy(st.q) - self.mass * g @ st.X[:2]
        return float(kin + pot)


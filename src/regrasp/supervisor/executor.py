r"""The slide executor: runs the slides a policy orders, phase by phase, and computes the torques.

A :class:`SlideOrder` names a contact, a direction, a target ξ* and how ξ_d moves: along a given
reference :math:`(\xi_d, \dot\xi_d, \ddot\xi_d)(t)` (a schedule's slide profile), or, without one,
along a second-order filter towards the target,
:math:`\ddot\xi_r = \omega_n^2 (\xi^* - \xi_r) - 2\zeta\omega_n\dot\xi_r`. Each ordered contact goes
through three phases (``docs/derivations.md`` §4, "lessons"):

1. **priming**: the fixed-contact law with the contact's force put just past the edge of its static
   cone, :math:`\mu_s` + ``prime_overshoot``, in the sliding direction, the overshoot growing linearly
   to ``prime_overshoot_max`` over ``prime_time`` (the plant's μ_s may exceed the model's), until the
   contact is sensed slipping (with ``start_speed``: and moving in the sliding direction faster than that), or
   for at most ``prime_time``. Switching to the sliding law while the contact is still stuck makes the plant
   redistribute the forces for a step and can slip another contact; with an actuation delay, a contact that
   has just broken away is still stuck one step later unless the priming has set it moving;
2. **sliding**: the sliding law (:class:`~regrasp.dynamics.laws.Proposition3Controller`, every slider on
   its kinetic cone edge, p ≥ 1) tracking ξ_d, until the contact is at the target and slow
   (*arrived*), sticks before it (*stuck*), or runs out of ``max_slide_time`` (*timed out*);
3. **settling**: a contact that ends its slide still sliding gets the fixed law with its force just
   inside its kinetic cone in the sliding direction, :math:`\mu_k - u` with the undershoot
   :math:`u = \max(` ``settle_undershoot``, ``settle_margin`` :math:`/ f_n)` (:math:`f_n` the sensed normal
   force when the slide ends), until the plant's contact sticks: it slows down gently. The margin in newtons
   is what a torque applied late (an actuation delay) needs: a contact that sticks before the settling
   torque arrives gets that torque as a fixed contact, with :math:`u f_n` of static margin against the
   force errors of the model.

**An actuation delay** of :math:`d` = ``actuation_delay`` control steps means that the torques of the
:math:`d` steps after a phase change were computed for the phase before. A slide therefore ends in the
settling phase even when the contact is sensed stuck, and settling ends only after :math:`d + 1` steps in a
row sensed stuck: until the torques in flight were all computed for a stuck contact, a slip is still the
slide's (the sliding law's torque, applied to a contact that stuck a step before, can break it away again).
While it is sensed stuck, a settling contact gets the plain fixed-contact law (its static cone, with the cone
margin the internal force seeks), no cone edge.

Contacts being primed or settled are fixed in the model with a cone edge each; the sliders are
sliding in the model; all of them share one control law per step. When no internal force keeps
the slides within their cones (the QP is infeasible), the slides are aborted: the contacts settle
or are held with the fixed law. Before that, a step gives up what it can (:mod:`regrasp.supervisor.fallbacks`): the
contacts' floors above ``f_min``, then the held contacts' friction margin down to its fallback, then the feedback's
correction (the planned motion stays), then a settling contact's kinetic cone edge. The executor decides nothing
about *which* slides to run: that is the policy's (:mod:`regrasp.supervisor.policies.scheduled`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ..core.contact import ContactMode, Friction
from ..core.events import Event, EventKind
from ..core.exceptions import InvalidParameterError
from ..dynamics.control import ComputedTorqueController, ControlOutput, Gains
from ..dynamics.grasp import Grasp
from ..dynamics.internal_force.problem import InternalForceInfeasibleError
from ..dynamics.internal_force.settings import ConeEdge
from ..dynamics.laws import FixedContactController, Proposition3Controller
from ..dynamics.reduced import ReducedModel
from ..kernels.stretch_layout import SLIDER, StretchExecutor
from ..model.hand import Hand
from ..model.sphere_tip import sphere_tip_torque
from .fallbacks import fallbacks, first_feasible, with_feedback
from .handover import HandoverHold
from .settings import ExecutorSettings
from .types import ContactPhase, SlideEnd, SlideOrder, SlideProfile

if TYPE_CHECKING:
    from ..core.measurement import Measurement
    from ..core.trajectory import TrajectorySample

__all__ = ["SlideExecutor"]

@dataclass
class _Active:
    order: SlideOrder
    phase_start: float
    slipped: bool = False
    aborted: bool = False
    reprimes: int = 0
    mu_hat: float = math.nan  # the slider's kinetic friction ratio, estimated while it slides
    held_ratio: float = math.nan  # the largest |f_t| / f_n sensed while primed and not yet slipping
    settle_sign: float = 0.0
    settle_undershoot: float = 0.0  # u of the settling phase (module docstring)
    still: int = 0  # steps in a row the settling contact was sensed stuck
    filter: list = field(default_factory=lambda: [0.0, 0.0])


class SlideExecutor:
    """Runs slides on a hand (module docstring).

    Args:
        hand: The fingers (finger i touches contact i).
        grasp: The contacts (edges; the modes are the executor's).
        xi: Initial contact positions [m], all fixed.
        friction: What the controllers assume: one :class:`~regrasp.core.contact.Friction` per contact.
        object_mass: The mass the controllers assume [kg].
        object_inertia: The inertia the controllers assume [kg m²].
        settings: :class:`ExecutorSettings`.
    """

    def __init__(self, hand: Hand, grasp: Grasp, xi: ArrayLike, friction: tuple[Friction, ...], *, object_mass: float,
                 object_inertia: float, settings: ExecutorSettings = ExecutorSettings()):
        self.hand = hand
        self.grasp = grasp
        self.friction = tuple(friction)
        self.object_mass = object_mass
        self.object_inertia = object_inertia
        self.settings = settings
        self.names = tuple(f.name for f in hand.fingers)
        self.xi = np.array(xi, dtype=float)
        self._xi_sensed = self.xi.copy()  # the sensed positions, the held ones filtered (hold_filter_time)
        self.phases = [ContactPhase.FIXED] * hand.m
        self.regrasps = [0] * hand.m
        self._active: dict[int, _Active] = {}
        self._controller: ComputedTorqueController | None = None
        self._key = None
        self._now = 0.0
        self._integral_X = np.zeros(3)          # ∫(X_d - X) dt
        self._integral_xi: dict[int, float] = {}  # ∫(ξ_d - ξ) dt per slider
        self._reflex_until = np.full(hand.m, -math.inf)  # each contact's reflex lasts until then [s]
        self._hold = HandoverHold(hand.m, settings.handover_time, settings.handover_load_max)

    # ------------------------------------------------------------------ state
    @property
    def active(self) -> tuple[int, ...]:
        """The contacts with a slide under way (priming, sliding or settling)."""
        return tuple(sorted(self._active))

    def order_of(self, i: int) -> SlideOrder | None:
        a = self._active.get(i)
        return None if a is None else a.order

    def _event(self, out: list, t: float, i: int, kind: EventKind, detail: str, **values) -> None:
        out.append(Event(float(t), self.names[i], kind, detail, values=values))

    # ------------------------------------------------------------------ orders
    def start(self, order: SlideOrder, meas: Measurement, out: list) -> None:
        """Prime ``order``'s contact (it must be fixed)."""
        i = order.contact
        if self.phases[i] is not ContactPhase.FIXED:
            raise InvalidParameterError("order", order, f"a slide of a fixed contact ({self.names[i]} is "
                                        f"{self.phases[i].value})")
        self._active[i] = _Active(order, float(meas.t))
        self.phases[i] = ContactPhase.PRIMING
        self.xi = self._sensed()
        self._event(out, meas.t, i, EventKind.PRIME, f"to slide {'+' if order.direction > 0 else '-'}xi from "
                    f"{meas.xi[i] * 1e3:.2f} mm to {order.target * 1e3:.2f} mm"
                    + (f" ({order.why})" if order.why else ""),
                    xi=float(meas.xi[i]), target=order.target, direction=order.direction)

    def _sense_held(self, meas: Measurement) -> None:
        """Filter the held contacts' sensed positions (``hold_filter_time``; the others are taken as sensed)
        and move their model positions there where they drifted by more than ``hold_resolution`` (a rolling
        fingertip)."""
        s = self.settings
        gain = 1.0 if s.hold_filter_time is None else min(1.0, s.control_period / s.hold_filter_time)
        sensed = self._xi_sensed
        for i, phase in enumerate(self.phases):
            if phase is ContactPhase.FIXED and not meas.sliding[i]:
                sensed[i] += gain * (meas.xi[i] - sensed[i])
                if s.hold_resolution is not None and abs(sensed[i] - self.xi[i]) > s.hold_resolution:
                    self.xi[i] = sensed[i]
            else:
                sensed[i] = meas.xi[i]

    def _reflex(self, meas: Measurement) -> None:
        """Start the reflex of every contact whose sensed normal force fell below ``reflex_below``."""
        below = self.settings.reflex_below
        if below > 0.0 and meas.normal_force is not None:
            until = float(meas.t) + self.settings.reflex_time
            for i, fn in enumerate(meas.normal_force.tolist()):
                if fn < below:
                    self._reflex_until[i] = until

    def floors(self) -> tuple[float, ...]:
        """Each contact's least normal force in the laws now [N] (0: the internal force's ``f_min``): a slider's
        ``slider_floor``, a holder's ``holder_preload`` while another contact is primed or slides, ``reflex_floor``
        while a reflex lasts, and the handover hold's (:mod:`regrasp.supervisor.handover`)."""
        s = self.settings
        moving = any(p in (ContactPhase.PRIMING, ContactPhase.SLIDING) for p in self.phases)
        out = []
        for i, (phase, hold) in enumerate(zip(self.phases, self._hold.floors(self._now).tolist())):
            floor = s.slider_floor if phase is not ContactPhase.FIXED else s.holder_preload if moving else 0.0
            if self._now < self._reflex_until[i]:
                floor = max(floor, s.reflex_floor)
            out.append(max(floor, hold))
        return tuple(out)

    def _sensed(self) -> np.ndarray:
        """Every contact's sensed position for the model (the held ones filtered)."""
        return self._xi_sensed.copy()

    def advance(self, meas: Measurement, out: list) -> list[SlideEnd]:
        """Move every slide's phase on; the slides whose sliding phase ended at this step."""
        s = self.settings
        ends = []
        self._sense_held(meas)
        self._reflex(meas)
        for i in list(self._active):
            a = self._active[i]
            phase = self.phases[i]
            t, xi, xi_dot, sliding = float(meas.t), float(meas.xi[i]), float(meas.xi_dot[i]), bool(meas.sliding[i])
            target = a.order.target
            started = sliding and (s.start_speed is None or xi_dot * a.order.direction > s.start_speed)
            if phase is ContactPhase.PRIMING and not sliding:  # the largest ratio it held: ≤ the plant's μ_s
                a.held_ratio = float(np.fmax(a.held_ratio, meas.force_ratio(i, s.friction_min_force)))
            if phase is ContactPhase.PRIMING and (started or t - a.phase_start >= s.prime_time - 1e-12):
                self.phases[i] = ContactPhase.SLIDING
                a.phase_start, a.slipped, a.filter = t, sliding, [xi, xi_dot]
                if s.breakaway_estimate:
                    # the first estimate: the force ratio it broke away at, or the largest it held primed (a soft
                    # contact's friction builds up as it slips): ≈ μ_s >= μ_k of the plant, no less friction than the
                    # plant's (a slider whose law expects less reverses within a step and sticks again)
                    self._estimate_friction(a, i, meas)
                    a.mu_hat = float(np.fmax(a.mu_hat, a.held_ratio))
                self.xi = self._sensed()
                self._event(out, t, i, EventKind.SLIDE, f"sliding law, target {target * 1e3:.2f} mm"
                            + ("" if sliding else " (not yet slipping)"), xi=xi, target=target)
            elif phase is ContactPhase.SLIDING:
                a.slipped = a.slipped or sliding  # the plant reports the slip one step after the law starts
                self._estimate_friction(a, i, meas)
                near = abs(xi - target) < s.arrive_tolerance
                if near and abs(xi_dot) < s.arrive_speed and (a.order.reference is None or not sliding
                                                              or a.order.planned_end is None
                                                              or t >= a.order.planned_end):
                    ends.append(self._end(meas, out, i, EventKind.ARRIVED, f"xi = {xi * 1e3:.2f} mm after "
                                          f"{t - a.phase_start:.3f} s"))
                elif a.slipped and not sliding:
                    if (a.order.reference is not None and a.reprimes < s.max_reprimes
                            and (a.order.planned_end is None or t < a.order.planned_end)):
                        # a planned slide goes on: break the contact away again (more friction than the
                        # model's stopped it) and keep tracking the plan
                        a.reprimes += 1
                        self.phases[i] = ContactPhase.PRIMING
                        a.phase_start, a.slipped = t, False
                        self.xi = self._sensed()
                        self._event(out, t, i, EventKind.STUCK, f"stuck at {xi * 1e3:.2f} mm on the way (target "
                                    f"{target * 1e3:.2f} mm)", xi=xi, target=target, reprime=a.reprimes)
                        self._event(out, t, i, EventKind.PRIME, f"again ({a.reprimes} of {s.max_reprimes}) to slide "
                                    f"{'+' if a.order.direction > 0 else '-'}xi to {target * 1e3:.2f} mm", xi=xi,
                                    target=target, direction=a.order.direction, reprime=a.reprimes)
                        continue
                    ends.append(self._end(meas, out, i, EventKind.STUCK, f"stuck at {xi * 1e3:.2f} mm (target "
                                          f"{target * 1e3:.2f} mm)"))
                elif t - a.phase_start > s.max_slide_time:
                    ends.append(self._end(meas, out, i, EventKind.TIMED_OUT, f"stopped after max_slide_time at "
                                          f"{xi * 1e3:.2f} mm (target {target * 1e3:.2f} mm)"))
            elif phase is ContactPhase.SETTLING:
                a.still = 0 if sliding else a.still + 1
                if a.still > s.actuation_delay:
                    self._finish(meas, out, i)
        return ends

    def _estimate_friction(self, a: _Active, i: int, meas) -> None:
        """Update the slider's kinetic friction ratio from the sensed forces (``friction_filter_time``)."""
        s = self.settings
        ratio = meas.force_ratio(i, s.friction_min_force)
        if s.friction_filter_time is None or not meas.sliding[i] or math.isnan(ratio):
            return
        a.mu_hat = ratio if math.isnan(a.mu_hat) else \
            a.mu_hat + min(1.0, s.control_period / s.friction_filter_time) * (ratio - a.mu_hat)

    def _kinetic(self, i: int) -> float:
        """The kinetic friction ratio the laws use for contact i: the estimate while it slides, rounded to
        ``friction_resolution``, else the model's."""
        a = self._active.get(i)
        mu = self.friction[i].kinetic
        if a is None or math.isnan(a.mu_hat):
            return mu
        r = self.settings.friction_resolution
        return max(0.0, round(a.mu_hat / r) * r)

    def _end(self, meas, out: list, i: int, kind: EventKind, detail: str) -> SlideEnd:
        """End contact i's sliding phase where it is: settle if it still slides, else fix it."""
        a = self._active[i]
        t, xi = float(meas.t), float(meas.xi[i])
        self._event(out, t, i, kind, detail, xi=xi, target=a.order.target,
                    **({} if a.order.planned_end is None else {"planned_end": a.order.planned_end}))
        self.xi = self._sensed()
        if meas.sliding[i] or self.settings.actuation_delay > 0:
            self.phases[i] = ContactPhase.SETTLING
            a.still = 0 if meas.sliding[i] else 1
            moving = float(meas.xi_dot[i])
            a.settle_sign = math.copysign(1.0, moving) if moving else float(a.order.direction)
            fn = math.nan if meas.normal_force is None else float(meas.normal_force[i])
            s = self.settings
            a.settle_undershoot = s.settle_undershoot if not fn > s.friction_min_force else \
                max(s.settle_undershoot, s.settle_margin / fn)
        else:
            self._finish(meas, out, i)
        return SlideEnd(a.order, kind, t, xi)

    def _finish(self, meas, out: list, i: int) -> None:
        a = self._active.pop(i)
        self.phases[i] = ContactPhase.FIXED
        self.xi = self._sensed()
        if not a.aborted:  # an aborted slide that settles is not a regrasp
            self.regrasps[i] += 1
        self._event(out, meas.t, i, EventKind.SETTLED, f"fixed at {meas.xi[i] * 1e3:.2f} mm", xi=float(meas.xi[i]))

    def abort(self, meas: Measurement, out: list, reason: str) -> list[SlideEnd]:
        """Abort every slide being primed or slid (the QP found no forces for them)."""
        ends = []
        for i in list(self._active):
            if self.phases[i] not in (ContactPhase.PRIMING, ContactPhase.SLIDING):
                continue
            a = self._active[i]
            a.aborted = True
            ends.append(self._end(meas, out, i, EventKind.SLIDE_ABORTED, reason))
        return ends

    # ------------------------------------------------------------------ stretches (regrasp.rollout.stretch)
    def law(self) -> ComputedTorqueController:
        """The law the next step tries first (the current phases', whole floors and friction margin; cached)."""
        return self._law()

    def stretch_view(self) -> StretchExecutor | None:
        """What a compiled stretch (:mod:`regrasp.rollout.stretch`) reads and updates of the executor: (held (m,) bool,
        the law's held positions ξ [m], the filtered sensed positions [m] and ∫(X_d - X) dt, both the executor's own
        arrays, the sliders as :data:`~regrasp.kernels.stretch_layout.SLIDER` records); None where only the reference
        path serves: a contact being primed or settling, a reflex or a handover hold lasting or starting, a slide
        without a planned profile (:class:`~regrasp.supervisor.types.SlideProfile`) or spherical tips."""
        s = self.settings
        if s.tip_radius != 0.0 or bool((self._reflex_until > self._now).any()) or self._hold.changed(self.phases) \
                or self._hold.active(self._now):
            return None
        sliders = []
        for i, phase in enumerate(self.phases):
            if phase is ContactPhase.SLIDING:
                a = self._active[i]
                if not isinstance(a.order.reference, SlideProfile):
                    return None
                sliders.append(i)
            elif phase is not ContactPhase.FIXED:
                return None
        records = np.zeros(len(sliders), dtype=SLIDER)
        for c, i in enumerate(sliders):
            a = self._active[i]
            o = a.order
            slide, offset = o.reference.slide, o.reference.offset
            records[c] = (i, a.slipped, a.mu_hat, self._integral_xi.get(i, 0.0), a.phase_start, o.target,
                          math.nan if o.planned_end is None else o.planned_end, slide.start, slide.end,
                          slide.start_xi, slide.end_xi, slide.ramp, slide.speed, float(slide.direction), offset,
                          self._kinetic(i), self.friction[i].kinetic)
        held = np.array([p is ContactPhase.FIXED for p in self.phases])
        return StretchExecutor(held, self.xi, self._xi_sensed, self._integral_X, records)

    def take_stretch(self, sliders: np.ndarray, t: float, loads_n: np.ndarray) -> None:
        """After a stretch whose last step started at ``t`` [s]: the sliders' slip flags, friction estimates and
        integrals from its records (:meth:`stretch_view`), and its last step's predicted normal forces [N]."""
        self._hold.note(loads_n)
        for record in sliders:
            a = self._active[int(record["contact"])]
            a.slipped, a.mu_hat = bool(record["slipped"]), float(record["mu_hat"])
        if self.settings.integral > 0.0:
            self._integral_xi = {int(r["contact"]): float(r["integral"]) for r in sliders}
        self._now = float(t)

    # ------------------------------------------------------------------ control
    def _gains(self, n: int) -> Gains:
        s = self.settings
        omega = np.array([s.control_omega] * 3 + [s.slide_omega] * (n - 3))
        return Gains(2.0 * omega, omega**2)

    def _law(self, fraction: float = 1.0, settle_edges: bool = True, relaxed: bool = False) -> ComputedTorqueController:
        """The control law of the current phases (cached while they and the held positions stay); ``fraction``: how
        much of each contact's floor above the internal force's ``f_min`` (:meth:`floors`) it keeps (0: ``f_min``
        alone); ``settle_edges``: whether a settling contact still sensed sliding gets its kinetic cone's edge (False:
        the fixed-contact law, as once sensed stuck); ``relaxed``: whether it may take ``fallback_friction_margin``."""
        s = self.settings
        edges = []
        for i, a in sorted(self._active.items()):
            if self.phases[i] is ContactPhase.PRIMING:
                ramp = min(1.0, (self._now - a.phase_start) / s.prime_time)
                first = min(s.prime_overshoot_max, s.prime_overshoot + a.reprimes * s.reprime_overshoot_step)
                overshoot = first + ramp * (s.prime_overshoot_max - first)
                edges.append(ConeEdge(i, a.order.direction, self.friction[i].static + overshoot))
            elif self.phases[i] is ContactPhase.SETTLING and a.still == 0 and settle_edges:  # (stuck: the fixed
                # law's own cone)
                kinetic = self._kinetic(i)
                edges.append(ConeEdge(i, a.settle_sign, kinetic - min(a.settle_undershoot, 0.5 * kinetic)))
        sliders = [i for i in range(self.hand.m) if self.phases[i] is ContactPhase.SLIDING]
        friction = tuple(Friction(max(f.static, k), k) if k != f.kinetic else f
                         for f, k in zip(self.friction, (self._kinetic(i) for i in range(self.hand.m))))
        f_min = s.internal_force.f_min
        floors = tuple(f_min + fraction * (f - f_min) if f > f_min else f for f in self.floors()) if fraction > 0.0 \
            else ()
        relaxed = relaxed and s.internal_force.fallback_friction_margin is not None  # (else: the same law)
        key = (tuple(self.phases), tuple(edges), self.xi.tobytes(), friction, floors, relaxed)
        if key == self._key:
            return self._controller
        internal_force = s.internal_force
        if floors and any(f > internal_force.f_min for f in floors):
            internal_force = replace(internal_force, floors=floors)
        if not relaxed and internal_force.fallback_friction_margin is not None:
            internal_force = replace(internal_force, fallback_friction_margin=None, last_friction_margin=None)
        modes = [ContactMode.SLIDING if i in sliders else ContactMode.FIXED for i in range(self.hand.m)]
        model = ReducedModel(self.hand, self.grasp.with_modes(modes), self.xi, object_mass=self.object_mass,
                             object_inertia=self.object_inertia)
        cone_edge = None if not edges else (edges[0] if len(edges) == 1 else tuple(edges))
        if sliders:
            directions = [self._active[i].order.direction for i in sliders]
            # a planned slide (a reference from rest to rest) never reverses; a filtered one may overshoot
            planned = all(self._active[i].order.reference is not None for i in sliders)
            law = Proposition3Controller(model, self._gains(3 + len(sliders)), friction,
                                         direction=directions if len(directions) > 1 else directions[0],
                                         reversible=not planned, internal_force=internal_force, cone_edge=cone_edge)
        else:
            law = FixedContactController(model, self._gains(3), friction, internal_force=internal_force,
                                         cone_edge=cone_edge)
        self._controller, self._key = law, key
        return law

    def _slider_reference(self, i: int, t: float, dt: float) -> tuple[float, float, float]:
        a = self._active[i]
        if a.order.reference is not None:
            return a.order.reference(t)
        w, z = self.settings.omega_n, self.settings.zeta
        x, v = a.filter
        acc = w * w * (a.order.target - x) - 2.0 * z * w * v
        v = v + acc * dt
        x = x + v * dt
        a.filter = [x, v]
        return x, v, w * w * (a.order.target - x) - 2.0 * z * w * v

    def _integrate(self, S_d: np.ndarray, S: np.ndarray, sliders: list, dt: float) -> np.ndarray:
        """S_d shifted by (K_i / K_s) ∫E dt (``ExecutorSettings.integral``); a slider's integral starts at
        its sliding phase and ends with it."""
        s = self.settings
        error = S_d - S
        self._integral_X += error[:3] * dt
        self._integral_xi = {i: self._integral_xi.get(i, 0.0) + float(e) * dt for i, e in zip(sliders, error[3:])}
        omega = np.array([s.control_omega] * 3 + [s.slide_omega] * len(sliders))
        integral = np.concatenate([self._integral_X, [self._integral_xi[i] for i in sliders]])
        return S_d + s.integral * omega * integral  # (K_i / K_s) = integral · ω

    def command(self, meas: Measurement, desired: TrajectorySample, dt: float,
                out: list) -> tuple[ControlOutput, str, np.ndarray, list[SlideEnd]]:
        """(the law's output, the law's name, ξ_d per contact (NaN where not sliding), slides aborted at
        this step) for the measurement ``meas`` and the desired object state ``desired``
        (a :class:`~regrasp.core.trajectory.TrajectorySample`)."""
        m = self.hand.m
        self._now = float(meas.t)
        self._hold.see(self.phases, self._now)
        reference = np.full(m, np.nan)
        sliders = [i for i in range(m) if self.phases[i] is ContactPhase.SLIDING]
        refs = [self._slider_reference(i, float(meas.t), dt) for i in sliders]
        for i, r in zip(sliders, refs):
            reference[i] = r[0]
        S = np.concatenate([meas.X, meas.xi[sliders]])
        S_dot = np.concatenate([meas.V, meas.xi_dot[sliders]])
        S_d = np.concatenate([desired.pose, [r[0] for r in refs]])
        if self.settings.integral > 0.0:
            S_d = self._integrate(S_d, S, sliders, dt)
        S_d_dot = np.concatenate([desired.velocity, [r[1] for r in refs]])
        S_d_ddot = np.concatenate([desired.acceleration, [r[2] for r in refs]])
        ends = []
        try:
            law, output = self._feasible(S, S_dot, S_d, S_d_dot, S_d_ddot)
        except InternalForceInfeasibleError as exc:
            if not any(self.phases[i] in (ContactPhase.PRIMING, ContactPhase.SLIDING) for i in self._active):
                raise
            ends = self.abort(meas, out, f"no internal force keeps the slide in its cones ({exc.status})")
            law, output = self._feasible(meas.X, meas.V, desired.pose, desired.velocity, desired.acceleration)
            reference = np.full(m, np.nan)
        self._hold.note(output.contact_forces_surface[:, 0])
        return self._tipped(output, meas), _name(law), reference, ends

    def _feasible(self, S: np.ndarray, S_dot: np.ndarray, S_d: np.ndarray, S_d_dot: np.ndarray,
                  S_d_ddot: np.ndarray) -> tuple[ComputedTorqueController, ControlOutput]:
        """The first law of :func:`~regrasp.supervisor.fallbacks.fallbacks` whose forces exist, and its output; the
        last one's :class:`InternalForceInfeasibleError` where none's do."""
        settling = any(self.phases[i] is ContactPhase.SETTLING and a.still == 0 for i, a in self._active.items())

        def solve(fraction: float, gain: float, edges: bool,
                  relaxed: bool) -> tuple[ComputedTorqueController, ControlOutput]:
            law = self._law(fraction, edges, relaxed)
            return law, with_feedback(law, gain, S, S_dot, S_d, S_d_dot, S_d_ddot)

        order = fallbacks(self._law().internal_force.floors != (), self.settings.internal_force.fallback_friction_margin
                          is not None, settling)
        return first_feasible(order, solve, InternalForceInfeasibleError)

    def _tipped(self, output: ControlOutput, meas: Measurement) -> ControlOutput:
        """``output`` with the spherical tips' couple added to its torque (``tip_radius``)."""
        r = self.settings.tip_radius
        if r == 0.0:
            return output
        c, s = math.cos(meas.X[2]), math.sin(meas.X[2])  # (on a curve: the normals at the measured positions)
        normals = self.grasp.surface_frames(meas.X, meas.xi)[:, :, 0] if self.grasp.curved else \
            np.array([e.inward_normal for e in self.grasp.edges]) @ np.array([[c, s], [-s, c]])
        return replace(output, tau=output.tau + sphere_tip_torque(normals, output.contact_forces, r))


def _name(law: ComputedTorqueController) -> str:
    return law.law + (" (cone edge)" if law.cone_edge is not None else "")

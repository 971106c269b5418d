r"""Control of the object and of sliding contacts (paper §3.3–3.4), corrected.

All laws are computed torque on the reduced dynamics derived in ``docs/derivations.md``,

.. math:: (H^T M H + M_s)\,\ddot S + N_s = H^T \tau + [f_g;\ -f_\xi].

With :math:`a = \ddot S_d + K_v \dot E + K_s E` (:math:`E = S_d - S`) and an estimate
:math:`\hat f_\xi` of the friction at the sliding contacts,

.. math:: \tau = (H^T)^+ \big[(H^T M H + M_s)\,a + N_s - [f_g;\ -\hat f_\xi]\big] + J^T f_c,
          \qquad (H^T)^+ = H (H^T H)^{-1},

which gives :math:`(H^T M H + M_s)(\ddot S - a) = [0;\ \hat f_\xi - f_\xi]`, so
:math:`\ddot E + K_v \dot E + K_s E = 0` whenever :math:`\hat f_\xi = f_\xi`. Written out,
:math:`(H^T)^+ (H^T M H + M_s) a + (H^T)^+ N_s = [M H + (H^T)^+ M_s] a + M \dot H \dot S + N` plus a
null-space term, which is the paper's form. The laws differ only in :math:`\hat f_\xi`:

* :class:`FixedContactController`: p = 0 (the paper's reference [5]); no sliding contact.
* :class:`Proposition1Controller`: :math:`\hat f_\xi = 0` (3.3.1).
* :class:`Proposition2Controller`: :math:`\hat f_\xi` measured (3.3.8).
* :class:`Proposition3Controller`: :math:`\hat f_\xi` predicted from the commanded motion with every
  slider on its kinetic cone edge; for m = 2, p = 1 the paper's :math:`P (M_o a_X - f_g)` (3.4.9,
  3.4.11), with P for the commanded sliding direction; any p >= 1 with 2m >= 3 + p otherwise.

Two corrections to the printed laws (``docs/derivations.md``): the gravity term enters as
:math:`-(H^T)^+[f_g; 0]`, where (3.3.1) and (3.3.8) print :math:`+`; and (3.3.8)/(3.4.11) drop
the :math:`G R_f B_v f_\xi` terms, which count the friction twice.

The internal force :math:`J^T f_c` (3.3.7) is chosen by :mod:`regrasp.dynamics.internal_force.solver`: the
least squeeze that keeps every contact pushing and every fixed contact inside its static friction
cone (:math:`\mu_s`) with margins, given the contact forces :math:`f_m` the motion torque produces.
Each controller keeps a persistent OSQP solver (:class:`~regrasp.dynamics.internal_force.solver.InternalForceSolver`).

Friction (:class:`~regrasp.core.contact.Friction`): a controller's ``friction`` is what it assumes of the
fingertips; a sliding contact carries the kinetic coefficient :math:`\mu_k` (Proposition 3 puts it
on its kinetic cone edge), a fixed one is kept inside its static cone. The reported cone margins use
the coefficient of each contact's mode.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import lapack

from ..core.contact import DEFAULT_FRICTION, FrictionLike, as_frictions, coefficients, cone_margin
from ..core.exceptions import InvalidParameterError, SingularModelError
from ..core.scalar import solve_small
from ..core.validation import as_finite_array, as_finite_vectors, as_integer, as_positive_float, expect_type
from ..kernels.control import CONTROL_OK, control_layout, control_step_into, sliding_step_into
from .internal_force.solver import (
    ConeEdge,
    InternalForceResult,
    InternalForceSettings,
    InternalForceSolver,
    as_cone_edges,
)
from .reduced import ReducedModel, ReducedState

__all__ = [
    "ComputedTorqueController",
    "ControlOutput",
    "FixedContactController",
    "Gains",
    "Proposition1Controller",
    "Proposition2Controller",
    "Proposition3Controller",
]


@dataclass(frozen=True)
class Gains:
    """Diagonal gains per reduced coordinate: K_v [1/s] and K_s [1/s^2], each shape (3 + p,)."""

    kv: np.ndarray
    ks: np.ndarray

    def __post_init__(self) -> None:
        kv = as_finite_array("kv", self.kv, (-1,))
        ks = as_finite_array("ks", self.ks, (-1,))
        if len(kv) != len(ks) or len(kv) < 3:
            raise InvalidParameterError("ks", self.ks, f"one gain per reduced coordinate, as many as kv ({len(kv)} >= 3)")
        for name, gains, value in (("kv", kv, self.kv), ("ks", ks, self.ks)):
            if (gains <= 0.0).any():
                raise InvalidParameterError(name, value, "positive gains (> 0)")
        object.__setattr__(self, "kv", kv)
        object.__setattr__(self, "ks", ks)

    @classmethod
    def critically_damped(cls, omega: float, n: int) -> "Gains":
        """K_s = ω², K_v = 2ω on all n coordinates (ω [rad/s], at most 10⁶)."""
        omega = as_positive_float("omega", omega)
        if omega > 1e6:
            raise InvalidParameterError("omega", omega, "a bandwidth in (0, 1e6] rad/s")
        n = as_integer("n", n, 3)
        if n > 1000:
            raise InvalidParameterError("n", n, "a number of reduced coordinates from 3 to 1000")
        return cls(np.full(n, 2.0 * omega), np.full(n, omega**2))


@dataclass(frozen=True)
class ControlOutput:
    """One control step's torque and diagnostics.

    Attributes:
        tau: Joint torques (2m,) [N m].
        command: a = S̈_d + K_v Ė + K_s E, the commanded S̈.
        error: E = S_d - S.
        error_rate: Ė = Ṡ_d - Ṡ.
        friction_estimate: f̂_ξ at the sliding contacts (p,) [N] (force on the object along t).
        contact_forces: Predicted contact forces on the object (m, 2) [N], hand frame.
        contact_forces_surface: The same in each surface frame (normal, tangential).
        cone_margins: μ f_n - |f_t| per contact [N]: μ_s at a fixed contact, μ_k at a sliding one
            (≈ 0 there).
        internal: The internal-force QP's result, or None when disabled.
        seconds: Wall time of the step [s].
    """

    tau: np.ndarray
    command: np.ndarray
    error: np.ndarray
    error_rate: np.ndarray
    friction_estimate: np.ndarray
    contact_forces: np.ndarray
    contact_forces_surface: np.ndarray
    cone_margins: np.ndarray
    internal: InternalForceResult | None
    seconds: float


class ComputedTorqueController:
    r"""Computed torque in the reduced coordinates, with a QP-chosen internal force.

    Args:
        model: The reduced model (its grasp sets which contacts slide).
        gains: K_v and K_s, one per reduced coordinate.
        friction: The friction the controller assumes: a :class:`~regrasp.core.contact.Friction` or a
            coefficient [-] for all contacts, or one per contact.
        internal_force: QP margins, or None to apply no internal force.
        cone_edge: Put this contact on a cone edge, with the coefficient the
            :class:`~regrasp.dynamics.internal_force.solver.ConeEdge` carries (the transition before a slide); or a tuple
            of them, on distinct contacts (several transitions at once). Kept as given in ``cone_edge``.
        compiled: Take the compiled step (:mod:`regrasp.kernels.control`) where it applies: a compiled model, a
            law whose friction estimate needs no state (the fixed-contact law, Proposition 1) and the QP's
            compiled solver; anything else it does not settle goes the reference path. None: where it applies.
    """

    law = "computed torque"

    def __init__(self, model: ReducedModel, gains: Gains, friction: FrictionLike = DEFAULT_FRICTION, *,
                 internal_force: InternalForceSettings | None = InternalForceSettings(),
                 cone_edge: ConeEdge | tuple[ConeEdge, ...] | None = None, compiled: bool | None = None):
        expect_type("model", model, ReducedModel, "a ReducedModel")
        expect_type("gains", gains, Gains, "a Gains")
        if internal_force is not None:
            expect_type("internal_force", internal_force, InternalForceSettings, "an InternalForceSettings or None")
        n = model.n
        kv = as_finite_array("gains.kv", gains.kv, (n,))
        ks = as_finite_array("gains.ks", gains.ks, (n,))
        if np.any(kv <= 0) or np.any(ks <= 0):
            raise InvalidParameterError("gains", gains, "positive K_v and K_s")
        self.model = model
        self.gains = Gains(kv, ks)
        self.friction = as_frictions(friction, model.grasp.m)
        self.internal_force = internal_force
        self.cone_edge = cone_edge
        self._cone_edges = as_cone_edges(cone_edge, model.grasp.m)  # what the QP gets (validated)
        self._qp = InternalForceSolver(internal_force) if internal_force is not None else None
        self._modes = model.grasp.modes
        # the cone margins' coefficients: μ_s where fixed, μ_k where sliding
        self._margin_mu = coefficients(self.friction, self._modes)
        # whether the law's f̂_ξ needs the ReducedState (the base law's is zero)
        self._estimates_friction = type(self).friction_estimate is not ComputedTorqueController.friction_estimate
        self._kernel = None
        if compiled is not False and model.compiled and not self._estimates_friction \
                and type(self)._torque is ComputedTorqueController._torque \
                and (self._qp is None or self._qp.compiled):
            self._kernel = self._kernel_arguments()

    def _kernel_arguments(self) -> tuple:
        """The compiled step's constant arguments (:func:`~regrasp.kernels.control.control_step_into`)."""
        model, hand, m = self.model, self.model.hand, self.model.grasp.m
        fingers, iks, edges, columns = model.kernel_constants
        if self._qp is not None:
            rows = self._qp.rows_arrays(m, self._modes, self.friction, self._cone_edges or None)
        else:
            rows = (np.zeros((0, 2 * m)), np.zeros(0), 0, np.zeros(0, np.bool_), 0.0, np.zeros(0), 1.0, 0.0)
        head = (fingers, iks, edges, hand.gravity_in_hand, hand.damping_enabled, model.xi, columns)
        tail = (self.gains.kv, self.gains.ks, np.array(model.m_s_diagonal), float(model.object_mass),
                np.zeros(model.grasp.p), float(hand.singular_threshold), np.array(self._margin_mu, dtype=float),
                self._qp is not None, *rows)
        layout = control_layout(m, model.n)
        return head, tail, layout, layout["f_hat"].stop

    @property
    def compiled_arguments(self) -> tuple | None:
        """The compiled step's constant arguments (``(head, tail, layout, size)`` for
        :func:`~regrasp.kernels.control.control_step_into`; Proposition 3 with m > 2: ``(head, sliding_tail, rest,
        layout, size)`` for :func:`~regrasp.kernels.control.sliding_step_into`), or None: the reference path runs."""
        return self._kernel

    def friction_estimate(self, st: ReducedState, command: np.ndarray,
                          tangential_force: ArrayLike | None) -> np.ndarray:
        """f̂_ξ (p,) [N]; the laws override this."""
        return np.zeros(self.model.grasp.p)

    def __call__(self, S: ArrayLike, S_dot: ArrayLike, S_d: ArrayLike, S_d_dot: ArrayLike, S_d_ddot: ArrayLike, *,
                 tangential_force: ArrayLike | None = None) -> ControlOutput:
        """Torques for the measured (S, Ṡ) and the desired (S_d, Ṡ_d, S̈_d).

        ``tangential_force``: the measured friction force at the sliding contacts (p,) [N], for
        Proposition 2 (not the coefficients: those are the constructor's ``friction``).
        """
        start = time.perf_counter()
        model = self.model
        args = as_finite_vectors(_ARGUMENTS, (S, S_dot, S_d, S_d_dot, S_d_ddot), model.n)
        if self._kernel is not None:
            output = self._call_compiled(args, start)
            if output is not None:
                return output
        s, s_dot, s_d, s_d_dot, s_d_ddot = args.tolist()
        terms = model._terms(s, s_dot)
        # the law in plain floats (numpy's per-call cost would dominate on these (2m, 3 + p) arrays)
        error = [a - b for a, b in zip(s_d, s)]
        error_rate = [a - b for a, b in zip(s_d_dot, s_dot)]
        command = [a + kv * r + ks * e
                   for a, kv, r, ks, e in zip(s_d_ddot, self.gains.kv.tolist(), error_rate, self.gains.ks.tolist(), error)]
        command_array = np.array(command)
        tau, f_hat, forces, force_list, internal = self._torque(terms, args, command_array, tangential_force)
        # (n_i^T f_i, t_i^T f_i) per contact, and the cone margins μ f_n - |f_t| (μ of the contact's mode)
        surface = [(nx * force_list[2 * i] + ny * force_list[2 * i + 1], tx * force_list[2 * i] + ty * force_list[2 * i + 1])
                   for i, (nx, ny, tx, ty) in enumerate(terms.frames)]
        margins = [cone_margin(mu, f_n, f_t) for mu, (f_n, f_t) in zip(self._margin_mu, surface)]
        return ControlOutput(np.array(tau), command_array, np.array(error), np.array(error_rate), f_hat, forces,
                             np.array(surface), np.array(margins), internal, time.perf_counter() - start)

    def _call_compiled(self, args: np.ndarray, start: float) -> ControlOutput | None:
        """The compiled step (:mod:`regrasp.kernels.control`), or None where the reference path must answer."""
        head, tail, layout, size = self._kernel
        out = np.empty(size)
        status, k, margin = control_step_into(*head, args[0], args[1], args[2], args[3], args[4], *tail, out)
        if status != CONTROL_OK:
            return None
        return self._output(out, layout, k, margin, tail[4].copy(), start)

    def _output(self, out: np.ndarray, layout: dict, k: int, margin: float, f_hat: np.ndarray,
                start: float) -> ControlOutput:
        """The :class:`ControlOutput` of a compiled step's ``out`` (views into it)."""
        m = self.model.grasp.m
        forces = out[layout["forces"]].reshape(m, 2)
        internal = None
        if self._qp is not None:
            internal = InternalForceResult(out[layout["f_c"]], forces, k, True, "solved" if k else "empty null space",
                                           time.perf_counter() - start, margin)
        return ControlOutput(out[layout["tau"]], out[layout["command"]], out[layout["error"]],
                             out[layout["error_rate"]], f_hat, forces, out[layout["surface"]].reshape(m, 2),
                             out[layout["margins"]], internal, time.perf_counter() - start)

    def _torque(self, terms, args: np.ndarray, command_array: np.ndarray, tangential_force):
        """(τ (list), f̂_ξ, predicted contact forces (m, 2), the same as a flat list, internal-force
        result) for the commanded S̈ (``args``: the validated (S, Ṡ, ...) rows)."""
        model = self.model
        if self._estimates_friction:
            st = model._state_from(args[0], args[1], terms)
            f_hat = self.friction_estimate(st, command_array, tangential_force)
        else:
            f_hat = np.zeros(model.grasp.p)
        tau, wrench = _computed_torque(model, terms, command_array, np.asarray(f_hat, dtype=float).tolist())
        # f = J^{-T}(τ - M q̈ - N)
        motion_forces = []
        for i, (i00, i01, i10, i11) in enumerate(terms.inverses):
            d0, d1 = tau[2 * i] - wrench[2 * i], tau[2 * i + 1] - wrench[2 * i + 1]
            motion_forces += (i00 * d0 + i10 * d1, i01 * d0 + i11 * d1)
        internal = None
        if self._qp is not None:
            internal = self._qp._solve(np.array(terms.a_rows), motion_forces, terms.frames, self._modes, self.friction,
                                      self._cone_edges, time.perf_counter())
            f_c = internal.f_c.tolist()
            for i, (a, b, c, d) in enumerate(terms.jacobians):  # τ + J^T f_c
                f0, f1 = f_c[2 * i], f_c[2 * i + 1]
                tau[2 * i] += a * f0 + c * f1
                tau[2 * i + 1] += b * f0 + d * f1
            forces = internal.forces
            force_list = forces.reshape(-1).tolist()
        else:
            forces = np.array(motion_forces).reshape(model.grasp.m, 2)
            force_list = motion_forces
        return tau, f_hat, forces, force_list, internal


_ARGUMENTS = ("S", "S_dot", "S_d", "S_d_dot", "S_d_ddot")


def _computed_torque(model: ReducedModel, terms, command: np.ndarray, f_hat: list) -> tuple[list, list]:
    r"""The motion torque :math:`\tau = (H^T)^+ [(H^T M H + M_s) a + N_s - [f_g; -\hat f_\xi]]` and the
    wrench :math:`M \ddot q + N` (lists, q̈ = H a + Ḣ Ṡ), from the model's :class:`~regrasp.dynamics.reduced._Terms`:
    :math:`(H^T M H + M_s) a + N_s = H^T (M \ddot q + N) + M_s a` and :math:`(H^T)^+ = H (H^T H)^{-1}`.
    (ndarray.dot for the products with H: matmul's ufunc machinery costs ~1 us per call here.)"""
    H, h_dot_s_dot, nonlinear = terms.H, terms.h_dot_s_dot, terms.nonlinear
    q_ddot = H.dot(command).tolist()
    wrench = []
    for i, (m00, m01, m11) in enumerate(terms.masses):  # M is block diagonal
        r = 2 * i
        a0, a1 = q_ddot[r] + h_dot_s_dot[r], q_ddot[r + 1] + h_dot_s_dot[r + 1]
        wrench += (m00 * a0 + m01 * a1 + nonlinear[r], m01 * a0 + m11 * a1 + nonlinear[r + 1])
    H_t = H.T
    gx, gy = model.hand.gravity_in_hand.tolist()  # -[f_g; -f̂_ξ], f_g = m_o g
    mass = model.object_mass
    rhs = [h + ms * a + e for h, ms, a, e in zip(H_t.dot(wrench).tolist(), model._m_s_diagonal, command.tolist(),
                                                 (-mass * gx, -mass * gy, 0.0, *f_hat))]
    normal = H_t.dot(H)
    if len(rhs) <= 3:  # Cramer's rule in floats
        return H.dot(solve_small(normal.tolist(), rhs)).tolist(), wrench
    _, _, x, info = lapack.dgesv(normal, rhs)  # (np.linalg.solve's LAPACK routine without its overhead)
    if info != 0:
        raise SingularModelError("the control law's force equations are singular (a singular grasp or finger)")
    return H.dot(x).tolist(), wrench


class FixedContactController(ComputedTorqueController):
    """All contacts fixed (p = 0): the coordinated computed-torque law of the paper's reference [5]."""

    law = "fixed contacts"

    def __init__(self, model: ReducedModel, gains: Gains, friction: FrictionLike = DEFAULT_FRICTION, **kwargs: Any):
        if expect_type("model", model, ReducedModel, "a ReducedModel").grasp.p != 0:
            raise InvalidParameterError("model", model.grasp.modes, "only fixed contacts (p = 0)")
        super().__init__(model, gains, friction, **kwargs)


class Proposition1Controller(ComputedTorqueController):
    """Proposition 1 (3.3.1, corrected): friction at the sliding contacts assumed zero."""

    law = "Proposition 1"


class Proposition2Controller(ComputedTorqueController):
    """Proposition 2 (3.3.8, corrected): the measured friction force is fed forward."""

    law = "Proposition 2"

    def friction_estimate(self, st: ReducedState, command: np.ndarray,
                          tangential_force: ArrayLike | None) -> np.ndarray:
        if tangential_force is None:
            raise InvalidParameterError("tangential_force", None, "the measured friction force at each sliding contact")
        return as_finite_array("tangential_force", tangential_force, (self.model.grasp.p,))


class Proposition3Controller(ComputedTorqueController):
    r"""Proposition 3 (3.4.11, corrected), and its generalisation to m >= 2 fingers and p >= 1 sliders.

    The friction at the sliding contacts is not measured but predicted from the commanded motion.
    The contact forces f that move the object as commanded with every slider j on the edge of its
    kinetic friction cone in its sliding direction :math:`s_j` solve the 3 + p equations

    .. math:: G f = M_o a_X - f_g, \qquad (t_j - s_j \mu_{k,j} n_j)^T f_j = 0\ \ (j \text{ sliding})

    in 2m unknowns (2m >= 3 + p, Remark 3.2).

    * m = 2, p = 1: four equations in four unknowns; f is unique and
      :math:`\hat f_\xi = t_j^T f_j = P (M_o a_X - f_g)` with the paper's P (3.4.9).
    * otherwise f has 2m - 3 - p degrees of freedom. The internal-force QP (:mod:`regrasp.dynamics.internal_force.solver`)
      picks f, :math:`f = f_p + N_c y` with :math:`f_p` the least-norm solution and :math:`N_c` a basis
      of the null space of the same equations (columns 3 .. 3 + p of its matrix: one edge column per
      slider), so that every contact pushes and every fixed contact stays in its static cone while the
      sliders stay on their cone edges (2m = 3 + p: f is unique, and only checked); then
      :math:`\hat f_\xi = (t_j^T f_j)_j` and :math:`\tau = M(H a + \dot H \dot S) + N + J^T f`. Because
      :math:`H^T J^T = A^T`, this τ satisfies the reduced equation with that :math:`\hat f_\xi`,
      so the error obeys the same ODE. Unlike Proposition 2 with a slider held on its cone edge,
      which pins the slider's normal force to the measured friction over μ, the sliders' normal
      forces are chosen together with the other contacts' (``docs/derivations.md``, §4). The
      ``internal`` result's ``f_c`` is then relative to :math:`f_p`.

    The sliding direction :math:`s_j` of each slider: the direction the contact will slide in during
    the next sample, the sign of its measured ξ̇, unless ξ̇ crosses zero within ``sample_time`` under the
    commanded ξ̈ (a reversal), in which case the sign of the commanded ξ̈. Using the desired ξ̇ instead
    would predict the wrong friction for a step or two at every reversal, and the contact would stick
    there. ``direction`` sets the :math:`s_j` until the first such decision: ±1 for every slider
    (+1 by default) or one sign per slider. With ``reversible=False`` the :math:`s_j` stay as given: a
    planned slide from rest to rest in one direction decelerates to a stop without reversing, and a
    predicted reversal there would put the slider's friction on the wrong cone edge.
    """

    law = "Proposition 3"

    def __init__(self, model: ReducedModel, gains: Gains, friction: FrictionLike = DEFAULT_FRICTION, *, sample_time: float = 1e-3,
                 direction: float | Sequence[float] = 1.0, reversible: bool = True, compiled: bool | None = None,
                 **kwargs: Any):
        m, p = model.grasp.m, model.grasp.p
        if m < 2 or p < 1 or 2 * m < 3 + p:
            raise InvalidParameterError("model", model.grasp.modes,
                                        "m >= 2 fingers with p >= 1 sliding contacts (p = 1 for m = 2), 2m >= 3 + p")
        super().__init__(model, gains, friction, compiled=compiled, **kwargs)
        if not np.isfinite(sample_time) or sample_time <= 0:
            raise InvalidParameterError("sample_time", sample_time, "a control period > 0 [s]")
        directions = [direction] * p if np.ndim(direction) == 0 else list(direction)
        if len(directions) != p or not all(d in (-1, 1, -1.0, 1.0) for d in directions):
            raise InvalidParameterError("direction", direction, f"+1 or -1, or one of them per slider ({p})")
        if self._cone_edges and (m == 2 or any(e.contact in model.grasp.sliding for e in self._cone_edges)):
            raise InvalidParameterError("cone_edge", self.cone_edge, "cone edges only on fixed contacts, with m > 2 "
                                        "(the sliding contacts are on their kinetic edges already)")
        if not isinstance(reversible, bool):
            raise InvalidParameterError("reversible", reversible, "True or False")
        self.sample_time = float(sample_time)
        self.reversible = reversible
        self._directions = [float(d) for d in directions]
        self._sliders = model.grasp.sliding
        if compiled is not False and model.compiled and m > 2 and (self._qp is None or self._qp.compiled):
            head, tail, layout, size = self._kernel_arguments()
            kinetic = np.array([self.friction[j].kinetic for j in self._sliders], dtype=float)
            sliding_tail = (tail[0], tail[1], np.diag(model.M_o).copy(), tail[3], np.array(self._sliders, np.int64),
                            kinetic)
            self._kernel = (head, sliding_tail, tail[5:], layout, size)

    @property
    def directions(self) -> tuple[float, ...]:
        """The sliders' current sliding directions s_j = ±1 (in the grasp's order of sliding contacts)."""
        return tuple(self._directions)

    @directions.setter
    def directions(self, values: Sequence[float]) -> None:
        values = [float(v) for v in values]
        if len(values) != len(self._directions) or any(v not in (-1.0, 1.0) for v in values):
            raise InvalidParameterError("directions", values, f"one sign (+1 or -1) per slider ({len(self._directions)})")
        self._directions = values

    @property
    def _direction(self) -> float:
        """The first slider's direction (p = 1)."""
        return self._directions[0]

    def sliding_direction(self, xi_dot: float, xi_ddot_command: float) -> float:
        """±1: the sign of ξ̇ over the next sample (see the class docstring); p = 1 only."""
        if len(self._directions) != 1:
            raise InvalidParameterError("xi_dot", xi_dot, f"one rate per slider ({len(self._directions)}): "
                                        "use sliding_directions")
        return self.sliding_directions((xi_dot,), (xi_ddot_command,))[0]

    def sliding_directions(self, xi_dots: Sequence[float], xi_ddot_commands: Sequence[float]) -> tuple[float, ...]:
        """±1 per slider: the sign of its ξ̇ over the next sample (see the class docstring), from the
        measured ξ̇ [m/s] and the commanded ξ̈ [m/s²] of each slider."""
        if len(xi_dots) != len(self._directions) or len(xi_ddot_commands) != len(self._directions):
            raise InvalidParameterError("xi_dots", xi_dots, f"one rate per slider ({len(self._directions)})")
        if not self.reversible:
            return tuple(self._directions)
        for j, (xi_dot, xi_ddot_command) in enumerate(zip(xi_dots, xi_ddot_commands)):
            after = xi_dot + xi_ddot_command * self.sample_time
            if xi_dot * after <= 0.0 and xi_ddot_command != 0.0:
                self._directions[j] = float(np.sign(xi_ddot_command))
            elif xi_dot != 0.0:
                self._directions[j] = float(np.sign(xi_dot))
        return tuple(self._directions)

    def _call_compiled(self, args: np.ndarray, start: float) -> ControlOutput | None:
        """The compiled step (:func:`~regrasp.kernels.control.sliding_step_into`), or None where the reference
        path must answer (it then decides the directions afresh, from the same ones)."""
        head, sliding_tail, rest, layout, size = self._kernel
        out = np.empty(size)
        directions = np.array(self._directions)
        status, k, margin = sliding_step_into(*head, args[0], args[1], args[2], args[3], args[4], *sliding_tail,
                                              directions, self.reversible, self.sample_time, *rest, out)
        if status != CONTROL_OK:
            return None
        self._directions = directions.tolist()
        return self._output(out, layout, k, margin, out[layout["f_hat"]], start)

    def friction_estimate(self, st: ReducedState, command: np.ndarray,
                          tangential_force: ArrayLike | None) -> np.ndarray:
        """m = 2: :math:`P (M_o a_X - f_g)` (3.4.9, the slider's μ_k); otherwise see :meth:`_torque`."""
        direction = self.sliding_direction(float(st.S_dot[3]), float(command[3]))
        P = self.model.grasp.friction_map(st.S[:3], st.xi, [direction], self.friction)
        return P @ (self.model.M_o @ command[:3] - self.model.f_g)

    def _torque(self, terms, args, command_array, tangential_force):
        if self.model.grasp.m == 2:
            return super()._torque(terms, args, command_array, tangential_force)
        directions = self.sliding_directions(args[1][3:].tolist(), command_array[3:].tolist())
        st = self.model._state_from(args[0], args[1], terms)
        tau, f_hat, forces, internal = self._distributed_torque(st, terms, command_array, directions)
        return tau.tolist(), f_hat, forces, forces.reshape(-1).tolist(), internal

    def _distributed_torque(self, st, terms, command, directions):
        """The law of the class docstring for m > 2 (valid for m = 2 too: then f is unique);
        ``directions``: one sign per slider (a number for p = 1)."""
        model = self.model
        if np.ndim(directions) == 0:
            directions = (directions,)
        edge = np.array(terms.a_rows)  # [G^T | e_j (t_j - s_j μ_k,j n_j)]: its columns' transposes are the equations
        edge[:, 3:] = 0.0
        for col, (j, direction) in enumerate(zip(self._sliders, directions), start=3):
            nx, ny, tx, ty = terms.frames[j]
            kinetic = self.friction[j].kinetic
            edge[2 * j:2 * j + 2, col] = (tx - direction * kinetic * nx, ty - direction * kinetic * ny)
        rhs = np.concatenate([model.M_o.dot(command[:3]) - model.f_g, np.zeros(len(self._sliders))])
        _, _, x, info = lapack.dgesv(edge.T.dot(edge), rhs)
        if info != 0:
            raise SingularModelError("the control law's force equations are singular (a singular grasp or finger)")
        particular = edge.dot(x)  # least-norm f_p
        internal = None
        if self._qp is not None:
            internal = self._qp._solve(edge, particular.tolist(), terms.frames, self._modes, self.friction,
                                      self._cone_edges or None, time.perf_counter())
            forces = internal.forces
        else:
            forces = particular.reshape(model.grasp.m, 2)
        q_ddot = st.H.dot(command) + st.H_dot_S_dot
        tau = st.hand.mass_matrix.dot(q_ddot) + st.hand.nonlinear + st.hand.jacobian.T.dot(forces.reshape(-1))
        f_hat = np.array([terms.frames[j][2] * forces[j, 0] + terms.frames[j][3] * forces[j, 1]
                          for j in self._sliders])
        return tau, f_hat, forces, internal

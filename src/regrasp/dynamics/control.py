r"""Computed-torque control of the object and of sliding contacts (paper §3.3–3.4), corrected: the law all the
controllers share.

All laws are computed torque on the reduced dynamics derived in ``docs/derivations.md``,

.. math:: (H^T M H + M_s)\,\ddot S + N_s = H^T \tau + [f_g;\ -f_\xi].

With :math:`a = \ddot S_d + K_v \dot E + K_s E` (:math:`E = S_d - S`) and an estimate
:math:`\hat f_\xi` of the friction at the sliding contacts,

.. math:: \tau = (H^T)^+ \big[(H^T M H + M_s)\,a + N_s - [f_g;\ -\hat f_\xi]\big] + J^T f_c,
          \qquad (H^T)^+ = H (H^T H)^{-1},

which gives :math:`(H^T M H + M_s)(\ddot S - a) = [0;\ \hat f_\xi - f_\xi]`, so
:math:`\ddot E + K_v \dot E + K_s E = 0` whenever :math:`\hat f_\xi = f_\xi`. Written out,
:math:`(H^T)^+ (H^T M H + M_s) a + (H^T)^+ N_s = [M H + (H^T)^+ M_s] a + M \dot H \dot S + N` plus a
null-space term, which is the paper's form. The laws (:mod:`regrasp.dynamics.laws`) differ only in
:math:`\hat f_\xi`:

* :class:`~regrasp.dynamics.laws.FixedContactController`: p = 0 (the paper's reference [5]); no sliding contact.
* :class:`~regrasp.dynamics.laws.Proposition1Controller`: :math:`\hat f_\xi = 0` (3.3.1).
* :class:`~regrasp.dynamics.laws.Proposition2Controller`: :math:`\hat f_\xi` measured (3.3.8).
* :class:`~regrasp.dynamics.laws.Proposition3Controller`: :math:`\hat f_\xi` predicted from the commanded motion
  with every slider on its kinetic cone edge; for m = 2, p = 1 the paper's :math:`P (M_o a_X - f_g)` (3.4.9,
  3.4.11), with P for the commanded sliding direction; any p >= 1 with 2m >= 3 + p otherwise.

Two corrections to the printed laws (``docs/derivations.md``): the gravity term enters as
:math:`-(H^T)^+[f_g; 0]`, where (3.3.1) and (3.3.8) print :math:`+`; and (3.3.8)/(3.4.11) drop
the :math:`G R_f B_v f_\xi` terms, which count the friction twice.

The internal force :math:`J^T f_c` (3.3.7) is chosen by :mod:`regrasp.dynamics.internal_force.problem`'s QP: the
least squeeze that keeps every contact pushing and every fixed contact inside its static friction
cone (:math:`\mu_s`) with margins, and every joint within its torque limit
(:attr:`~regrasp.model.hand.Hand.effort_limit`, :mod:`regrasp.dynamics.internal_force.torque`), given the contact
forces :math:`f_m` the motion torque produces.
Each controller keeps a persistent solver (:class:`~regrasp.dynamics.internal_force.solver.InternalForceSolver`).

Friction (:class:`~regrasp.core.contact.Friction`): a controller's ``friction`` is what it assumes of the
fingertips; a sliding contact carries the kinetic coefficient :math:`\mu_k` (Proposition 3 puts it
on its kinetic cone edge), a fixed one is kept inside its static cone. The reported cone margins use
the coefficient of each contact's mode.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import lapack

from ..core.contact import DEFAULT_FRICTION, FrictionLike, as_frictions, coefficients, cone_margin
from ..core.exceptions import InvalidParameterError, SingularModelError
from ..core.scalar import solve_small
from ..core.validation import as_finite_array, as_finite_vectors, as_integer, as_positive_float, expect_type
from ..kernels.control import CONTROL_OK, control_layout, control_step_into
from .internal_force.problem import InternalForceResult
from .internal_force.settings import ConeEdge, InternalForceSettings, as_cone_edges
from .internal_force.solver import InternalForceSolver
from .internal_force.torque import JointTorques
from .reduced import ReducedModel, ReducedState, ReducedTerms

__all__ = ["ComputedTorqueController", "ControlOutput", "Gains"]


@dataclass(frozen=True)
class Gains:
    """Diagonal gains per reduced coordinate: K_v [1/s] and K_s [1/s^2], each shape (3 + p,)."""

    kv: np.ndarray
    ks: np.ndarray

    def __post_init__(self) -> None:
        kv = as_finite_array("kv", self.kv, (-1,))
        ks = as_finite_array("ks", self.ks, (-1,))
        if len(kv) != len(ks) or len(kv) < 3:
            raise InvalidParameterError("ks", self.ks,
                                        f"one gain per reduced coordinate, as many as kv ({len(kv)} >= 3)")
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
            :class:`~regrasp.dynamics.internal_force.settings.ConeEdge` carries (the transition before a slide); or a
            tuple of them, on distinct contacts (several transitions at once). Kept as given in ``cone_edge``, and
            validated as a tuple in ``cone_edges``.
        compiled: Take the compiled step (:mod:`regrasp.kernels.control`) where it applies: a compiled model, a
            law whose friction estimate needs no state (the fixed-contact law, Proposition 1) and the QP's
            compiled solver (:meth:`compiled_step_arguments`); anything else it does not settle goes the reference
            path. None: where it applies.

    The laws (:mod:`regrasp.dynamics.laws`) are subclasses: they override :meth:`friction_estimate`, and where
    their torque is not this one's, :meth:`law_torque`, :meth:`compiled_step_arguments` and :meth:`compiled_step`.
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
        #: ``cone_edge`` as the QP gets it: a tuple of ConeEdge on distinct contacts, validated (empty: none).
        self.cone_edges: tuple[ConeEdge, ...] = as_cone_edges(cone_edge, model.grasp.m)
        #: The internal-force QP's persistent solver, or None when ``internal_force`` is None.
        self.internal_force_solver: InternalForceSolver | None = (
            InternalForceSolver(internal_force) if internal_force is not None else None)
        self._modes = model.grasp.modes
        # the cone margins' coefficients: μ_s where fixed, μ_k where sliding
        self._margin_mu = coefficients(self.friction, self._modes)
        # whether the law's f̂_ξ needs the ReducedState (the base law's is zero)
        self._estimates_friction = type(self).friction_estimate is not ComputedTorqueController.friction_estimate
        effort = model.hand.effort_limit.tolist()
        #: The joints' torque limits [N m] the internal-force QP keeps (2m; inf: none), or None where no joint has
        #: one: the hand's :attr:`~regrasp.model.hand.Hand.effort_limit`.
        self.effort_limit: list[float] | None = effort if any(map(math.isfinite, effort)) else None
        self._finger_names = tuple(f.name for f in model.hand.fingers)
        self._kernel = None if compiled is False else self.compiled_step_arguments()

    def compiled_step_arguments(self) -> tuple | None:
        """What :attr:`compiled_arguments` holds, decided by the constructor (unless its ``compiled`` is False) once
        every attribute above is set (before a subclass's own): :meth:`kernel_arguments` where the compiled step
        applies (a compiled model, a law whose f̂_ξ needs no state and which keeps :meth:`law_torque`, and no QP or
        its compiled solver), else None. A law with its own compiled step overrides it."""
        qp = self.internal_force_solver
        if self.model.compiled and not self._estimates_friction \
                and type(self).law_torque is ComputedTorqueController.law_torque \
                and (qp is None or qp.compiled):
            return self.kernel_arguments()
        return None

    def kernel_arguments(self) -> tuple:
        """The constant arguments of :func:`~regrasp.kernels.control.control_step_into` for this controller, as
        ``(head, tail, layout, size)``: the arguments before the five rows (S, Ṡ, S_d, Ṡ_d, S̈_d), those after
        them (but ``out``), the layout of ``out`` (:func:`~regrasp.kernels.control.control_layout`) and its size;
        the model must be compiled."""
        model, hand, m = self.model, self.model.hand, self.model.grasp.m
        fingers, iks, edges, columns = model.kernel_constants
        qp = self.internal_force_solver
        if qp is not None:
            rows = qp.rows_arrays(m, self._modes, self.friction, self.cone_edges or None)
        else:
            rows = (np.zeros((0, 2 * m)), np.zeros(0), 0, np.zeros(0, np.bool_), 0.0, np.zeros(0), 1.0, 0.0)
        head = (fingers, iks, edges, hand.gravity_in_hand, hand.damping_enabled, model.xi, columns)
        tail = (self.gains.kv, self.gains.ks, np.array(model.m_s_diagonal), float(model.object_mass),
                np.zeros(model.grasp.p), float(hand.singular_threshold), np.array(self._margin_mu, dtype=float),
                qp is not None, *rows)
        layout = control_layout(m, model.n)
        return head, tail, layout, layout["f_hat"].stop

    @property
    def compiled_arguments(self) -> tuple | None:
        """The compiled step's constant arguments (``(head, tail, layout, size)`` for
        :func:`~regrasp.kernels.control.control_step_into`; Proposition 3 with m > 2: ``(head, sliding_tail, rest,
        layout, size)`` for :func:`~regrasp.kernels.control.sliding_step_into`), or None: the reference path runs."""
        return self._kernel

    @property
    def compiled(self) -> bool:
        """Whether the compiled step answers (:attr:`compiled_arguments` is set), where it can (else the reference
        path)."""
        return self._kernel is not None

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
            output = self.compiled_step(args, start)
            if output is not None:
                return output
        s, s_dot, s_d, s_d_dot, s_d_ddot = args.tolist()
        terms = model.terms(s, s_dot)
        # the law in plain floats (numpy's per-call cost would dominate on these (2m, 3 + p) arrays)
        error = [a - b for a, b in zip(s_d, s)]
        error_rate = [a - b for a, b in zip(s_d_dot, s_dot)]
        command = [a + kv * r + ks * e
                   for a, kv, r, ks, e in zip(s_d_ddot, self.gains.kv.tolist(), error_rate, self.gains.ks.tolist(),
                                              error)]
        command_array = np.array(command)
        tau, f_hat, forces, force_list, internal = self.law_torque(terms, args, command_array, tangential_force)
        # (n_i^T f_i, t_i^T f_i) per contact, and the cone margins μ f_n - |f_t| (μ of the contact's mode)
        surface = [(nx * force_list[2 * i] + ny * force_list[2 * i + 1],
                    tx * force_list[2 * i] + ty * force_list[2 * i + 1])
                   for i, (nx, ny, tx, ty) in enumerate(terms.frames)]
        margins = [cone_margin(mu, f_n, f_t) for mu, (f_n, f_t) in zip(self._margin_mu, surface)]
        return ControlOutput(np.array(tau), command_array, np.array(error), np.array(error_rate), f_hat, forces,
                             np.array(surface), np.array(margins), internal, time.perf_counter() - start)

    def compiled_step(self, args: np.ndarray, start: float) -> ControlOutput | None:
        """The compiled step (:mod:`regrasp.kernels.control`; :attr:`compiled` must be True) at ``args``, the five
        validated rows (S, Ṡ, S_d, Ṡ_d, S̈_d) (5, n), its ``seconds`` counted from ``start``
        (``time.perf_counter()``); or None where the reference path must answer."""
        head, tail, layout, size = self._kernel
        out = np.empty(size)
        status, k, margin = control_step_into(*head, args[0], args[1], args[2], args[3], args[4], *tail, out)
        if status != CONTROL_OK:
            return None
        return self.compiled_output(out, layout, k, margin, tail[4].copy(), start)

    def compiled_output(self, out: np.ndarray, layout: dict[str, slice], k: int, margin: float, f_hat: np.ndarray,
                        start: float) -> ControlOutput:
        """The :class:`ControlOutput` (views into ``out``) of a compiled step's ``out`` laid out as ``layout``
        (:func:`~regrasp.kernels.control.control_layout`), with the QP's null-space dimension ``k``, its cone margin
        [N], the friction estimate f̂_ξ [N] and the step's start (``time.perf_counter()``)."""
        m = self.model.grasp.m
        forces = out[layout["forces"]].reshape(m, 2)
        internal = None
        if self.internal_force_solver is not None:
            internal = InternalForceResult(out[layout["f_c"]], forces, k, True, "solved" if k else "empty null space",
                                           time.perf_counter() - start, margin)
        return ControlOutput(out[layout["tau"]], out[layout["command"]], out[layout["error"]],
                             out[layout["error_rate"]], f_hat, forces, out[layout["surface"]].reshape(m, 2),
                             out[layout["margins"]], internal, time.perf_counter() - start)

    def joint_torques(self, terms: ReducedTerms, wrench: list[float]) -> JointTorques | None:
        """The QP's joint torque limits at ``terms`` (τ = ``wrench`` + Jᵀ f, ``wrench`` = M q̈ + N [N m]), or None
        where no joint has one (:mod:`regrasp.dynamics.internal_force.torque`)."""
        if self.effort_limit is None:
            return None
        return JointTorques(terms.jacobians, wrench, self.effort_limit, self._finger_names)

    def law_torque(self, terms: ReducedTerms, args: np.ndarray, command_array: np.ndarray,
                   tangential_force: ArrayLike | None) -> tuple[list[float], np.ndarray, np.ndarray, list[float],
                                                                 InternalForceResult | None]:
        """The reference path's law: (τ [N m] (a list), f̂_ξ [N], the predicted contact forces (m, 2) [N] (hand frame),
        the same as a flat list, the internal-force result) for the commanded S̈ ``command_array`` at the model's
        ``terms`` (``args``: the validated rows (S, Ṡ, S_d, Ṡ_d, S̈_d); ``tangential_force`` as :meth:`__call__`
        takes it)."""
        model = self.model
        if self._estimates_friction:
            st = model.state_from_terms(args[0], args[1], terms)
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
        if self.internal_force_solver is not None:
            internal = self.internal_force_solver.solve_floats(np.array(terms.a_rows), motion_forces, terms.frames,
                                                               self._modes, self.friction, self.cone_edges,
                                                               time.perf_counter(), self.joint_torques(terms, wrench))
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


def _computed_torque(model: ReducedModel, terms: ReducedTerms, command: np.ndarray, f_hat: list) -> tuple[list, list]:
    r"""The motion torque :math:`\tau = (H^T)^+ [(H^T M H + M_s) a + N_s - [f_g; -\hat f_\xi]]` and the
    wrench :math:`M \ddot q + N` (lists, q̈ = H a + Ḣ Ṡ), from the model's
    :class:`~regrasp.dynamics.reduced.ReducedTerms`:
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
    rhs = [h + ms * a + e for h, ms, a, e in zip(H_t.dot(wrench).tolist(), model.m_s_diagonal, command.tolist(),
                                                 (-mass * gx, -mass * gy, 0.0, *f_hat))]
    normal = H_t.dot(H)
    if len(rhs) <= 3:  # Cramer's rule in floats
        return H.dot(solve_small(normal.tolist(), rhs)).tolist(), wrench
    _, _, x, info = lapack.dgesv(normal, rhs)  # (np.linalg.solve's LAPACK routine without its overhead)
    if info != 0:
        raise SingularModelError("the control law's force equations are singular (a singular grasp or finger)")
    return H.dot(x).tolist(), wrench

r"""The control laws (paper §3.3–3.4, corrected), each the computed torque of
:class:`~regrasp.dynamics.control.ComputedTorqueController` with its own estimate :math:`\hat f_\xi` of the friction
at the sliding contacts (:mod:`regrasp.dynamics.control` derives the law and lists the corrections):

* :class:`FixedContactController`: p = 0 (the paper's reference [5]); no sliding contact.
* :class:`Proposition1Controller`: :math:`\hat f_\xi = 0` (3.3.1).
* :class:`Proposition2Controller`: :math:`\hat f_\xi` measured (3.3.8).
* :class:`Proposition3Controller`: :math:`\hat f_\xi` predicted from the commanded motion with every slider on its
  kinetic cone edge (3.4.9, 3.4.11), and its generalisation to m >= 2 fingers and p >= 1 sliders.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import lapack

from ..core.contact import DEFAULT_FRICTION, FrictionLike
from ..core.exceptions import InvalidParameterError, SingularModelError
from ..core.validation import as_finite_array, as_positive_float, expect_type
from ..kernels.control import CONTROL_OK, sliding_step_into
from .control import ComputedTorqueController, ControlOutput, Gains
from .internal_force.problem import InternalForceResult
from .reduced import ReducedModel, ReducedState, ReducedTerms

__all__ = ["FixedContactController", "Proposition1Controller", "Proposition2Controller", "Proposition3Controller"]



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
    * otherwise f has 2m - 3 - p degrees of freedom. The internal-force QP
      (:mod:`regrasp.dynamics.internal_force.problem`) picks f, :math:`f = f_p + N_c y` with :math:`f_p` the
      least-norm solution and :math:`N_c` a basis of the null space of the same equations (columns 3 .. 3 + p
      of its matrix: one edge column per slider), so that every contact pushes and every fixed contact stays in
      its static cone while the sliders stay on their cone edges (2m = 3 + p: f is unique, and only checked); then
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

    def __init__(self, model: ReducedModel, gains: Gains, friction: FrictionLike = DEFAULT_FRICTION, *,
                 sample_time: float = 1e-3, direction: float | Sequence[float] = 1.0, reversible: bool = True,
                 compiled: bool | None = None, **kwargs: Any):
        m, p = model.grasp.m, model.grasp.p
        if m < 2 or p < 1 or 2 * m < 3 + p:
            raise InvalidParameterError("model", model.grasp.modes,
                                        "m >= 2 fingers with p >= 1 sliding contacts (p = 1 for m = 2), 2m >= 3 + p")
        super().__init__(model, gains, friction, compiled=compiled, **kwargs)
        sample_time = as_positive_float("sample_time", sample_time)  # (a control period [s])
        directions = [direction] * p if np.ndim(direction) == 0 else list(direction)
        if len(directions) != p or not all(d in (-1, 1, -1.0, 1.0) for d in directions):
            raise InvalidParameterError("direction", direction, f"+1 or -1, or one of them per slider ({p})")
        if self.cone_edges and (m == 2 or any(e.contact in model.grasp.sliding for e in self.cone_edges)):
            raise InvalidParameterError("cone_edge", self.cone_edge, "cone edges only on fixed contacts, with m > 2 "
                                        "(the sliding contacts are on their kinetic edges already)")
        if not isinstance(reversible, bool):
            raise InvalidParameterError("reversible", reversible, "True or False")
        self.sample_time = sample_time
        self.reversible = reversible
        self._directions = [float(d) for d in directions]
        self._sliders = model.grasp.sliding

    def compiled_step_arguments(self) -> tuple | None:
        """The compiled sliding step's constant arguments, ``(head, sliding_tail, rest, layout, size)`` for
        :func:`~regrasp.kernels.control.sliding_step_into` (the arguments before the five rows, those between
        them and the directions, those after ``sample_time`` but ``out``, the layout of ``out`` and its size), where
        it applies: a compiled model, m > 2, and no QP or its compiled solver; else None (the reference path)."""
        model, qp = self.model, self.internal_force_solver
        if model.compiled and model.grasp.m > 2 and (qp is None or qp.compiled):
            sliders = model.grasp.sliding
            head, tail, layout, size = self.kernel_arguments()
            kinetic = np.array([self.friction[j].kinetic for j in sliders], dtype=float)
            sliding_tail = (tail[0], tail[1], np.diag(model.M_o).copy(), tail[3], np.array(sliders, np.int64),
                            kinetic)
            return (head, sliding_tail, tail[5:], layout, size)
        return None

    @property
    def directions(self) -> tuple[float, ...]:
        """The sliders' current sliding directions s_j = ±1 (in the grasp's order of sliding contacts)."""
        return tuple(self._directions)

    @directions.setter
    def directions(self, values: Sequence[float]) -> None:
        values = [float(v) for v in values]
        if len(values) != len(self._directions) or any(v not in (-1.0, 1.0) for v in values):
            raise InvalidParameterError("directions", values,
                                        f"one sign (+1 or -1) per slider ({len(self._directions)})")
        self._directions = values

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

    def compiled_step(self, args: np.ndarray, start: float) -> ControlOutput | None:
        """The compiled step (:func:`~regrasp.kernels.control.sliding_step_into`; ``args`` and ``start`` as the base
        class's), or None where the reference path must answer (it then decides the directions afresh, from the
        same ones)."""
        head, sliding_tail, rest, layout, size = self.compiled_arguments
        out = np.empty(size)
        directions = np.array(self._directions)
        status, k, margin = sliding_step_into(*head, args[0], args[1], args[2], args[3], args[4], *sliding_tail,
                                              directions, self.reversible, self.sample_time, *rest, out)
        if status != CONTROL_OK:
            return None
        self._directions = directions.tolist()
        return self.compiled_output(out, layout, k, margin, out[layout["f_hat"]], start)

    def friction_estimate(self, st: ReducedState, command: np.ndarray,
                          tangential_force: ArrayLike | None) -> np.ndarray:
        """m = 2: :math:`P (M_o a_X - f_g)` (3.4.9, the slider's μ_k); otherwise see :meth:`law_torque`."""
        direction = self.sliding_direction(float(st.S_dot[3]), float(command[3]))
        P = self.model.grasp.friction_map(st.S[:3], st.xi, [direction], self.friction)
        return P @ (self.model.M_o @ command[:3] - self.model.f_g)

    def law_torque(self, terms: ReducedTerms, args: np.ndarray, command_array: np.ndarray,
                   tangential_force: ArrayLike | None) -> tuple[list[float], np.ndarray, np.ndarray, list[float],
                                                                 InternalForceResult | None]:
        """The base class's law for m = 2; for m > 2 :meth:`distributed_torque` in the sliding directions of
        :meth:`sliding_directions` (the same outputs as the base class's)."""
        if self.model.grasp.m == 2:
            return super().law_torque(terms, args, command_array, tangential_force)
        directions = self.sliding_directions(args[1][3:].tolist(), command_array[3:].tolist())
        st = self.model.state_from_terms(args[0], args[1], terms)
        tau, f_hat, forces, internal = self.distributed_torque(st, terms, command_array, directions)
        return tau.tolist(), f_hat, forces, forces.reshape(-1).tolist(), internal

    def distributed_torque(self, st: ReducedState, terms: ReducedTerms, command: np.ndarray,
                           directions: float | Sequence[float]) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                                         InternalForceResult | None]:
        """The law of the class docstring for m > 2 (valid for m = 2 too: then f is unique) at the state ``st`` and
        its ``terms``, for the commanded S̈ ``command``: (τ [N m], f̂_ξ [N], the contact forces (m, 2) [N], hand frame,
        the internal-force result or None); ``directions``: one sign per slider (a number for p = 1)."""
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
        q_ddot = st.H.dot(command) + st.H_dot_S_dot
        wrench = st.hand.mass_matrix.dot(q_ddot) + st.hand.nonlinear  # τ = wrench + Jᵀ f
        internal = None
        if self.internal_force_solver is not None:
            internal = self.internal_force_solver.solve_floats(edge, particular.tolist(), terms.frames,
                                                               model.grasp.modes, self.friction,
                                                               self.cone_edges or None, time.perf_counter(),
                                                               self.joint_torques(terms, wrench.tolist()))
            forces = internal.forces
        else:
            forces = particular.reshape(model.grasp.m, 2)
        tau = wrench + st.hand.jacobian.T.dot(forces.reshape(-1))
        f_hat = np.array([terms.frames[j][2] * forces[j, 0] + terms.frames[j][3] * forces[j, 1]
                          for j in self._sliders])
        return tau, f_hat, forces, internal

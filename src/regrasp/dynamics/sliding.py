r"""When is a slide possible? (paper Remark 3.3)

A contact j can slide in direction :math:`s = \pm 1` only if the contact forces that produce the
desired object acceleration can have contact j on the edge of its kinetic friction cone in that
direction, :math:`t_j^T f_j = s\,\mu_{k,j}\, n_j^T f_j` (what a sliding contact carries), while
every contact still pushes (:math:`n_i^T f_i \ge f_{min}`) and every fixed contact stays inside its
static cone (:math:`\mu_{s,i}`). The forces must satisfy the object's equation
:math:`G f = M_o \ddot X - f_g`. The fingers can produce any tip force (J is invertible), so this is
a question about forces on the object alone:

.. math:: \exists f:\quad \begin{bmatrix} G \\ e_j^T (t_j - s\mu_{k,j} n_j) \end{bmatrix} f
          = \begin{bmatrix} M_o \ddot X - f_g \\ 0 \end{bmatrix},\quad
          n_i^T f_i \ge f_{min},\ |t_i^T f_i| \le (\mu_{s,i} - \text{margin})\, n_i^T f_i\ (i \ne j\ \text{fixed}).

``edge_mu`` replaces :math:`\mu_{k,j}` by another ratio: the supervisor asks with
:math:`\mu_{s,j}` + its priming overshoot where a slide starts, since the priming must break the
contact away past its static cone.

With m = 2 the system is square and f is unique (the paper's P of eq. 3.4.9); with more
fingers the least-squeeze f is found by the same QP as the internal force
(:mod:`regrasp.dynamics.internal_force.problem`). For the paper's Figure 3.4, a block held against gravity,
the predicate allows a slide in one direction and not in the other.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

import numpy as np
from numpy.typing import ArrayLike

from ..core.contact import ContactMode, FrictionLike, as_frictions, cone_margin
from ..core.exceptions import InvalidParameterError
from ..core.validation import as_finite_array, as_finite_float, as_inertia, as_integer, as_mass, as_sign, expect_type
from .grasp import Grasp
from .internal_force.problem import InternalForceInfeasibleError, build_internal_force_qp, solve_internal_force_qp
from .internal_force.settings import InternalForceSettings
from .internal_force.solver import InternalForceSolver

__all__ = ["SlideFeasibility", "SlideObstacle", "sliding_feasibility"]


class SlideObstacle(str, Enum):
    """What makes a slide impossible (:attr:`SlideFeasibility.obstacle`)."""

    SINGULAR = "singular"        #: no finite contact forces produce the motion with that slide
    NO_SQUEEZE = "no_squeeze"    #: the QP found no internal force
    PULL = "pull"                #: a contact would have to pull
    WEAK_PUSH = "weak_push"      #: a contact would push less than f_min
    TOO_STRONG = "too_strong"    #: a contact would push more than f_max
    FIXED_SLIP = "fixed_slip"    #: a fixed contact would leave its static cone


@dataclass(frozen=True)
class SlideFeasibility:
    """The verdict of :func:`sliding_feasibility`.

    Attributes:
        possible: Whether contact ``contact`` can slide in ``direction``.
        contact: The contact that would slide.
        direction: +1 (along the edge's ξ) or -1.
        forces_surface: Predicted contact forces (normal, tangential) per contact [N]
            (for an impossible slide: the least-norm forces that move the object as asked).
        normal_forces: Their normal components [N].
        cone_margins: μ f_n - |f_t| per contact [N]: μ_s at the fixed contacts, μ_k at the sliding one
            (0 there by construction, unless ``edge_mu`` put it on another edge).
        reason: Why it is impossible, or None.
        obstacle: The same as a :class:`SlideObstacle`, or None.
    """

    possible: bool
    contact: int
    direction: float
    forces_surface: np.ndarray
    normal_forces: np.ndarray
    cone_margins: np.ndarray
    reason: str | None
    obstacle: SlideObstacle | None = None


def sliding_feasibility(
    grasp: Grasp,
    pose: ArrayLike,
    xi: ArrayLike,
    object_acceleration: ArrayLike,
    contact: int,
    direction: float,
    friction: FrictionLike,
    *,
    object_mass: float,
    object_inertia: float,
    gravity_in_hand: ArrayLike = (0.0, -9.81),
    settings: InternalForceSettings = InternalForceSettings(f_min=0.0, friction_margin=0.0),
    solver: InternalForceSolver | None = None,
    edge_mu: float | None = None,
) -> SlideFeasibility:
    r"""Whether contact ``contact`` can slide in ``direction`` while the object accelerates as asked.

    Args:
        grasp: The contacts (their modes are ignored: ``contact`` slides, the others are fixed).
        pose: Object pose (x, y, β) in the hand frame.
        xi: ξ [m] of every contact.
        object_acceleration: Desired Ẍ = (a_x, a_y, α) [m/s², rad/s²].
        contact: Index of the contact that would slide.
        direction: +1 to slide along the edge's ξ direction, -1 against it.
        friction: The contacts' :class:`~regrasp.core.contact.Friction` (one for all, a coefficient [-], or
            one per contact): the slider on its kinetic edge, the fixed contacts in their static cones.
        object_mass: [kg].
        object_inertia: [kg m²].
        gravity_in_hand: [m/s²].
        settings: Minimum normal force and cone margin (default: the bare physics, 0 and 0).
        solver: A persistent :class:`~regrasp.dynamics.internal_force.solver.InternalForceSolver` with these
            ``settings``, for callers that ask many times (a supervisor); the same QP, solved
            warm-started instead of set up anew (~20x faster). None: the one-shot ``qpsolvers`` path.
        edge_mu: The slider's ratio t_j·f_j / (s n_j·f_j) [-], >= 0, instead of its μ_k (e.g. μ_s + an
            overshoot, for a slide that must first break away).
    """
    m = expect_type("grasp", grasp, Grasp, "a Grasp").m
    expect_type("settings", settings, InternalForceSettings, "an InternalForceSettings")
    if solver is not None and expect_type("solver", solver, InternalForceSolver, "an InternalForceSolver or None"
                                          ).settings != settings:
        raise InvalidParameterError("solver", solver.settings, f"a solver with the same settings ({settings})")
    if not as_integer("contact", contact) < m:
        raise InvalidParameterError("contact", contact, f"a contact index in 0..{m - 1}")
    direction = as_sign("direction", direction)
    frictions = as_frictions(friction, m)
    if edge_mu is None:
        edge_mu = frictions[contact].kinetic
    else:
        edge_mu = as_finite_float("edge_mu", edge_mu)
        if edge_mu < 0.0:
            raise InvalidParameterError("edge_mu", edge_mu, "a friction ratio >= 0")
    object_mass = as_mass("object_mass", object_mass)
    object_inertia = as_inertia("object_inertia", object_inertia)
    pose = as_finite_array("pose", pose, (3,))
    xi = as_finite_array("xi", xi, (m,))
    acc = as_finite_array("object_acceleration", object_acceleration, (3,))
    g = as_finite_array("gravity_in_hand", gravity_in_hand, (2,))
    wrench = np.array([object_mass * (acc[0] - g[0]), object_mass * (acc[1] - g[1]), object_inertia * acc[2]])

    frames = grasp.surface_frames(pose, xi)
    G = grasp.grasp_matrix(pose, xi)
    row = np.zeros(2 * m)
    n, t = frames[contact][:, 0], frames[contact][:, 1]
    row[2 * contact:2 * contact + 2] = t - direction * edge_mu * n
    system = np.vstack([G, row])                      # system @ f = rhs
    rhs = np.concatenate([wrench, [0.0]])
    particular = np.linalg.lstsq(system, rhs, rcond=None)[0]
    modes = tuple(ContactMode.SLIDING if i == contact else ContactMode.FIXED for i in range(m))
    # the cone margins' coefficients: μ_s where fixed, μ_k at the slider
    mu = np.array([f.coefficient(mode) for f, mode in zip(frictions, modes)])
    scale = max(1.0, float(np.abs(rhs).max()))
    if np.abs(system @ particular - rhs).max() > 1e-9 * scale:
        # no contact forces at all produce this motion with contact j on that cone edge (at this
        # geometry the required force is unbounded)
        surface = np.einsum("mji,mj->mi", frames, particular.reshape(m, 2))
        return SlideFeasibility(False, contact, float(direction), surface, surface[:, 0].copy(),
                                cone_margin(mu, surface[:, 0], surface[:, 1]),
                                "no finite contact forces produce this motion with that slide (singular geometry)",
                                SlideObstacle.SINGULAR)
    reason = obstacle = None
    try:
        if solver is None:
            result = solve_internal_force_qp(build_internal_force_qp(system.T, particular, frames, modes, frictions,
                                                                     settings), frames, modes, frictions)
        else:
            result = solver.solve(system.T, particular, frames, modes, frictions)
        forces = result.forces
        possible = result.feasible
    except InternalForceInfeasibleError as exc:
        forces = particular.reshape(m, 2)
        possible = False
        reason, obstacle = f"no squeeze makes it possible ({exc.status})", SlideObstacle.NO_SQUEEZE
    surface = np.einsum("mji,mj->mi", frames, forces)
    if not possible and obstacle is None:
        worst = int(np.argmin(surface[:, 0]))
        strongest = int(np.argmax(surface[:, 0]))
        if surface[worst, 0] < 0.0:
            reason, obstacle = (f"contact {worst} would pull (normal force {surface[worst, 0]:.3g} N)",
                                SlideObstacle.PULL)
        elif surface[worst, 0] < settings.f_min:
            reason = f"contact {worst} would push only {surface[worst, 0]:.3g} N < f_min = {settings.f_min:.3g} N"
            obstacle = SlideObstacle.WEAK_PUSH
        elif surface[strongest, 0] > settings.f_max:
            reason = f"contact {strongest} would need {surface[strongest, 0]:.3g} N > f_max = {settings.f_max:.3g} N"
            obstacle = SlideObstacle.TOO_STRONG
        else:
            obstacle = SlideObstacle.FIXED_SLIP
            margins = cone_margin(mu - settings.friction_margin, surface[:, 0], surface[:, 1])
            worst = int(np.argmin(np.where(np.arange(m) != contact, margins, np.inf)))
            reason = (f"fixed contact {worst} would slip (cone margin {margins[worst]:.3g} N with friction margin "
                      f"{settings.friction_margin})")
    margins = cone_margin(mu, surface[:, 0], surface[:, 1])
    return SlideFeasibility(bool(possible), contact, float(direction), surface, surface[:, 0].copy(), margins,
                            reason, obstacle)


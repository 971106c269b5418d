"""The project plant on the compiled path (:class:`PlantKernel`): what the kernels of :mod:`regrasp.kernels.plant`
(a plant step) and :mod:`regrasp.kernels.stretch` (a stretch of steps) take of a plant, packed as their records and
arrays, and what they give back, unpacked.

This is the only place that knows both the plant and the kernels' layouts: the plant steps, its reference path and
its events do not. The kernel is the same arithmetic as the reference path (:mod:`regrasp.plants.project.equations`);
``tests/kernels/test_finger_and_plant.py`` checks the two against each other.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ...core.contact import ContactMode, Friction
from ...core.exceptions import InvalidParameterError
from ...kernels.finger import FINGER_TERMS
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
from ...model.hand import Hand
from .equations import PlantEquations
from .events import Accelerations, PlantEvents
from .state import PlantContact, PlantState, PlantStep, check_finite_step, rigid_contact_report

__all__ = ["PlantKernel"]

#: Where the elbow's two fields sit in :data:`~regrasp.kernels.finger.FINGER_TERMS` (the reference layout has none).
_ELBOW = FINGER_TERMS.names.index("ex")
_CODES = {ContactMode.FIXED: FIXED, ContactMode.SLIDING: SLIDING, ContactMode.SEPARATED: SEPARATED}


class PlantKernel:
    """The compiled path (module docstring) of a plant of ``hand`` with ``friction`` per contact, ``equations`` (its
    object's mass and inertia, its Baumgarte α, its edges), event ``checks`` (their collision certificates and link
    radii), control step ``dt`` [s] and ``contact_events``: its step (:meth:`step`), its accelerations
    (:meth:`accelerations`) and what a compiled stretch needs of it (:meth:`stretch_view`,
    :meth:`clear_collisions`, :meth:`take_stretch`). The plant's state and contacts are passed in; the caller adopts
    the state a step or a stretch reaches."""

    def __init__(self, hand: Hand, friction: Sequence[Friction], equations: PlantEquations, checks: PlantEvents,
                 dt: float, contact_events: bool):
        self.hand, self.friction, self.equations, self.checks = hand, tuple(friction), equations, checks
        self.dt, self.contact_events = dt, contact_events
        m, n = hand.m, hand.nq
        self._contacts: tuple | None = None  # (key, records): see contact_records()
        self._parameters: tuple | None = None  # (key, record): see parameters()
        #: The size of a step's output (:func:`~regrasp.kernels.plant.output_size`).
        self.output_size = output_size(m)
        self._no_torques = np.zeros(n)
        # the step's workspace (read within a step only): finger terms, which fingers need coal, their postures
        self.workspace = (np.empty(m, dtype=FINGER_TERMS), np.empty(m, np.bool_), np.empty((m, 7)))

    def contact_records(self, contacts: Sequence[PlantContact], keep: bool = False) -> np.ndarray:
        """``contacts`` as :data:`~regrasp.kernels.plant.PLANT_CONTACT` records (``keep``: the plant's own contacts,
        whose records are cached while they stay the same)."""
        key = tuple((c.edge, c.mode, c.xi, c.sign) for c in contacts)
        cached = self._contacts
        if keep and cached is not None and cached[0] == key:
            return cached[1]
        out = np.zeros(len(contacts), dtype=PLANT_CONTACT)
        for i, c in enumerate(contacts):
            if c.mode not in _CODES:
                raise InvalidParameterError("mode", c.mode, "a ContactMode member (PlantContact converts strings)")
            g = self.equations.edge(c.edge)
            f = self.friction[i]
            out[i] = (_CODES[c.mode], c.xi, c.sign, f.static, f.kinetic, g.nx, g.ny, g.tx, g.ty, g.ox, g.oy, g.offset,
                      g.lo, g.hi)
        if keep:
            self._contacts = (key, out)
        return out

    def parameters(self) -> np.void:
        """The plant's constants as a :data:`~regrasp.kernels.plant.PLANT_PARAMETERS` record (cached; a record, not
        a 0-d array of one: numba then reads its fields as numbers, not as 0-d arrays whose arithmetic it compiles
        as array expressions, slower to compile and to run)."""
        hand, equations = self.hand, self.equations
        gx, gy = hand.gravity_in_hand.tolist()
        key = (equations.mass, equations.inertia, gx, gy, equations.alpha, hand.damping_enabled, self.dt,
               self.contact_events, hand.singular_threshold)
        if self._parameters is None or self._parameters[0] != key:
            record = np.zeros((), dtype=PLANT_PARAMETERS)
            for name, value in zip(PLANT_PARAMETERS.names, key):
                record[name] = value
            self._parameters = (key, record[()])
        return self._parameters[1]

    @staticmethod
    def terms_as_pass(terms: np.ndarray) -> list[tuple]:
        """The kernel's terms in :meth:`~regrasp.plants.project.equations.PlantEquations.pin_pass`'s layout (for the
        event logic): :data:`FINGER_TERMS`'s fields but the elbow (``ex``, ``ey``), in order."""
        return [t[:_ELBOW] + t[_ELBOW + 2:] for t in terms.tolist()]

    def arguments(self, state: PlantState, contacts: list[PlantContact], tau: np.ndarray) -> tuple:
        """The arguments :func:`~regrasp.kernels.plant.plant_step_into` takes (before its outputs) at ``state``
        with the plant's ``contacts``, torques ``tau`` [N m] (a float array)."""
        checks = self.checks
        return (self.hand.kernel_parameters, self.parameters(), self.contact_records(contacts, keep=True),
                state.flat(), tau, checks.certificates, checks.link_radii)

    def accelerations(self, st: PlantState, tau: tuple,
                      contacts: Sequence[PlantContact]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q̈, Ẍ, forces) at ``st`` for torques ``tau`` with ``contacts``' modes (the plant's ``accelerations``)."""
        n = self.hand.nq
        dy, forces, _ = plant_evaluate(self.hand.kernel_parameters, self.parameters(), self.contact_records(contacts),
                                       st.flat(), np.array(tau))
        return dy[n:2 * n], dy[2 * n + 3:2 * n + 6], forces

    def step(self, state: PlantState, contacts: list[PlantContact], tau: tuple,
             accelerations: Accelerations) -> PlantStep:
        """A step from ``state`` with the plant's ``contacts`` (switched on events) and torques ``tau`` [N m] (checked
        already), with the compiled kernel (:func:`~regrasp.kernels.plant.plant_step_into`); ``accelerations``: the
        plant's (for the event checks)."""
        n, m = self.hand.nq, self.hand.m
        modes = tuple(c.mode for c in contacts)
        size = 2 * n + 9
        out = np.empty(self.output_size)  # (one allocation: the step's arrays are views of it)
        terms, needs_coal, posture = self.workspace
        err, attention, any_coal = plant_step_into(*self.arguments(state, contacts, np.array(tau)), out, terms,
                                                   needs_coal, posture)
        check_finite_step(state, out[:size].tolist())
        new = PlantState.from_flat(state.t + self.dt, out, n)
        surface = out[size:size + 2 * m].reshape(m, 2)
        xi, xi_dot = out[size + 6 * m:size + 7 * m], out[size + 7 * m:]
        checks = self.checks
        if attention:
            forces = out[size + 2 * m:size + 4 * m].reshape(m, 2)
            events, xis = checks.detect(new, tau, forces.tolist(), self.terms_as_pass(terms), contacts, accelerations)
            xi, xi_dot = np.array([x[0] for x in xis]), np.array([x[1] for x in xis])
        else:
            events = []
            if any_coal and checks.checkers is not None:
                for i in np.flatnonzero(needs_coal).tolist():
                    checks.coal(new, i, tuple(posture[i].tolist()), events)
        gap, slip = rigid_contact_report(modes, xi_dot, self.dt, lambda i: self.equations.gap(new, i, contacts[i].edge))
        return PlantStep(new, surface, xi, xi_dot, modes, err, gap, slip, tuple(events))

    # ------------------------------------------------------------------ stretches (regrasp.rollout.stretch)
    def stretch_view(self, state: PlantState, contacts: list[PlantContact]) -> tuple:
        """What :func:`~regrasp.kernels.stretch.stretch_into` steps the plant with from ``state``: (fingers, plant,
        contacts, the flat state y (a copy), certificates, radii, the step's ``out``, terms, needs_coal, posture)."""
        fingers, plant, records, y, _, certificates, radii = self.arguments(state, contacts, self._no_torques)
        terms, needs_coal, posture = self.workspace
        return (fingers, plant, records, y, certificates, radii, np.empty(self.output_size), terms, needs_coal,
                posture)

    def clear_collisions(self, out: np.ndarray, needs_coal: np.ndarray, posture: np.ndarray) -> bool:
        """Whether no link of the fingers ``needs_coal`` penetrates the object at the state ``out`` (a kernel
        step's output), asking coal; their certificates are renewed (as a step does). Logs nothing: a
        stretch hands a colliding step to the plant's step, which logs it."""
        n = self.hand.nq
        q, X = out[:n], out[2 * n:2 * n + 3]
        clear = True
        for i in np.flatnonzero(needs_coal).tolist():
            dist, _ = self.checks.certify(q, X, i, tuple(posture[i].tolist()))
            clear = clear and not (dist and min(dist) < 0.0)
        return clear

    def take_stretch(self, y: np.ndarray, last_out: np.ndarray, t: float, contacts: list[PlantContact],
                     last_error: float) -> PlantStep:
        """The step a stretch ended with: the flat state ``y`` at time ``t`` [s], the stretch's last step
        (``last_out``: its kernel output; ``last_error``: its constraint violation [m]) with ``contacts``' modes."""
        n, m = self.hand.nq, self.hand.m
        size = 2 * n + 9
        state = PlantState.from_flat(t, y.copy(), n)
        out = last_out.copy()
        modes = tuple(c.mode for c in contacts)
        xi_dot = out[size + 7 * m:]
        gap, slip = rigid_contact_report(modes, xi_dot, self.dt,
                                         lambda i: self.equations.gap(state, i, contacts[i].edge))
        return PlantStep(state, out[size:size + 2 * m].reshape(m, 2), out[size + 6 * m:size + 7 * m], xi_dot, modes,
                         last_error, gap, slip, ())

r"""Drake as a third, independent plant: the hand and the object of :mod:`regrasp.plants.drake.model`, stepped by
Drake's discrete ``MultibodyPlant``.

:class:`DrakePlant` is driven exactly like :class:`~regrasp.plants.project.plant.Plant` and
:class:`~regrasp.plants.mujoco.plant.MujocoPlant` (:class:`~regrasp.plants.simulation.PlantLike`). Its physics is
Drake's alone: compliant point contact (stiffness k, Hunt–Crossley dissipation d) with regularized Coulomb
friction between sphere tips and the object, solved by Drake's convex SAP solver in its ``lagged`` approximation
(``docs/derivations.md``, "A third plant: Drake"); it shares no equation with the project's reduced model or plant.

**Friction.** Drake's discrete solver uses one coefficient per contact, μ_k (its "dynamic" friction): it never reads
μ_s. A scenario with μ_s > μ_k gets contacts that break away at μ_k f_n, earlier than the model's μ_s f_n, and the
plant reports its friction as ``Friction(μ_k)``. The friction is regularized (``DrakeSettings.stiction_tolerance``):
a stuck contact creeps, 15 µm/s at 83 % of its cone on Figure 3.4's hold, far below the slip sensor's thresholds.

**Stepping.** Each control step of ``dt`` holds the joint torques τ (the plant's applied generalized force input,
zero-order hold) over ``round(dt / time_step)`` Drake steps, each one discrete update of the plant's state. On a
curved object other than a disc each tip's prism is a face tangent to the eroded curve at the foot of the tip's
centre (:mod:`regrasp.plants.drake.model`), put there before each Drake step, and before the solves of
``accelerations`` and ``contact_results``: a projection on the curve and a ``SceneGraph.ChangeShape`` per tip and
step (a 1 ms control step of two tips takes 3.4 ms on the rounded box and 4.2 ms on the ellipse of the tests, 1.1 ms
on the disc's cylinders).

**What it reports** (:class:`~regrasp.plants.project.state.PlantStep`), as the MuJoCo plant does:

* the state: joint angles and rates, the object's pose X = (x, y, β) and twist;
* each contact's force on the object in its surface frame (inward normal, ξ direction) [N]: Drake's contact results
  of each of its steps (the force that acted over it) averaged over the control step; on a curved object the frame
  is the curve's at the step's mean ξ;
* ξ and ξ̇ of each tip: its sphere's centre (the tip frame) projected on its edge's line, and its velocity
  relative to the object along the edge; on a curved object (:mod:`regrasp.core.curves`) the centre's foot on the
  curve (the arc length, continuous and unbounded: each contact's last ξ is the projection's ``near``) and its rate
  (:mod:`regrasp.plants.sphere_sensing`);
* the contact modes from a **slip sensor**: the slip over the control step of the tip's material point at the
  contact, ξ + r φ (φ the distal link's angle relative to the object: a sphere that rolls moves its centre, not
  that point; on a curve (1 + κδ) ξ̇ + r φ̇). A fixed contact slipping faster than ``slip_speed`` *slips*, a sliding
  one slower than ``stick_speed`` in its direction *sticks*;
* the constraint error, each contact's ``gap`` (its tip centre's distance from its edge's line or the curve,
  negative when penetrating) and ``slip`` (the sensor's reading times dt);
* events of the project plant's kinds: ``separation`` (no force over a whole control step and the tip more than
  ``separation_gap`` off its edge), ``slip``, ``stick``, ``left_edge``, ``collision`` (a finger link penetrates
  the object: link 0 proximal or 1 distal, and the depth; the links are in the physics, as on MuJoCo) and
  ``singular`` (a tip Jacobian's condition number above the hand's threshold). Kinds in ``stop_on`` stop it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from ...core.contact import DEFAULT_FRICTION, ContactMode, Friction, FrictionLike, as_frictions
from ...core.curves import CurvedObject
from ...core.events import Event, EventKind
from ...core.exceptions import InvalidParameterError
from ...core.polygon import ConvexPolygon
from ...core.validation import as_finite_array, as_finite_float, expect_choices, expect_sequence_of, expect_type
from ...model.hand import Hand
from ..project.state import PLANT_EVENT_KINDS, PlantContact, PlantState, PlantStep, checked_state
from ..saturation import Saturation
from ..sphere_sensing import SphereTipSensing
from .model import DrakeSettings, build_drake, require_drake, tangent_face

__all__ = ["DrakePlant"]

_FIXED, _SLIDING, _SEPARATED = ContactMode.FIXED, ContactMode.SLIDING, ContactMode.SEPARATED


class DrakePlant(SphereTipSensing):
    r"""The hand and the object in Drake, with the project plant's interface (module docstring).

    Args:
        hand: The fingers (from URDF files) and gravity; only their URDFs, base poses, names, gravity, link mass
            scale and singularity threshold are read.
        polygon: The object: a convex polygon or a curved object (:mod:`regrasp.core.curves`; its one face, 0).
        contacts: One :class:`~regrasp.plants.project.state.PlantContact` per finger: its edge and initial mode (on a
            curve its ``xi`` also picks which of the periodic ξ the sensing continues from).
        friction: Anything :class:`~regrasp.plants.project.plant.Plant` takes; Drake gets ``CoulombFriction(μ_s,
            μ_k)`` and uses μ_k; the plant reports ``Friction(μ_k)``.
        object_mass: Overrides the object's mass [kg].
        object_inertia: Overrides the object's inertia [kg m²].
        dt: Control step [s] (a multiple of ``settings.time_step``).
        settings: :class:`~regrasp.plants.drake.model.DrakeSettings` (tip radius, contact parameters, Drake's step).
        tip_clearance: Per finger, the distal link's tip clearance [m] for the collision shapes (None: default).
        slip_speed: A fixed contact whose slip velocity exceeds this slips [m/s].
        stick_speed: A sliding contact whose slip velocity in its sliding direction falls below this sticks [m/s].
        separation_gap: A contact with no force over a control step is released when its tip ends the step more
            than this [m] off its edge.
        stop_on: Event kinds that stop the simulation.

    Attributes:
        built: The :class:`~regrasp.plants.drake.model.DrakeHand` (Drake's diagram and plant, the indices).
        context: The plant's ``Context`` (the state now).
        friction: One ``Friction(μ_k)`` per contact: what Drake's discrete solver uses.
        max_gap: The largest distance [m] a touching tip's centre ended a step off its edge since the last reset.
    """

    def __init__(self, hand: Hand, polygon: ConvexPolygon | CurvedObject, contacts: Sequence[PlantContact], *,
                 friction: FrictionLike = DEFAULT_FRICTION, object_mass: float | None = None,
                 object_inertia: float | None = None, dt: float = 1e-3, settings: DrakeSettings = DrakeSettings(),
                 tip_clearance: Sequence[float | None] | None = None, slip_speed: float = 2e-3,
                 stick_speed: float = 1e-3, separation_gap: float = 2.5e-5,
                 stop_on: Sequence[str] = ("separation", "left_edge", "collision", "singular")):
        require_drake()
        expect_type("hand", hand, Hand, "a Hand")
        expect_type("polygon", polygon, (ConvexPolygon, CurvedObject), "a ConvexPolygon or a CurvedObject")
        expect_type("settings", settings, DrakeSettings, "a DrakeSettings")
        contacts = expect_sequence_of("contacts", contacts, PlantContact, "PlantContact")
        if len(contacts) != hand.m:
            raise InvalidParameterError("contacts", contacts, f"one contact per finger ({hand.m})")
        self.hand, self.polygon, self.settings = hand, polygon, settings
        self.configure_sensing(dt, settings.time_step, "Drake's time step", slip_speed, stick_speed, separation_gap)
        stop_on = expect_choices("stop_on", stop_on, PLANT_EVENT_KINDS, "plant event kinds")
        self.stop_on = frozenset(EventKind(k) for k in stop_on)
        built = build_drake(hand.fingers, polygon, as_frictions(friction, hand.m),
                            gravity_in_hand=hand.gravity_in_hand, object_mass=object_mass,
                            object_inertia=object_inertia, tip_clearance=tip_clearance, settings=settings)
        self.built = built
        plant = built.plant
        self._plant = plant
        self._root = built.diagram.CreateDefaultContext()
        self.context = plant.GetMyMutableContextFromRoot(self._root)
        for links in built.link_bodies:  # (SetMass scales the rotational inertia with it)
            for body in links:
                body.SetMass(self.context, body.default_mass() * hand.link_mass_scale)
        self._scratch_root = self._root.Clone()
        self._scratch = plant.GetMyMutableContextFromRoot(self._scratch_root)
        self._force_port = plant.get_applied_generalized_force_input_port()
        self._results_port = plant.get_contact_results_output_port()
        self._nv = plant.num_velocities()
        self._force_port.FixValue(self.context, np.zeros(self._nv))
        self._force_port.FixValue(self._scratch, np.zeros(self._nv))
        #: The friction the plant has: Drake's dynamic coefficient per contact.
        self.friction = tuple(Friction(mu) for mu in built.friction)
        self.mass = built.object_body.get_mass(self.context)
        self.inertia = float(built.object_body.CalcSpatialInertiaInBodyFrame(self.context)
                             .CalcRotationalInertia().get_moments()[2])
        self._fq, self._fv, self._oq, self._ov = built.finger_q, built.finger_v, built.object_q, built.object_v
        self._damping = self._joint_damping()
        self._source = plant.get_source_id()
        self.contacts = self.copy_contacts(contacts)
        self._face_xi = [c.xi for c in self.contacts]  # (each tangent face's ξ: the next foot's search starts there)
        self.state: PlantState | None = None
        self.events: list[Event] = []
        self.stopped = False
        self.max_constraint_error = 0.0
        #: The motors' torque limits (:mod:`regrasp.plants.saturation`).
        self.saturation = Saturation(hand.effort_limit.tolist())
        self._energy0 = 0.0

    def _joint_damping(self) -> np.ndarray:
        """The fingers' joint damping [N m s/rad] (the URDFs'), in the order of ``finger_v``."""
        plant = self._plant
        by_v = {}
        for k in plant.GetJointIndices():
            joint = plant.get_joint(k)
            if joint.num_velocities() == 1:
                by_v[joint.velocity_start()] = float(joint.default_damping())
        return np.array([by_v[v] for v in self._fv.tolist()])

    @property
    def tip_radius(self) -> float:
        """The fingertips' sphere radius r [m]."""
        return self.settings.tip_radius

    # ------------------------------------------------------------------ state
    def _load(self, context, q, v, X, V, t: float) -> None:
        nq = self._plant.num_positions()  # (x = [q; v])
        x = np.empty(nq + self._nv)
        x[self._fq], x[self._oq] = q, X
        x[nq + self._fv], x[nq + self._ov] = v, V
        self._plant.SetPositionsAndVelocities(context, x)
        (self._root if context is self.context else self._scratch_root).SetTime(t)

    def _energy(self, context) -> float:
        return float(self._plant.EvalKineticEnergy(context) + self._plant.EvalPotentialEnergy(context))

    def _read_state(self, torque_work: float, damping_work: float) -> PlantState:
        ctx, plant = self.context, self._plant
        q, v = plant.GetPositions(ctx), plant.GetVelocities(ctx)
        return PlantState(float(ctx.get_time()), q[self._fq], v[self._fv], q[self._oq], v[self._ov], torque_work,
                          damping_work, self._energy(ctx) - self._energy0 - torque_work - damping_work)

    def reset(self, q: ArrayLike, v: ArrayLike, X: ArrayLike, V: ArrayLike, t: float = 0.0,
              contacts: Sequence[PlantContact] | None = None) -> PlantState:
        """Set the state (q, v [rad, rad/s], X = (x, y, β), V = (vx, vy, ω)) and clear the event log; the
        contacts' modes persist unless ``contacts`` is given."""
        n = self.hand.nq
        if contacts is not None:
            contacts = expect_sequence_of("contacts", contacts, PlantContact, "PlantContact")
            if len(contacts) != self.hand.m:
                raise InvalidParameterError("contacts", contacts, f"one contact per finger ({self.hand.m})")
            self.contacts = self.copy_contacts(contacts)
        values = checked_state(n, q, v, X, V)
        self._load(self.context, *values, as_finite_float("t", t))
        self._energy0 = self._energy(self.context)
        self.state = self._read_state(0.0, 0.0)
        self.events, self.stopped, self.max_gap = [], False, -np.inf
        self.saturation.clear()
        for i, c in enumerate(self.contacts):  # a fixed contact is held where its tip is
            c.xi = self._measure(self.context, i)[0]
        self._face_xi = [c.xi for c in self.contacts]
        self._place_faces(self.context)
        self.max_constraint_error = self.constraint_error(self.state)
        return self.state

    # ------------------------------------------------------------------ sensing
    def _measure(self, context, i: int) -> tuple[float, float, float, float]:
        r"""(ξ, ξ̇, the distance of the tip's centre from the edge's line (positive outside), the distal link's
        angle relative to the object φ) of tip i in ``context`` [m, m/s, m, rad]."""
        plant = self._plant
        q, v = plant.GetPositions(context), plant.GetVelocities(context)
        body = self.built.tip_bodies[i]
        pose = body.EvalPoseInWorld(context)
        rot = pose.rotation().matrix()
        return self.edge_measure(i, q[self._oq].tolist(), v[self._ov].tolist(), pose.translation().tolist(),
                                 body.EvalSpatialVelocityInWorld(context).translational().tolist(),
                                 math.atan2(rot[1, 0], rot[0, 0]))

    def _context_at(self, st: PlantState):
        if st is self.state:
            return self.context
        self._load(self._scratch, st.q, st.v, st.X, st.V, st.t)
        return self._scratch

    def contact_xi(self, st: PlantState, i: int, tip: Sequence[float] | np.ndarray | None = None,
                   tip_vel: Sequence[float] | np.ndarray | None = None) -> tuple[float, float]:
        """ξ [m] of tip i's centre projected on its edge's line, and its velocity along the edge relative to the
        object ξ̇ [m/s] (``tip``, ``tip_vel``: ignored, Drake's tip bodies are read)."""
        return self._measure(self._context_at(st), i)[:2]

    def constraint_error(self, st: PlantState) -> float:
        """Largest distance [m] of a touching tip's centre from its edge's line."""
        context = self._context_at(st)
        return max((abs(self._measure(context, i)[2]) for i, c in enumerate(self.contacts)
                    if c.mode is not _SEPARATED), default=0.0)

    def _place_faces(self, context) -> None:
        """On a curved object other than a disc, put each tip's face (:func:`~regrasp.plants.drake.model.tangent_face`)
        at the foot of its tip's centre on the curve in ``context``'s state (the main context remembers the feet: the
        next projections start there)."""
        built = self.built
        if built.face_filter is None:
            return
        main = context is self.context
        graph = built.scene_graph
        graph_context = graph.GetMyMutableContextFromRoot(self._root if main else self._scratch_root)
        s = self.settings
        x, y, beta = self._plant.GetPositions(context)[self._oq].tolist()
        c, sn = math.cos(beta), math.sin(beta)
        for i, (body, face) in enumerate(zip(built.tip_bodies, built.faces)):
            px, py = body.EvalPoseInWorld(context).translation()[:2].tolist()
            xi = self.polygon.project_floats(c * (px - x) + sn * (py - y), c * (py - y) - sn * (px - x),
                                             self._face_xi[i])[0]
            shape, pose = tangent_face(self.polygon, s.tip_radius - s.contact_depth, xi, s.object_thickness)
            graph.ChangeShape(graph_context, self._source, face, shape, pose)
            if main:
                self._face_xi[i] = xi
        graph.collision_filter_manager(graph_context).Apply(built.face_filter)  # (ChangeShape dropped them)
        # ChangeShape on a context invalidates none of its cached results (contact results, the discrete update)
        # already computed from the old faces at this state: setting the same positions again does
        self._plant.SetPositions(context, self._plant.GetPositions(context))

    def contact_results(self) -> object:
        """Drake's ``ContactResults`` at the current state: the contact solve of the next Drake step from it (its
        forces act over that step; a slip speed is of the step's end velocities), the tangent faces placed."""
        if self.state is None:
            raise InvalidParameterError("state", None, "a state: call reset() first")
        self._place_faces(self.context)
        return self._results_port.Eval(self.context)

    def _advance(self, context) -> tuple[np.ndarray, np.ndarray, dict]:
        """Drake's discrete update from ``context``'s state: (the next [q; v], each tip's contact force on the object
        during it (m, 2), hand frame, the deepest link penetration per finger as {finger: (link, depth)})."""
        self._place_faces(context)
        update = self._plant.EvalUniquePeriodicDiscreteUpdate(context).get_vector(0).CopyToVector()
        results = self._results_port.Eval(context)  # (the contact solver's results of that update, cached)
        forces = np.zeros((self.hand.m, 2))
        links: dict[int, tuple[int, float]] = {}
        geometries = self.built.geometries
        for k in range(results.num_point_pair_contacts()):
            info = results.point_pair_contact_info(k)
            pair = info.point_pair()
            a, b = geometries.get(pair.id_A), geometries.get(pair.id_B)
            if a is None or b is None or (a[0] == "object") == (b[0] == "object"):
                continue
            finger, sign = (a, 1.0) if b[0] == "object" else (b, -1.0)  # contact_force is on B
            kind, i, link = finger
            if kind == "link":
                depth = float(pair.depth)
                if depth > 0.0 and (i not in links or depth > links[i][1]):
                    links[i] = (link, depth)
                continue
            forces[i] += sign * info.contact_force()[:2]
        return update, forces, links

    def accelerations(self, st: PlantState, tau: ArrayLike,
                      modes: Sequence[PlantContact] | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q̈, Ẍ, forces) at state ``st`` under torques ``tau``: Drake's discrete forward dynamics, the mean
        acceleration over one of its steps from that state, (v⁺ − v) / time_step, and the contact forces of that
        step; ``forces`` (m, 2) on the object, hand frame. ``modes`` must be None (Drake decides the contacts)."""
        if modes is not None:
            raise InvalidParameterError("modes", modes, "None: the Drake plant's contacts are Drake's")
        tau = np.array(self.saturation.clip(as_finite_array("tau", tau, (self.hand.nq,)).tolist())[0])
        applied = np.zeros(self._nv)
        applied[self._fv] = tau
        self._load(self._scratch, st.q, st.v, st.X, st.V, st.t)
        self._force_port.FixValue(self._scratch, applied)
        update, forces, _ = self._advance(self._scratch)
        v = self._plant.GetVelocities(self._scratch)
        accel = (update[self._plant.num_positions():] - v) / self.settings.time_step
        return accel[self._fv], accel[self._ov], forces

    # ------------------------------------------------------------------ stepping
    def step(self, tau: ArrayLike) -> PlantStep:
        """Advance one control step with constant joint torques ``tau`` [N m]."""
        if self.state is None:
            raise InvalidParameterError("state", None, "a state: call reset() first")
        if self.stopped:
            raise InvalidParameterError("plant", "stopped", "a running plant (it stopped on an event)")
        commanded = as_finite_array("tau", tau, (self.hand.nq,)).tolist()
        clipped, saturated = self.saturation.clip(commanded)  # (the motors' limits, as every plant's)
        saturation: list[Event] = []
        for i, detail, values in self.saturation.onsets(commanded, saturated):  # (at the step's start)
            self.log_event(i, EventKind.SATURATION, detail, saturation, **values)
        tau = np.array(clipped)
        applied = np.zeros(self._nv)
        applied[self._fv] = tau
        ctx, plant = self.context, self._plant
        self._force_port.FixValue(ctx, applied)
        h, m = self.settings.time_step, self.hand.m
        surface = np.zeros((m, 2))
        links: dict[int, tuple[int, float]] = {}
        torque_work, damping_work = self.state.torque_work, self.state.damping_work
        # an edge's surface frame is constant; a curve's turns with ξ: its force is summed in the object frame and
        # taken into the frame at the step's mean ξ at the end (as on MuJoCo)
        frames = [None if getattr(e, "curved", False) else np.array([e.inward_normal, e.xi_direction])
                  for e in self.contact_edges]
        in_object_sum = np.zeros((m, 2))
        before = [self._measure(ctx, i) for i in range(m)]
        t0 = float(ctx.get_time())
        for k in range(self.substeps):
            v = plant.GetVelocities(ctx)[self._fv]
            torque_work += h * float(tau @ v)
            damping_work -= h * float(self._damping @ (v * v))
            beta = float(plant.GetPositions(ctx)[self._oq[2]])
            update, forces, deepest = self._advance(ctx)
            for i, (link, depth) in deepest.items():
                if i not in links or depth > links[i][1]:
                    links[i] = (link, depth)
            c, s = math.cos(beta), math.sin(beta)
            in_object = forces @ np.array([[c, -s], [s, c]])  # R(β)ᵀ f per row
            for i in range(m):
                if frames[i] is None:
                    in_object_sum[i] += in_object[i]
                else:
                    surface[i] += frames[i] @ in_object[i]
            plant.SetPositionsAndVelocities(ctx, update)
            self._root.SetTime(t0 + (k + 1) * h)
        surface /= self.substeps
        after = [self._measure(ctx, i) for i in range(m)]
        for i in range(m):
            if frames[i] is None:
                surface[i] = self.surface_frame(i, 0.5 * (before[i][0] + after[i][0])) @ in_object_sum[i] \
                    / self.substeps
        modes = tuple(c.mode for c in self.contacts)
        self.state = self._read_state(torque_work, damping_work)
        events, xi, xi_dot, err, gap, slip = self._events(surface, links, before, after)
        self.max_constraint_error = max(self.max_constraint_error, err)
        return PlantStep(self.state, surface, np.array(xi), np.array(xi_dot), modes, err, gap, slip,
                         (*saturation, *events))

    def _events(self, surface: np.ndarray, links: dict, before: list, after: list) -> tuple[list, list, list, float,
                                                                                          np.ndarray, np.ndarray]:
        """The events at the step's end (module docstring); ξ, ξ̇, the constraint error, each tip's gap [m] and
        each contact's slip over the step [m] there (``before``, ``after``: each contact's :meth:`_measure` at the
        step's start and end)."""
        out, xis, rates, err, gaps, slips = self.contact_events(surface, links, before, after.__getitem__)
        self._check_singular(out)
        return out, xis, rates, err, gaps, slips

    def _check_singular(self, out: list) -> None:
        from pydrake.multibody.tree import JacobianWrtVariable

        plant, world = self._plant, self._plant.world_frame()
        for i, body in enumerate(self.built.tip_bodies):
            jac = plant.CalcJacobianTranslationalVelocity(self.context, JacobianWrtVariable.kV, body.body_frame(),
                                                          np.zeros(3), world, world)
            cond = np.linalg.cond(jac[:2, self._fv[2 * i:2 * i + 2]])
            if not cond <= self.hand.singular_threshold:
                self.log_event(i, EventKind.SINGULAR, f"Jacobian condition number {cond:.3g}", out)

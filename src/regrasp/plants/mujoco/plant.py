r"""MuJoCo as a second, independent plant: the hand and the object of :mod:`regrasp.plants.mujoco.mjcf`, stepped by
MuJoCo.

:class:`MujocoPlant` is driven exactly like :class:`~regrasp.plants.project.plant.Plant` (the simulation loop, the
rollout, the recorder: :class:`~regrasp.plants.simulation.PlantLike`). Its physics is MuJoCo's alone: soft
contacts with elliptic friction cones between sphere tips and the object (``docs/derivations.md``,
"A second plant: MuJoCo"); it shares no equation with the project's reduced model or plant.

**Stepping.** Each control step of ``dt`` holds the joint torques τ (``qfrc_applied``, zero-order hold)
over ``round(dt / timestep)`` MuJoCo steps, saturated at the joints' limits first: clip(τ, -effort, effort), with a
``saturation`` event where a joint starts to saturate (:mod:`regrasp.plants.saturation`, as the project's plant;
``actuatorfrcrange`` would limit only actuators' forces, and this plant applies joint forces directly).

**What it reports** (:class:`~regrasp.plants.project.state.PlantStep`), all of it what a hand could sense:

* the state: joint angles and rates, the object's pose X = (x, y, β) and twist;
* each contact's force on the object in its surface frame (inward normal, ξ direction) [N]: MuJoCo's
  contact force averaged over the control step (the impulse over ``dt``: what a 1 kHz force sensor reads);
  on a curved object the frame is the curve's at the step's mean ξ;
* ξ and ξ̇ of each tip: its sphere's centre (the tip frame) projected on its edge's line, and its
  velocity relative to the object along the edge; on a curved object (:mod:`regrasp.core.curves`) the centre's foot
  on the curve (the arc length, continuous and unbounded) and its rate
  (:mod:`regrasp.plants.sphere_sensing`);
* the contact modes, which are what a **slip sensor** says. Its reading is the slip velocity over the
  control step: how far the tip's material point at the contact moved along the edge (or curve) relative to the
  object's, over ``dt`` (a sphere that rolls moves its centre, not that point). A fixed contact whose
  slip exceeds ``slip_speed`` *slips* (it is sliding in that direction), a sliding one whose slip in its
  direction falls below ``stick_speed`` *sticks*. A soft contact creeps inside its cone, far slower than
  either (below 0.75 mm/s on the scheduled rollout, 0.07 mm/s on a hold);
* the constraint error: the largest distance of a touching tip's centre from its edge's line [m]
  (the soft contact's penetration, or a hop's gap);
* events, of the same kinds as the project's plant: ``separation`` (a contact carried no force over a
  whole control step and its tip ended it more than ``separation_gap`` off the edge: it is released),
  ``slip``, ``stick``, ``left_edge`` (ξ off the edge), ``collision`` (a finger link touches the object:
  link 0 proximal or 1 distal, and the depth), ``singular`` (a tip Jacobian's condition number above the
  hand's threshold). Kinds in ``stop_on`` stop the plant.

A sliding contact of MuJoCo's convex contact model hops: sliding pushes the bodies apart (MuJoCo's
documentation: "the only way to initiate slip is to produce some motion in the normal direction"), so a
slider's normal force comes in pulses, with 0.1 to 2 ms of flight between them and gaps of a few µm
(12.6 µm at most on the scheduled rollout). Whole control steps without force are then not a lost grasp,
hence the gap in the separation test (``docs/derivations.md``, "A second plant: MuJoCo").
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
from ..project.state import PlantContact, PlantState, PlantStep, checked_state
from ..saturation import Saturation
from ..sphere_sensing import SphereTipSensing
from .mjcf import MujocoSettings, build_mjcf, require_mujoco

__all__ = ["MujocoPlant"]

_FIXED, _SLIDING, _SEPARATED = ContactMode.FIXED, ContactMode.SLIDING, ContactMode.SEPARATED
_STOP_KINDS = frozenset(k.value for k in (EventKind.SEPARATION, EventKind.SLIP, EventKind.STICK, EventKind.LEFT_EDGE,
                                          EventKind.COLLISION, EventKind.SINGULAR, EventKind.SATURATION))


class MujocoPlant(SphereTipSensing):
    r"""The hand and the object in MuJoCo, with the project plant's interface (module docstring).

    Args:
        hand: The fingers (from URDF files) and gravity; only their URDFs, base poses, names, gravity,
            link mass scale and singularity threshold are read.
        polygon: The object: a convex polygon or a curved object (:mod:`regrasp.core.curves`; its one face, 0).
        contacts: One :class:`~regrasp.plants.project.state.PlantContact` per finger: its edge and initial mode (on a
            curve its ``xi`` also picks which of the periodic ξ the sensing continues from).
        friction: Anything :class:`~regrasp.plants.project.plant.Plant` takes; MuJoCo gets μ_k
            (:class:`~regrasp.plants.mujoco.mjcf.MujocoSettings`) and the plant reports ``Friction(μ_k)``.
        object_mass: Overrides the object's mass [kg].
        object_inertia: Overrides the object's inertia [kg m²].
        dt: Control step [s] (a multiple of ``settings.timestep``).
        settings: :class:`~regrasp.plants.mujoco.mjcf.MujocoSettings` (tip radius, contact parameters, MuJoCo's step).
        tip_clearance: Per finger, the distal link's tip clearance [m] for the collision shapes (None: default).
        slip_speed: A fixed contact whose slip velocity exceeds this slips [m/s].
        stick_speed: A sliding contact whose slip velocity in its sliding direction falls below this sticks [m/s].
        separation_gap: A contact with no force over a control step is released when its tip ends the step more
            than this [m] off its edge (twice the largest hop's gap on the scheduled rollout).
        stop_on: Event kinds that stop the simulation.

    Attributes:
        model, data: MuJoCo's compiled model and its data (the state now).
        mjcf: The :class:`~regrasp.plants.mujoco.mjcf.MjcfHand` it was compiled from.
        friction: One ``Friction(μ)`` per contact, μ MuJoCo's coefficient.
        max_gap: The largest distance [m] a touching tip's centre ended a step off its edge since the last reset.
    """

    def __init__(self, hand: Hand, polygon: ConvexPolygon | CurvedObject, contacts: Sequence[PlantContact], *,
                 friction: FrictionLike = DEFAULT_FRICTION, object_mass: float | None = None,
                 object_inertia: float | None = None, dt: float = 1e-3, settings: MujocoSettings = MujocoSettings(),
                 tip_clearance: Sequence[float | None] | None = None, slip_speed: float = 2e-3,
                 stick_speed: float = 1e-3, separation_gap: float = 2.5e-5,
                 stop_on: Sequence[str] = ("separation", "left_edge", "collision", "singular")):
        mujoco = require_mujoco()
        expect_type("hand", hand, Hand, "a Hand")
        expect_type("polygon", polygon, (ConvexPolygon, CurvedObject), "a ConvexPolygon or a CurvedObject")
        expect_type("settings", settings, MujocoSettings, "a MujocoSettings")
        contacts = expect_sequence_of("contacts", contacts, PlantContact, "PlantContact")
        if len(contacts) != hand.m:
            raise InvalidParameterError("contacts", contacts, f"one contact per finger ({hand.m})")
        self.hand, self.polygon, self.settings = hand, polygon, settings
        self.configure_sensing(dt, settings.timestep, "MuJoCo's timestep", slip_speed, stick_speed, separation_gap)
        stop_on = expect_choices("stop_on", stop_on, _STOP_KINDS, "plant event kinds")
        self.stop_on = frozenset(EventKind(k) for k in stop_on)
        built = build_mjcf(hand.fingers, polygon, as_frictions(friction, hand.m),
                           gravity_in_hand=hand.gravity_in_hand, object_mass=object_mass, object_inertia=object_inertia,
                           tip_clearance=tip_clearance, link_mass_scale=hand.link_mass_scale, settings=settings)
        self.mjcf = built
        self.model = built.spec.compile()
        self.data = mujoco.MjData(self.model)
        self._scratch = mujoco.MjData(self.model)
        self._mj = mujoco
        #: The friction the plant has: MuJoCo's one coefficient per contact.
        self.friction = tuple(Friction(mu) for mu in built.friction)
        self.mass = float(self.model.body("object").mass[0])
        self.inertia = float(self.model.body("object").inertia[2])
        model = self.model
        self._finger_q = np.array([model.joint(j).qposadr[0] for pair in built.finger_joints for j in pair])
        self._finger_v = np.array([model.joint(j).dofadr[0] for pair in built.finger_joints for j in pair])
        self._object_q = np.array([model.joint(j).qposadr[0] for j in built.object_joints])
        self._object_v = np.array([model.joint(j).dofadr[0] for j in built.object_joints])
        self._sites = [model.site(s).id for s in built.tip_sites]
        self._damping = model.dof_damping[self._finger_v].copy()
        # geom id -> ("tip", finger, -1) or ("link", finger, link)
        self._geoms = {model.geom(g).id: ("tip", i, -1) for i, g in enumerate(built.tip_geoms)}
        self._geoms.update({model.geom(name).id: ("link", i, link) for i, links in enumerate(built.link_geoms)
                            for name, link in links})
        self._object_geoms = {model.geom(built.object_geom).id, model.geom(built.hull_geom).id}
        self.contacts = self.copy_contacts(contacts)
        self.state: PlantState | None = None
        self.events: list[Event] = []
        self.stopped = False
        self.max_constraint_error = 0.0
        self._energy0 = 0.0
        #: The motors' torque limits (the module docstring).
        self.saturation = Saturation(hand.effort_limit.tolist())

    @property
    def tip_radius(self) -> float:
        """The fingertips' sphere radius r [m]."""
        return self.settings.tip_radius

    # ------------------------------------------------------------------ state
    def _load(self, data, q, v, X, V, t: float) -> None:
        data.qpos[self._finger_q], data.qvel[self._finger_v] = q, v
        data.qpos[self._object_q], data.qvel[self._object_v] = X, V
        data.time = t
        self._mj.mj_forward(self.model, data)

    def _read_state(self, torque_work: float, damping_work: float) -> PlantState:
        d = self.data
        energy = float(d.energy[0] + d.energy[1])
        return PlantState(float(d.time), d.qpos[self._finger_q].copy(), d.qvel[self._finger_v].copy(),
                          d.qpos[self._object_q].copy(), d.qvel[self._object_v].copy(), torque_work, damping_work,
                          energy - self._energy0 - torque_work - damping_work)

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
        self._mj.mj_resetData(self.model, self.data)
        self._load(self.data, *values, as_finite_float("t", t))
        self._energy0 = float(self.data.energy[0] + self.data.energy[1])
        self.state = self._read_state(0.0, 0.0)
        self.events, self.stopped, self.max_gap = [], False, -np.inf
        self.saturation.clear()
        for i, c in enumerate(self.contacts):  # a fixed contact is held where its tip is
            c.xi = self._measure(self.data, i)[0]
        self.max_constraint_error = self.constraint_error(self.state)
        return self.state

    # ------------------------------------------------------------------ sensing
    def _measure(self, data, i: int) -> tuple[float, float, float, float]:
        r"""(ξ, ξ̇, the distance of the tip's centre from the edge's line or the curve (positive outside), the distal
        link's angle relative to the object φ = θ₂ − β) of tip i in ``data`` [m, m/s, m, rad]."""
        site = self._sites[i]
        vel = np.empty(6)
        self._mj.mj_objectVelocity(self.model, data, self._mj.mjtObj.mjOBJ_SITE, site, vel, 0)
        xmat = data.site_xmat[site]
        return self.edge_measure(i, data.qpos[self._object_q].tolist(), data.qvel[self._object_v].tolist(),
                                 data.site_xpos[site, :2].tolist(), vel[3:5].tolist(), math.atan2(xmat[3], xmat[0]))

    def _data_at(self, st: PlantState):
        if st is self.state:
            return self.data
        self._load(self._scratch, st.q, st.v, st.X, st.V, st.t)
        return self._scratch

    def contact_xi(self, st: PlantState, i: int, tip: Sequence[float] | np.ndarray | None = None,
                   tip_vel: Sequence[float] | np.ndarray | None = None) -> tuple[float, float]:
        """ξ [m] of tip i's centre projected on its edge's line (or curve), and its velocity along the edge relative
        to the object ξ̇ [m/s] (``tip``, ``tip_vel``: ignored, MuJoCo's sites are read)."""
        return self._measure(self._data_at(st), i)[:2]

    def constraint_error(self, st: PlantState) -> float:
        """Largest distance [m] of a touching tip's centre from its edge's line (or curve)."""
        data = self._data_at(st)
        return max((abs(self._measure(data, i)[2]) for i, c in enumerate(self.contacts) if c.mode is not _SEPARATED),
                   default=0.0)

    def _contact_forces(self, data, forces: np.ndarray, links: dict) -> None:
        """Add each tip's contact force on the object (hand frame) at ``data``'s step to ``forces`` (m, 2),
        and note the deepest link contact per finger in ``links``."""
        n = data.ncon
        if not n:
            return
        con, efc = data.contact, data.efc_force
        for g, adr, frame, dist in zip(con.geom[:n].tolist(), con.efc_address[:n].tolist(), con.frame[:n],
                                       con.dist[:n]):
            first = self._geoms.get(g[0])
            finger = first if first is not None else self._geoms.get(g[1])
            if finger is None or (g[0] if first is None else g[1]) not in self._object_geoms:
                continue
            kind, i, link = finger
            if kind == "link":
                if dist < 0.0 and (i not in links or -dist > links[i][1]):
                    links[i] = (link, -float(dist))
                continue
            if adr < 0:
                continue
            f = efc[adr:adr + 3] @ frame.reshape(3, 3)  # on geom 2, world frame
            forces[i] += f[:2] if first is not None else -f[:2]  # (on the object when the tip is geom 1)

    def accelerations(self, st: PlantState, tau: ArrayLike,
                      modes: Sequence[PlantContact] | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q̈, Ẍ, forces) at state ``st`` under torques ``tau``: MuJoCo's forward dynamics (its contact
        forces at that state); ``forces`` (m, 2) on the object, hand frame. ``modes`` must be None (MuJoCo
        decides the contacts)."""
        if modes is not None:
            raise InvalidParameterError("modes", modes, "None: the MuJoCo plant's contacts are MuJoCo's")
        data = self._scratch
        data.qfrc_applied[:] = 0.0
        tau = as_finite_array("tau", tau, (self.hand.nq,)).tolist()
        data.qfrc_applied[self._finger_v] = self.saturation.clip(tau)[0]
        self._load(data, st.q, st.v, st.X, st.V, st.t)
        forces = np.zeros((self.hand.m, 2))
        self._contact_forces(data, forces, {})
        return data.qacc[self._finger_v].copy(), data.qacc[self._object_v].copy(), forces

    # ------------------------------------------------------------------ stepping
    def step(self, tau: ArrayLike) -> PlantStep:
        """Advance one control step with constant joint torques ``tau`` [N m]."""
        if self.state is None:
            raise InvalidParameterError("state", None, "a state: call reset() first")
        if self.stopped:
            raise InvalidParameterError("plant", "stopped", "a running plant (it stopped on an event)")
        commanded = as_finite_array("tau", tau, (self.hand.nq,)).tolist()
        applied, saturated = self.saturation.clip(commanded)
        saturation: list[Event] = []
        for i, detail, values in self.saturation.onsets(commanded, saturated):  # (at the step's start)
            self.log_event(i, EventKind.SATURATION, detail, saturation, **values)
        tau = np.array(applied)
        mj, model, d = self._mj, self.model, self.data
        d.qfrc_applied[self._finger_v] = tau
        h = model.opt.timestep
        m = self.hand.m
        surface = np.zeros((m, 2))
        links: dict[int, tuple[int, float]] = {}
        torque_work, damping_work = self.state.torque_work, self.state.damping_work
        # an edge's surface frame is constant; a curve's turns with ξ: its force is summed in the object frame and
        # taken into the frame at the step's mean ξ at the end
        frames = [None if getattr(e, "curved", False) else np.array([e.inward_normal, e.xi_direction])
                  for e in self.contact_edges]
        in_object_sum = np.zeros((m, 2))
        before = [self._measure(d, i) for i in range(m)]  # (d is at the step's start: see below)
        for _ in range(self.substeps):
            v = d.qvel[self._finger_v]
            torque_work += h * float(tau @ v)
            damping_work -= h * float(self._damping @ (v * v))
            beta = float(d.qpos[self._object_q[2]])
            mj.mj_step(model, d)
            forces = np.zeros((m, 2))
            self._contact_forces(d, forces, links)  # (the forces of the step just taken, at its start state)
            c, s = math.cos(beta), math.sin(beta)
            in_object = forces @ np.array([[c, -s], [s, c]])  # R(β)ᵀ f per row
            for i in range(m):
                if frames[i] is None:
                    in_object_sum[i] += in_object[i]
                else:
                    surface[i] += frames[i] @ in_object[i]
        surface /= self.substeps
        mj.mj_forward(model, d)  # the end state's kinematics (and its energy) for the sensors
        after = [self._measure(d, i) for i in range(m)]
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
        """The events at the step's end (module docstring); ξ, ξ̇, the constraint error, each tip's gap [m] (its
        centre's distance from its edge's line: the plant's object is eroded by the tip's radius) and each contact's
        slip over the step [m] (:meth:`slip_velocity` × dt) there (``before``, ``after``: each contact's
        :meth:`_measure` at the step's start and end)."""
        out, xis, rates, err, gaps, slips = self.contact_events(surface, links, before, after.__getitem__)
        jac = np.empty((3, self.model.nv))
        for i in range(self.hand.m):
            self._mj.mj_jacSite(self.model, self.data, jac, None, self._sites[i])
            block = jac[:2, self._finger_v[2 * i:2 * i + 2]]
            cond = np.linalg.cond(block)
            if not cond <= self.hand.singular_threshold:
                self.log_event(i, EventKind.SINGULAR, f"Jacobian condition number {cond:.3g}", out)
        return out, xis, rates, err, gaps, slips

r"""``regrasp.rollout.recording``: Recording rollouts to rerun: an ``.rrd`` file, a live viewer, or both
(:class:`RolloutRecorder`).

This docstring is the layout of a recording: its timelines, where its values come from, its entities, their units
and colours, and what it costs. How to record is
:class:`~regrasp.rollout.recording.recorder.RolloutRecorder`'s (:mod:`~regrasp.rollout.recording.recorder`).

**Timelines.** ``time`` (a duration: the plant's time [s] of the logged state) and ``step``
(a sequence). Step 0 is the state before the first control step
(:meth:`~regrasp.rollout.recording.recorder.RolloutRecorder.log_initial`, or when the hook was made) and step k the
state after the k-th control step (record k - 1); ``decimation = n`` logs only the steps that are multiples of n
(:func:`regrasp.kernels.decimation.logged`), one row of every per-step entity each (events and the failure are
logged whatever the decimation).

**Two sources.** :meth:`~regrasp.rollout.recording.recorder.RolloutRecorder.log_record` with a supervised record
logs from the record alone: the state after the step (``record.plant.state``, ξ = ``record.plant.xi``), the
plant's forces at the step's start (``record.plant.forces_surface``) and their cone margins
(``record.cone_margins``), the controller's prediction (``record.command.control``) and the
supervisor's view at the step's start (``record.supervision``: phases, envelopes, the interval
holding each ξ, ξ_d): each row is "the step that led here", what the supervisor saw and did at
its start and where the plant ended (:mod:`~regrasp.rollout.recording.rows`; a compiled stretch's steps,
``log_stretch_step``, the same). Nothing is recomputed (no envelope evaluation, no KKT solve); only the drawing
needs the fingers' forward kinematics and the contacts' modes now (``plant.contacts``). Without a supervisor
(``hook``, ``log_step``, a record with ``supervision`` None) the recorder measures the plant
(:mod:`~regrasp.rollout.recording.measure`): ξ from the tips, envelopes with
:class:`~regrasp.envelope.finger_envelope.FingerEnvelope`, forces from the ``PlantStep`` or one KKT solve; the
phase series are then NaN.

**Scene** (entities under ``scene/``, the hand frame, in **millimetres**;
:mod:`~regrasp.rollout.recording.scene`). Rerun's 2-D view draws y *downwards* (image convention), so the recorder
logs every point as (1000 x, -1000 y): the picture is upright (gravity points down the screen) and values read off
the viewer are mm with the sign of y flipped.

* ``scene/object``: the object at the plant's pose: a polygon's ``vertices`` through X, a curved object's outline
  (:mod:`~regrasp.rollout.recording.outline`: evenly in ξ, every chord within 0.05 mm of the curve).
* ``scene/desired``: the desired pose (``reference(t)``'s first three entries), a faint ghost.
* ``scene/fingers/<finger>``: each link's URDF collision shape as its outline in the plane
  (cylinders and boxes are rectangles, capsules stadiums): the shape's points, placed by Pinocchio
  (``data.oMi[joint] * placement``), are the 2-D convex hull computed once in the joint frame
  (:mod:`~regrasp.rollout.recording.hand`); the last strip is the joint chain (joint 1, elbow, tip) as a thick
  polyline. ``scene/joints``: the joints and tips as dots.
* ``scene/contacts/forces``: each contact's force on the object, an arrow from the fingertip,
  ``force_scale`` mm per N (default 10 mm/N). It is the plant's force: the ``PlantStep``'s
  (at the step's start) when one is passed, otherwise recomputed at the logged state under the
  step's torque (``plant.accelerations``, one KKT solve; ``plant_forces=False`` skips it).
  ``scene/contacts/forces_predicted``: the controller's predicted force
  (``ControlOutput.contact_forces``), thinner.
* ``scene/contacts/cones``: each friction cone as two rays of ``cone_length`` mm around the inward
  normal, at :math:`\pm\arctan\mu_s` and green while the contact is fixed, at
  :math:`\pm\arctan\mu_k` and orange while it slides, grey (at :math:`\mu_s`) once separated. On a curved
  object the normal (and the force arrows' frame) is the one at the contact's ξ of the step.
* ``scene/envelope/safe`` and ``scene/envelope/danger``: each drawn edge's feasible set as thick segments drawn just
  outside the edge (3 mm, and 3 mm further for each other envelope drawn along it; on a curved object polylines
  along the curve at that distance outside it), in the finger's colour, with the last ``danger_fraction`` of each
  interval's width at both ends in red: the supervisor's samples (``SupervisorOutput.envelopes``, each contact's own
  edge) for a supervised record, else :class:`~regrasp.envelope.finger_envelope.FingerEnvelope` ``.at`` the plant's
  current pose (the ``envelope_edges``).
* ``scene/failure`` (logged once, by ``log_failure``, at the failure's time and the last step): the failure
  marked in red, labelled with its kind, finger and time (short, to stay in the view; the reason is in
  ``events``): a collision's link
  outline (the colliding link of the plant's last ``collision`` event of that finger, both links
  if unknown), a circle around the tip of the contact any other contact failure names
  (separation, unplanned slip, left envelope or edge, singular), the object's outline for a
  failure of no one contact (the control law's); nothing for an interruption.

**Plots** (under ``plots/``; each entity holds several series, named by static
``rr.SeriesLines``; NaN where a value is absent; one unit per entity and per view, the views' legends hidden:
each view's name says what its lines are, and hovering a line names it): ``plots/error/position`` the tracking
error's x, y and each reduced ξ [mm] and ``plots/error/angle`` its β [deg], measured at the logged state against the
desired S_d when the reference is known, otherwise the controller's ``ControlOutput.error``;
``plots/xi/<finger>`` (one view per finger, Figure 4.3) seven series [mm]: 0 the actual ξ,
1 the control law's ξ_d (the sliding law's ``reference_xi``, or the closed loop's S_d), 2-3 the
feasible interval holding ξ (lo, hi; the supervisor's ``bounds``), 4-5 where the danger zones
start (:func:`~regrasp.core.intervals.danger_zones`: lo + f w, hi − f w with f = ``danger_fraction``, by default
:data:`~regrasp.core.intervals.DANGER_FRACTION` as in the PNG figures, w = hi − lo), 6 the schedule's ξ_d
(``planned_xi``); a separated contact's are all NaN; ``plots/xi/<finger>/band`` fills that band (rerun's time
series draw no filled area): :data:`~regrasp.rollout.recording.rows.BAND_LINES` wide translucent green lines evenly
inside its safe part and :data:`~regrasp.rollout.recording.rows.ZONE_LINES` red ones inside each danger zone
(:func:`~regrasp.rollout.recording.rows.band_fill`); ``plots/force`` normal and tangential
forces (plant and predicted); ``plots/cone_margin`` μ f_n − |f_t| (plant and predicted; μ_s at a
fixed contact, μ_k at a sliding one); ``plots/mode`` 0 fixed, 1 sliding, 2 separated
(:data:`~regrasp.rollout.recording.rows.MODE_CODES`); ``plots/phase/<finger>`` the supervisor's phase of the
contact during the step (:data:`~regrasp.rollout.recording.rows.PHASE_CODES`: 0 fixed, 1 priming, 2 sliding,
3 settling; NaN without a supervisor).

**Events** (``events``, a text log, at each event's own time; the supervisor's decisions at the
step whose state they were taken at, the plant's at the step after which they were detected;
:mod:`~regrasp.rollout.recording.events`): ``t = … s  <source> <finger>: <kind> (<detail>)``, level WARN for the
kinds in :data:`~regrasp.rollout.recording.events.WARN_KINDS` (slip, separation, collision, a contact off its edge
or singular, left envelope, slide rejected or aborted, re-plan failed), INFO otherwise; a failure is one ERROR
line ``FAILURE (<kind>): <reason>``.

**Static data** (logged once; :mod:`~regrasp.rollout.recording.static`): ``model/object`` (the object in its own
frame, mm, with its edge numbers, a curved object's ξ = 0 marked, and its centre of mass), ``model/setup`` (a
Markdown table of the fingers, their edges, modes and friction), the styling of every entity above, and the viewer's
layout (the blueprint: :mod:`~regrasp.rollout.recording.blueprint`).

**Cost.** Per logged step the recorder keeps what the step needs: Pinocchio forward kinematics
(the joint frames and the chain), without a supervisor one ``FingerEnvelope.at`` per drawn edge
(~20 µs each in the ``ideal`` geometry; a supervised record brings its own), and the plotted
numbers. Every ``flush_every`` logged steps (default 5000 for a file alone: one chunk per entity, so that a viewer
opens the file sooner; 500 with a viewer) and on closing it turns the buffered steps into each
entity's rows with numpy operations over the whole block (outlines, arrows, cones, envelope segments) and sends
them with one ``send_columns`` per entity (:mod:`~regrasp.rollout.recording.writer`), so a live viewer sees the
data in blocks of that many steps. The recorded values are the same whatever ``flush_every`` is.
``RolloutRecorder.seconds_per_step`` reports the measured mean cost (about 0.1-0.2 ms on the three-finger
rollout). **Size.** A 1 s three-finger rollout (``policy="paper"``, 1000 steps) writes 1.7 MB at decimation 1,
0.45 MB at 10 and 0.30 MB at 100: about 1.4 kB per logged step on top of about 0.29 MB per file (each
entity's chunk schemas, static and per block sent).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ...core.lazy import lazy_exports

if TYPE_CHECKING:
    from .events import WARN_KINDS  # noqa: F401
    from .recorder import RolloutRecorder  # noqa: F401
    from .rows import MODE_CODES, PHASE_CODES  # noqa: F401

__getattr__, __dir__, __all__ = lazy_exports(__name__)

"""A logged step's rows measured from the plant, for a step without a supervisor (a bare control law's, or a record
without ``supervision``): ξ from the fingertips, the envelopes evaluated here
(:class:`~regrasp.envelope.finger_envelope.FingerEnvelope`, reused while the object moves less than a tolerance),
the forces from the step's :class:`~regrasp.plants.project.state.PlantStep` or one KKT solve at the logged state.

On a curved object (:mod:`regrasp.core.curves`) a tip's ξ is its foot on the curve
(:meth:`~regrasp.core.curves.base.CurvedObject.project_floats`) within half a perimeter of the contact's ξ at the
previous logged step (at first, the plant's :attr:`~regrasp.plants.project.state.PlantContact.xi`), so that ξ is
continuous however far a contact slides round; each envelope is sampled ``near`` its previous sample's foot (at
first, the contact's ξ), and the band plotted is the feasible interval nearest ξ modulo the perimeter.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ...core.contact import ContactMode, coefficients, cone_margin
from ...core.curves import CurvedObject
from ...core.exceptions import RegraspError
from ...dynamics.control import ControlOutput
from ...envelope.finger_envelope import EnvelopeSample, FingerEnvelope
from ...plants.project.state import PlantStep
from ...plants.simulation import PlantLike
from .rows import Layout, StepRow, mode_codes, poses, segments, series

__all__ = ["PlantMeasure"]


class PlantMeasure:
    """The recorder's own measurement of the plant: its envelopes and their latest samples.

    Args:
        layout: What the rows hold.
        plant: The recorder's plant (its fingers, object and friction; its contacts' edges now get their envelopes
            now, so that a bad ``geometry`` raises here).
        envelope_edges: The edges drawn per finger, or None: each contact's current edge.
        geometry: The envelopes' geometry (``"ideal"`` or ``"urdf"``).
        tolerance: Reuse an edge's envelope sample while the object has moved less than this [m] (each
            coordinate, and β times the object's scale); 0: evaluate at every logged step.
        plant_forces: Without a ``PlantStep``, recompute the plant's contact forces at the logged state.

    Raises:
        InvalidParameterError: an unknown geometry.
    """

    def __init__(self, layout: Layout, plant: PlantLike, *, envelope_edges: Sequence[tuple[int, ...]] | None,
                 geometry: str, tolerance: float, plant_forces: bool):
        self.layout = layout
        self.fingers = plant.hand.fingers
        self.polygon = plant.polygon
        self.edges = plant.polygon.edges
        self.friction = plant.friction
        self.envelope_edges = envelope_edges
        self.geometry = geometry
        self.tolerance = tolerance
        self.plant_forces = plant_forces
        self._envelopes: dict[tuple[int, int], FingerEnvelope] = {}
        self._samples: dict[tuple[int, int], tuple[tuple[float, float, float], EnvelopeSample]] = {}
        self.curve = plant.polygon if isinstance(plant.polygon, CurvedObject) else None
        self._xi = [c.xi for c in plant.contacts]  # a curve's contacts' last ξ (each foot is sought near it)
        for i, c in enumerate(plant.contacts):
            self.envelope(i, c.edge)
            for e in (envelope_edges[i] if envelope_edges is not None else ()):
                self.envelope(i, e)

    def envelope(self, i: int, edge: int) -> FingerEnvelope:
        """Finger ``i``'s envelope on ``edge`` (made once)."""
        env = self._envelopes.get((i, edge))
        if env is None:
            env = FingerEnvelope(self.fingers[i], self.polygon, edge, geometry=self.geometry)
            self._envelopes[(i, edge)] = env
        return env

    def row(self, plant: PlantLike, output: ControlOutput | None, desired: np.ndarray | None,
            plant_step: PlantStep | None) -> StepRow:
        """The row of ``plant``'s current state: ``output`` the controller's output for the step that led here
        (None: no predicted forces), ``desired`` the desired S_d or pose (None: no ghost, the error is
        ``output``'s), ``plant_step`` the step (its forces at its start; None: recomputed)."""
        layout = self.layout
        m = len(layout.hand.fingers)
        st = plant.state
        X = st.X
        x, y, beta = X.tolist()
        c_, s_ = math.cos(beta), math.sin(beta)
        RT = np.array([[c_, -s_], [s_, c_]]).T
        origin = X[:2]
        frames, chains = layout.hand.kinematics(st.q)
        tips = chains[:, 2]

        # contacts: ξ, forces
        contacts = plant.contacts
        xi = []
        edges = []
        curve = self.curve
        for i, c in enumerate(contacts):
            edges.append(c.edge)
            if curve is not None:  # the foot on the curve, near the contact's last ξ
                px, py = (RT @ (tips[i] - origin)).tolist()
                xi.append(curve.project_floats(px, py, self._xi[i])[0])
                self._xi[i] = xi[-1]
                continue
            e = self.edges[c.edge]
            xi.append(float(e.xi_direction @ (RT @ (tips[i] - origin) - e.xi_origin)))
        modes = [c.mode for c in contacts]
        surface = None
        if plant_step is not None:
            surface = np.array(plant_step.forces_surface, dtype=float)
        elif self.plant_forces and output is not None:
            try:
                forces = plant.accelerations(st, output.tau)[2]
                surface = plant.surface_forces(st, forces)
            except (np.linalg.LinAlgError, RegraspError):
                surface = None
        nan = math.nan
        nan_m = [nan] * m
        if surface is not None:
            fn, ft = surface[:, 0].tolist(), surface[:, 1].tolist()
            # the coefficient of each contact's mode while these forces acted (μ_s fixed, μ_k sliding)
            during = plant_step.modes if plant_step is not None else modes
            margin = [cone_margin(mu, a, b) for mu, a, b in zip(coefficients(self.friction, during), fn, ft)]
        else:
            fn = ft = margin = nan_m
        if output is not None:
            predicted = np.array(output.contact_forces, dtype=float)
            pred = np.asarray(output.contact_forces_surface, dtype=float)
            pfn, pft = pred[:, 0].tolist(), pred[:, 1].tolist()
            pmargin = np.asarray(output.cone_margins, dtype=float).tolist()
        else:
            predicted = None
            pfn = pft = pmargin = nan_m

        # envelopes (drawn) and the bounds around each contact's ξ (plotted)
        samples: dict[tuple[int, int], EnvelopeSample] = {}
        tol = self.tolerance
        scale = self.polygon.scale

        def sample(i: int, edge: int) -> EnvelopeSample:
            found = samples.get((i, edge))
            if found is None:
                cached = self._samples.get((i, edge))
                if cached is not None and tol > 0.0:
                    cx, cy, cb = cached[0]
                    if abs(x - cx) <= tol and abs(y - cy) <= tol and abs(beta - cb) * scale <= tol:
                        samples[(i, edge)] = cached[1]
                        return cached[1]
                if curve is None:
                    found = self.envelope(i, edge).at(X, st.t)
                else:  # near the previous sample's foot (at first, the contact's ξ)
                    found = self.envelope(i, edge).at(X, st.t, near=xi[i] if cached is None else cached[1].xi_foot)
                samples[(i, edge)] = found
                self._samples[(i, edge)] = ((x, y, beta), found)
            return found

        drawn = [(i, edge) for i in range(m)
                 for edge in ((contacts[i].edge,) if self.envelope_edges is None else self.envelope_edges[i])]
        drawn_segments = segments(drawn, lambda i, edge: sample(i, edge).feasible)
        bands = []
        for i in range(m):
            band = (nan, nan)
            if modes[i] is not ContactMode.SEPARATED:
                feasible = sample(i, contacts[i].edge).feasible
                if curve is not None:  # each interval's representative nearest ξ (ξ is unbounded)
                    feasible = [_nearest_turn(iv, xi[i], curve.perimeter) for iv in feasible]
                if feasible:
                    band = min(feasible, key=lambda iv: 0.0 if iv[0] <= xi[i] <= iv[1]
                               else min(abs(xi[i] - iv[0]), abs(xi[i] - iv[1])))
            bands.append(band)
        law_xi = [nan] * m
        if desired is not None:
            for j, i in enumerate(layout.sliding):
                if 3 + j < desired.size:
                    law_xi[i] = float(desired[3 + j])
        values = series(layout, X, xi, modes, desired, None if output is None else output.error,
                        fn + ft + pfn + pft, margin + pmargin, bands, law_xi, nan_m, nan_m)
        pose, ghost = poses(X, desired)
        return StepRow(pose, ghost, frames, chains, np.array(edges, dtype=np.intp), mode_codes(modes), surface,
                       predicted, drawn_segments, values, np.array(xi, dtype=float))


def _nearest_turn(interval: tuple[float, float], xi: float, period: float) -> tuple[float, float]:
    """``interval`` [m] moved by the whole number of periods [m] that brings its middle nearest ``xi`` [m]."""
    lo, hi = interval
    shift = period * round((xi - 0.5 * (lo + hi)) / period)
    return lo + shift, hi + shift

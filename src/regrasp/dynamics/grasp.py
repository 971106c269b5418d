r"""Contacts on a polygon and the grasp matrices of paper §3.1 and §3.4.

A grasp is m contacts, one per finger, each on an object edge and either ``fixed`` (the
fingertip stays at one point of the object) or ``sliding`` (it moves along the edge).
Contact i sits at :math:`c_i(\xi_i) = o_i + \xi_i t^o_i` in the object frame (the edge's ξ
origin and direction, :mod:`regrasp.core.polygon`). In the hand frame, with
:math:`R = R(\beta)`:

* lever arm :math:`r_i = R c_i(\xi_i)` (from the centre of mass to the contact);
* surface frame :math:`R_{fi} = R\,[n^o_i\ t^o_i] = [n_i\ t_i]` (x = inward normal,
  y = tangent = ξ direction; a proper rotation, :math:`t_i = \perp n_i`).

Velocity of the contact point, for :math:`\dot X = (v_o, \omega)` (eqs. 3.1.2–3.1.4):

.. math:: \dot x_{ci} = v_o + \omega \perp r_i + t_i \dot\xi_i
          = U_i^T \dot X + R_{fi} B_{vi} \dot\xi_i,\qquad
          U_i^T = [\,I_2 \mid \perp r_i\,],\ B_{vi} = (0, 1)^T.

(:math:`\dot R R^T = \omega [[0, -1], [1, 0]] = \omega\perp`: the paper's ``ω×`` matrix has the
opposite sign.) The grasp matrix :math:`G = [U_1 \dots U_m] \in \mathbb R^{3 \times 2m}` maps
contact forces on the object (hand frame) to the wrench at the centre of mass:
:math:`G f = \sum_i (f_i,\ r_i \times f_i)`. ``R_f`` is block-diagonal with :math:`R_{fi}` for
sliding contacts and :math:`I_2` for fixed ones, :math:`B_v \in \mathbb R^{2m \times p}` has a
:math:`(0, 1)^T` block per sliding contact (eq. 3.1.7). Contacts keep the fingers' order;
the paper lists sliding contacts first, which only permutes rows.

Friction (§3.4): a sliding contact's force on the object is
:math:`f_i = R_{fi} B_{fi} \eta_i`, :math:`B_{fi} = (1, \mathrm{sign}(\dot\xi_i)\mu_{k,i})^T`
(eq. 3.4.1 with the kinetic coefficient :math:`\mu_{k,i}` of :class:`~regrasp.core.contact.Friction`:
the fingertip drags the object along its sliding direction), a fixed one is
:math:`f_i = \eta_i \in \mathbb R^2`; :math:`G_f = G R_f B_f` (3.4.5) and, for m = 2, p = 1,
:math:`P = B_v^T B_f G_f^{-1}` (3.4.9) gives the friction force
:math:`f_\xi = P (M_o \ddot X - f_g)`.

Time derivatives are exact (no numerical differentiation):
:math:`\dot r_i = \omega \perp r_i + t_i \dot\xi_i`, :math:`\dot U_i^T = [\,0 \mid \perp\dot r_i\,]`,
:math:`\dot R_{fi} = (\omega - \kappa_i \dot\xi_i) \perp R_{fi}`.

**Curved objects** (:mod:`regrasp.core.curves`; ``docs/derivations.md``, "Contacts on curves"): a contact on a
curve's one face has :math:`c_i(\xi_i)` with :math:`c_i' = t^o_i(\xi_i)` (ξ is the arc length) and a frame that
turns with it, :math:`t^{o\prime}_i = \kappa_i n^o_i`, :math:`n^{o\prime}_i = -\kappa_i t^o_i`. The velocity
relation above is unchanged (the curve's tangent is the sliding direction); the frame's rate gains
:math:`-\kappa_i\dot\xi_i\perp`, which the paper's edge-only text (:math:`\dot R_f = \omega\perp R_f`) lacks.
On such a grasp the frames depend on ξ: :meth:`Grasp.surface_frames` and the methods built on it take ``xi``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from ..core.contact import ContactMode, FrictionLike, as_frictions
from ..core.curves import CurvedObject
from ..core.exceptions import InvalidParameterError, SlidingContactCountError
from ..core.planar import rotation
from ..core.polygon import ConvexPolygon
from ..core.validation import as_finite_array, expect_sequence_of, expect_type

__all__ = ["ContactMode", "Grasp"]


class Grasp:
    r"""m contacts on an object's faces (a polygon's edges, or a curved object's one face 0), each fixed or
    sliding, and their matrices.

    Args:
        polygon: The object: a :class:`~regrasp.core.polygon.ConvexPolygon` or a
            :class:`~regrasp.core.curves.CurvedObject`.
        edges: Face (edge) index of each contact (one per finger, in finger order).
        modes: ``"fixed"`` or ``"sliding"`` per contact.

    Raises:
        SlidingContactCountError: when :math:`2m < 3 + p` (Remark 3.2).
    """

    def __init__(self, polygon: ConvexPolygon, edges: Sequence[int], modes: Sequence[ContactMode | str]):
        expect_type("polygon", polygon, (ConvexPolygon, CurvedObject), "a ConvexPolygon or a CurvedObject")
        edges = expect_sequence_of("edges", edges, object, "edge indices")
        modes = expect_sequence_of("modes", modes, object, "contact modes")
        if len(edges) != len(modes) or len(edges) == 0:
            raise InvalidParameterError("modes", modes, f"one mode per contact ({len(edges)} edges)")
        try:
            self.modes = tuple(ContactMode(m) for m in modes)
        except (ValueError, TypeError):
            raise InvalidParameterError("modes", modes, "'fixed' or 'sliding' for each contact") from None
        if ContactMode.SEPARATED in self.modes:
            raise InvalidParameterError("modes", modes, "'fixed' or 'sliding' for each contact (not 'separated')")
        self.polygon = polygon
        self.edges = tuple(polygon.edge(k) for k in edges)
        self.m = len(self.edges)
        self.sliding = tuple(i for i, mode in enumerate(self.modes) if mode is ContactMode.SLIDING)
        self.p = len(self.sliding)
        if 2 * self.m < 3 + self.p:
            raise SlidingContactCountError(self.m, self.p)
        #: Per contact, whether its face is curved (a curved object's); ``curved``: whether any is.
        self.curved_contacts = tuple(bool(getattr(e, "curved", False)) for e in self.edges)
        self.curved = any(self.curved_contacts)
        nan2 = np.full(2, np.nan)
        self._origins = np.array([nan2 if c else e.xi_origin for c, e in zip(self.curved_contacts, self.edges)])
        self._tangents = np.array([nan2 if c else e.xi_direction for c, e in zip(self.curved_contacts, self.edges)])
        self._normals = np.array([nan2 if c else e.inward_normal for c, e in zip(self.curved_contacts, self.edges)])
        self._frames0 = np.stack([np.column_stack([n, t]) for n, t in zip(self._normals, self._tangents)])
        #: Per contact, as floats for scalar hot paths: its edge's ξ origin [m], ξ direction and inward normal,
        #: (o_x, o_y, t_x, t_y, n_x, n_y), object frame; None for a contact on a curve (its frame depends on ξ:
        #: ``polygon.local_floats``).
        self.contact_constants: tuple[tuple[float, ...] | None, ...] = tuple(
            None if c else tuple(float(v) for v in (*o, *t, *n))
            for c, o, t, n in zip(self.curved_contacts, self._origins, self._tangents, self._normals))
        bv = np.zeros((2 * self.m, self.p))
        for j, i in enumerate(self.sliding):
            bv[2 * i + 1, j] = 1.0
        self._bv = bv

    def with_modes(self, modes: Sequence[ContactMode | str]) -> "Grasp":
        """The same contacts with other modes."""
        return Grasp(self.polygon, [e.index for e in self.edges], modes)

    # ------------------------------------------------------------------ kernels (validated input)
    def _in_object(self, xi: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Contact points (m, 2) [m], surface frames [n° t°] (m, 2, 2) and curvatures (m,) [1/m], object frame."""
        if not self.curved:
            return self._origins + xi[:, None] * self._tangents, self._frames0, np.zeros(self.m)
        points, frames, kappa = self._origins + xi[:, None] * self._tangents, self._frames0.copy(), np.zeros(self.m)
        for i, curved in enumerate(self.curved_contacts):
            if curved:
                cx, cy, nx, ny, kappa[i] = self.polygon.local_floats(float(xi[i]))
                points[i] = cx, cy
                frames[i] = ((nx, -ny), (ny, nx))
        return points, frames, kappa

    def _lever(self, beta: float, xi: np.ndarray) -> np.ndarray:
        if not self.curved:
            return (self._origins + xi[:, None] * self._tangents) @ rotation(beta).T
        return self._in_object(xi)[0] @ rotation(beta).T

    def _frames(self, beta: float, xi: np.ndarray | None = None) -> np.ndarray:
        if not self.curved:
            return np.einsum("ij,mjk->mik", rotation(beta), self._frames0)
        return np.einsum("ij,mjk->mik", rotation(beta), self._in_object(xi)[1])

    def _xi_for_frames(self, xi: ArrayLike | None) -> np.ndarray | None:
        """``xi`` validated, required when a contact is on a curve (its frame turns with ξ)."""
        if xi is None:
            if self.curved:
                raise InvalidParameterError("xi", None, "ξ [m] of every contact: a contact on a curve has a surface "
                                            "frame that depends on ξ")
            return None
        return as_finite_array("xi", xi, (self.m,))

    def _grasp_matrix(self, r: np.ndarray) -> np.ndarray:
        g = np.zeros((3, 2 * self.m))
        g[0, 0::2] = 1.0
        g[1, 1::2] = 1.0
        g[2, 0::2] = -r[:, 1]  # (⊥r)ᵀ = (-r_y, r_x)
        g[2, 1::2] = r[:, 0]
        return g

    def _grasp_matrix_dot(self, r: np.ndarray, tangents: np.ndarray, omega: float, xi_dot: np.ndarray) -> np.ndarray:
        r_dot = omega * np.column_stack([-r[:, 1], r[:, 0]]) + xi_dot[:, None] * tangents
        g = np.zeros((3, 2 * self.m))
        g[2, 0::2] = -r_dot[:, 1]
        g[2, 1::2] = r_dot[:, 0]
        return g

    def _surface_rotation(self, frames: np.ndarray) -> np.ndarray:
        rf = np.eye(2 * self.m)
        for i in self.sliding:
            rf[2 * i:2 * i + 2, 2 * i:2 * i + 2] = frames[i]
        return rf

    def _surface_rotation_dot(self, frames: np.ndarray, omega: float, rates: np.ndarray | None = None) -> np.ndarray:
        """Ṙ_f with the frames' rotation rates ``rates`` (ω - κ_i ξ̇_i per contact; None: ω for all)."""
        rf = np.zeros((2 * self.m, 2 * self.m))
        for i in self.sliding:
            f = frames[i]
            rate = omega if rates is None else rates[i]
            rf[2 * i:2 * i + 2, 2 * i:2 * i + 2] = rate * np.array([[-f[1, 0], -f[1, 1]], [f[0, 0], f[0, 1]]])
        return rf

    # ------------------------------------------------------------------ state helpers
    def _check(self, pose, xi):
        pose = as_finite_array("pose", pose, (3,))
        xi = as_finite_array("xi", xi, (self.m,))
        return pose, xi

    def points_in_object(self, xi: ArrayLike) -> np.ndarray:
        """Contact points c_i(ξ_i) [m] in the object frame, shape (m, 2)."""
        xi = as_finite_array("xi", xi, (self.m,))
        if not self.curved:
            return self._origins + xi[:, None] * self._tangents
        return self._in_object(xi)[0]

    def curvatures(self, xi: ArrayLike) -> np.ndarray:
        """κ_i(ξ_i) [1/m] of every contact's face at its ξ (0 on an edge), shape (m,)."""
        return self._in_object(as_finite_array("xi", xi, (self.m,)))[2]

    def lever_arms(self, pose: ArrayLike, xi: ArrayLike) -> np.ndarray:
        """r_i = R(β) c_i(ξ_i) [m], hand-frame orientation, shape (m, 2)."""
        pose, xi = self._check(pose, xi)
        return self._lever(pose[2], xi)

    def points(self, pose: ArrayLike, xi: ArrayLike) -> np.ndarray:
        """Contact points [m] in the hand frame, shape (m, 2)."""
        pose, xi = self._check(pose, xi)
        return pose[:2] + self._lever(pose[2], xi)

    def surface_frames(self, pose: ArrayLike, xi: ArrayLike | None = None) -> np.ndarray:
        """R_fi = R(β) [n_i t_i] per contact, shape (m, 2, 2) (columns: normal, tangent); ``xi`` [m] (every
        contact's) is needed on a curve, where the frame turns with ξ."""
        beta = as_finite_array("pose", pose, (3,))[2]
        return self._frames(beta, self._xi_for_frames(xi))

    # ------------------------------------------------------------------ matrices
    def grasp_matrix(self, pose: ArrayLike, xi: ArrayLike) -> np.ndarray:
        r"""G (3 x 2m): column pair i maps contact force f_i to :math:`(f_i, r_i \times f_i)`."""
        return self._grasp_matrix(self.lever_arms(pose, xi))

    def grasp_matrix_dot(self, pose: ArrayLike, xi: ArrayLike, pose_dot: ArrayLike, xi_dot: ArrayLike) -> np.ndarray:
        r"""Exact :math:`\dot G` for object twist ``pose_dot`` = (v_o, ω) and contact rates ``xi_dot``."""
        pose, xi = self._check(pose, xi)
        pose_dot = as_finite_array("pose_dot", pose_dot, (3,))
        xi_dot = as_finite_array("xi_dot", xi_dot, (self.m,))
        r = self._lever(pose[2], xi)
        return self._grasp_matrix_dot(r, self._frames(pose[2], xi)[:, :, 1], pose_dot[2], xi_dot)

    def surface_rotation(self, pose: ArrayLike, xi: ArrayLike | None = None) -> np.ndarray:
        """R_f (2m x 2m): block R_fi for sliding contacts, I_2 for fixed ones (eq. 3.1.7); ``xi`` as in
        :meth:`surface_frames`."""
        return self._surface_rotation(self.surface_frames(pose, xi))

    def surface_rotation_dot(self, pose: ArrayLike, pose_dot: ArrayLike, xi: ArrayLike | None = None,
                             xi_dot: ArrayLike | None = None) -> np.ndarray:
        r"""Exact :math:`\dot R_f`: :math:`(\omega - \kappa_i\dot\xi_i) \perp R_{fi}` on sliding blocks, 0
        elsewhere (``xi`` and ``xi_dot`` [m/s] needed on a curve; on edges κ = 0)."""
        frames = self.surface_frames(pose, xi)
        omega = as_finite_array("pose_dot", pose_dot, (3,))[2]
        if not self.curved:
            return self._surface_rotation_dot(frames, omega)
        if xi_dot is None:
            raise InvalidParameterError("xi_dot", None, "ξ̇ [m/s] of every contact: a contact on a curve turns its "
                                        "frame at κ ξ̇")
        kappa = self._in_object(as_finite_array("xi", xi, (self.m,)))[2]
        rates = omega - kappa * as_finite_array("xi_dot", xi_dot, (self.m,))
        return self._surface_rotation_dot(frames, omega, rates)

    def sliding_directions(self) -> np.ndarray:
        """B_v (2m x p): the sliding direction (0, 1) of each sliding contact in its surface frame."""
        return self._bv.copy()

    def force_basis(self, signs: ArrayLike, friction: FrictionLike) -> np.ndarray:
        r"""B_f (2m x (2m - p)): :math:`(1, s_i \mu_{k,i})^T` per sliding contact, :math:`I_2` per fixed one.

        ``signs`` are the sliding directions :math:`s_i = \mathrm{sign}(\dot\xi_i) \in \{-1, +1\}`
        of the sliding contacts, in order; ``friction`` is one :class:`~regrasp.core.contact.Friction` or
        coefficient [-] for all contacts, or one per contact (:func:`~regrasp.core.contact.as_frictions`):
        a sliding contact's kinetic coefficient :math:`\mu_{k,i}` is used.
        """
        signs = as_finite_array("signs", signs, (self.p,))
        if not np.all(np.isin(signs, (-1.0, 1.0))):
            raise InvalidParameterError("signs", signs, "+1 or -1 per sliding contact")
        frictions = as_frictions(friction, self.m)
        bf = np.zeros((2 * self.m, 2 * self.m - self.p))
        col, k = 0, 0
        for i, mode in enumerate(self.modes):
            if mode is ContactMode.SLIDING:
                bf[2 * i:2 * i + 2, col] = (1.0, signs[k] * frictions[i].kinetic)
                col, k = col + 1, k + 1
            else:
                bf[2 * i:2 * i + 2, col:col + 2] = np.eye(2)
                col += 2
        return bf

    def sliding_grasp_matrix(
        self, pose: ArrayLike, xi: ArrayLike, signs: ArrayLike, friction: FrictionLike
    ) -> np.ndarray:
        """G_f = G R_f B_f (3 x (2m - p)), the sliding grasp matrix (eq. 3.4.5; ``friction`` as in
        :meth:`force_basis`)."""
        return self.grasp_matrix(pose, xi) @ self.surface_rotation(pose, xi) @ self.force_basis(signs, friction)

    def friction_map(self, pose: ArrayLike, xi: ArrayLike, signs: ArrayLike, friction: FrictionLike) -> np.ndarray:
        r"""P = B_v^T B_f G_f^{-1} (p x 3, eq. 3.4.9): :math:`f_\xi = P (M_o \ddot X - f_g)`, with the
        sliding contact's kinetic coefficient (``friction`` as in :meth:`force_basis`).

        Defined only when G_f is square (m = 2, p = 1): otherwise the friction force is not
        determined by the object's motion alone.
        """
        if 2 * self.m - self.p != 3:
            raise InvalidParameterError(
                "grasp", f"m={self.m}, p={self.p}", "m = 2 fingers with p = 1 sliding contact for P (eq. 3.4.9)"
            )
        frictions = as_frictions(friction, self.m)
        bf = self.force_basis(signs, frictions)
        gf = self.grasp_matrix(pose, xi) @ self.surface_rotation(pose, xi) @ bf
        return self._bv.T @ bf @ np.linalg.inv(gf)

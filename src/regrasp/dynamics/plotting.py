"""PNG figure of when a contact can slide, after the paper's Figure 3.4 (matplotlib, headless).

* :func:`plot_slide_feasibility` (Fig. 3.4): the object, the fingers and, per slide direction, the predicted contact
  forces inside their friction cones (:func:`~regrasp.dynamics.sliding.sliding_feasibility`), and whether the slide
  is possible.

matplotlib is imported on first use (:mod:`regrasp.core.figures`).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ..core.figures import MM, pyplot, save_figure

if TYPE_CHECKING:
    from ..core.contact import FrictionLike
    from ..core.polygon import ConvexPolygon
    from ..model.finger import Finger
    from .sliding import SlideFeasibility

__all__ = ["plot_slide_feasibility"]


def plot_slide_feasibility(polygon: ConvexPolygon, pose: ArrayLike, fingers: Sequence[Finger],
                           points_in_hand: np.ndarray | Sequence[ArrayLike], edges: Sequence[int],
                           friction: FrictionLike, results: Sequence[SlideFeasibility], path: str | Path, *,
                           gravity_in_hand: ArrayLike = (0.0, -9.81), title: str = "") -> Path:
    """Figure 3.4: the object, the fingers and, per slide direction, the predicted contact forces
    inside their friction cones, and whether the slide is possible.

    Args:
        polygon: The object; ``pose`` its pose (x, y, β) in the hand frame.
        fingers: The fingers (drawn through their inverse kinematics to ``points_in_hand``).
        points_in_hand: Contact points (m, 2) [m], on edges ``edges``.
        friction: The contacts' :class:`~regrasp.core.contact.Friction` (one for all, a coefficient, or one
            per contact): cone half-angle atan μ_k at each panel's sliding contact, atan μ_s elsewhere.
        results: One :class:`~regrasp.dynamics.sliding.SlideFeasibility` per panel.
        path: Output PNG.
    """
    from matplotlib.patches import Polygon as PolygonPatch

    from ..core.contact import ContactMode, as_frictions
    from ..core.planar import rotation

    plt = pyplot()

    friction = as_frictions(friction, len(edges))
    pose = np.asarray(pose, dtype=float)
    verts = polygon.vertices_in(pose) * MM
    rot = rotation(pose[2])
    chains = [finger.joint_positions_in_hand(finger.inverse_kinematics(point)) * MM
              for finger, point in zip(fingers, points_in_hand)]
    everything = np.vstack([verts, *chains])
    fig, axes = plt.subplots(1, len(results), figsize=(5.2 * len(results), 5.6), squeeze=False)
    for ax, res in zip(axes[0], results):
        ax.add_patch(PolygonPatch(verts, closed=True, facecolor="#d9d9d9", edgecolor="k", lw=1.5))
        for joints in chains:
            ax.plot(joints[:, 0], joints[:, 1], "-o", color="#4d4d4d", lw=4, ms=5, solid_capstyle="round")
        scale = 25.0 / max(1e-9, np.abs(res.forces_surface).max())  # [mm per N]
        for i, (point, k) in enumerate(zip(points_in_hand, edges)):
            n = rot @ polygon.edge(k).inward_normal
            t = rot @ polygon.edge(k).xi_direction
            p = np.asarray(point) * MM
            half = np.arctan(friction[i].coefficient(ContactMode.SLIDING if i == res.contact else ContactMode.FIXED))
            for side in (1.0, -1.0):  # the cone of forces the finger can push with, around n
                d = np.cos(half) * n + side * np.sin(half) * t
                ax.plot([p[0], p[0] + 30 * d[0]], [p[1], p[1] + 30 * d[1]], color="#66a61e", lw=1, ls=":")
            force = res.forces_surface[i, 0] * n + res.forces_surface[i, 1] * t
            color = "#1b9e77" if res.forces_surface[i, 0] >= 0 else "#d95f02"
            ax.annotate("", xy=p + scale * force, xytext=p, arrowprops=dict(arrowstyle="-|>", color=color, lw=2.2))
            ax.text(*(p + scale * force + 4 * n), f"{res.forces_surface[i, 0]:.2f} N", fontsize=8, color=color,
                    ha="center")
            if i == res.contact:
                ax.annotate("", xy=p + 14 * res.direction * t - 6 * n, xytext=p - 6 * n,
                            arrowprops=dict(arrowstyle="->", color="#7570b3", lw=1.8))
        g = np.asarray(gravity_in_hand, dtype=float)
        c = pose[:2] * MM
        unit = g / max(np.linalg.norm(g), 1e-9)
        ax.annotate("", xy=c + 12 * unit, xytext=c, arrowprops=dict(arrowstyle="-|>", color="k", lw=1.2))
        ax.text(*(c + 15 * unit), "g", ha="center", va="center")
        verdict = "possible" if res.possible else "impossible"
        ax.set_title(f"slide {'up' if res.direction > 0 else 'down'}: {verdict}"
                     + ("" if res.possible else f"\n{res.reason}"), fontsize=9)
        ax.set_aspect("equal")
        ax.set_xlabel("x [mm]")
        ax.set_ylabel("y [mm]")
        lo, hi = np.min(everything, axis=0) - 15, np.max(everything, axis=0) + 35
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
    if title:
        fig.suptitle(title, fontsize=10)
    return save_figure(fig, path)

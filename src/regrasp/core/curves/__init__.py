r"""``regrasp.core.curves``: objects bounded by smooth convex closed curves (the paper's §3.1 "general curve in the
plane"): discs, ellipses, rounded polygons and support-function curves, each with one contact face whose ξ is the
arc length (:mod:`regrasp.core.curves.base`)."""

from .base import CurvedObject, CurveFace, SurfacePoint
from .conics import Disc, Ellipse
from .rounded import RoundedPolygon, rounded
from .support import SupportCurve

__all__ = ["CurveFace", "CurvedObject", "Disc", "Ellipse", "RoundedPolygon", "SupportCurve", "SurfacePoint",
           "rounded"]

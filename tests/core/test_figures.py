"""What the figures share: one colour per failure kind, the same in every figure, and none of them a success's."""

import numpy as np
from matplotlib.colors import to_rgb

from regrasp.core.curves import Disc, RoundedPolygon
from regrasp.core.events import FailureKind
from regrasp.core.figures import FAILURE_COLOUR, FAILURE_COLOURS, MM, SUCCESS_COLOUR, pyplot, shade_arcs


def test_every_failure_kind_has_its_own_colour_and_none_is_a_successs():
    assert set(FAILURE_COLOURS) == {k.value for k in FailureKind}
    colours = [to_rgb(c) for c in FAILURE_COLOURS.values()]
    assert len(set(colours)) == len(colours)
    assert to_rgb(SUCCESS_COLOUR) not in colours and to_rgb(SUCCESS_COLOUR) != to_rgb(FAILURE_COLOUR)
    for r, g, b in colours:  # (no failure is drawn green: green is success)
        assert not (g > r + 0.15 and g > b + 0.15), (r, g, b)


def test_a_rounded_polygon_s_arcs_are_shaded_where_its_corners_are_and_a_disc_has_none():
    box = RoundedPolygon([[-0.03, -0.03], [0.03, -0.03], [0.03, 0.03], [-0.03, 0.03]], 0.01, mass=0.1)
    fig, ax = pyplot().subplots()
    lo, hi = -0.05, 0.3  # (more than a turn round the boundary)
    assert shade_arcs(ax, box, lo, hi)
    spans = sorted((p.get_y() / MM, (p.get_y() + p.get_height()) / MM) for p in ax.patches)
    arcs = [(a, b) for kind, _, a, b in box.pieces_between(lo, hi) if kind == "arc"]
    np.testing.assert_allclose(spans, arcs, atol=1e-12)
    quarter = 0.5 * np.pi * 0.01  # (each corner a quarter circle, each straight part 40 mm)
    assert len(arcs) == 7 and all(abs(b - a - quarter) < 1e-12 for a, b in arcs[1:-1])
    np.testing.assert_allclose(np.diff([a for a, _ in arcs[1:]]), 0.04 + quarter, atol=1e-12)
    assert not shade_arcs(ax, Disc(0.04, mass=0.1), lo, hi)
    pyplot().close(fig)

"""What the figures share: one colour per failure kind, the same in every figure, and none of them a success's."""

from matplotlib.colors import to_rgb

from regrasp.core.events import FailureKind
from regrasp.core.figures import FAILURE_COLOUR, FAILURE_COLOURS, SUCCESS_COLOUR


def test_every_failure_kind_has_its_own_colour_and_none_is_a_successs():
    assert set(FAILURE_COLOURS) == {k.value for k in FailureKind}
    colours = [to_rgb(c) for c in FAILURE_COLOURS.values()]
    assert len(set(colours)) == len(colours)
    assert to_rgb(SUCCESS_COLOUR) not in colours and to_rgb(SUCCESS_COLOUR) != to_rgb(FAILURE_COLOUR)
    for r, g, b in colours:  # (no failure is drawn green: green is success)
        assert not (g > r + 0.15 and g > b + 0.15), (r, g, b)

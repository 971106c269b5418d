"""The two-finger slide rule (regrasp.schedule.slide_rule) against the sliding predicate, and its corollaries.

The predicate (regrasp.dynamics.sliding.sliding_feasibility) solves the object's balance with the slider on
its kinetic cone edge and the holder inside its static cone; it knows nothing of the rule. On
random rectangles, orientations, heights and friction pairs, held still against gravity along
their side edges, the rule's range must say exactly when the predicate allows the slide.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from factories import rot
from regrasp import Friction, Grasp
from regrasp.core.exceptions import InvalidParameterError
from regrasp.core.polygon import ConvexPolygon
from regrasp.dynamics.internal_force.settings import InternalForceSettings
from regrasp.dynamics.sliding import sliding_feasibility
from regrasp.schedule.slide_rule import two_finger_slide_range

#: the bare physics: push >= 0, no cone margin, no force limit
BARE = InternalForceSettings(f_min=0.0, friction_margin=0.0)


def _height(edge: int, xi: float) -> float:
    """Height of a contact above the centre along the side edges (edge 1: ξ up; edge 3: ξ down)."""
    return xi if edge == 1 else -xi


@pytest.mark.parametrize("seed", range(6))
def test_the_rule_says_exactly_when_the_predicate_allows_the_slide(seed):
    rng = np.random.default_rng(seed)
    checked = {True: 0, False: 0}
    for _ in range(60):
        width, height = rng.uniform(0.04, 0.15), rng.uniform(0.03, 0.2)
        box = ConvexPolygon.rectangle(width, height, mass=rng.uniform(0.02, 0.5))
        grasp = Grasp(box, [1, 3], ["fixed", "fixed"])
        beta = rng.uniform(-np.pi, np.pi)
        gravity = rot(beta) @ np.array([0.0, -9.81])  # along the side edges, whatever the pose
        frictions = []
        for _ in range(2):
            ms = rng.uniform(0.1, 1.5)
            frictions.append(Friction(ms, ms * rng.choice([1.0, rng.uniform(0.05, 1.0)])))
        slider = int(rng.integers(0, 2))
        holder = 1 - slider
        xi = np.array([rng.uniform(-height / 2, height / 2) for _ in range(2)])
        edges = (1, 3)
        for upward in (True, False):
            up_in_xi = 1.0 if edges[slider] == 1 else -1.0
            direction = up_in_xi if upward else -up_in_xi
            rule = two_finger_slide_range(width, frictions[slider], frictions[holder], upward=upward)
            delta = _height(edges[slider], xi[slider]) - _height(edges[holder], xi[holder])
            if min(abs(delta - rule.low), abs(delta - rule.high)) < 1e-6 * width:
                continue  # on a bound
            verdict = sliding_feasibility(grasp, (0.0, 0.1, beta), xi, (0.0, 0.0, 0.0), slider, direction, frictions,
                                          object_mass=box.mass, object_inertia=box.inertia, gravity_in_hand=gravity,
                                          settings=BARE)
            assert verdict.possible == rule.contains(delta), (upward, delta, rule, verdict.reason)
            if verdict.possible:
                weight = box.mass * 9.81
                assert verdict.normal_forces[slider] == pytest.approx(rule.normal_force(delta, width, weight), rel=1e-6)
            checked[verdict.possible] += 1
    assert checked[True] >= 10 and checked[False] >= 10  # both answers, often


@pytest.mark.parametrize("mu", [0.1, 0.5, 1.3])
def test_the_lower_contact_never_slides_down_and_with_one_mu_the_upper_never_slides_up(mu):
    width = 0.1
    down = two_finger_slide_range(width, Friction(mu), Friction(mu), upward=False)
    up = two_finger_slide_range(width, Friction(mu), Friction(mu), upward=True)
    assert down.empty  # μ_s = μ_k: no downward slide at all
    assert up.high == pytest.approx(0.0) and up.low < 0  # upward only from at or below the holder
    for ms in (mu, 1.5 * mu, 3 * mu):
        assert two_finger_slide_range(width, Friction(ms, mu), Friction(ms, mu), upward=False).low > 0
    assert not two_finger_slide_range(width, Friction(mu, 0.5 * mu), Friction(mu), upward=False).empty


def test_bad_width_is_rejected():
    with pytest.raises(InvalidParameterError):
        two_finger_slide_range(-0.1, Friction(0.5), Friction(0.5), upward=True)
    with pytest.raises(InvalidParameterError):
        two_finger_slide_range(math.nan, Friction(0.5), Friction(0.5), upward=True)

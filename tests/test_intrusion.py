"""How deep the stylus cuts into the part (planning/intrusion.py), against analytic
spheres, where the depth is known in closed form."""

from __future__ import annotations

import numpy as np
import pytest
from fuzzing import examples
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from probegen.planning.collision import SphereObstacle, Stylus, describe
from probegen.planning.intrusion import DEPTH_TOLERANCE, Element, deepest, depth_at, elements

coord = st.floats(-20.0, 20.0, allow_nan=False)


@settings(max_examples=examples(60))
@given(x=coord, y=coord, z=coord, big=st.floats(1.0, 15.0), r=st.floats(0.3, 5.0))
def test_the_ball_s_depth_is_the_overlap_of_two_spheres(x: float, y: float, z: float,
                                                        big: float, r: float) -> None:
    """A ball of radius ``r`` at (x, y, z) and a sphere of radius ``big`` at the origin:
    the part reaches ``r + big - d`` into the ball (its centre inside too), 0 apart."""
    sphere = SphereObstacle(np.zeros((1, 3)), np.array([big]))
    centre = np.array([x, y, z])
    side, up = depth_at(sphere.overlaps, centre, Element("ball", r), beneath=sphere.beneath)
    expected = max(0.0, r + big - float(np.linalg.norm(centre)))
    assert up is None
    assert side == pytest.approx(expected, abs=2.0 * DEPTH_TOLERANCE)


@settings(max_examples=examples(60))
@given(x=st.floats(-12.0, 12.0), z=st.floats(-30.0, 30.0), big=st.floats(1.0, 10.0))
def test_a_cylinder_s_side_and_up_figures(x: float, z: float, big: float) -> None:
    """The body (radius 5, from 10 to 40 above the ball's centre at (x, 0, z)) against a
    sphere of radius ``big`` at the origin; the analytic check rounds the cylinder's ends
    (a capsule: the distance to its axis segment less the radius), as its clearance
    does.  From the side: the radius less what clears, ``5 + big - d`` with ``d`` the
    sphere's centre from the axis segment; from below: how far the lower end must rise
    for the rest to clear, the whole length when the sphere lies above its top."""
    sphere = SphereObstacle(np.zeros((1, 3)), np.array([big]))
    side, up = depth_at(sphere.overlaps, np.array([x, 0.0, z]), Element("body", 5.0, 10.0,
                                                                        40.0))
    low, high = z + 10.0, z + 40.0  # the axis segment's ends, work Z
    d = float(np.hypot(x, min(max(0.0, low), high)))
    assume(abs(d - (big + 5.0)) > 0.01)
    if d > big + 5.0:
        assert (side, up) == (0.0, 0.0)
        return
    assert side == pytest.approx(min(5.0, 5.0 + big - d), abs=2 * DEPTH_TOLERANCE)
    level = float(np.sqrt((big + 5.0) ** 2 - x ** 2))  # a lower end from here clears
    assume(abs(high - level) > 0.01)
    expected = 30.0 if high < level else max(0.0, level - low)
    assert up == pytest.approx(expected, abs=2 * DEPTH_TOLERANCE)


def test_the_deepest_point_of_a_move_through_a_sphere() -> None:
    """A ball of 1 mm radius straight down through a sphere of 10 at the origin: deepest
    where the centres meet, 11 mm (within the sampling's half spacing)."""
    sphere = SphereObstacle(np.zeros((1, 3)), np.array([10.0]))
    parts = elements(1.0, ())
    hit = deepest(sphere.overlaps, parts, np.array([0.0, 0.0, 11.0]),
                  np.array([0.0, 0.0, -40.0]), sphere.beneath)
    assert hit is not None and hit.element == "ball"
    assert 10.5 < hit.depth <= 11.0 + DEPTH_TOLERANCE
    assert deepest(sphere.overlaps, parts, np.array([0.0, 0.0, 12.0]),
                   np.array([5.0, 0.0, 12.0]), sphere.beneath) is None


def test_the_message_names_the_body_and_its_depth() -> None:
    """The body 30 mm above a ball beside a sphere of 20: the body meets it, the ball
    does not: the message is the body's, with its measured figures."""
    sphere = SphereObstacle(np.array([[0.0, 0.0, 40.0]]), np.array([20.0]))
    stylus = Stylus(1.0, 0.5, 30.0, 6.6, 65.0)
    centre = np.array([24.0, 0.0, 0.0])  # the body's axis 24 from the sphere's centre
    ball, shank = sphere.clearance(centre, stylus)
    assert ball > 0.0 > shank
    said = describe(sphere, ball - 0.15, shank - 0.15, 0.15, centre, stylus, centre)
    # level with the sphere's centre: 6.6 + 20 - 24 = 2.6 in from the side
    assert said.startswith("the probe body cuts 2.600 mm (2.600 mm in from its side, ")
    assert said.endswith("into sphere 1; expected a clearance of at least 0.150 mm")

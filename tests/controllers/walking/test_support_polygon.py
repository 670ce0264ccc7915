"""The support polygon of the soles on the ground and a point's signed margin inside it."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial import Delaunay

from redundancy_gym.controllers.exceptions import ControllerError
from redundancy_gym.controllers.walking import SOLE_HALF_WIDTH, SOLE_X, sole_corners, support_margin, support_polygon

FEET = np.array([[0.0, -0.09, 0.0], [0.0, 0.09, 0.0]])  # right, left: the standing pose's sole points


def test_single_sole_margins() -> None:
    polygon = support_polygon(FEET, (True, False))
    assert polygon.shape == (4, 2)
    right = FEET[0, :2]
    # the sole point: nearest edge the side (0.075 m), not the heel (0.095) or the toe tip (0.165)
    assert support_margin(right, polygon) == pytest.approx(SOLE_HALF_WIDTH)
    assert support_margin(right + (0.15, 0.0), polygon) == pytest.approx(SOLE_X[1] - 0.15)  # near the toe tip
    assert support_margin(right + (0.0, 0.1), polygon) == pytest.approx(SOLE_HALF_WIDTH - 0.1)  # outside the side
    # outside a corner: the Euclidean distance to it (a 3-4-5 triangle), negative
    corner = np.array((SOLE_X[1], -0.09 + SOLE_HALF_WIDTH))
    assert support_margin(corner + (0.03, 0.04), polygon) == pytest.approx(-0.05)


def test_double_support_is_the_hull_of_both_soles() -> None:
    polygon = support_polygon(FEET, (True, True))
    assert polygon.shape == (4, 2)  # two side-by-side rectangles: their hull is one rectangle
    assert np.ptp(polygon[:, 1]) == pytest.approx(2 * (0.09 + SOLE_HALF_WIDTH))
    # between the feet, off both soles but inside the hull: the nearest edge is the heel line
    assert support_margin((0.0, 0.0), polygon) == pytest.approx(-SOLE_X[0])
    # a foot ahead of the other: the hull's slanted edge bounds the point between them
    ahead = FEET.copy()
    ahead[1, 0] = 0.3
    slanted = support_polygon(ahead, (True, True))
    assert len(slanted) == 6
    inside = support_margin((0.15, 0.0), slanted)
    assert 0.0 < inside < SOLE_HALF_WIDTH + 0.09


def test_yaw_turns_the_sole() -> None:
    corners = sole_corners((0.0, 0.0), math.pi / 2)  # heading +y: the toe tip at y = +0.165
    assert corners[:, 1].max() == pytest.approx(SOLE_X[1])
    assert corners[:, 0].max() == pytest.approx(SOLE_HALF_WIDTH)
    polygon = support_polygon(np.zeros((2, 3)), (True, False), yaw=(math.pi / 2, 0.0))
    assert support_margin((0.0, 0.12), polygon) == pytest.approx(SOLE_X[1] - 0.12)


def test_margin_is_the_distance_to_the_boundary_on_random_points() -> None:
    """Inside, the margin is the distance to the nearest edge; outside, minus the distance to the polygon: checked
    against a dense sampling of the boundary, and its sign against scipy's triangulation of the hull."""
    rng = np.random.default_rng(0)
    ahead = FEET.copy()
    ahead[1, :2] += (0.25, 0.05)
    polygon = support_polygon(ahead, (True, True), yaw=(0.0, 0.3))
    edges = zip(polygon, np.roll(polygon, -1, axis=0), strict=True)
    hull = Delaunay(polygon)
    boundary = np.concatenate([a + np.linspace(0.0, 1.0, 2001)[:, None] * (b - a) for a, b in edges])
    for point in rng.uniform((-0.3, -0.4), (0.7, 0.4), size=(200, 2)):
        nearest = float(np.min(np.linalg.norm(boundary - point, axis=1)))
        margin = support_margin(point, polygon)
        assert abs(margin) == pytest.approx(nearest, abs=2e-4)
        assert (margin > 0.0) == bool(hull.find_simplex(point) >= 0)


def test_no_foot_on_the_ground_has_no_polygon() -> None:
    with pytest.raises(ControllerError, match="no foot"):
        support_polygon(FEET, (False, False))

"""The biped's support polygon (the convex hull of the soles on the ground) and a point's signed distance inside it:
how much room a ZMP leaves to the polygon's edge (:func:`support_margin`).

The sole of ``assets/biped.xml`` is a plate and a toe box, 0.26 x 0.15 m around the sole point (the foothold of
:class:`~redundancy_gym.controllers.walking.WalkingPattern`): from :data:`SOLE_X` behind it to the toe tip ahead of
it, :data:`SOLE_HALF_WIDTH` to either side, turned by the foot's heading.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..exceptions import ControllerError

__all__ = ["SOLE_HALF_WIDTH", "SOLE_X", "sole_corners", "support_margin", "support_polygon"]

SOLE_X: tuple[float, float] = (-0.095, 0.165)
"""The sole's extent along the foot [m]: heel and toe tip, from the sole point (biped.xml's plate and toe boxes)."""
SOLE_HALF_WIDTH = 0.075
"""Half the sole's width [m]."""


def sole_corners(position: ArrayLike, yaw: float = 0.0) -> NDArray[np.float64]:
    """The four corners (4, 2) [m] of a sole whose sole point is at ``position`` (x, y, ...) and heading ``yaw``
    [rad], counter-clockwise from the heel's right corner."""
    p = np.asarray(position, dtype=np.float64)
    c, s = math.cos(yaw), math.sin(yaw)
    local = ((SOLE_X[0], -SOLE_HALF_WIDTH), (SOLE_X[1], -SOLE_HALF_WIDTH), (SOLE_X[1], SOLE_HALF_WIDTH),
             (SOLE_X[0], SOLE_HALF_WIDTH))  # fmt: skip
    return np.array([(p[0] + c * x - s * y, p[1] + s * x + c * y) for x, y in local])


def support_polygon(feet: ArrayLike, contact: Sequence[bool], yaw: ArrayLike | None = None) -> NDArray[np.float64]:
    """The convex hull (n, 2) [m], counter-clockwise, of the soles on the ground: ``feet`` the sole points (2, >= 2)
    [m] (rows right, left), ``contact`` which touch the ground, ``yaw`` their headings (2,) [rad] (0 without).

    Raises:
        ControllerError: no foot on the ground (a flight phase has no support polygon).
    """
    points = np.asarray(feet, dtype=np.float64)
    headings = np.zeros(len(points)) if yaw is None else np.asarray(yaw, dtype=np.float64)
    corners = [sole_corners(points[i], float(headings[i])) for i in range(len(points)) if contact[i]]
    if not corners:
        raise ControllerError("support_polygon: no foot on the ground")
    return _convex_hull(np.concatenate(corners))


def support_margin(point: ArrayLike, polygon: ArrayLike) -> float:
    """Signed distance [m] of ``point`` (x, y) from the edge of the convex ``polygon`` (counter-clockwise, as
    :func:`support_polygon` gives it): positive inside (the room to the nearest edge), negative outside (minus the
    distance to the polygon)."""
    p = np.asarray(point, dtype=np.float64)[:2]
    vertices = np.asarray(polygon, dtype=np.float64)
    inside = True
    nearest = math.inf
    for a, b in zip(vertices, np.roll(vertices, -1, axis=0), strict=True):
        edge = b - a
        length = math.hypot(edge[0], edge[1])
        # left of every counter-clockwise edge: inside
        if edge[0] * (p[1] - a[1]) - edge[1] * (p[0] - a[0]) < 0.0:
            inside = False
        w = min(max(float(np.dot(p - a, edge)) / (length * length), 0.0), 1.0)
        nearest = min(nearest, math.hypot(*(p - (a + w * edge))))
    return nearest if inside else -nearest


def _convex_hull(points: NDArray[np.float64]) -> NDArray[np.float64]:
    """Andrew's monotone chain: the hull's vertices counter-clockwise, collinear points dropped."""
    ordered = sorted(map(tuple, points.tolist()))

    def turn(o: tuple[float, ...], a: tuple[float, ...], b: tuple[float, ...]) -> float:
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower: list[tuple[float, ...]] = []
    for q in ordered:
        while len(lower) >= 2 and turn(lower[-2], lower[-1], q) <= 0.0:
            lower.pop()
        lower.append(q)
    upper: list[tuple[float, ...]] = []
    for q in reversed(ordered):
        while len(upper) >= 2 and turn(upper[-2], upper[-1], q) <= 0.0:
            upper.pop()
        upper.append(q)
    return np.array(lower[:-1] + upper[:-1])

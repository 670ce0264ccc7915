"""Obstacles on the biped's path (the BipedObstacles scene) and seeded course generators.

An :class:`Obstacle` is a box, a triangular prism or a cylinder standing in the world. It gives the three things a
scene and a controller need: its MJCF geom (with a mesh asset for the prism), its swept-sphere model (volumes of
:mod:`redundancy_gym.geometry` that contain the shape) and its axis-aligned bounding box. The course generators
return tuples of obstacles: the monograph's two experiments (:func:`beam_course`, :func:`triangle_course`) and a
seeded random course (:func:`random_course`). :mod:`redundancy_gym.assets.biped_scene` composes the MJCF.

Coordinates are the world frame of the biped scene: x forward along the walking direction, y to the robot's left,
z up, the ground at z = 0, the robot standing at the origin.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..geometry import LSS, SSV, TSS
from ..validation import check_choice, check_range_pair, check_real, check_real_array

__all__ = [
    "BEAM_POSITION",
    "BESIDE",
    "COURSE_KINDS",
    "FOOT_PATH_Y",
    "FOOT_Y",
    "MAX_OBSTACLE_DEPTH",
    "NOMINAL_STEP_LENGTH",
    "OBSTACLE_COLORS",
    "OBSTACLE_KINDS",
    "OBSTACLE_SHAPES",
    "SOLE_LENGTH",
    "SOLE_WIDTH",
    "STEP_OVER",
    "SWING_AROUND",
    "MjcfElement",
    "MjcfParts",
    "Obstacle",
    "beam_course",
    "random_course",
    "triangle_course",
]

OBSTACLE_SHAPES = ("box", "prism", "cylinder")
"""Shapes of :class:`Obstacle`: ``size`` is (depth, width, height) [m] for a box and a prism, (radius, height) [m]
for a cylinder."""
COURSE_KINDS = ("step_over", "swing_around", "beside")
"""The classes of obstacles a random course draws from (uniformly)."""
OBSTACLE_KINDS = (*COURSE_KINDS, "custom")
"""Every ``Obstacle.kind``: a course class, or ``"custom"`` for an obstacle given by hand."""
OBSTACLE_COLORS: dict[str, tuple[float, float, float, float]] = {
    "step_over": (0.9, 0.45, 0.1, 1.0),
    "swing_around": (0.8, 0.15, 0.15, 1.0),
    "beside": (0.2, 0.45, 0.75, 1.0),
    "custom": (0.85, 0.7, 0.1, 1.0),
}
"""RGBA per obstacle class: saturated colours that stand out against the grey robot and the grey checker floor."""

NOMINAL_STEP_LENGTH = 0.32
"""Step length [m] of the walking reference at 0.4 m/s: the nominal footholds lie at ``x = (j - 1) * 0.32`` for
the j-th foothold, j >= 2 (the first two are the standing feet at x = 0; odd j are left footfalls)."""
SOLE_LENGTH, SOLE_WIDTH = 0.26, 0.15
"""Sole size [m] (x, y) of the biped (``assets/biped.xml``): the sole point lies 0.165 m behind the toe tip and
0.095 m ahead of the heel."""
FOOT_Y = 0.09
"""Lateral position [m] of the feet's centre lines (+ left, - right)."""
FOOT_PATH_Y = (FOOT_Y - 0.5 * SOLE_WIDTH, FOOT_Y + 0.5 * SOLE_WIDTH)
"""The band of y [m] the left sole sweeps when walking straight, (0.015, 0.165); the right one's is mirrored."""

STEP_OVER: dict[str, tuple[float, float]] = {
    "height": (0.04, 0.18),
    "depth": (0.04, 0.15),
    "width": (0.30, 0.80),
    "lateral_offset": (-0.05, 0.05),
}
"""Ranges [m] of a random course's ``step_over`` obstacles: boxes (beams) across the path, centred on y = 0 plus a
uniform lateral offset; depth along x, width along y."""
SWING_AROUND: dict[str, tuple[float, float]] = {
    "height": (0.20, 0.40),
    "width": (0.05, 0.13),
    "overlap": (0.0, 0.10),
    "prism_depth": (0.06, 0.12),
}
"""Ranges [m] of a random course's ``swing_around`` obstacles: tall narrow triangular prisms or posts (cylinders,
``width`` their diameter), half each, beside one foot (left or right, half each) and reaching into that foot's path
(:data:`FOOT_PATH_Y`) from its outer edge by ``overlap``: the obstacle's y extent overlaps the sole's band by
exactly ``overlap`` (drawn first; the width is then drawn from ``[max(0.05, overlap), 0.13]`` so that it can).
The prisms' depth along x (the monograph's triangle is 0.09 m deep) is ``prism_depth``."""
BESIDE: dict[str, tuple[float, float]] = {
    "height": (0.10, 0.40),
    "gap": (0.05, 0.30),
    "depth": (0.10, 0.40),
    "width": (0.10, 0.30),
}
"""Ranges [m] of a random course's ``beside`` obstacles: boxes left or right of the path (half each), ``gap``
outside the outer edge of the sole bands (|y| >= 0.165 + gap: clear of both soles' paths by at least 5 cm)."""
MAX_OBSTACLE_DEPTH = max(
    STEP_OVER["depth"][1], SWING_AROUND["prism_depth"][1], SWING_AROUND["width"][1], BESIDE["depth"][1]
)
"""Largest extent [m] along x of a random course's obstacles (0.4 m, the deepest ``beside`` block)."""


class MjcfElement(NamedTuple):
    """One MJCF element: its tag (``"geom"``, ``"mesh"``) and attributes as MJCF text."""

    tag: str
    attributes: dict[str, str]


class MjcfParts(NamedTuple):
    """The MJCF of an obstacle: ``assets`` (elements of ``<asset>``, the prism's mesh) and ``geoms`` (elements of
    ``<worldbody>``)."""

    assets: tuple[MjcfElement, ...]
    geoms: tuple[MjcfElement, ...]


def _text(values: Sequence[float] | NDArray[np.float64]) -> str:
    """MJCF text of numbers (17 significant digits: the compiled model sees the float64 values)."""
    return " ".join(f"{float(v):.17g}" for v in values)


@dataclass(frozen=True)
class Obstacle:
    """A static obstacle: a box, a triangular prism or a cylinder, turned by ``yaw`` about the vertical.

    Attributes:
        shape: ``"box"``, ``"prism"`` or ``"cylinder"``.
        center: (x, y, z) [m], the centre of the obstacle's bounding box before the yaw turn, which the yaw turns
            about (a shape standing on the ground of height h has z = h / 2).
        size: a box: full extents (depth along x, width along y, height) [m] in its own frame; a prism: the
            triangle in the y-z plane with base ``width`` on its bottom face and its apex ``height`` above the base's
            centre, extruded ``depth`` along x, as (depth, width, height) [m]; a cylinder: (radius, height) [m],
            vertical.
        yaw: rotation [rad] about the vertical axis through ``center`` (0: depth along the walking direction x).
        kind: the class it was drawn from (:data:`COURSE_KINDS`), or ``"custom"``; reports count by it.

    Raises:
        ValueError: an unknown shape or kind, a ``size`` of the wrong length or not > 0, or a non-finite number.
    """

    shape: str
    center: tuple[float, float, float]
    size: tuple[float, ...]
    yaw: float = 0.0
    kind: str = "custom"

    def __post_init__(self) -> None:
        check_choice("shape", self.shape, OBSTACLE_SHAPES)
        check_choice("kind", self.kind, OBSTACLE_KINDS)
        center = check_real_array(
            "center", self.center, shape=(3,), unit="m", what="an (x, y, z) triple of finite real numbers"
        )
        n = 2 if self.shape == "cylinder" else 3
        what = ("(radius, height)" if n == 2 else "(depth, width, height)") + " of finite real numbers"
        size = check_real_array(
            "size", self.size, shape=(n,), low=0.0, low_open=True, unit="m", what=f"a {self.shape}'s {what}"
        )
        # plain tuples of floats: the obstacle stays hashable and two courses compare by value
        object.__setattr__(self, "center", tuple(float(v) for v in center))
        object.__setattr__(self, "size", tuple(float(v) for v in size))
        object.__setattr__(self, "yaw", float(check_real("yaw", self.yaw, unit="rad")))  # type: ignore[arg-type]

    # ------------------------------------------------------------------ frame
    @property
    def height(self) -> float:
        """Vertical extent [m]."""
        return self.size[-1]

    @property
    def rotation(self) -> NDArray[np.float64]:
        """The yaw as a rotation matrix (3, 3): local (obstacle) axes to world."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])

    def to_world(self, local: NDArray[np.float64]) -> NDArray[np.float64]:
        """Points (..., 3) [m] in the obstacle's frame (origin at :attr:`center`, x along its depth) in world."""
        return np.asarray(local, dtype=np.float64) @ self.rotation.T + np.asarray(self.center)

    def vertices(self) -> NDArray[np.float64]:
        """Corner points [m] in world coordinates of a box (8, 3) or a prism (6, 3: the triangle at ``-depth/2``,
        then at ``+depth/2``, each ordered right base corner, left base corner, apex); a cylinder has none (0, 3)."""
        return self.to_world(self._local_vertices())

    def _local_vertices(self) -> NDArray[np.float64]:
        """:meth:`vertices` in the obstacle's frame."""
        if self.shape == "cylinder":
            return np.zeros((0, 3))
        d, w, h = (0.5 * v for v in self.size)
        if self.shape == "box":
            return np.array([[x, y, z] for x in (-d, d) for y in (-w, w) for z in (-h, h)])
        return np.array([[x, y, z] for x in (-d, d) for y, z in ((-w, -h), (w, -h), (0.0, h))])

    # ------------------------------------------------------------------ (a) MJCF
    def mjcf(self, name: str) -> MjcfParts:
        """The MJCF of the obstacle: a geom named ``name`` in the world body (and for a prism the mesh asset
        ``{name}_prism`` with the six corners as inline vertices, in the geom's frame; MuJoCo takes their convex
        hull). The geom collides like the scene's floor (``contype = conaffinity = 1``): with the robot's soles and
        body capsules (``contype`` 2, ``conaffinity`` 1), not with the robot's contact-free swept-sphere volumes,
        and never with other world geoms. Coloured by :data:`OBSTACLE_COLORS` of its ``kind``.
        """
        half = math.sin(0.5 * self.yaw), math.cos(0.5 * self.yaw)
        common = {
            "name": name,
            "pos": _text(self.center),
            "quat": _text((half[1], 0.0, 0.0, half[0])),
            "rgba": _text(OBSTACLE_COLORS[self.kind]),
            "contype": "1",
            "conaffinity": "1",
            "condim": "3",
            "friction": "1 0.02 0.001",
        }
        if self.shape == "box":
            return MjcfParts(
                (), (MjcfElement("geom", {**common, "type": "box", "size": _text([0.5 * v for v in self.size])}),)
            )
        if self.shape == "cylinder":
            radius, height = self.size
            return MjcfParts(
                (), (MjcfElement("geom", {**common, "type": "cylinder", "size": _text((radius, 0.5 * height))}),)
            )
        mesh = f"{name}_prism"
        return MjcfParts(
            (MjcfElement("mesh", {"name": mesh, "vertex": _text(self._local_vertices().reshape(-1))}),),
            (MjcfElement("geom", {**common, "type": "mesh", "mesh": mesh}),),
        )

    # ------------------------------------------------------------------ (b) swept-sphere model
    def volumes(self) -> tuple[SSV, ...]:
        """The swept-sphere model [m], world coordinates.

        - box: a rectangle of two TSS in the box's mid-plane perpendicular to its smallest extent, radius ``r`` half
          that extent, the rectangle the box's other two extents less ``r`` on each side: the box with its edges
          rounded by ``r``. It lies inside the box and touches all six faces, so its bounding box is the box's (what
          the walking controller's step planning reads); a box point lies at most ``(sqrt 2 - 1) r`` outside it
          along an edge, ``(sqrt 3 - 1) r`` at a corner. (A rectangle spanning the full extents would contain the box
          but overhang every face by ``r``: a 15 cm deep, 18 cm high block would plan as 30 cm deep and 25 cm high,
          deeper than a step.)
        - prism: one TSS, the triangle in the mid-plane ``x = 0`` of its frame, radius ``depth / 2``: it contains
          the prism (the triangle extruded by ``+-depth / 2``), overhanging its faces by the radius (a thin
          triangle has no inset triangle of that radius).
        - cylinder: a vertical LSS of the cylinder's radius from the bottom face's centre (the ground, for an
          obstacle standing on it) to the top face's centre: it contains the cylinder, with rounded caps.
        """
        if self.shape == "cylinder":
            radius, height = self.size
            x, y, z = self.center
            return (LSS((x, y, z - 0.5 * height), (x, y, z + 0.5 * height), radius),)
        if self.shape == "prism":
            depth, width, height = self.size
            triangle = np.array(
                [[0.0, -0.5 * width, -0.5 * height], [0.0, 0.5 * width, -0.5 * height], [0.0, 0.0, 0.5 * height]]
            )
            p0, p1, p2 = self.to_world(triangle)
            return (TSS(p0, p1, p2, radius=0.5 * depth),)
        extents = np.asarray(self.size)
        thin = int(np.argmin(extents))  # the rectangle is perpendicular to the smallest extent
        a, b = (k for k in range(3) if k != thin)
        corners = np.zeros((4, 3))
        radius = 0.5 * float(extents[thin])
        for row, (sa, sb) in enumerate(((-1, -1), (1, -1), (1, 1), (-1, 1))):  # around the rectangle
            corners[row, a] = sa * (0.5 * extents[a] - radius)
            corners[row, b] = sb * (0.5 * extents[b] - radius)
        p = self.to_world(corners)
        return TSS(p[0], p[1], p[2], radius=radius), TSS(p[0], p[2], p[3], radius=radius)

    # ------------------------------------------------------------------ (c) bounding box
    def bounding_box(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The axis-aligned bounding box ``(lower, upper)`` [m] of the shape (not of its swept-sphere model)."""
        if self.shape == "cylinder":
            radius, height = self.size
            half = np.array([radius, radius, 0.5 * height])  # a circle's extent does not depend on the yaw
            center = np.asarray(self.center)
            return center - half, center + half
        corners = self.vertices()
        return corners.min(axis=0), corners.max(axis=0)


# ---------------------------------------------------------------------- courses
BEAM_POSITION = (5 - 1) * NOMINAL_STEP_LENGTH
"""x [m] of the monograph's obstacles: the nominal 5th foothold at 0.4 m/s (1.28 m), a left footfall."""


def beam_course() -> tuple[Obstacle, ...]:
    """The monograph's first experiment: a block 16.1 cm high, 8 cm deep (x) and 35 cm wide (y), centred on y = 0 at
    x = 1.28 m, the nominal 5th foothold at 0.4 m/s, a left footfall: the left foot would land on it, the right
    foot's swing crosses it (``kind="step_over"``)."""
    return (Obstacle("box", (BEAM_POSITION, 0.0, 0.5 * 0.161), (0.08, 0.35, 0.161), 0.0, "step_over"),)


def triangle_course() -> tuple[Obstacle, ...]:
    """The monograph's second experiment: a triangular prism 30 cm high, 9 cm deep (x) and 13 cm wide at its base,
    centred on y = 0 at x = 1.28 m: with the soles 0.15 m wide at y = +-0.09 it overlaps each foot's path by 5 cm
    (``kind="swing_around"``)."""
    return (Obstacle("prism", (BEAM_POSITION, 0.0, 0.15), (0.09, 0.13, 0.30), 0.0, "swing_around"),)


def random_course(
    rng: np.random.Generator,
    *,
    n_obstacles: tuple[int, int] = (3, 6),
    spacing: tuple[float, float] = (1.2, 3.0),
    first_obstacle_distance: float = 1.5,
) -> tuple[Obstacle, ...]:
    """A seeded random course along +x: obstacles of the three classes of :data:`COURSE_KINDS`, drawn uniformly.

    Every draw comes from ``rng`` (the same generator state gives the same course). The ranges of each class are
    :data:`STEP_OVER`, :data:`SWING_AROUND` and :data:`BESIDE`; every obstacle stands on the ground, yaw 0.

    Args:
        rng: the generator (the env's ``np_random``).
        n_obstacles: inclusive range of the number of obstacles (ints >= 1).
        spacing: range [m] of the distance along x between the centres of consecutive obstacles (> 0).
        first_obstacle_distance: x [m] of the first obstacle's centre (> 0).

    Raises:
        ValueError: an argument out of its range.
    """
    low, high = check_range_pair("n_obstacles", n_obstacles, low=1, integer=True)
    gap = check_range_pair("spacing", spacing, low=0.0, low_open=True, unit="m")
    x = check_real("first_obstacle_distance", first_obstacle_distance, low=0.0, low_open=True, unit="m")
    assert x is not None  # not optional: a float or ValueError
    count = int(rng.integers(int(low), int(high) + 1))  # ints already (integer=True); int() tells the type checker
    course = []
    for k in range(count):
        if k:
            x += float(rng.uniform(*gap))
        kind = COURSE_KINDS[int(rng.integers(len(COURSE_KINDS)))]
        course.append(_draw(kind, float(x), rng))
    return tuple(course)


def _draw(kind: str, x: float, rng: np.random.Generator) -> Obstacle:
    """One obstacle of class ``kind`` centred at ``x`` [m]."""
    side = 1.0 if rng.uniform() < 0.5 else -1.0  # left or right (unused by step_over)
    if kind == "step_over":
        r = STEP_OVER
        height, depth, width = (float(rng.uniform(*r[k])) for k in ("height", "depth", "width"))
        y = float(rng.uniform(*r["lateral_offset"]))
        return Obstacle("box", (x, y, 0.5 * height), (depth, width, height), 0.0, kind)
    if kind == "swing_around":
        r = SWING_AROUND
        height = float(rng.uniform(*r["height"]))
        overlap = float(rng.uniform(*r["overlap"]))
        # wide enough to overlap the sole's band by `overlap` from outside it
        width = float(rng.uniform(max(r["width"][0], overlap), r["width"][1]))
        inner = FOOT_PATH_Y[1] - overlap  # |y| of the obstacle's edge inside the band
        y = side * (inner + 0.5 * width)
        if rng.uniform() < 0.5:
            depth = float(rng.uniform(*r["prism_depth"]))
            return Obstacle("prism", (x, y, 0.5 * height), (depth, width, height), 0.0, kind)
        return Obstacle("cylinder", (x, y, 0.5 * height), (0.5 * width, height), 0.0, kind)
    if kind != "beside":
        raise ValueError(f"kind must be one of {', '.join(COURSE_KINDS)}; got {kind!r}")
    r = BESIDE
    height, gap, depth, width = (float(rng.uniform(*r[k])) for k in ("height", "gap", "depth", "width"))
    y = side * (FOOT_PATH_Y[1] + gap + 0.5 * width)
    return Obstacle("box", (x, y, 0.5 * height), (depth, width, height), 0.0, kind)

"""Terrain on the biped's path (the BipedTerrain scene): stairs, platforms, stepping stones, slopes and rough ground,
and the seeded generator that lays them out.

A :class:`Terrain` is a sequence of :class:`TerrainSegment` along +x on the flat ground (z = 0). Every segment is
made of three kinds of parts, each with an exact height function and an MJCF form:

- boxes standing on the ground, axis-aligned: ``(x0, x1, y0, y1, top)`` [m] (stair steps and landings, platforms,
  stones); MuJoCo ``box`` geoms;
- ramps across the terrain's width: a trapezoid in the x-z plane, ``(x0, x_top0, x_top1, x1, height, y0, y1)``
  [m], rising from ``x0`` to ``x_top0``, flat to ``x_top1``, falling to ``x1``; a convex MuJoCo mesh;
- rough patches: a heightfield of vertex heights on a square grid (:class:`RoughPatch`), a MuJoCo ``hfield`` whose
  cells are split into two triangles along the diagonal from the (row, column) vertex to the (row + 1, column + 1)
  one, as MuJoCo's collision and ray tests do (:meth:`RoughPatch.heights`).

The terrain's height at a point is the largest of the ground (0) and every part that covers it: the height scan of
the env and its support metrics read :meth:`Terrain.heights`, which the tests hold equal to MuJoCo's rays.

Coordinates are the world frame of the biped scene: x forward along the walking direction, y to the robot's left,
z up, the robot standing at the origin.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..validation import check_choice, check_range_pair, check_real
from .obstacle_course import FOOT_Y, MjcfElement, MjcfParts

__all__ = [
    "SEGMENT_KEYS",
    "TERRAIN_COLORS",
    "TERRAIN_KINDS",
    "TERRAIN_RANGES",
    "TERRAIN_WIDTH",
    "RoughPatch",
    "Terrain",
    "TerrainSegment",
    "draw_segment",
    "explicit_terrain",
    "random_terrain",
    "segment_length_bound",
]

TERRAIN_KINDS = ("stairs", "platform", "stepping_stones", "slope", "rough")
"""The classes of terrain segments."""
TERRAIN_WIDTH = 2.0
"""Extent [m] across the walk (y in [-1, 1]) of stairs, platforms, ramps and rough patches."""
TERRAIN_COLORS: dict[str, tuple[float, float, float, float]] = {
    "stairs": (0.62, 0.5, 0.38, 1.0),
    "platform": (0.45, 0.55, 0.35, 1.0),
    "stepping_stones": (0.5, 0.5, 0.55, 1.0),
    "slope": (0.7, 0.6, 0.4, 1.0),
    "rough": (0.55, 0.45, 0.35, 1.0),
}
"""RGBA per terrain class: earthy tones that stand out against the grey checker floor."""

TERRAIN_RANGES: dict[str, dict[str, tuple[float, float]]] = {
    "stairs": {"steps": (3, 6), "rise": (0.08, 0.16), "tread": (0.25, 0.35), "landing": (0.6, 1.0)},
    "platform": {"height": (0.08, 0.16), "length": (0.5, 1.5)},
    "stepping_stones": {
        "stones": (4, 6),
        "length": (0.20, 0.35),
        "width": (0.15, 0.30),
        "gap": (0.05, 0.20),
        "height": (0.10, 0.10),
        "height_spread": (0.05, 0.05),
    },
    "slope": {"angle": (3.0, 10.0), "length": (1.0, 2.0), "top": (0.5, 1.0)},
    "rough": {"amplitude": (0.01, 0.03), "length": (2.0, 3.0), "spacing": (0.1, 0.1)},
}
"""The default ranges of every segment parameter, drawn uniformly per segment (ints where the range holds ints):

- ``stairs``: ``steps`` rises of ``rise`` [m] (the last one onto the landing), treads ``tread`` [m] deep, a landing
  ``landing`` [m] long, then as many steps down;
- ``platform``: a block ``height`` [m] high, ``length`` [m] long;
- ``stepping_stones``: ``stones`` stones per foot (two staggered lanes at y = +-0.09 m), each ``length`` [m]
  along the walk and ``width`` [m] across (moved outwards where a wide stone would cross the centre line), ``gap``
  [m] between stones of a lane, tops at ``height`` +- ``height_spread`` [m] (the gaps go down to the ground);
- ``slope``: ramps of ``angle`` [deg] over ``length`` [m] up and down, a flat top ``top`` [m] long;
- ``rough``: a patch ``length`` [m] long of vertex heights drawn in ``[0, 2 amplitude]`` [m] every ``spacing`` [m]
  (a mean level ``amplitude`` above the ground, +- ``amplitude``), the border vertices at 0 (flush with the
  ground).

A range is the target of the issue, not a filter: a class the reference cannot walk stays in the distribution."""
SEGMENT_KEYS: dict[str, tuple[str, ...]] = {kind: tuple(ranges) for kind, ranges in TERRAIN_RANGES.items()}
"""The parameters of each segment class (the keys of an explicit segment besides ``kind`` and ``gap``)."""
_INTEGER_KEYS = frozenset({"steps", "stones"})
_BASE_DEPTH = 0.02  # [m] an hfield's base below its zero level (MuJoCo needs a positive base)


def _text(values: Sequence[float] | NDArray[np.float64]) -> str:
    """MJCF text of numbers (17 significant digits: the compiled model sees the float64 values)."""
    return " ".join(f"{float(v):.17g}" for v in values)


@dataclass(frozen=True, eq=False)
class RoughPatch:
    """A heightfield of vertex heights on a square grid.

    Attributes:
        x0, y0: the grid's corner of smallest x and y [m] (vertex (0, 0)).
        spacing: vertex distance [m] along x and y.
        heights: (rows along y, columns along x) vertex heights [m], >= 0, float32-exact (the values MuJoCo
            stores).
    """

    x0: float
    y0: float
    spacing: float
    heights: NDArray[np.float64]

    @property
    def length(self) -> float:
        """Extent along x [m]."""
        return (self.heights.shape[1] - 1) * self.spacing

    @property
    def width(self) -> float:
        """Extent along y [m]."""
        return (self.heights.shape[0] - 1) * self.spacing

    @property
    def top(self) -> float:
        """The largest vertex height [m] (the hfield's elevation scale)."""
        return float(self.heights.max())

    def __eq__(self, other: object) -> bool:
        return (
            isinstance(other, RoughPatch)
            and (self.x0, self.y0, self.spacing) == (other.x0, other.y0, other.spacing)
            and np.array_equal(self.heights, other.heights)
        )

    def __hash__(self) -> int:
        return hash((self.x0, self.y0, self.spacing, self.heights.tobytes()))

    def heights_at(self, x: NDArray[np.float64], y: NDArray[np.float64]) -> NDArray[np.float64]:
        """Surface height [m] at points (x, y) inside the patch (NaN outside): each cell's two triangles split
        along the diagonal from vertex (r, c) to (r + 1, c + 1), MuJoCo's triangulation."""
        rows, cols = self.heights.shape
        u = (np.asarray(x) - self.x0) / self.spacing
        v = (np.asarray(y) - self.y0) / self.spacing
        inside = (u >= 0.0) & (u <= cols - 1) & (v >= 0.0) & (v <= rows - 1)
        c = np.clip(np.floor(u).astype(np.int64), 0, cols - 2)
        r = np.clip(np.floor(v).astype(np.int64), 0, rows - 2)
        fu, fv = u - c, v - r
        h = self.heights
        z00, z01, z10, z11 = h[r, c], h[r, c + 1], h[r + 1, c], h[r + 1, c + 1]
        lower = z00 + fu * (z01 - z00) + fv * (z11 - z01)  # below the diagonal (fu >= fv)
        upper = z00 + fv * (z10 - z00) + fu * (z11 - z10)
        return np.where(inside, np.where(fu >= fv, lower, upper), np.nan)


@dataclass(frozen=True)
class TerrainSegment:
    """One terrain segment along x.

    Attributes:
        kind: its class (:data:`TERRAIN_KINDS`).
        start, end: the x range [m] it occupies.
        boxes: ``(x0, x1, y0, y1, top)`` [m] per box standing on the ground.
        ramps: ``(x0, x_top0, x_top1, x1, height, y0, y1)`` [m] per ramp.
        patches: its rough patches.
        parameters: the values it was drawn with (name, value), for reports.
    """

    kind: str
    start: float
    end: float
    boxes: tuple[tuple[float, float, float, float, float], ...] = ()
    ramps: tuple[tuple[float, float, float, float, float, float, float], ...] = ()
    patches: tuple[RoughPatch, ...] = ()
    parameters: tuple[tuple[str, float], ...] = field(default=())

    def describe(self) -> str:
        """One line: the class, where, and the drawn parameters."""
        values = ", ".join(f"{k} {v:.3g}" for k, v in self.parameters)
        return f"{self.kind} at x {self.start:.2f}-{self.end:.2f} m ({values})"


@dataclass(frozen=True)
class Terrain:
    """A terrain: its segments in walking order (non-overlapping along x), on flat ground at z = 0."""

    segments: tuple[TerrainSegment, ...]

    @property
    def end(self) -> float:
        """The largest x [m] of the terrain (0 without segments)."""
        return max((s.end for s in self.segments), default=0.0)

    @property
    def boxes(self) -> NDArray[np.float64]:
        """(B, 5) every box ``(x0, x1, y0, y1, top)`` [m]."""
        rows = [b for s in self.segments for b in s.boxes]
        return np.array(rows, dtype=np.float64).reshape(-1, 5)

    @property
    def ramps(self) -> NDArray[np.float64]:
        """(R, 7) every ramp ``(x0, x_top0, x_top1, x1, height, y0, y1)`` [m]."""
        rows = [r for s in self.segments for r in s.ramps]
        return np.array(rows, dtype=np.float64).reshape(-1, 7)

    @property
    def patches(self) -> tuple[RoughPatch, ...]:
        """Every rough patch."""
        return tuple(p for s in self.segments for p in s.patches)

    def kind_at(self, x: float) -> str:
        """The class of the segment whose x range holds ``x`` [m], ``"flat"`` between segments."""
        for s in self.segments:
            if s.start <= x <= s.end:
                return s.kind
        return "flat"

    def heights(self, points: NDArray[np.float64]) -> NDArray[np.float64]:
        """Terrain height [m] at each (x, y) row of ``points`` (..., 2): the largest of the ground and every part
        that covers the point (a box's footprint and sides inclusive)."""
        p = np.asarray(points, dtype=np.float64)
        x, y = p[..., 0], p[..., 1]
        z = np.zeros(x.shape)
        for x0, x1, y0, y1, top in self.boxes:
            z = np.where((x >= x0) & (x <= x1) & (y >= y0) & (y <= y1), np.maximum(z, top), z)
        for x0, a, b, x1, height, y0, y1 in self.ramps:
            up = height * np.clip((x - x0) / (a - x0), 0.0, 1.0)
            down = height * np.clip((x1 - x) / (x1 - b), 0.0, 1.0)
            ramp = np.minimum(up, down)
            z = np.where((x >= x0) & (x <= x1) & (y >= y0) & (y <= y1), np.maximum(z, ramp), z)
        for patch in self.patches:
            h = patch.heights_at(x, y)
            z = np.where(np.isnan(h), z, np.maximum(z, np.nan_to_num(h)))
        return z

    def edge_distance(self, corners: NDArray[np.float64], center: NDArray[np.float64], cap: float = 1.0) -> float:
        """Signed distance [m] of a sole's footprint from the nearest edge: on a box top (the box under
        ``center``, the highest where several are), the smallest distance of a ``corners`` point (K, 2) inside the
        top's rectangle (negative for a corner beyond it: the sole overhangs the edge or stands against a riser);
        elsewhere, the smallest distance of a corner outside every box's footprint (negative for a corner inside
        one). Ramps and rough patches have no step edges. At most ``cap``."""
        boxes = self.boxes
        c = np.asarray(corners, dtype=np.float64)
        x, y = c[:, 0:1], c[:, 1:2]
        # per corner and box: the distance inside the rectangle (negative outside, the axis-wise gap)
        inside = np.minimum(np.minimum(x - boxes[:, 0], boxes[:, 1] - x), np.minimum(y - boxes[:, 2], boxes[:, 3] - y))
        cx, cy = float(center[0]), float(center[1])
        under = [b for b in range(len(boxes)) if boxes[b, 0] <= cx <= boxes[b, 1] and boxes[b, 2] <= cy <= boxes[b, 3]]
        if under:
            top = max(under, key=lambda b: boxes[b, 4])
            return float(min(inside[:, top].min(), cap))
        if not len(boxes):
            return float(cap)
        # outside every box: the Euclidean gap to the nearest footprint (negative: a corner inside one)
        gx = np.maximum(np.maximum(boxes[:, 0] - x, x - boxes[:, 1]), 0.0)
        gy = np.maximum(np.maximum(boxes[:, 2] - y, y - boxes[:, 3]), 0.0)
        outside = np.where(inside > 0.0, -inside, np.hypot(gx, gy))
        return float(min(outside.min(), cap))

    def mjcf(self, prefix: str = "terrain") -> MjcfParts:
        """The MJCF of the terrain: geoms named ``{prefix}_{k}`` in the order boxes, ramps, patches (meshes and
        hfields in ``<asset>``), colliding like the floor (``contype = conaffinity = 1``), coloured per class."""
        assets: list[MjcfElement] = []
        geoms: list[MjcfElement] = []
        k = 0
        for segment in self.segments:
            rgba = _text(TERRAIN_COLORS[segment.kind])
            common = {"contype": "1", "conaffinity": "1", "condim": "3", "friction": "1 0.02 0.001", "rgba": rgba}
            for x0, x1, y0, y1, top in segment.boxes:
                center = (0.5 * (x0 + x1), 0.5 * (y0 + y1), 0.5 * top)
                size = (0.5 * (x1 - x0), 0.5 * (y1 - y0), 0.5 * top)
                geoms.append(
                    MjcfElement(
                        "geom",
                        {"name": f"{prefix}_{k}", "type": "box", "pos": _text(center), "size": _text(size), **common},
                    )
                )
                k += 1
            for x0, a, b, x1, height, y0, y1 in segment.ramps:
                mesh = f"{prefix}_{k}_ramp"
                profile = ((x0, 0.0), (a, height), (b, height), (x1, 0.0))
                vertices = [(x, y, z) for y in (y0, y1) for x, z in profile]
                assets.append(MjcfElement("mesh", {"name": mesh, "vertex": _text(np.ravel(vertices))}))
                geoms.append(MjcfElement("geom", {"name": f"{prefix}_{k}", "type": "mesh", "mesh": mesh, **common}))
                k += 1
            for patch in segment.patches:
                hfield = f"{prefix}_{k}_hfield"
                rows, cols = patch.heights.shape
                top = patch.top
                # MuJoCo normalizes the elevation to [0, 1] and lists rows from +y down: the border vertices are 0
                # and the largest is ``top``, so the normalized values are the heights over ``top``
                elevation = (patch.heights / top)[::-1].ravel() if top > 0.0 else np.zeros(rows * cols)
                half = (0.5 * patch.length, 0.5 * patch.width, top if top > 0.0 else 1e-6, _BASE_DEPTH)
                assets.append(
                    MjcfElement(
                        "hfield",
                        {
                            "name": hfield,
                            "nrow": str(rows),
                            "ncol": str(cols),
                            "size": _text(half),
                            "elevation": _text(elevation),
                        },
                    )
                )
                center = (patch.x0 + 0.5 * patch.length, patch.y0 + 0.5 * patch.width, 0.0)
                geoms.append(
                    MjcfElement(
                        "geom",
                        {"name": f"{prefix}_{k}", "type": "hfield", "hfield": hfield, "pos": _text(center), **common},
                    )
                )
                k += 1
        return MjcfParts(tuple(assets), tuple(geoms))

    @property
    def geom_count(self) -> int:
        """How many geoms :meth:`mjcf` makes."""
        return len(self.boxes) + len(self.ramps) + len(self.patches)


# ---------------------------------------------------------------------- generators
def _value(rng: np.random.Generator, name: str, low_high: tuple[float, float]) -> float:
    low, high = low_high
    if name in _INTEGER_KEYS:
        return float(rng.integers(int(low), int(high) + 1))
    return float(rng.uniform(low, high)) if high > low else float(low)


def draw_segment(
    kind: str,
    start: float,
    rng: np.random.Generator,
    ranges: Mapping[str, tuple[float, float]] | None = None,
    fixed: Mapping[str, float] | None = None,
) -> TerrainSegment:
    """One segment of class ``kind`` beginning at x = ``start`` [m].

    Args:
        kind: a class of :data:`TERRAIN_KINDS`.
        start: its first x [m].
        rng: the generator of every draw (the env's ``np_random``).
        ranges: ``(low, high)`` per parameter (:data:`TERRAIN_RANGES` for those not given).
        fixed: parameter values that are not drawn.

    Raises:
        ValueError: an unknown class or parameter, or a value out of its bounds.
    """
    check_choice("kind", kind, TERRAIN_KINDS)
    spec = dict(TERRAIN_RANGES[kind])
    for name, pair in (ranges or {}).items():
        if name not in spec:
            raise ValueError(f"{kind} has no parameter {name!r}; valid: {', '.join(SEGMENT_KEYS[kind])}")
        spec[name] = check_range_pair(f"{kind} {name}", pair, low=0.0, integer=name in _INTEGER_KEYS)
    values: dict[str, float] = {}
    for name, pair in spec.items():  # drawn in the order of TERRAIN_RANGES: a fixed value skips its draw
        if fixed is not None and name in fixed:
            values[name] = float(fixed[name])
        else:
            values[name] = _value(rng, name, pair)
    _check_values(kind, values)
    half = 0.5 * TERRAIN_WIDTH
    if kind == "stairs":
        n, rise, tread, landing = int(values["steps"]), values["rise"], values["tread"], values["landing"]
        boxes = []
        x = start
        for i in range(1, n):
            boxes.append((x, x + tread, -half, half, i * rise))
            x += tread
        boxes.append((x, x + landing, -half, half, n * rise))
        x += landing
        for i in range(n - 1, 0, -1):
            boxes.append((x, x + tread, -half, half, i * rise))
            x += tread
        return TerrainSegment(kind, start, x, boxes=tuple(boxes), parameters=tuple(values.items()))
    if kind == "platform":
        end = start + values["length"]
        return TerrainSegment(
            kind, start, end, boxes=((start, end, -half, half, values["height"]),), parameters=tuple(values.items())
        )
    if kind == "stepping_stones":
        return _stones(start, rng, spec, values)
    if kind == "slope":
        rise = values["length"] * math.tan(math.radians(values["angle"]))
        a, b = start + values["length"], start + values["length"] + values["top"]
        end = b + values["length"]
        return TerrainSegment(
            kind, start, end, ramps=((start, a, b, end, rise, -half, half),), parameters=tuple(values.items())
        )
    spacing = values["spacing"]
    cols = max(int(round(values["length"] / spacing)), 2) + 1
    rows = int(round(TERRAIN_WIDTH / spacing)) + 1
    heights = np.zeros((rows, cols))
    heights[1:-1, 1:-1] = rng.uniform(0.0, 2.0 * values["amplitude"], (rows - 2, cols - 2))
    top = float(heights.max())
    if top > 0.0:  # MuJoCo stores the normalized values as float32 and scales them by the (double) elevation
        heights = (heights / top).astype(np.float32).astype(np.float64) * top
    patch = RoughPatch(start, -0.5 * (rows - 1) * spacing, spacing, heights)
    return TerrainSegment(kind, start, start + patch.length, patches=(patch,), parameters=tuple(values.items()))


def _stones(
    start: float, rng: np.random.Generator, spec: dict[str, tuple[float, float]], values: dict[str, float]
) -> TerrainSegment:
    """Two staggered lanes of stones (right lane first); each stone's size, gap and top drawn on its own."""
    boxes = []
    count = int(values["stones"])
    end = start
    for lane, side in enumerate((-1.0, 1.0)):
        x = start + (0.5 * (values["length"] + values["gap"]) if lane else 0.0)  # the left lane half a pitch on
        for i in range(count):
            length = values["length"] if i == 0 else _value(rng, "length", spec["length"])
            width = values["width"] if i == 0 else _value(rng, "width", spec["width"])
            gap = values["gap"] if i == 0 else _value(rng, "gap", spec["gap"])
            spread = values["height_spread"]
            top = values["height"] + float(rng.uniform(-spread, spread))
            inner = max(FOOT_Y - 0.5 * width, 0.005)  # a wide stone moves outwards: it never crosses y = 0
            y0, y1 = (inner, inner + width) if side > 0 else (-inner - width, -inner)
            boxes.append((x, x + length, y0, y1, top))
            x += length + gap
        end = max(end, x - gap)
    return TerrainSegment("stepping_stones", start, end, boxes=tuple(boxes), parameters=tuple(values.items()))


def _check_values(kind: str, values: dict[str, float]) -> None:
    """Raise ValueError for a parameter value no terrain can have."""
    positive = {
        "stairs": ("rise", "tread", "landing"),
        "platform": ("height", "length"),
        "stepping_stones": ("length", "width", "height"),
        "slope": ("length",),
        "rough": ("length", "spacing"),
    }[kind]
    for name in positive:
        if not values[name] > 0.0:
            raise ValueError(f"{kind} {name} must be > 0, got {values[name]!r}")
    if kind == "stairs" and values["steps"] < 1:
        raise ValueError(f"stairs steps must be >= 1, got {values['steps']!r}")
    if kind == "stepping_stones":
        if values["stones"] < 1:
            raise ValueError(f"stepping_stones stones must be >= 1, got {values['stones']!r}")
        if values["height_spread"] >= values["height"]:
            raise ValueError(
                f"stepping_stones height_spread ({values['height_spread']!r} m) must be below height "
                f"({values['height']!r} m): a stone's top must stay above the ground"
            )
    if kind == "slope" and not 0.0 < values["angle"] < 45.0:
        raise ValueError(f"slope angle must be in (0, 45) deg, got {values['angle']!r}")
    if kind == "rough" and values["amplitude"] < 0.0:
        raise ValueError(f"rough amplitude must be >= 0, got {values['amplitude']!r}")


def segment_length_bound(ranges: Mapping[str, Mapping[str, tuple[float, float]]] = TERRAIN_RANGES) -> float:
    """The greatest length [m] along x a segment of any class can have with ``ranges``."""
    r = {kind: {**TERRAIN_RANGES[kind], **ranges.get(kind, {})} for kind in TERRAIN_KINDS}
    stairs = 2.0 * (r["stairs"]["steps"][1] - 1) * r["stairs"]["tread"][1] + r["stairs"]["landing"][1]
    stones = r["stepping_stones"]
    pitch = stones["length"][1] + stones["gap"][1]
    lengths = (
        stairs,
        r["platform"]["length"][1],
        0.5 * pitch + stones["stones"][1] * pitch - stones["gap"][0],
        2.0 * r["slope"]["length"][1] + r["slope"]["top"][1],
        r["rough"]["length"][1] + r["rough"]["spacing"][1],
    )
    return float(max(lengths))


def random_terrain(
    rng: np.random.Generator,
    *,
    kinds: Sequence[str] = TERRAIN_KINDS,
    n_segments: tuple[int, int] = (1, 1),
    spacing: tuple[float, float] = (1.0, 1.5),
    first_distance: float = 1.5,
    ranges: Mapping[str, Mapping[str, tuple[float, float]]] | None = None,
) -> Terrain:
    """A seeded terrain along +x: ``n_segments`` segments of classes drawn uniformly from ``kinds``, the first one
    starting at ``first_distance`` [m], each next one ``spacing`` [m] of flat ground after the last.

    Every draw comes from ``rng`` (the same generator state gives the same terrain).

    Raises:
        ValueError: an argument out of its range.
    """
    low, high = check_range_pair("n_segments", n_segments, low=1, integer=True)
    gap = check_range_pair("spacing", spacing, low=0.0, unit="m")
    x = check_real("first_distance", first_distance, low=0.0, low_open=True, unit="m")
    assert x is not None
    for kind in kinds:
        check_choice("kinds", kind, TERRAIN_KINDS)
    count = int(rng.integers(int(low), int(high) + 1))
    segments: list[TerrainSegment] = []
    for k in range(count):
        if k:
            x = segments[-1].end + float(rng.uniform(*gap))
        kind = kinds[int(rng.integers(len(kinds)))]
        segments.append(draw_segment(kind, float(x), rng, (ranges or {}).get(kind)))
    return Terrain(tuple(segments))


def explicit_terrain(
    entries: Sequence[Mapping[str, Any]],
    rng: np.random.Generator,
    *,
    first_distance: float,
    default_gap: float,
    ranges: Mapping[str, Mapping[str, tuple[float, float]]] | None = None,
) -> Terrain:
    """A terrain of the given segments, in order: each entry ``{"kind": ..., "gap": [m] of flat ground before it
    (the first's from the robot: ``first_distance``; later ones ``default_gap``), parameter: value, ...}``; a
    parameter not given is drawn from ``ranges`` (:data:`TERRAIN_RANGES`)."""
    segments: list[TerrainSegment] = []
    for i, entry in enumerate(entries):
        kind = entry["kind"]
        gap = float(entry.get("gap", first_distance if i == 0 else default_gap))
        x = (segments[-1].end if segments else 0.0) + gap
        fixed = {k: float(v) for k, v in entry.items() if k not in ("kind", "gap")}
        segments.append(draw_segment(kind, x, rng, (ranges or {}).get(kind), fixed))
    return Terrain(tuple(segments))

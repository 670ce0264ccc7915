"""The terrain as the walker knows it: a height profile along each foot's lane, filled from the height scans it
observes, and the footholds and swing heights planned on it.

The walker reads the terrain from its observation only: a grid of terrain heights around the pelvis (BipedTerrain's
``height_scan``). Each scan's column nearest to a foot's lane writes its points into that lane's profile, a row of
1 cm cells along x in the world frame; as the robot walks the scan rows sweep over every cell, so an edge between
two scan rows 0.1 m apart is located to the distance the robot moves in a control period (a few millimetres).
Cells not seen yet take the height of the nearest seen cell.

A foothold is placed where the sole (heel ``heel`` behind the sole point, toe tip ``toe`` ahead), extended by
``margin`` at both ends, rests on one plane: the profile over the footprint is fitted by a line, and the share of
cells within ``surface_tolerance`` of it is the foothold's support. The planner takes the best supported position
near the nominal one (a step of ``distance_cost`` support per metre off it), the line's height at the sole point and
its slope as the foot's pitch. A tread or stone shorter than the sole gets the sole centred on it; a ramp gets the
foot pitched along it.

A swing passes the terrain between its lift-off and landing with ``clearance`` under the sole: the profile's
envelope (the highest cell under the sole's length at each position of the sole point) gives the height to hold
and the band of x over which to hold it (the swing over an obstacle of the SSTA, monograph 5.4.2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from numpy.typing import NDArray

from ...kernel_options import BORROW_EXACT, DEFAULT_BACKEND
from ...validation import check_backend
from ..exceptions import ControllerError

__all__ = ["Foothold", "SwingEnvelope", "TerrainMap", "TerrainMapConfig"]


@dataclass(frozen=True)
class TerrainMapConfig:
    """Parameters of :class:`TerrainMap`.

    Attributes:
        cell: profile cell length [m] along x.
        lane_tolerance: a scan point writes a lane's cell only when it lies within this [m] of the lane's line (the
            points of a row nearest to the lane; a yawed pelvis turns the scan's far rows off the lane).
        x_min, length: the profile's first x and its extent [m] (world frame).
        heel, toe: the sole's extent behind and ahead of the sole point [m].
        margin: length [m] added to the footprint at both ends: the distance kept from an edge.
        riser_margin: distance [m] kept between the sole's ends and terrain higher than the surface it stands on (a
            riser ahead of a short tread; the feet land a centimetre or two off their plan).
        surface_tolerance: a cell within this of the footprint's level surface supports the sole [m].
        line_tolerance: a cell within this of the footprint's fitted line (a ramp) supports the sole [m]: the
            profile's cells lie within a millimetre of a ramp, and a sole across the top or foot of a ramp (a kink,
            on which it rocks) deviates from the line through both by less than a centimetre (a third of the sole on
            either side of a 6 deg kink: 4 mm).
        distance_cost: support traded per metre of foothold moved off the nominal one [1/m] (where every candidate
            meets higher terrain).
        rise_delay, descent_delay: the CoM's height moves up (down) to a step's level over one step duration from
            this long [s] after the step's start.
        min_slope: a footprint's fitted line steeper than this [rad] is a ramp (the foot pitched along it); a flatter
            one is level ground.
        search_back, search_ahead: the window [m] around the nominal foothold searched.
        clearance: height [m] of the sole above the terrain it swings over.
        min_rise: a swing's apex at least this [m] above its higher end.
        height_step: a landing more than this [m] above or below the stance foothold is a step up or down.
        step_reach: a step up or down reaches at most this [m] beyond the nominal step length (a longer one would
            stretch the leg past its length: the landing moves before the edge and the next step takes the height).
        rough_ground: a foothold whose :attr:`Foothold.roughness` exceeds this [m] stands on rough ground (treads,
            stones and ramps: up to 9 mm where a ramp meets the ground).
    """

    cell: float = 0.01
    lane_tolerance: float = 0.06
    x_min: float = -2.0
    length: float = 60.0
    heel: float = 0.095
    toe: float = 0.165
    margin: float = 0.02
    riser_margin: float = 0.04
    surface_tolerance: float = 0.012
    distance_cost: float = 0.6
    min_slope: float = 0.035
    rise_delay: float = 0.0
    descent_delay: float = 0.25
    search_back: float = 0.25
    search_ahead: float = 0.2
    clearance: float = 0.05
    min_rise: float = 0.05
    height_step: float = 0.03
    step_reach: float = 0.03
    rough_ground: float = 0.01
    line_tolerance: float = 0.0025

    def __post_init__(self) -> None:
        for name in (
            "cell",
            "lane_tolerance",
            "line_tolerance",
            "length",
            "heel",
            "toe",
            "surface_tolerance",
            "search_back",
            "search_ahead",
        ):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0.0):
                raise ControllerError(f"TerrainMapConfig.{name} must be a finite number > 0, got {value!r}")
        for name in (
            "margin",
            "riser_margin",
            "distance_cost",
            "clearance",
            "min_rise",
            "height_step",
            "step_reach",
            "rough_ground",
        ):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0.0):
                raise ControllerError(f"TerrainMapConfig.{name} must be a finite number >= 0, got {value!r}")


@dataclass(frozen=True)
class Foothold:
    """A planned foothold on the terrain.

    Attributes:
        x: the sole point's x [m].
        z: its height [m] (the surface line's height there).
        pitch: the sole's pitch [rad] along the surface (positive: toes down, a downhill surface).
        support: share [0, 1] of the (margin-extended) footprint on the surface.
        roughness: peak-to-peak [m] of the profile under the sole (margins left out) about its surface, over the
            cells within the map's ``height_step`` of it (an edge's other level is not roughness): 0 on a tread or a
            stone, about a millimetre on a ramp (the profile's cells), up to a centimetre where a ramp meets the
            ground, 1-3 cm on BipedTerrain's rough ground.
    """

    x: float
    z: float
    pitch: float
    support: float
    roughness: float = 0.0


@dataclass(frozen=True)
class SwingEnvelope:
    """What a swing must pass: ``top`` [m], the height to hold over the band ``(x0, x1)`` [m] of sole-point x."""

    top: float
    band: tuple[float, float]


class TerrainMap:
    """Height profiles along the feet's lanes from observed height scans (world frame).

    Args:
        lanes: the lanes' y [m] (right, left): the starting feet's.
        config: the parameters.
        backend: how :meth:`observe` writes a scan (:data:`~redundancy_gym.kernel_options.BACKENDS`): one compiled
            call (:func:`write_scan`, ``"compiled"``) or its NumPy reference (``"python"``); the same cells, bit
            for bit (a test holds them equal).
    """

    def __init__(
        self, lanes: tuple[float, float], config: TerrainMapConfig | None = None, backend: str = DEFAULT_BACKEND
    ) -> None:
        self.config = config or TerrainMapConfig()
        self.backend = check_backend("backend", backend, error=ControllerError)
        self.lanes = (float(lanes[0]), float(lanes[1]))
        self._lane_array = np.array(self.lanes)
        n = int(round(self.config.length / self.config.cell)) + 1
        self._heights = np.full((2, n), np.nan)
        self._filled: list[NDArray[np.float64] | None] = [None, None]
        self._row_cache: tuple[bytes, NDArray[np.int64]] | None = None
        c = self.config
        self._foot = int(round((c.heel + c.toe + 2.0 * c.margin) / c.cell)) + 1  # cells under a footprint
        offsets = np.arange(self._foot) * c.cell - (c.heel + c.margin)
        self._fit = (offsets, offsets - offsets.mean())
        # the cells within riser_margin of the sole (relative to the footprint's first cell)
        self._clear = np.arange(
            int(round((c.margin - c.riser_margin) / c.cell)),
            int(round((c.margin + c.heel + c.toe + c.riser_margin) / c.cell)) + 1,
        )

    # ------------------------------------------------------------------ observation
    def observe(
        self,
        base: tuple[float, float, float, float],
        scan: NDArray[np.float64],
        offsets: NDArray[np.float64],
    ) -> None:
        """Write a height scan into the lanes' profiles.

        Args:
            base: the pelvis's x, y, z [m] and yaw [rad] when the scan was taken.
            scan: terrain height minus the pelvis height [m] at each scan point (N,).
            offsets: the scan points (forward, left) [m] in the pelvis's heading frame (N, 2).
        """
        x, y, z, yaw = base
        if offsets.shape[0] == 0:
            return
        rows = self._rows(offsets)
        c, s = math.cos(yaw), math.sin(yaw)
        if self.backend == "compiled":
            # one call in place of some thirty NumPy calls on arrays of a hundred points (about 50 us every few
            # control periods, a tenth of the terrain walk's controller step)
            write_scan(
                self._heights, rows, np.ascontiguousarray(offsets, dtype=np.float64),
                np.ascontiguousarray(scan, dtype=np.float64), self._lane_array, float(x), float(y), float(z),
                c, s, float(self.config.lane_tolerance), float(self.config.x_min), float(self.config.cell),
            )  # fmt: skip
            self._filled = [None, None]
            return
        forward, left = offsets[:, 0], offsets[:, 1]
        world_x = x + c * forward - s * left
        world_y = y + s * forward + c * left
        cell, x_min, n = self.config.cell, self.config.x_min, self._heights.shape[1]
        across = np.arange(rows.shape[0])
        for lane, lane_y in enumerate(self.lanes):
            # per row of the scan, its point nearest to the lane's line writes the lane's cell there (a whole column
            # would leave the lane at the far rows when the pelvis yaws a little: a stone's gap read as the stone)
            distance = np.abs(world_y[rows] - lane_y)
            nearest = distance.argmin(axis=1)
            index = rows[across, nearest][distance[across, nearest] <= self.config.lane_tolerance]
            cells = np.rint((world_x[index] - x_min) / cell).astype(np.int64)
            keep = (cells >= 0) & (cells < n)
            self._heights[lane, cells[keep]] = scan[index[keep]] + z
            self._filled[lane] = None

    def _rows(self, offsets: NDArray[np.float64]) -> NDArray[np.int64]:
        """The scan's points grouped by row (equal forward offset): an index array (rows, points per row), made once
        per scan layout (a layout whose rows differ in length is padded with the row's last point)."""
        key = offsets.tobytes()
        cached = self._row_cache
        if cached is None or cached[0] != key:
            xs = np.unique(np.round(offsets[:, 0], 9))
            groups = [np.flatnonzero(np.abs(offsets[:, 0] - v) < 1e-9) for v in xs]
            width = max(len(g) for g in groups)
            rows = np.array([np.concatenate([g, np.full(width - len(g), g[-1])]) for g in groups], dtype=np.int64)
            cached = self._row_cache = (key, rows)
        return cached[1]

    def profile(self, lane: int) -> NDArray[np.float64]:
        """The lane's heights [m] per cell, cells not seen yet filled from the nearest seen one (0 without any)."""
        filled = self._filled[lane]
        if filled is None:
            raw = self._heights[lane]
            seen = np.flatnonzero(~np.isnan(raw))
            if seen.size == 0:
                filled = np.zeros_like(raw)
            else:
                index = np.arange(raw.size)
                # the nearest seen cell: the one before or after, whichever is closer
                after = np.searchsorted(seen, index).clip(0, seen.size - 1)
                before = (after - 1).clip(0, seen.size - 1)
                nearer = np.where(
                    np.abs(seen[before] - index) <= np.abs(seen[after] - index), seen[before], seen[after]
                )
                filled = raw[nearer]
            self._filled[lane] = filled
        return filled

    def heights_at(self, lane: int, x: NDArray[np.float64] | float) -> NDArray[np.float64]:
        """The lane's profile at world ``x`` [m] (nearest cell)."""
        cells = np.rint((np.asarray(x, dtype=np.float64) - self.config.x_min) / self.config.cell).astype(np.int64)
        return self.profile(lane)[cells.clip(0, self._heights.shape[1] - 1)]

    # ------------------------------------------------------------------ planning
    def place(self, lane: int, nominal: float, low: float, high: float) -> Foothold:
        """The foothold of ``lane`` near the nominal sole-point x ``nominal`` [m], within ``[low, high]`` [m] (the
        reach), that rests best on one plane (module docstring)."""
        c = self.config
        start = max(nominal - c.search_back, low)
        stop = min(nominal + c.search_ahead, high)
        if stop < start:  # the reach and the window do not meet: the nearest reachable point
            start = stop = min(max(nominal, low), high)
        candidates = np.arange(start, stop + 0.5 * c.cell, c.cell)
        profile = self.profile(lane)
        offsets, centred = self._fit
        first = np.rint((candidates + offsets[0] - c.x_min) / c.cell).astype(np.int64)
        cells = (first[:, None] + np.arange(self._foot)[None, :]).clip(0, profile.size - 1)
        heights = profile[cells]
        # two surfaces per candidate: a level one at the footprint's median height (a tread, a stone, a platform:
        # a plane fit across an edge would tilt the foot onto both levels) and a least-squares line (a ramp)
        level = np.median(heights, axis=1)
        flat = (np.abs(heights - level[:, None]) <= c.surface_tolerance).mean(axis=1)
        mean = heights.mean(axis=1)
        slope = (heights - mean[:, None]) @ centred / (centred @ centred)
        line = mean[:, None] + slope[:, None] * (offsets[None, :] - offsets.mean())
        sloped = (np.abs(heights - line) <= c.line_tolerance).mean(axis=1)
        # a ramp only where the line is steeper than min_slope: on rough ground a line through the bumps would tilt
        # the foot for nothing
        use_line = (sloped > flat) & (np.abs(slope) > math.tan(c.min_slope))
        support = np.where(use_line, sloped, flat)
        # terrain above the surface within riser_margin of the sole (a riser ahead of a short tread) would meet it:
        # overhanging the lower side is a loss of support, standing against the higher one a collision
        near = profile[(first[:, None] + self._clear[None, :]).clip(0, profile.size - 1)]
        along = self._clear * c.cell + offsets[0]
        surface = np.where(
            use_line[:, None], mean[:, None] + slope[:, None] * (along[None, :] - offsets.mean()), level[:, None]
        )
        blocked = np.any(near > surface + c.surface_tolerance, axis=1)
        best = int(np.argmax(support - blocked - c.distance_cost * np.abs(candidates - nominal)))
        inner = slice(int(round(c.margin / c.cell)), self._foot - int(round(c.margin / c.cell)))
        # the sole's cells about its surface; those beyond height_step are another level (an edge's), not bumps
        about = (heights[best] - (line[best] if use_line[best] else level[best]))[inner]
        bumps = about[np.abs(about) <= c.height_step]
        roughness = float(bumps.max() - bumps.min()) if bumps.size else 0.0
        if use_line[best]:
            z = float(mean[best] + slope[best] * (0.0 - offsets.mean()))  # the line at the sole point (offset 0)
            pitch = -math.atan(float(slope[best]))
            return Foothold(float(candidates[best]), z, pitch, float(support[best]), roughness)
        # a rigid sole rests on the highest points under it: a step within it (a tread's top above the ground its
        # heel overhangs) is a surface; bumps lower than height_step are below what the scan resolves under a sole
        # 15 cm wide (it samples the lane's centre line): the level is the footprint's median there
        under = heights[best, inner]
        z = float(under.max()) if float(under.max()) - float(level[best]) > c.height_step else float(level[best])
        return Foothold(float(candidates[best]), z, 0.0, float(support[best]), roughness)

    def envelope(self, lane: int, start: float, end: float) -> SwingEnvelope:
        """The height a swing of ``lane``'s sole point from x ``start`` to ``end`` [m] holds, and where: the highest
        cell under the sole's length on the way (the sole's ends past the lift-off and landing footprints left out)
        plus ``clearance``; the band is where that envelope stands more than ``height_step`` above the lower end's
        surface (lower bumps are passed by the nominal swing's height)."""
        c = self.config
        a, b = min(start, end), max(start, end)
        xs = np.arange(a, b + 0.5 * c.cell, c.cell)
        # both lanes: the swing foot's inner edge passes a centimetre or two from the other lane's stones, and a
        # foot that sways or yaws a little clips a higher one
        profile = np.maximum(self.profile(0), self.profile(1))
        under = np.rint((xs[:, None] + np.arange(-c.heel, c.toe + 0.5 * c.cell, c.cell)[None, :] - c.x_min) / c.cell)
        highest = profile[under.astype(np.int64).clip(0, profile.size - 1)].max(axis=1)
        top = float(highest.max()) + c.clearance
        ends = self.heights_at(lane, np.array([start, end]))
        above = np.flatnonzero(highest > float(ends.min()) + c.height_step)
        band = (float(xs[above[0]]), float(xs[above[-1]])) if above.size else (a, a)
        return SwingEnvelope(max(top, float(ends.max()) + c.min_rise), band)


@njit(**BORROW_EXACT)
def write_scan(
    heights: NDArray[np.float64],
    rows: NDArray[np.int64],
    offsets: NDArray[np.float64],
    scan: NDArray[np.float64],
    lanes: NDArray[np.float64],
    x: float,
    y: float,
    z: float,
    c: float,
    s: float,
    tolerance: float,
    x_min: float,
    cell: float,
) -> None:  # pragma: no cover - compiled (held equal to TerrainMap.observe's NumPy path by a test)
    """:meth:`TerrainMap.observe`'s writes in one call: per lane and scan row, the row's point nearest to the lane's
    line (the first of equals, a NaN distance taken as NumPy's argmin takes it) writes ``scan + z`` into the lane's
    cell at its world x, where it lies within ``tolerance`` [m] of the line and the cell on the map. The pelvis at
    ``(x, y, z)`` [m] with heading cosine ``c`` and sine ``s``; the NumPy path's operations in its order."""
    n = heights.shape[1]
    for lane in range(lanes.shape[0]):
        lane_y = lanes[lane]
        for r in range(rows.shape[0]):
            best = -1
            best_distance = 0.0
            for q in range(rows.shape[1]):
                p = rows[r, q]
                distance = abs(y + s * offsets[p, 0] + c * offsets[p, 1] - lane_y)
                if math.isnan(distance):
                    best, best_distance = q, distance
                    break
                if best < 0 or distance < best_distance:
                    best, best_distance = q, distance
            if best < 0 or not best_distance <= tolerance:
                continue
            p = rows[r, best]
            index = np.rint((x + c * offsets[p, 0] - s * offsets[p, 1] - x_min) / cell)
            if 0.0 <= index < n:
                heights[lane, int(index)] = scan[p] + z

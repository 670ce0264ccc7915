"""Seeded generator of a double-row sweet-pepper crop (the AgriReach scene), as swept-sphere primitives.

Plants are trained on wires: near-vertical stems (LSS), 0.25-0.35 m apart along the row (the y axis), in two
rows (the near one at ``x = row_distance``, the far one ``row_gap`` behind it). Each stem carries leaves (a
petiole LSS and a blade of two TSS) and 1-3 peppers (PSS) on short peduncles in a harvest band. The result is
plain arrays: :mod:`redundancy_gym.assets.agri_scene` composes the MJCF, the env builds the collision model.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["DIFFICULTIES", "PART_KINDS", "PART_REACH", "CropRow", "crop_row_defaults", "generate_crop_row"]

PART_KINDS = ("stem", "fruit", "petiole", "leaf", "shoot")
"""Categories of plant parts; stems, shoots and fruits are hard obstacles, petioles and leaves soft."""
_HARD = {"stem": True, "fruit": True, "petiole": False, "leaf": False, "shoot": True}
_KIND_CODE = {"stem": 1, "fruit": 0, "petiole": 1, "leaf": 2, "shoot": 1}  # PSS 0, LSS 1, TSS 2
STEM_HEIGHT = 2.2  # [m]
LEAF_LENGTH = (0.15, 0.25)  # [m] blade length range
PETIOLE_LENGTH = 0.1  # [m] longest petiole
SHOOT_LENGTH = 0.22  # [m] longest horizontal run of a side shoot
PETIOLE_RADIUS = 0.002  # [m]
LEAF_RADIUS = 0.002  # [m] half thickness of a blade
PART_REACH = PETIOLE_LENGTH + LEAF_LENGTH[1] + 0.05
"""Bound on how far [m] a part reaches horizontally from its stem's axis (leaves are the longest; 0.05 m covers
the stem's lean at working height)."""

DIFFICULTIES = ("easy", "medium", "hard")
_DIFFICULTY = {
    # leaves per stem, fruits per stem (min, max), probability of a side shoot per stem, cluster spread [m]
    "easy": {"leaves_per_stem": 3, "fruits_per_stem": (1, 2), "shoot_probability": 0.0, "cluster_spread": 0.12},
    "medium": {"leaves_per_stem": 6, "fruits_per_stem": (1, 3), "shoot_probability": 0.25, "cluster_spread": 0.08},
    "hard": {"leaves_per_stem": 10, "fruits_per_stem": (2, 3), "shoot_probability": 0.6, "cluster_spread": 0.05},
}


def crop_row_defaults(difficulty: str = "medium") -> dict[str, Any]:
    """Scene quantities of a difficulty level (a fresh dict); explicit env kwargs override them."""
    if difficulty not in _DIFFICULTY:
        raise ValueError(f"unknown difficulty {difficulty!r}; valid: {', '.join(DIFFICULTIES)}")
    return dict(_DIFFICULTY[difficulty])


@dataclass(frozen=True)
class CropRow:
    """Plant parts as swept-sphere primitives (world frame, z up).

    Attributes:
        category: (N,) part category, one of :data:`PART_KINDS`.
        kind: (N,) SSV kind code (0 PSS, 1 LSS, 2 TSS).
        vertices: (N, 3, 3) generating vertices [m] (unused rows repeat the last vertex).
        radius: (N,) [m].
        plant: (N,) index of the stem the part belongs to.
        hard: (N,) True for stems, shoots and fruits (contact is a collision), False for leaves and petioles.
        stem_base: (S, 3) stem foot points [m]; stem_top: (S, 3) stem top points [m].
        near_row: (S,) True for stems of the near row.
        blade: (N,) index of the leaf blade a TSS belongs to (the two triangles of a blade share it), -1 for
            other parts.
    """

    category: NDArray[np.str_]
    kind: NDArray[np.int64]
    vertices: NDArray[np.float64]
    radius: NDArray[np.float64]
    plant: NDArray[np.int64]
    hard: NDArray[np.bool_]
    stem_base: NDArray[np.float64]
    stem_top: NDArray[np.float64]
    near_row: NDArray[np.bool_]
    blade: NDArray[np.int64]

    def __len__(self) -> int:
        return int(self.kind.size)

    def whole_blades(self, keep: NDArray[np.int64]) -> NDArray[np.int64]:
        """Sorted part indices: ``keep`` plus the other triangle of every leaf blade it touches."""
        mask = np.zeros(len(self), dtype=bool)
        mask[keep] = True
        blades = np.unique(self.blade[mask & (self.blade >= 0)])
        mask |= (self.blade >= 0) & np.isin(self.blade, blades)
        return np.flatnonzero(mask)

    def subset(self, keep: NDArray[np.int64]) -> CropRow:
        """The parts :meth:`whole_blades` of ``keep`` (a blade stays whole), in their order; stems stay listed
        in ``stem_base``/``stem_top``."""
        k = self.whole_blades(keep)
        return CropRow(
            self.category[k],
            self.kind[k],
            self.vertices[k],
            self.radius[k],
            self.plant[k],
            self.hard[k],
            self.stem_base,
            self.stem_top,
            self.near_row,
            self.blade[k],
        )

    def stem_point(self, plant: int, z: float) -> NDArray[np.float64]:
        """Point of stem ``plant`` at height ``z`` [m]."""
        a, b = self.stem_base[plant], self.stem_top[plant]
        return a + (z - a[2]) / (b[2] - a[2]) * (b - a)


def generate_crop_row(
    rng: np.random.Generator,
    *,
    row_distance: float = 1.05,
    row_gap: float = 0.45,
    row_length: float = 8.0,
    stem_spacing: tuple[float, float] = (0.25, 0.35),
    stem_diameter: tuple[float, float] = (0.010, 0.015),
    stem_height: float = STEM_HEIGHT,
    fruit_diameter: tuple[float, float] = (0.08, 0.09),
    fruits_per_stem: tuple[int, int] = (1, 3),
    harvest_band: tuple[float, float] = (0.9, 1.3),
    leaves_per_stem: int = 6,
    leaf_length: tuple[float, float] = LEAF_LENGTH,
    shoot_probability: float = 0.25,
    cluster_spread: float = 0.08,
) -> CropRow:
    """A seeded double row of pepper plants centred on ``y = 0``.

    Vectorized over plants (a reset draws a row every episode, so this is on the training loop's path). Parts
    are ordered stems, peppers, petioles, leaf triangles (the two of a blade adjacent), shoots.

    Args:
        rng: the env's generator (every draw comes from it).
        row_distance: x of the near row [m]; row_gap: distance to the far row [m].
        row_length: length of the rows along y [m].
        stem_spacing: range of the distance between neighbouring stems [m].
        stem_diameter, fruit_diameter: ranges [m]; stem_height: top of the stems [m].
        fruits_per_stem: inclusive range of the number of peppers per stem.
        harvest_band: heights (low, high) between which peppers hang [m].
        leaves_per_stem: leaves per stem, spread over the band +-0.25 m.
        leaf_length: range of the blade length [m].
        shoot_probability: chance per stem of a side shoot reaching into the path (occluding stem).
        cluster_spread: vertical spread of the peppers of one stem [m] (small = clustered fruit).
    """
    half = 0.5 * row_length
    n_max = int(np.ceil(row_length / stem_spacing[0])) + 2
    ys, near = [], []
    for row in range(2):
        y = (
            -half
            + rng.uniform(0.0, stem_spacing[1])
            + np.concatenate([[0.0], np.cumsum(rng.uniform(stem_spacing[0], stem_spacing[1], n_max - 1))])
        )
        y = y[y <= half]
        ys.append(y)
        near.append(np.full(y.size, row == 0))
    y = np.concatenate(ys)
    near_row = np.concatenate(near)
    n_stems = y.size
    x0 = np.where(near_row, row_distance, row_distance + row_gap)
    base = np.column_stack([x0 + rng.uniform(-0.02, 0.02, n_stems), y, np.full(n_stems, 0.3)])
    top = base + np.column_stack([rng.normal(0.0, 0.03, (n_stems, 2)), stem_height - base[:, 2]])
    stem_radius = 0.5 * rng.uniform(stem_diameter[0], stem_diameter[1], n_stems)
    slope = (top - base) / (top[:, 2:3] - base[:, 2:3])  # stem point at height z: base + (z - base_z) * slope

    def stem_point(plant: NDArray[np.int64], z: NDArray[np.float64]) -> NDArray[np.float64]:
        return base[plant] + (z - base[plant, 2])[:, None] * slope[plant]

    def horizontal(phi: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.column_stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)])

    low, high = harvest_band
    # peppers: a cluster centre per plant, then each fruit hangs below its peduncle, its shoulder at the stem
    n_fruit = rng.integers(fruits_per_stem[0], fruits_per_stem[1] + 1, n_stems)
    z_center = rng.uniform(low + 0.5 * cluster_spread, high - 0.5 * cluster_spread, n_stems)
    f_plant = np.repeat(np.arange(n_stems), n_fruit)
    n_f = f_plant.size
    f_z = np.clip(z_center[f_plant] + rng.uniform(-0.5, 0.5, n_f) * cluster_spread, low, high)
    f_radius = 0.5 * rng.uniform(fruit_diameter[0], fruit_diameter[1], n_f)
    f_center = (
        stem_point(f_plant, f_z + f_radius)
        + (f_radius + 0.012)[:, None] * horizontal(rng.uniform(0.0, 2.0 * np.pi, n_f))
    ) - np.column_stack([np.zeros((n_f, 2)), 0.8 * f_radius])
    # leaves: a petiole out of the stem, then a drooping kite-shaped blade of two triangles
    l_plant = np.repeat(np.arange(n_stems), leaves_per_stem)
    n_l = l_plant.size
    out = horizontal(rng.uniform(0.0, 2.0 * np.pi, n_l))
    side = np.column_stack([-out[:, 1], out[:, 0], np.zeros(n_l)])
    start = stem_point(l_plant, rng.uniform(low - 0.25, high + 0.25, n_l))
    end = start + rng.uniform(0.05, 0.1, n_l)[:, None] * out
    end[:, 2] += rng.uniform(0.0, 0.04, n_l)
    length = rng.uniform(leaf_length[0], leaf_length[1], n_l)
    droop = rng.uniform(0.1, 0.6, n_l)
    direction = (out - np.column_stack([np.zeros((n_l, 2)), droop])) / np.sqrt(1.0 + droop * droop)[:, None]
    tip = end + length[:, None] * direction
    width = rng.uniform(0.4, 0.5, n_l) * length
    mid = end + (0.4 * length)[:, None] * direction
    left, right = mid + (0.5 * width)[:, None] * side, mid - (0.5 * width)[:, None] * side
    blades = np.empty((2 * n_l, 3, 3))
    blades[0::2] = np.stack([end, left, tip], axis=1)
    blades[1::2] = np.stack([end, tip, right], axis=1)
    # side shoots grow towards the path, where the arm works
    s_plant = np.flatnonzero(rng.uniform(size=n_stems) < shoot_probability)
    n_s = s_plant.size
    s_start = stem_point(s_plant, rng.uniform(low, high, n_s))
    s_end = s_start + rng.uniform(0.12, SHOOT_LENGTH, n_s)[:, None] * horizontal(np.pi + rng.uniform(-0.8, 0.8, n_s))
    s_end[:, 2] += rng.uniform(0.05, 0.2, n_s)
    s_radius = 0.4 * rng.uniform(stem_diameter[0], stem_diameter[1], n_s)

    def segments(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.stack([a, b, b], axis=1)

    counts = {"stem": n_stems, "fruit": n_f, "petiole": n_l, "leaf": 2 * n_l, "shoot": n_s}
    category = np.repeat(np.array(list(counts)), list(counts.values()))
    vertices = np.concatenate(
        [
            segments(base, top),
            np.repeat(f_center[:, None], 3, axis=1),
            segments(start, end),
            blades,
            segments(s_start, s_end),
        ]
    )
    radius = np.concatenate(
        [stem_radius, f_radius, np.full(n_l, PETIOLE_RADIUS), np.full(2 * n_l, LEAF_RADIUS), s_radius]
    )
    plant = np.concatenate([np.arange(n_stems), f_plant, l_plant, np.repeat(l_plant, 2), s_plant])
    blade = np.full(category.size, -1, dtype=np.int64)
    blade[category == "leaf"] = np.repeat(np.arange(n_l), 2)
    return CropRow(
        category,
        np.array([_KIND_CODE[c] for c in counts]).repeat(list(counts.values())),
        vertices,
        radius,
        plant,
        np.array([_HARD[c] for c in counts]).repeat(list(counts.values())),
        base,
        top,
        near_row,
        blade,
    )

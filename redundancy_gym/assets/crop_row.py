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

__all__ = ["DIFFICULTIES", "PART_KINDS", "CropRow", "crop_row_defaults", "generate_crop_row"]

PART_KINDS = ("stem", "fruit", "petiole", "leaf", "shoot")
"""Categories of plant parts; stems, shoots and fruits are hard obstacles, petioles and leaves soft."""
_HARD = {"stem": True, "fruit": True, "petiole": False, "leaf": False, "shoot": True}
_KIND_CODE = {"stem": 1, "fruit": 0, "petiole": 1, "leaf": 2, "shoot": 1}  # PSS 0, LSS 1, TSS 2

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

    def __len__(self) -> int:
        return int(self.kind.size)

    def subset(self, keep: NDArray[np.int64]) -> CropRow:
        """The parts with indices ``keep`` (stems stay listed in ``stem_base``/``stem_top``)."""
        return CropRow(self.category[keep], self.kind[keep], self.vertices[keep], self.radius[keep], self.plant[keep],
                       self.hard[keep], self.stem_base, self.stem_top, self.near_row)

    def stem_point(self, plant: int, z: float) -> NDArray[np.float64]:
        """Point of stem ``plant`` at height ``z`` [m]."""
        a, b = self.stem_base[plant], self.stem_top[plant]
        return a + (z - a[2]) / (b[2] - a[2]) * (b - a)


def _uniform(rng: np.random.Generator, bounds: tuple[float, float]) -> float:
    return float(rng.uniform(bounds[0], bounds[1]))


def generate_crop_row(rng: np.random.Generator, *, row_distance: float = 1.05, row_gap: float = 0.45,
                      row_length: float = 8.0, stem_spacing: tuple[float, float] = (0.25, 0.35),
                      stem_diameter: tuple[float, float] = (0.010, 0.015), stem_height: float = 2.2,
                      fruit_diameter: tuple[float, float] = (0.08, 0.09), fruits_per_stem: tuple[int, int] = (1, 3),
                      harvest_band: tuple[float, float] = (0.9, 1.3), leaves_per_stem: int = 6,
                      leaf_length: tuple[float, float] = (0.15, 0.25), shoot_probability: float = 0.25,
                      cluster_spread: float = 0.08) -> CropRow:
    """A seeded double row of pepper plants centred on ``y = 0``.

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
    parts: list[tuple[str, list[NDArray[np.float64]], float, int]] = []
    bases, tops, near = [], [], []
    half = 0.5 * row_length
    for row, x0 in enumerate((row_distance, row_distance + row_gap)):
        y = -half + _uniform(rng, (0.0, stem_spacing[1]))
        while y <= half:
            base = np.array([x0 + rng.uniform(-0.02, 0.02), y, 0.3])
            lean = rng.normal(0.0, 0.03, 2)
            top = np.array([base[0] + lean[0], base[1] + lean[1], stem_height])
            plant = len(bases)
            bases.append(base)
            tops.append(top)
            near.append(row == 0)
            parts.append(("stem", [base, top], 0.5 * _uniform(rng, stem_diameter), plant))
            y += _uniform(rng, stem_spacing)
    row_data = CropRow(np.array([]), np.array([]), np.zeros((0, 3, 3)), np.array([]), np.array([]), np.array([]),
                       np.array(bases), np.array(tops), np.array(near))
    low, high = harvest_band
    for plant in range(len(bases)):
        n_fruit = int(rng.integers(fruits_per_stem[0], fruits_per_stem[1] + 1))
        z_center = rng.uniform(low + 0.5 * cluster_spread, high - 0.5 * cluster_spread)
        for _ in range(n_fruit):
            z = float(np.clip(z_center + rng.uniform(-0.5, 0.5) * cluster_spread, low, high))
            phi = rng.uniform(0.0, 2.0 * np.pi)
            r = 0.5 * _uniform(rng, fruit_diameter)
            radial = np.array([np.cos(phi), np.sin(phi), 0.0])
            attach = row_data.stem_point(plant, z + r)
            # the pepper hangs below its peduncle, its shoulder touching the stem's side
            center = attach + (r + 0.012) * radial - np.array([0.0, 0.0, 0.8 * r])
            parts.append(("fruit", [center], r, plant))
        for _ in range(leaves_per_stem):
            z = rng.uniform(low - 0.25, high + 0.25)
            phi = rng.uniform(0.0, 2.0 * np.pi)
            out = np.array([np.cos(phi), np.sin(phi), 0.0])
            side = np.array([-out[1], out[0], 0.0])
            start = row_data.stem_point(plant, z)
            end = start + rng.uniform(0.05, 0.1) * out + np.array([0.0, 0.0, rng.uniform(0.0, 0.04)])
            parts.append(("petiole", [start, end], 0.002, plant))
            length = _uniform(rng, leaf_length)
            droop = rng.uniform(0.1, 0.6)
            direction = (out + np.array([0.0, 0.0, -droop])) / np.sqrt(1.0 + droop * droop)
            tip = end + length * direction
            width = rng.uniform(0.4, 0.5) * length
            mid = end + 0.4 * length * direction
            left, right = mid + 0.5 * width * side, mid - 0.5 * width * side
            parts.append(("leaf", [end, left, tip], 0.002, plant))
            parts.append(("leaf", [end, tip, right], 0.002, plant))
        if rng.uniform() < shoot_probability:
            z = rng.uniform(low, high)
            phi = np.pi + rng.uniform(-0.8, 0.8)  # towards the path, where the arm works
            start = row_data.stem_point(plant, z)
            end = start + rng.uniform(0.12, 0.22) * np.array([np.cos(phi), np.sin(phi), 0.0]) \
                + np.array([0.0, 0.0, rng.uniform(0.05, 0.2)])
            parts.append(("shoot", [start, end], 0.5 * _uniform(rng, stem_diameter) * 0.8, plant))
    n = len(parts)
    vertices = np.empty((n, 3, 3))
    for k, (_, pts, _, _) in enumerate(parts):
        for i in range(3):
            vertices[k, i] = pts[min(i, len(pts) - 1)]
    category = np.array([p[0] for p in parts])
    return CropRow(category, np.array([_KIND_CODE[c] for c in category], dtype=np.int64), vertices,
                   np.array([p[2] for p in parts]), np.array([p[3] for p in parts], dtype=np.int64),
                   np.array([_HARD[c] for c in category]), row_data.stem_base, row_data.stem_top,
                   row_data.near_row)

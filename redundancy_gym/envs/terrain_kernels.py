"""Compiled twin of :meth:`redundancy_gym.assets.terrain.Terrain.heights` (BipedTerrain's height scan and support
metrics, every control step): the same arithmetic in one loop, the same bits (the tests hold them equal)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import NDArray

from ..assets.terrain import Terrain
from ..kernel_options import JIT_EXACT

__all__ = ["PackedTerrain", "pack_terrain", "terrain_heights_kernel"]

PackedTerrain = tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]
"""``(boxes (B, 5), ramps (R, 7), patches (P, 6): x0, y0, spacing, rows, columns, offset, heights (flat))``."""


def pack_terrain(terrain: Terrain) -> PackedTerrain:
    """The arrays :func:`terrain_heights_kernel` reads."""
    meta = np.zeros((len(terrain.patches), 6))
    flat: list[NDArray[np.float64]] = []
    offset = 0
    for k, patch in enumerate(terrain.patches):
        rows, cols = patch.heights.shape
        meta[k] = (patch.x0, patch.y0, patch.spacing, rows, cols, offset)
        flat.append(patch.heights.ravel())
        offset += rows * cols
    data = np.concatenate(flat) if flat else np.zeros(0)
    return np.ascontiguousarray(terrain.boxes), np.ascontiguousarray(terrain.ramps), meta, data


@njit(**JIT_EXACT)
def terrain_heights_kernel(x, y, boxes, ramps, meta, data, out):  # noqa: ANN001, ANN201
    """``out[i]`` = the terrain height [m] at ``(x[i], y[i])``: :meth:`Terrain.heights` point by point."""
    for i in range(x.size):
        px, py = x[i], y[i]
        z = 0.0
        for b in range(boxes.shape[0]):
            if boxes[b, 0] <= px <= boxes[b, 1] and boxes[b, 2] <= py <= boxes[b, 3]:
                z = max(z, boxes[b, 4])
        for r in range(ramps.shape[0]):
            x0, a, c, x1, height = ramps[r, 0], ramps[r, 1], ramps[r, 2], ramps[r, 3], ramps[r, 4]
            if x0 <= px <= x1 and ramps[r, 5] <= py <= ramps[r, 6]:
                up = height * min(max((px - x0) / (a - x0), 0.0), 1.0)
                down = height * min(max((x1 - px) / (x1 - c), 0.0), 1.0)
                z = max(z, min(up, down))
        for p in range(meta.shape[0]):
            spacing = meta[p, 2]
            rows, cols, offset = int(meta[p, 3]), int(meta[p, 4]), int(meta[p, 5])
            u = (px - meta[p, 0]) / spacing
            v = (py - meta[p, 1]) / spacing
            if not (u >= 0.0 and u <= cols - 1 and v >= 0.0 and v <= rows - 1):
                continue
            col = min(max(int(math.floor(u)), 0), cols - 2)
            row = min(max(int(math.floor(v)), 0), rows - 2)
            fu, fv = u - col, v - row
            k = offset + row * cols + col
            z00, z01, z10, z11 = data[k], data[k + 1], data[k + cols], data[k + cols + 1]
            if fu >= fv:
                h = z00 + fu * (z01 - z00) + fv * (z11 - z01)
            else:
                h = z00 + fv * (z10 - z00) + fu * (z11 - z10)
            z = max(z, h)
        out[i] = z
    return out

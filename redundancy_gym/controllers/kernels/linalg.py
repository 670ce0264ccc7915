"""Linear algebra shared by the compiled controllers: the rotation error ``log3`` of two rotations."""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["rotation_error", "rotation_error_into"]


@njit(cache=True)
def rotation_error_into(desired: np.ndarray, actual: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover
    """World rotation vector ``log(R_d R^T)`` [rad] taking ``actual`` to ``desired``, into ``out`` (3)."""
    r = np.empty((3, 3))
    for a in range(3):
        for b in range(3):
            r[a, b] = desired[a, 0] * actual[b, 0] + desired[a, 1] * actual[b, 1] + desired[a, 2] * actual[b, 2]
    cos = 0.5 * (r[0, 0] + r[1, 1] + r[2, 2] - 1.0)
    cos = min(1.0, max(-1.0, cos))
    angle = np.arccos(cos)
    ax, ay, az = r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]
    if angle < 1e-6:
        scale = 0.5  # sin(angle) / angle -> 1
    elif np.pi - angle < 1e-6:
        # near a half turn the antisymmetric part vanishes: the axis is the dominant column of R + I
        k = 0
        if r[1, 1] > r[k, k]:
            k = 1
        if r[2, 2] > r[k, k]:
            k = 2
        c0, c1, c2 = r[0, k], r[1, k], r[2, k]
        if k == 0:
            c0 += 1.0
        elif k == 1:
            c1 += 1.0
        else:
            c2 += 1.0
        norm = np.sqrt(c0 * c0 + c1 * c1 + c2 * c2)
        out[0], out[1], out[2] = angle * c0 / norm, angle * c1 / norm, angle * c2 / norm
        return
    else:
        scale = angle / (2.0 * np.sin(angle))
    out[0], out[1], out[2] = scale * ax, scale * ay, scale * az


@njit(cache=True)
def rotation_error(desired: np.ndarray, actual: np.ndarray) -> np.ndarray:  # pragma: no cover - compiled
    """World rotation vector ``log(R_d R^T)`` [rad] taking ``actual`` to ``desired``."""
    out = np.empty(3)
    rotation_error_into(desired, actual, out)
    return out

"""Compiled pieces of the whole-body IK step: the weighted solve with the rank-one weight (5.62) and ``log3``."""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["rotation_error", "rotation_error_into", "weighted_solve"]


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


@njit(cache=True)
def weighted_solve(jac: np.ndarray, rhs: np.ndarray, j_lz: np.ndarray, z: np.ndarray, gamma: float,
                   minimize_momentum: bool, damping: float) -> tuple[np.ndarray, float, bool]:  # pragma: no cover
    """``(qdot, sigma_min, ok)``: ``qdot = W^-1 (J^T lambda - z)``, ``(J W^-1 J^T + damping I) lambda = rhs + J W^-1 z``.

    ``W = gamma I + j_lz j_lz^T`` (5.62) is inverted by Sherman-Morrison-Woodbury; ``W = I`` when
    ``minimize_momentum`` is False. ``sigma_min`` is the smallest pivot of the Cholesky factor.
    """
    m, n = jac.shape
    if minimize_momentum:
        scale = 1.0 / (gamma + j_lz @ j_lz)
        jw = (jac - np.outer(jac @ j_lz, j_lz) * scale) / gamma
        wz = (z - j_lz * ((j_lz @ z) * scale)) / gamma
    else:
        jw = jac.copy()
        wz = z.copy()
    b = jw @ jac.T
    for i in range(m):
        b[i, i] += damping
    factor = np.zeros((m, m))
    sigma = np.inf
    for j in range(m):
        s = b[j, j] - factor[j, :j] @ factor[j, :j]
        if not s > 0.0:
            return np.zeros(n), 0.0, False
        factor[j, j] = np.sqrt(s)
        sigma = min(sigma, factor[j, j])
        for i in range(j + 1, m):
            factor[i, j] = (b[i, j] - factor[i, :j] @ factor[j, :j]) / factor[j, j]
    y = rhs + jw @ z
    for i in range(m):  # forward substitution
        y[i] = (y[i] - factor[i, :i] @ y[:i]) / factor[i, i]
    for i in range(m - 1, -1, -1):  # back substitution with the transpose
        acc = y[i]
        for k in range(i + 1, m):
            acc -= factor[k, i] * y[k]
        y[i] = acc / factor[i, i]
    qdot = jw.T @ y - wz
    return qdot, sigma, True

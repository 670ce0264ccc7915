"""Compiled piece of the whole-body IK step: the weighted solve with the rank-one weight (5.62)."""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["weighted_solve"]


@njit(cache=True)
def weighted_solve(
    jac: np.ndarray,
    rhs: np.ndarray,
    j_lz: np.ndarray,
    z: np.ndarray,
    gamma: float,
    minimize_momentum: bool,
    damping: float,
) -> tuple[np.ndarray, float, bool]:  # pragma: no cover
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

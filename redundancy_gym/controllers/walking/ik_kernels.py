"""Compiled piece of the whole-body IK step: the weighted solve with the rank-one weight (5.62)."""

from __future__ import annotations

import numpy as np
from numba import njit

from ...kernel_options import JIT_EXACT
from ..kernels.linalg import cholesky_factor, cholesky_solve

__all__ = ["weighted_solve"]


@njit(**JIT_EXACT)
def weighted_solve(
    jac: np.ndarray,
    rhs: np.ndarray,
    j_lz: np.ndarray,
    z: np.ndarray,
    gamma: float,
    minimize_momentum: bool,
    damping: float,
) -> tuple[np.ndarray, float, bool]:  # pragma: no cover
    """``(qdot, sigma_min, ok)``: ``qdot = W^-1 (J^T lambda - z)`` with
    ``(J W^-1 J^T + damping I) lambda = rhs + J W^-1 z``.

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
    factor = np.empty((m, m))
    sigma = cholesky_factor(b, m, factor)
    if not sigma > 0.0:
        return np.zeros(n), 0.0, False
    y = rhs + jw @ z
    cholesky_solve(factor, m, y)
    qdot = jw.T @ y - wz
    return qdot, sigma, True

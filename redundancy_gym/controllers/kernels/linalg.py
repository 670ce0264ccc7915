"""Linear algebra shared by the compiled controllers: the rotation error ``log3`` of two rotations and the one
Cholesky factorization and solve of the damped (weighted) minimum-norm steps (5.14), (5.22), (5.62), (5.91), (5.102).

The Cholesky pair is compiled ``inline="always"``: it runs inside the per-sample and per-step loops of the
fused kernels, where a call between compiled functions costs about 90 ns (numba passes every array as a struct)
against a few hundred ns of work for a 6 x 6 system. Inlined, it takes the caller's numba options (a kernel
compiled with :data:`~redundancy_gym.kernel_options.JIT_EXACT` keeps plain IEEE arithmetic). Both run in the
order of the loops of the controllers before they shared them, so their results are unchanged.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...kernel_options import BORROW, JIT_EXACT

__all__ = ["cholesky_factor", "cholesky_solve", "rotation_error", "rotation_error_into"]


@njit(**JIT_EXACT)
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


@njit(**JIT_EXACT)
def rotation_error(desired: np.ndarray, actual: np.ndarray) -> np.ndarray:  # pragma: no cover - compiled
    """World rotation vector ``log(R_d R^T)`` [rad] taking ``actual`` to ``desired``."""
    out = np.empty(3)
    rotation_error_into(desired, actual, out)
    return out


@njit(inline="always", **BORROW)
def cholesky_factor(a: np.ndarray, m: int, low: np.ndarray) -> float:  # pragma: no cover - compiled
    """The lower Cholesky factor ``L`` (``A = L L^T``) of the leading ``m x m`` block of the symmetric ``a`` into
    the lower triangle of ``low`` (its upper triangle untouched); returns the smallest pivot ``min_j L_jj``.

    Returns 0.0 when ``A`` is not positive definite, where LAPACK's ``potrf`` fails (a pivot not > 0, NaN
    included), and leaves ``low`` unfinished. Column by column; each entry is
    ``L_ij = (A_ij - sum_{k<j} L_ik L_jk) / L_jj`` summed in increasing ``k``. ``m = 0`` returns inf.
    """
    smallest = np.inf
    for j in range(m):
        s = a[j, j]
        for k in range(j):
            s -= low[j, k] * low[j, k]
        if not s > 0.0:
            return 0.0
        pivot = np.sqrt(s)
        low[j, j] = pivot
        smallest = min(smallest, pivot)
        for i in range(j + 1, m):
            t = a[i, j]
            for k in range(j):
                t -= low[i, k] * low[j, k]
            low[i, j] = t / low[j, j]  # the stored pivot, as before: under fast math t / pivot rounds otherwise
    return smallest


@njit(inline="always", **BORROW)
def cholesky_solve(low: np.ndarray, m: int, x: np.ndarray) -> None:  # pragma: no cover - compiled
    """``x <- A^-1 x`` in place (the first ``m`` entries) with the factor ``L`` of :func:`cholesky_factor`:
    ``L y = x`` forward, then ``L^T x = y`` back."""
    for i in range(m):
        t = x[i]
        for k in range(i):
            t -= low[i, k] * x[k]
        x[i] = t / low[i, i]
    for i in range(m - 1, -1, -1):
        t = x[i]
        for k in range(i + 1, m):
            t -= low[k, i] * x[k]
        x[i] = t / low[i, i]

"""Compiled kernels of the action wrappers' glue, the work a wrapper's step does around its controller: the action's
check and clip, and the joint command handed to the env. Each is one call instead of three or four NumPy calls on
a short vector, and gives the same bits as the NumPy expression it replaces (named in its docstring)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..kernel_options import JIT_EXACT

__all__ = ["clipped_finite", "joint_command", "residual_applied"]


@njit(**JIT_EXACT)
def clipped_finite(action):  # noqa: ANN001, ANN201
    """``(action.astype(float64).clip(-1, 1), all entries finite)`` of a 1-D float array (a new array)."""
    out = np.empty(action.shape[0])
    finite = True
    for j in range(action.shape[0]):
        a = np.float64(action[j])
        finite = finite and math.isfinite(a)
        out[j] = min(max(a, -1.0), 1.0)
    return out, finite


@njit(**JIT_EXACT)
def joint_command(qdot, speeds):  # noqa: ANN001, ANN201
    """``(qdot / speeds).clip(-1, 1).astype(float32)``: the env's normalized joint action of a joint velocity
    command (``speeds`` the joints' speeds at action 1)."""
    out = np.empty(qdot.shape[0], dtype=np.float32)
    for j in range(qdot.shape[0]):
        out[j] = np.float32(min(max(qdot[j] / speeds[j], -1.0), 1.0))
    return out


@njit(**JIT_EXACT)
def residual_applied(reference, scaled_range, action, low, high):  # noqa: ANN001, ANN201
    """``(applied, applied - reference)`` with ``applied = np.clip(reference + (scaled_range * action).astype(
    reference.dtype), low, high)``: a residual action on the reference's, in the env's dtype (that of ``reference``,
    ``low`` and ``high``), so that ``action = 0`` gives the reference bit for bit."""
    n = reference.shape[0]
    applied = np.empty_like(reference)
    delta = np.empty_like(reference)
    for j in range(n):
        residual = reference.dtype.type(scaled_range[j] * action[j])
        value = min(max(reference[j] + residual, low[j]), high[j])
        applied[j] = value
        delta[j] = value - reference[j]
    return applied, delta

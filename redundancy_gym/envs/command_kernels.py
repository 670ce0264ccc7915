"""The compiled command kernel of the velocity-commanded arms (PlanarReach-v0, AgriReach-v0,
``backend="compiled"``): an action's joint velocity commands into the servos' and the feed-forwards' controls in
one pass, with the finiteness check of the action folded in."""

from __future__ import annotations

import math

from numba import njit

from ..kernel_options import JIT_EXACT

__all__ = ["velocity_commands"]


@njit(**JIT_EXACT)
def velocity_commands(action, scale, ctrl):  # noqa: ANN001, ANN201
    """``scale * clip(action, -1, 1)`` (per joint [rad/s or m/s]) into both halves of ``ctrl`` (the servos', then
    the feed-forwards'); returns False, writing nothing, when an entry of ``action`` is not finite."""
    n = action.shape[0]
    for j in range(n):
        if not math.isfinite(action[j]):
            return False
    for j in range(n):
        c = scale[j] * min(max(action[j], -1.0), 1.0)
        ctrl[j] = c
        ctrl[n + j] = c
    return True

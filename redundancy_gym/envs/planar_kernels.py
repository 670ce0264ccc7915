"""The compiled kernel of PlanarReach-v0's step (``backend="compiled"``): the observation with the step's metrics
in one pass. It computes what the ``backend="python"`` reference does
with NumPy, in its order (elementwise expressions, the norms of 2-vectors and the sums as NumPy forms them), so the
two agree bit for bit.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..kernel_options import JIT_EXACT

__all__ = ["planar_state"]


@njit(**JIT_EXACT)
def planar_state(  # noqa: ANN201
    qpos,  # noqa: ANN001
    qvel,  # noqa: ANN001
    qpos_index,  # noqa: ANN001
    qvel_index,  # noqa: ANN001
    tcp_xpos,  # noqa: ANN001
    line_start,  # noqa: ANN001
    line_end,  # noqa: ANN001
    law,  # noqa: ANN001
    obstacle,  # noqa: ANN001
    lower,  # noqa: ANN001
    upper,  # noqa: ANN001
):
    """The observation (20,) without noise, and the step's numbers: ``(obs, tracking error [m], goal error [m],
    qdot^T qdot [rad^2/s^2], joint-limit margin [rad], peak joint speed [rad/s], tcp (2,) [m], reference (2,) [m],
    phase [-])``.

    ``obstacle`` is ``(center x, center z, radius)`` [m] (zeros without one); ``tcp_xpos`` the TCP site's world
    position (3,); ``law`` the reference's ``(phase, s, ds/dt [1/s])`` at this time, from
    :meth:`~redundancy_gym.envs.planar_reach.PlanarReachEnv.reference`'s law (Python's ``**``, whose ``pow``
    rounds differently from the kernel's).
    """
    tau, s, sdot = law
    obs = np.zeros(20)
    n = qpos_index.shape[0]
    energy = 0.0
    peak = 0.0
    margin = np.inf
    for j in range(n):
        q = qpos[qpos_index[j]]
        v = qvel[qvel_index[j]]
        obs[j] = q
        obs[n + j] = v
        energy += v * v
        peak = max(peak, abs(v))
        margin = min(margin, min(q - lower[j], upper[j] - q))
    tcp = np.empty(2)
    ref = np.empty(2)
    tcp[0] = tcp_xpos[0]
    tcp[1] = tcp_xpos[2]
    for c in range(2):
        delta = line_end[c] - line_start[c]
        ref[c] = line_start[c] + s * delta
        obs[8 + c] = tcp[c]
        obs[10 + c] = ref[c]
        obs[12 + c] = sdot * delta
        obs[15 + c] = obstacle[c]
        obs[18 + c] = ref[c] - tcp[c]
    obs[14] = tau
    obs[17] = obstacle[2]
    error = math.sqrt((tcp[0] - ref[0]) ** 2 + (tcp[1] - ref[1]) ** 2)
    goal = math.sqrt((tcp[0] - line_end[0]) ** 2 + (tcp[1] - line_end[1]) ** 2)
    return obs, error, goal, energy, margin, peak, tcp, ref, tau

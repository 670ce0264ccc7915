"""The compiled kernel of AgriReach-v0's step (``backend="compiled"``): the observation's per-step entries and the
step's metrics in one pass, from one sample of the reference path for both, with the three swept-sphere clearance
queries of the step. It computes what the ``backend="python"`` reference does, in the same order (the same
floating-point operations, the same compiled sampler and pair loops), so the two agree bit for bit but for the
squares of two distances (a product here, ``pow`` in Python's ``**``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..geometry.grasp_path import sample_grasp_path
from ..geometry.ssv_kernels import near_pairs_at
from ..kernel_options import JIT_EXACT

__all__ = ["agri_state"]


@njit(**JIT_EXACT)
def agri_state(  # noqa: ANN201
    qpos,  # noqa: ANN001
    qvel,  # noqa: ANN001
    qpos_index,  # noqa: ANN001
    qvel_index,  # noqa: ANN001
    lower,  # noqa: ANN001
    upper,  # noqa: ANN001
    tcp_xpos,  # noqa: ANN001
    tcp_xmat,  # noqa: ANN001
    path,  # noqa: ANN001
    sample,  # noqa: ANN001
    time,  # noqa: ANN001
    grasp,  # noqa: ANN001
    approach,  # noqa: ANN001
    obs,  # noqa: ANN001
    slots,  # noqa: ANN001
    batches,  # noqa: ANN001
    horizon,  # noqa: ANN001
):
    """The step's numbers ``(goal error [m], tracking error [m], orientation error [rad], qdot^T qdot, joint-limit
    margin, peak joint speed, tcp (3,) [m], reference position (3,) [m], hard-part clearance [m], self-clearance
    [m], smallest leaf distance [m])``, and the observation's per-step entries written into ``obs`` (noise-free;
    the TCP quaternion is left to the caller).

    ``path`` are the reference path's constants (:attr:`~redundancy_gym.geometry.GraspPath.params`), sampled at
    ``time`` [s] into ``sample`` (12,: target, then its velocity) by the compiled sampler
    :meth:`~redundancy_gym.geometry.GraspPath.sample` calls; ``batches`` the ``(header, moving, frames)`` addresses
    (:attr:`~redundancy_gym.geometry.PairBatch.address`) of the hard-part, self-collision and leaf pair batches,
    whose :meth:`~redundancy_gym.geometry.PairBatch.compute_near` run here with margins ``horizon``, ``horizon``
    and 0 (the clearances capped at ``horizon`` [m]); ``slots`` the first index in ``obs`` of ``q``, ``qdot``,
    ``tcp_position``, ``time``, ``tcp_reference``, ``tcp_reference_velocity`` and ``tcp_error``; ``tcp_xmat`` the
    TCP site's row-major rotation, whose first column is the tool axis.
    """
    sample_grasp_path(path, time, sample)
    x, y, z = tcp_xpos[0], tcp_xpos[1], tcp_xpos[2]
    gx, gy, gz = grasp[0], grasp[1], grasp[2]
    error = math.sqrt((x - gx) ** 2 + (y - gy) ** 2 + (z - gz) ** 2)
    rx, ry, rz = sample[0], sample[1], sample[2]
    tracking = math.sqrt((x - rx) ** 2 + (y - ry) ** 2 + (z - rz) ** 2)
    cos_angle = tcp_xmat[0] * approach[0] + tcp_xmat[3] * approach[1] + tcp_xmat[6] * approach[2]
    angle = math.acos(min(1.0, max(-1.0, cos_angle)))
    n = qpos_index.shape[0]
    energy = 0.0
    peak = 0.0
    margin = np.inf
    for j in range(n):
        q = qpos[qpos_index[j]]
        v = qvel[qvel_index[j]]
        obs[slots[0] + j] = q
        obs[slots[1] + j] = v
        energy += v * v
        peak = max(peak, abs(v))
        margin = min(margin, min(q - lower[j], upper[j] - q))
    tcp = np.empty(3)
    ref = np.empty(3)
    for c in range(3):
        tcp[c] = tcp_xpos[c]
        ref[c] = sample[c]
        obs[slots[2] + c] = tcp_xpos[c]
        obs[slots[6] + c] = sample[c] - tcp_xpos[c]
    obs[slots[3]] = time
    for c in range(6):
        obs[slots[4] + c] = sample[c]
        obs[slots[5] + c] = sample[6 + c]
    hard, own, leaf = batches
    obstacle = min(near_pairs_at(hard[0], horizon, hard[1], hard[2]), horizon)
    self_clearance = min(near_pairs_at(own[0], horizon, own[1], own[2]), horizon)
    leaves = near_pairs_at(leaf[0], 0.0, leaf[1], leaf[2])
    return error, tracking, angle, energy, margin, peak, tcp, ref, obstacle, self_clearance, leaves

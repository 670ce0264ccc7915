"""Compiled kinematics of chains of 1-DoF joints: forward kinematics and point Jacobians (monograph 5.1).

The kernels work on the arrays of a :class:`~redundancy_gym.model.SerialChain` (exported once from the
pinocchio model) and run inside other numba kernels, such as the fused CLIK step of
:class:`~redundancy_gym.controllers.CompiledClik`, with no Python in between. Joint ``j``'s frame is
``M_parent(j) * P_j * exp(axis_j q_j)`` (pinocchio's convention); Jacobians are world-aligned at the point,
like :meth:`~redundancy_gym.model.RobotModel.frame_jacobian`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["chain_forward", "chain_jacobian", "chain_jacobian_transpose_times", "place_frame"]

# same numerics contract as the SSV kernels: no checked divisions; FMA contraction allowed
_JIT = {"cache": True, "error_model": "numpy", "fastmath": {"contract", "arcp", "nsz"}}


@njit(**_JIT)
def chain_forward(parent, placement_rotation, placement_translation, axis, prismatic, q_index, q,
                  rotation, position, world_axis):
    """World placement of every joint frame at ``q`` into ``rotation`` (J, 3, 3) and ``position`` (J, 3),
    and each joint's axis in world coordinates into ``world_axis`` (J, 3). Parents precede children."""
    for j in range(parent.shape[0]):
        p = parent[j]
        # M = M_parent * P_j
        for r in range(3):
            for c in range(3):
                if p < 0:
                    rotation[j, r, c] = placement_rotation[j, r, c]
                else:
                    rotation[j, r, c] = (rotation[p, r, 0] * placement_rotation[j, 0, c]
                                         + rotation[p, r, 1] * placement_rotation[j, 1, c]
                                         + rotation[p, r, 2] * placement_rotation[j, 2, c])
            if p < 0:
                position[j, r] = placement_translation[j, r]
            else:
                position[j, r] = (position[p, r] + rotation[p, r, 0] * placement_translation[j, 0]
                                  + rotation[p, r, 1] * placement_translation[j, 1]
                                  + rotation[p, r, 2] * placement_translation[j, 2])
        ax, ay, az = axis[j, 0], axis[j, 1], axis[j, 2]
        for r in range(3):
            world_axis[j, r] = rotation[j, r, 0] * ax + rotation[j, r, 1] * ay + rotation[j, r, 2] * az
        qj = q[q_index[j]]
        if prismatic[j] != 0:
            for r in range(3):
                position[j, r] += world_axis[j, r] * qj
            continue
        # M.R <- M.R * exp([a]x q), Rodrigues: I + s K + (1 - c) K^2
        s = np.sin(qj)
        t = 1.0 - np.cos(qj)
        e00 = 1.0 - t * (ay * ay + az * az)
        e11 = 1.0 - t * (ax * ax + az * az)
        e22 = 1.0 - t * (ax * ax + ay * ay)
        e01 = t * ax * ay - s * az
        e10 = t * ax * ay + s * az
        e02 = t * ax * az + s * ay
        e20 = t * ax * az - s * ay
        e12 = t * ay * az - s * ax
        e21 = t * ay * az + s * ax
        for r in range(3):
            m0, m1, m2 = rotation[j, r, 0], rotation[j, r, 1], rotation[j, r, 2]
            rotation[j, r, 0] = m0 * e00 + m1 * e10 + m2 * e20
            rotation[j, r, 1] = m0 * e01 + m1 * e11 + m2 * e21
            rotation[j, r, 2] = m0 * e02 + m1 * e12 + m2 * e22


@njit(**_JIT)
def place_frame(rotation, position, joint, local_rotation, local_translation, out_rotation, out_translation):
    """``M_joint * (R_local, p_local)`` into ``out_rotation`` (3, 3) and ``out_translation`` (3,); ``joint`` < 0
    is the world."""
    for r in range(3):
        if joint < 0:
            out_translation[r] = local_translation[r]
            for c in range(3):
                out_rotation[r, c] = local_rotation[r, c]
            continue
        out_translation[r] = (position[joint, r] + rotation[joint, r, 0] * local_translation[0]
                              + rotation[joint, r, 1] * local_translation[1]
                              + rotation[joint, r, 2] * local_translation[2])
        for c in range(3):
            out_rotation[r, c] = (rotation[joint, r, 0] * local_rotation[0, c]
                                  + rotation[joint, r, 1] * local_rotation[1, c]
                                  + rotation[joint, r, 2] * local_rotation[2, c])


@njit(**_JIT)
def chain_jacobian(parent, prismatic, v_index, position, world_axis, joint, px, py, pz, out):
    """World-aligned 6 x nv Jacobian ``[J_T; J_R]`` of the point ``(px, py, pz)`` [m] moving with ``joint``
    into ``out`` (the columns of joints that do not carry it are set to zero)."""
    out[:, :] = 0.0
    k = joint
    while k >= 0:
        c = v_index[k]
        wx, wy, wz = world_axis[k, 0], world_axis[k, 1], world_axis[k, 2]
        if prismatic[k] != 0:
            out[0, c] = wx
            out[1, c] = wy
            out[2, c] = wz
        else:
            rx = px - position[k, 0]
            ry = py - position[k, 1]
            rz = pz - position[k, 2]
            out[0, c] = wy * rz - wz * ry
            out[1, c] = wz * rx - wx * rz
            out[2, c] = wx * ry - wy * rx
            out[3, c] = wx
            out[4, c] = wy
            out[5, c] = wz
        k = parent[k]


@njit(**_JIT)
def chain_jacobian_transpose_times(parent, prismatic, v_index, position, world_axis, joint, px, py, pz,
                                   nx, ny, nz, scale, out):
    """``out += scale * J_T(p)^T n``: the gradient of ``n . p`` for the point ``p`` moving with ``joint``
    (5.61), without forming the Jacobian."""
    k = joint
    while k >= 0:
        c = v_index[k]
        wx, wy, wz = world_axis[k, 0], world_axis[k, 1], world_axis[k, 2]
        if prismatic[k] != 0:
            out[c] += scale * (wx * nx + wy * ny + wz * nz)
        else:
            # n . (w x r) = w . (r x n)
            rx = px - position[k, 0]
            ry = py - position[k, 1]
            rz = pz - position[k, 2]
            out[c] += scale * (wx * (ry * nz - rz * ny) + wy * (rz * nx - rx * nz) + wz * (rx * ny - ry * nx))
        k = parent[k]

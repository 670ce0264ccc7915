"""Compiled kinematics of trees of 1-DoF joints on a fixed or free-flying root: forward kinematics, point
Jacobians, the centre of mass with the centroidal momentum matrix, and integration (monograph 5.1).

The kernels work on the arrays of a :class:`~redundancy_gym.model.SerialChain` (exported once from the
pinocchio model) and run inside other numba kernels, such as the fused CLIK step of
:class:`~redundancy_gym.controllers.CompiledClik`, with no Python in between. Joint ``j``'s frame is
``M_parent(j) * P_j * exp(axis_j q_j)`` (pinocchio's convention); a free flyer's is ``M_parent(j) * P_j *
(R(quat), p)`` with ``q = [p; quat (x, y, z, w)]`` and velocity ``[v; omega]`` in its own frame (pinocchio's
free flyer). Jacobians are world-aligned at the point, like
:meth:`~redundancy_gym.model.RobotModel.frame_jacobian`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..kernel_options import JIT

__all__ = [
    "FREE",
    "JOINT_DOFS",
    "PRISMATIC",
    "REVOLUTE",
    "chain_centroidal",
    "chain_forward",
    "chain_integrate",
    "chain_jacobian",
    "chain_jacobian_transpose_times",
    "place_frame",
]

REVOLUTE, PRISMATIC, FREE = 0, 1, 2
"""Joint type codes of :attr:`SerialChain.joint_type`."""
JOINT_DOFS: dict[int, tuple[int, int]] = {REVOLUTE: (1, 1), PRISMATIC: (1, 1), FREE: (7, 6)}
"""``(nq, nv)`` of each joint type."""


@njit(**JIT)
def chain_forward(
    parent, placement_rotation, placement_translation, axis, joint_type, q_index, q, rotation, position, world_axis
):
    """World placement of every joint frame at ``q`` into ``rotation`` (J, 3, 3) and ``position`` (J, 3),
    and each 1-DoF joint's axis in world coordinates into ``world_axis`` (J, 3). Parents precede children."""
    for j in range(parent.shape[0]):
        p = parent[j]
        # M = M_parent * P_j
        for r in range(3):
            for c in range(3):
                if p < 0:
                    rotation[j, r, c] = placement_rotation[j, r, c]
                else:
                    rotation[j, r, c] = (
                        rotation[p, r, 0] * placement_rotation[j, 0, c]
                        + rotation[p, r, 1] * placement_rotation[j, 1, c]
                        + rotation[p, r, 2] * placement_rotation[j, 2, c]
                    )
            if p < 0:
                position[j, r] = placement_translation[j, r]
            else:
                position[j, r] = (
                    position[p, r]
                    + rotation[p, r, 0] * placement_translation[j, 0]
                    + rotation[p, r, 1] * placement_translation[j, 1]
                    + rotation[p, r, 2] * placement_translation[j, 2]
                )
        k = q_index[j]
        if joint_type[j] == FREE:
            # M <- M * (R(quat), p); the quaternion's matrix as Eigen forms it (pinocchio's free flyer)
            x, y, z, w = q[k + 3], q[k + 4], q[k + 5], q[k + 6]
            e00, e01, e02 = 1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w)
            e10, e11, e12 = 2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w)
            e20, e21, e22 = 2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y)
            for r in range(3):
                m0, m1, m2 = rotation[j, r, 0], rotation[j, r, 1], rotation[j, r, 2]
                position[j, r] += m0 * q[k] + m1 * q[k + 1] + m2 * q[k + 2]
                rotation[j, r, 0] = m0 * e00 + m1 * e10 + m2 * e20
                rotation[j, r, 1] = m0 * e01 + m1 * e11 + m2 * e21
                rotation[j, r, 2] = m0 * e02 + m1 * e12 + m2 * e22
                world_axis[j, r] = 0.0
            continue
        ax, ay, az = axis[j, 0], axis[j, 1], axis[j, 2]
        for r in range(3):
            world_axis[j, r] = rotation[j, r, 0] * ax + rotation[j, r, 1] * ay + rotation[j, r, 2] * az
        qj = q[k]
        if joint_type[j] == PRISMATIC:
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


@njit(**JIT)
def place_frame(rotation, position, joint, local_rotation, local_translation, out_rotation, out_translation):
    """``M_joint * (R_local, p_local)`` into ``out_rotation`` (3, 3) and ``out_translation`` (3,); ``joint`` < 0
    is the world."""
    for r in range(3):
        if joint < 0:
            out_translation[r] = local_translation[r]
            for c in range(3):
                out_rotation[r, c] = local_rotation[r, c]
            continue
        out_translation[r] = (
            position[joint, r]
            + rotation[joint, r, 0] * local_translation[0]
            + rotation[joint, r, 1] * local_translation[1]
            + rotation[joint, r, 2] * local_translation[2]
        )
        for c in range(3):
            out_rotation[r, c] = (
                rotation[joint, r, 0] * local_rotation[0, c]
                + rotation[joint, r, 1] * local_rotation[1, c]
                + rotation[joint, r, 2] * local_rotation[2, c]
            )


@njit(**JIT)
def chain_jacobian(parent, joint_type, v_index, rotation, position, world_axis, joint, px, py, pz, out):
    """World-aligned 6 x nv Jacobian ``[J_T; J_R]`` of the point ``(px, py, pz)`` [m] moving with ``joint``
    into ``out`` (the columns of joints that do not carry it are set to zero)."""
    out[:, :] = 0.0
    k = joint
    while k >= 0:
        c = v_index[k]
        rx, ry, rz = px - position[k, 0], py - position[k, 1], pz - position[k, 2]
        if joint_type[k] == FREE:
            # body-frame twist: linear columns R e_i, angular columns R e_i about the joint origin
            for i in range(3):
                wx, wy, wz = rotation[k, 0, i], rotation[k, 1, i], rotation[k, 2, i]
                out[0, c + i] = wx
                out[1, c + i] = wy
                out[2, c + i] = wz
                out[0, c + 3 + i] = wy * rz - wz * ry
                out[1, c + 3 + i] = wz * rx - wx * rz
                out[2, c + 3 + i] = wx * ry - wy * rx
                out[3, c + 3 + i] = wx
                out[4, c + 3 + i] = wy
                out[5, c + 3 + i] = wz
        elif joint_type[k] == PRISMATIC:
            out[0, c] = world_axis[k, 0]
            out[1, c] = world_axis[k, 1]
            out[2, c] = world_axis[k, 2]
        else:
            wx, wy, wz = world_axis[k, 0], world_axis[k, 1], world_axis[k, 2]
            out[0, c] = wy * rz - wz * ry
            out[1, c] = wz * rx - wx * rz
            out[2, c] = wx * ry - wy * rx
            out[3, c] = wx
            out[4, c] = wy
            out[5, c] = wz
        k = parent[k]


@njit(**JIT)
def chain_jacobian_transpose_times(
    parent, joint_type, v_index, rotation, position, world_axis, joint, px, py, pz, nx, ny, nz, scale, out
):
    """``out += scale * J_T(p)^T n``: the gradient of ``n . p`` for the point ``p`` moving with ``joint``
    (5.61), without forming the Jacobian."""
    k = joint
    while k >= 0:
        c = v_index[k]
        # n . (w x r) = w . (r x n)
        rx, ry, rz = px - position[k, 0], py - position[k, 1], pz - position[k, 2]
        cx, cy, cz = ry * nz - rz * ny, rz * nx - rx * nz, rx * ny - ry * nx
        if joint_type[k] == FREE:
            for i in range(3):
                wx, wy, wz = rotation[k, 0, i], rotation[k, 1, i], rotation[k, 2, i]
                out[c + i] += scale * (wx * nx + wy * ny + wz * nz)
                out[c + 3 + i] += scale * (wx * cx + wy * cy + wz * cz)
        elif joint_type[k] == PRISMATIC:
            out[c] += scale * (world_axis[k, 0] * nx + world_axis[k, 1] * ny + world_axis[k, 2] * nz)
        else:
            out[c] += scale * (world_axis[k, 0] * cx + world_axis[k, 1] * cy + world_axis[k, 2] * cz)
        k = parent[k]


@njit(**JIT)
def _momentum_column(composite, j, o, v, c, mass, column, jac_com, jac_angular):
    """Column ``column`` of the CoM Jacobian and of the centroidal angular momentum rows for a unit motion of
    the subtree ``j`` with angular velocity ``o`` and velocity ``v`` of the point at the world origin (3-tuples;
    ``c`` the CoM): ``p = m v + o x h``, ``L_0 = K o + h x v``, ``L_c = L_0 - c x p``."""
    ox, oy, oz = o
    vx, vy, vz = v
    cx, cy, cz = c
    m = composite[j, 0]
    hx, hy, hz = composite[j, 1], composite[j, 2], composite[j, 3]
    px = m * vx + oy * hz - oz * hy
    py = m * vy + oz * hx - ox * hz
    pz = m * vz + ox * hy - oy * hx
    lx = composite[j, 4] * ox + composite[j, 5] * oy + composite[j, 6] * oz + hy * vz - hz * vy
    ly = composite[j, 7] * ox + composite[j, 8] * oy + composite[j, 9] * oz + hz * vx - hx * vz
    lz = composite[j, 10] * ox + composite[j, 11] * oy + composite[j, 12] * oz + hx * vy - hy * vx
    jac_com[0, column] = px / mass
    jac_com[1, column] = py / mass
    jac_com[2, column] = pz / mass
    jac_angular[0, column] = lx - (cy * pz - cz * py)
    jac_angular[1, column] = ly - (cz * px - cx * pz)
    jac_angular[2, column] = lz - (cx * py - cy * px)


@njit(**JIT)
def chain_centroidal(
    parent,
    joint_type,
    v_index,
    rotation,
    position,
    world_axis,
    body_mass,
    body_com,
    body_inertia,
    composite,
    com,
    jac_com,
    jac_angular,
):
    """Centre of mass ``com`` [m], its Jacobian ``jac_com`` (3 x nv) and the angular rows of the centroidal
    momentum matrix ``jac_angular`` (3 x nv: ``L_G = jac_angular qdot`` about the CoM) after
    :func:`chain_forward`; returns the total mass [kg].

    ``composite`` (J, 13) receives each subtree's mass, first moment ``h = sum m_i c_i`` and rotational inertia
    about the world origin ``K = sum I_i - m_i [c_i]x^2`` (composite rigid bodies, leaves to root); a joint's
    column is then the subtree's momentum under a unit joint motion.
    """
    nj = parent.shape[0]
    for j in range(nj):
        m = body_mass[j]
        c0 = (
            position[j, 0]
            + rotation[j, 0, 0] * body_com[j, 0]
            + rotation[j, 0, 1] * body_com[j, 1]
            + rotation[j, 0, 2] * body_com[j, 2]
        )
        c1 = (
            position[j, 1]
            + rotation[j, 1, 0] * body_com[j, 0]
            + rotation[j, 1, 1] * body_com[j, 1]
            + rotation[j, 1, 2] * body_com[j, 2]
        )
        c2 = (
            position[j, 2]
            + rotation[j, 2, 0] * body_com[j, 0]
            + rotation[j, 2, 1] * body_com[j, 1]
            + rotation[j, 2, 2] * body_com[j, 2]
        )
        composite[j, 0] = m
        composite[j, 1] = m * c0
        composite[j, 2] = m * c1
        composite[j, 3] = m * c2
        cc = (c0, c1, c2)
        norm2 = c0 * c0 + c1 * c1 + c2 * c2
        for r in range(3):
            for s in range(3):
                # R I R^T + m (|c|^2 I - c c^T)
                acc = 0.0
                for a in range(3):
                    acc += rotation[j, r, a] * (
                        body_inertia[j, a, 0] * rotation[j, s, 0]
                        + body_inertia[j, a, 1] * rotation[j, s, 1]
                        + body_inertia[j, a, 2] * rotation[j, s, 2]
                    )
                acc -= m * cc[r] * cc[s]
                if r == s:
                    acc += m * norm2
                composite[j, 4 + 3 * r + s] = acc
    mass = 0.0
    hx = hy = hz = 0.0
    for j in range(nj - 1, -1, -1):
        p = parent[j]
        if p >= 0:
            for k in range(13):
                composite[p, k] += composite[j, k]
        else:
            mass += composite[j, 0]
            hx += composite[j, 1]
            hy += composite[j, 2]
            hz += composite[j, 3]
    cx, cy, cz = hx / mass, hy / mass, hz / mass
    com[0], com[1], com[2] = cx, cy, cz
    jac_com[:, :] = 0.0
    jac_angular[:, :] = 0.0
    centre, still = (cx, cy, cz), (0.0, 0.0, 0.0)
    for j in range(nj):
        col = v_index[j]
        ox, oy, oz = position[j, 0], position[j, 1], position[j, 2]
        if joint_type[j] == FREE:
            for i in range(3):
                wx, wy, wz = rotation[j, 0, i], rotation[j, 1, i], rotation[j, 2, i]
                w = (wx, wy, wz)
                _momentum_column(composite, j, still, w, centre, mass, col + i, jac_com, jac_angular)
                # rotation about the joint origin o: the origin point moves with o x w
                moved = (oy * wz - oz * wy, oz * wx - ox * wz, ox * wy - oy * wx)
                _momentum_column(composite, j, w, moved, centre, mass, col + 3 + i, jac_com, jac_angular)
        elif joint_type[j] == PRISMATIC:
            axis = (world_axis[j, 0], world_axis[j, 1], world_axis[j, 2])
            _momentum_column(composite, j, still, axis, centre, mass, col, jac_com, jac_angular)
        else:
            wx, wy, wz = world_axis[j, 0], world_axis[j, 1], world_axis[j, 2]
            moved = (oy * wz - oz * wy, oz * wx - ox * wz, ox * wy - oy * wx)
            _momentum_column(composite, j, (wx, wy, wz), moved, centre, mass, col, jac_com, jac_angular)
    return mass


@njit(**JIT)
def chain_integrate(joint_type, q_index, v_index, q, v, dt, out):
    """``out = q (+) v dt`` on the configuration manifold, as ``pinocchio.integrate``: a free flyer moves by
    ``M exp6(v dt)`` (its quaternion renormalized), 1-DoF joints by ``q + v dt``. ``out`` may be ``q``."""
    for j in range(joint_type.shape[0]):
        k = q_index[j]
        c = v_index[j]
        if joint_type[j] != FREE:
            out[k] = q[k] + v[c] * dt
            continue
        ux, uy, uz = v[c] * dt, v[c + 1] * dt, v[c + 2] * dt
        wx, wy, wz = v[c + 3] * dt, v[c + 4] * dt, v[c + 5] * dt
        t2 = wx * wx + wy * wy + wz * wz
        t = np.sqrt(t2)
        if t < 1e-4:  # series of the coefficients below, exact to round-off at this angle
            a = 0.5 - t2 / 24.0
            b = 1.0 / 6.0 - t2 / 120.0
            h = 0.5 - t2 / 48.0
        else:
            a = (1.0 - np.cos(t)) / t2
            b = (t - np.sin(t)) / (t2 * t)
            h = np.sin(0.5 * t) / t
        # exp6 translation V u with V = I + a [w]x + b [w]x^2
        cx, cy, cz = wy * uz - wz * uy, wz * ux - wx * uz, wx * uy - wy * ux
        dx, dy, dz = wy * cz - wz * cy, wz * cx - wx * cz, wx * cy - wy * cx
        sx, sy, sz = ux + a * cx + b * dx, uy + a * cy + b * dy, uz + a * cz + b * dz
        x, y, z, w = q[k + 3], q[k + 4], q[k + 5], q[k + 6]
        # p <- p + R(quat) s
        px = q[k] + (1.0 - 2.0 * (y * y + z * z)) * sx + 2.0 * (x * y - z * w) * sy + 2.0 * (x * z + y * w) * sz
        py = q[k + 1] + 2.0 * (x * y + z * w) * sx + (1.0 - 2.0 * (x * x + z * z)) * sy + 2.0 * (y * z - x * w) * sz
        pz = q[k + 2] + 2.0 * (x * z - y * w) * sx + 2.0 * (y * z + x * w) * sy + (1.0 - 2.0 * (x * x + y * y)) * sz
        # quat <- quat * (h w, cos(t / 2))
        ex, ey, ez, ew = h * wx, h * wy, h * wz, np.cos(0.5 * t)
        nx = w * ex + x * ew + y * ez - z * ey
        ny = w * ey - x * ez + y * ew + z * ex
        nz = w * ez + x * ey - y * ex + z * ew
        nw = w * ew - x * ex - y * ey - z * ez
        norm = np.sqrt(nx * nx + ny * ny + nz * nz + nw * nw)
        if nx * x + ny * y + nz * z + nw * w < 0.0:  # keep the hemisphere of the input, as pinocchio does
            norm = -norm
        out[k], out[k + 1], out[k + 2] = px, py, pz
        out[k + 3], out[k + 4], out[k + 5], out[k + 6] = nx / norm, ny / norm, nz / norm, nw / norm

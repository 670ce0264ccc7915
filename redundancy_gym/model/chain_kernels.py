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
    "chain_acceleration_terms",
    "chain_centroidal",
    "chain_centroidal_drift",
    "chain_difference",
    "chain_forward",
    "chain_integrate",
    "chain_jacobian",
    "chain_jacobian_transpose_times",
    "chain_motion",
    "chain_rnea",
    "frame_jacobian",
    "place_frame",
    "point_drift",
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
def frame_jacobian(
    parent,
    joint_type,
    v_index,
    rotation,
    position,
    world_axis,
    joint,
    local_rotation,
    local_translation,
    out_rotation,
    out_position,
    out_jacobian,
):
    """A frame fixed to ``joint`` at ``(local_rotation, local_translation)``: its world placement into
    ``out_rotation``, ``out_position`` (:func:`place_frame`) and its world-aligned Jacobian at its origin into
    ``out_jacobian`` (6 x nv, :func:`chain_jacobian`)."""
    place_frame(rotation, position, joint, local_rotation, local_translation, out_rotation, out_position)
    px, py, pz = out_position[0], out_position[1], out_position[2]
    chain_jacobian(parent, joint_type, v_index, rotation, position, world_axis, joint, px, py, pz, out_jacobian)


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


@njit(**JIT)
def chain_motion(parent, joint_type, v_index, rotation, position, world_axis, v, a, omega, omega_dot, velocity, drift):
    """The motion of every joint frame at the velocity ``v`` and joint acceleration ``a`` after
    :func:`chain_forward`, world-aligned: angular velocity ``omega`` (J, 3) [rad/s] and acceleration ``omega_dot``
    (J, 3) [rad/s^2], the velocity ``velocity`` (J, 3) [m/s] and classical acceleration ``drift`` (J, 3) [m/s^2]
    of the frame's origin. With ``a = 0`` these are the drift terms ``Jdot qdot`` of the point Jacobians.
    Parents precede children.

    A joint's axis turns with its parent (``d/dt a = omega_p x a``), and its origin is fixed in the parent
    (prismatic: slides along ``a``), so ``omega_dot = omega_dot_p + omega_p x a qdot + a qddot`` and the origin's
    acceleration is the parent's point acceleration ``a_p + omega_dot_p x r + omega_p x (omega_p x r)`` (plus
    ``2 omega_p x a qdot + a qddot`` for a slide). A free flyer (the root) with the body-frame twist ``[v; omega]``
    and its rate: the origin's classical acceleration is ``R vdot + omega x v`` and ``omega_dot = R omegadot``."""
    for j in range(parent.shape[0]):
        p = parent[j]
        c = v_index[j]
        wx = wy = wz = dwx = dwy = dwz = 0.0
        vx = vy = vz = ax = ay = az = 0.0
        if p >= 0:
            wx, wy, wz = omega[p, 0], omega[p, 1], omega[p, 2]
            dwx, dwy, dwz = omega_dot[p, 0], omega_dot[p, 1], omega_dot[p, 2]
            rx, ry, rz = (
                position[j, 0] - position[p, 0],
                position[j, 1] - position[p, 1],
                position[j, 2] - position[p, 2],
            )
            # w x r, w x (w x r), wdot x r
            ux, uy, uz = wy * rz - wz * ry, wz * rx - wx * rz, wx * ry - wy * rx
            vx, vy, vz = velocity[p, 0] + ux, velocity[p, 1] + uy, velocity[p, 2] + uz
            ax = drift[p, 0] + dwy * rz - dwz * ry + wy * uz - wz * uy
            ay = drift[p, 1] + dwz * rx - dwx * rz + wz * ux - wx * uz
            az = drift[p, 2] + dwx * ry - dwy * rx + wx * uy - wy * ux
        if joint_type[j] == FREE:
            lx = rotation[j, 0, 0] * v[c] + rotation[j, 0, 1] * v[c + 1] + rotation[j, 0, 2] * v[c + 2]
            ly = rotation[j, 1, 0] * v[c] + rotation[j, 1, 1] * v[c + 1] + rotation[j, 1, 2] * v[c + 2]
            lz = rotation[j, 2, 0] * v[c] + rotation[j, 2, 1] * v[c + 1] + rotation[j, 2, 2] * v[c + 2]
            ox = rotation[j, 0, 0] * v[c + 3] + rotation[j, 0, 1] * v[c + 4] + rotation[j, 0, 2] * v[c + 5]
            oy = rotation[j, 1, 0] * v[c + 3] + rotation[j, 1, 1] * v[c + 4] + rotation[j, 1, 2] * v[c + 5]
            oz = rotation[j, 2, 0] * v[c + 3] + rotation[j, 2, 1] * v[c + 4] + rotation[j, 2, 2] * v[c + 5]
            # a free flyer is the root (the chains' trees have no other)
            vx, vy, vz = lx, ly, lz
            ax = (
                oy * lz
                - oz * ly
                + rotation[j, 0, 0] * a[c]
                + rotation[j, 0, 1] * a[c + 1]
                + rotation[j, 0, 2] * a[c + 2]
            )
            ay = (
                oz * lx
                - ox * lz
                + rotation[j, 1, 0] * a[c]
                + rotation[j, 1, 1] * a[c + 1]
                + rotation[j, 1, 2] * a[c + 2]
            )
            az = (
                ox * ly
                - oy * lx
                + rotation[j, 2, 0] * a[c]
                + rotation[j, 2, 1] * a[c + 1]
                + rotation[j, 2, 2] * a[c + 2]
            )
            dwx = rotation[j, 0, 0] * a[c + 3] + rotation[j, 0, 1] * a[c + 4] + rotation[j, 0, 2] * a[c + 5]
            dwy = rotation[j, 1, 0] * a[c + 3] + rotation[j, 1, 1] * a[c + 4] + rotation[j, 1, 2] * a[c + 5]
            dwz = rotation[j, 2, 0] * a[c + 3] + rotation[j, 2, 1] * a[c + 4] + rotation[j, 2, 2] * a[c + 5]
            wx, wy, wz = ox, oy, oz
        else:
            qd, qdd = v[c], a[c]
            ex, ey, ez = world_axis[j, 0] * qd, world_axis[j, 1] * qd, world_axis[j, 2] * qd
            if joint_type[j] == PRISMATIC:
                vx, vy, vz = vx + ex, vy + ey, vz + ez
                ax += 2.0 * (wy * ez - wz * ey) + world_axis[j, 0] * qdd
                ay += 2.0 * (wz * ex - wx * ez) + world_axis[j, 1] * qdd
                az += 2.0 * (wx * ey - wy * ex) + world_axis[j, 2] * qdd
            else:
                dwx += wy * ez - wz * ey + world_axis[j, 0] * qdd
                dwy += wz * ex - wx * ez + world_axis[j, 1] * qdd
                dwz += wx * ey - wy * ex + world_axis[j, 2] * qdd
                wx, wy, wz = wx + ex, wy + ey, wz + ez
        omega[j, 0], omega[j, 1], omega[j, 2] = wx, wy, wz
        omega_dot[j, 0], omega_dot[j, 1], omega_dot[j, 2] = dwx, dwy, dwz
        velocity[j, 0], velocity[j, 1], velocity[j, 2] = vx, vy, vz
        drift[j, 0], drift[j, 1], drift[j, 2] = ax, ay, az


@njit(**JIT)
def point_drift(position, omega, omega_dot, drift, joint, px, py, pz, out):
    """``Jdot qdot`` (6) of the world point ``(px, py, pz)`` [m] moving with ``joint`` after :func:`chain_motion`:
    its classical acceleration at zero joint acceleration [m/s^2], then the joint's ``omega_dot`` [rad/s^2]."""
    if joint < 0:
        out[:] = 0.0
        return
    wx, wy, wz = omega[joint, 0], omega[joint, 1], omega[joint, 2]
    dwx, dwy, dwz = omega_dot[joint, 0], omega_dot[joint, 1], omega_dot[joint, 2]
    rx, ry, rz = px - position[joint, 0], py - position[joint, 1], pz - position[joint, 2]
    ux, uy, uz = wy * rz - wz * ry, wz * rx - wx * rz, wx * ry - wy * rx
    out[0] = drift[joint, 0] + dwy * rz - dwz * ry + wy * uz - wz * uy
    out[1] = drift[joint, 1] + dwz * rx - dwx * rz + wz * ux - wx * uz
    out[2] = drift[joint, 2] + dwx * ry - dwy * rx + wx * uy - wy * ux
    out[3], out[4], out[5] = dwx, dwy, dwz


@njit(**JIT)
def _body_wrench(rotation, position, body_mass, body_com, body_inertia, omega, omega_dot, acceleration, j, gx, gy, gz):
    """Body ``j``'s ``(c, f, n)`` after :func:`chain_motion`, nine floats: its CoM ``c`` [m] (world), the force
    ``f = m (a_c - g)`` [N] its motion and the gravity ``(gx, gy, gz)`` need (``a_c`` the CoM's classical
    acceleration, from the joint origin's like :func:`point_drift`), and the moment about its CoM ``n = I
    omega_dot + omega x I omega`` [N m] (``I = R I_body R^T``, applied as ``R (I_body (R^T w))``)."""
    m = body_mass[j]
    bx, by, bz = body_com[j, 0], body_com[j, 1], body_com[j, 2]
    rx = rotation[j, 0, 0] * bx + rotation[j, 0, 1] * by + rotation[j, 0, 2] * bz
    ry = rotation[j, 1, 0] * bx + rotation[j, 1, 1] * by + rotation[j, 1, 2] * bz
    rz = rotation[j, 2, 0] * bx + rotation[j, 2, 1] * by + rotation[j, 2, 2] * bz
    wx, wy, wz = omega[j, 0], omega[j, 1], omega[j, 2]
    dwx, dwy, dwz = omega_dot[j, 0], omega_dot[j, 1], omega_dot[j, 2]
    ux, uy, uz = wy * rz - wz * ry, wz * rx - wx * rz, wx * ry - wy * rx
    fx = m * (acceleration[j, 0] + dwy * rz - dwz * ry + wy * uz - wz * uy - gx)
    fy = m * (acceleration[j, 1] + dwz * rx - dwx * rz + wz * ux - wx * uz - gy)
    fz = m * (acceleration[j, 2] + dwx * ry - dwy * rx + wx * uy - wy * ux - gz)
    bw0 = rotation[j, 0, 0] * wx + rotation[j, 1, 0] * wy + rotation[j, 2, 0] * wz
    bw1 = rotation[j, 0, 1] * wx + rotation[j, 1, 1] * wy + rotation[j, 2, 1] * wz
    bw2 = rotation[j, 0, 2] * wx + rotation[j, 1, 2] * wy + rotation[j, 2, 2] * wz
    bd0 = rotation[j, 0, 0] * dwx + rotation[j, 1, 0] * dwy + rotation[j, 2, 0] * dwz
    bd1 = rotation[j, 0, 1] * dwx + rotation[j, 1, 1] * dwy + rotation[j, 2, 1] * dwz
    bd2 = rotation[j, 0, 2] * dwx + rotation[j, 1, 2] * dwy + rotation[j, 2, 2] * dwz
    inertia = body_inertia[j]
    h0 = inertia[0, 0] * bw0 + inertia[0, 1] * bw1 + inertia[0, 2] * bw2
    h1 = inertia[1, 0] * bw0 + inertia[1, 1] * bw1 + inertia[1, 2] * bw2
    h2 = inertia[2, 0] * bw0 + inertia[2, 1] * bw1 + inertia[2, 2] * bw2
    e0 = inertia[0, 0] * bd0 + inertia[0, 1] * bd1 + inertia[0, 2] * bd2
    e1 = inertia[1, 0] * bd0 + inertia[1, 1] * bd1 + inertia[1, 2] * bd2
    e2 = inertia[2, 0] * bd0 + inertia[2, 1] * bd1 + inertia[2, 2] * bd2
    lx = rotation[j, 0, 0] * h0 + rotation[j, 0, 1] * h1 + rotation[j, 0, 2] * h2
    ly = rotation[j, 1, 0] * h0 + rotation[j, 1, 1] * h1 + rotation[j, 1, 2] * h2
    lz = rotation[j, 2, 0] * h0 + rotation[j, 2, 1] * h1 + rotation[j, 2, 2] * h2
    nx = rotation[j, 0, 0] * e0 + rotation[j, 0, 1] * e1 + rotation[j, 0, 2] * e2 + wy * lz - wz * ly
    ny = rotation[j, 1, 0] * e0 + rotation[j, 1, 1] * e1 + rotation[j, 1, 2] * e2 + wz * lx - wx * lz
    nz = rotation[j, 2, 0] * e0 + rotation[j, 2, 1] * e1 + rotation[j, 2, 2] * e2 + wx * ly - wy * lx
    cx, cy, cz = position[j, 0] + rx, position[j, 1] + ry, position[j, 2] + rz
    return cx, cy, cz, fx, fy, fz, nx, ny, nz


@njit(**JIT)
def chain_centroidal_drift(rotation, position, body_mass, body_com, body_inertia, omega, omega_dot, drift, com, out):
    """``Adot_G qdot`` (6) [N, N m] after :func:`chain_motion`: the rate of the centroidal momentum at zero joint
    acceleration, ``sum m_i a_i`` and ``sum (c_i - c) x m_i a_i + I_i omega_dot_i + omega_i x I_i omega_i``
    (``a_i`` the body CoM's acceleration, ``I_i`` its world inertia; the CoM's own motion drops out of the sum).
    """
    s0 = s1 = s2 = s3 = s4 = s5 = 0.0
    for j in range(position.shape[0]):
        cx, cy, cz, fx, fy, fz, nx, ny, nz = _body_wrench(
            rotation, position, body_mass, body_com, body_inertia, omega, omega_dot, drift, j, 0.0, 0.0, 0.0
        )
        gx, gy, gz = cx - com[0], cy - com[1], cz - com[2]
        s0 += fx
        s1 += fy
        s2 += fz
        s3 += gy * fz - gz * fy + nx
        s4 += gz * fx - gx * fz + ny
        s5 += gx * fy - gy * fx + nz
    out[0], out[1], out[2], out[3], out[4], out[5] = s0, s1, s2, s3, s4, s5


@njit(**JIT)
def chain_acceleration_terms(
    parent,
    placement_rotation,
    placement_translation,
    axis,
    joint_type,
    q_index,
    v_index,
    body_mass,
    body_com,
    body_inertia,
    frame_joint,
    frame_rotation,
    frame_translation,
    q,
    v,
    work_rotation,
    work_position,
    work_axis,
    work_omega,
    work_omega_dot,
    work_velocity,
    work_drift,
    work_composite,
    rotation,
    position,
    jacobian,
    drift,
    com,
    centroidal,
    centroidal_drift,
):
    """What :meth:`~redundancy_gym.model.RobotModel.acceleration_terms` gives, for the frames ``(frame_joint,
    frame_rotation, frame_translation)`` (:meth:`~redundancy_gym.model.RobotModel.frame_attachment`) at ``(q, v)``:
    their rotations (k, 3, 3), positions (k, 3) [m], Jacobians (k, 6, nv) and ``Jdot qdot`` (k, 6), the CoM (3)
    [m], ``A_G`` (6 x nv, linear rows first) and ``Adot_G qdot`` (6), into the last seven arrays; ``work_*``
    are scratch arrays of the joints (J, 3, 3), (J, 3) x 6 and (J, 13). Returns the total mass [kg]."""
    chain_forward(
        parent,
        placement_rotation,
        placement_translation,
        axis,
        joint_type,
        q_index,
        q,
        work_rotation,
        work_position,
        work_axis,
    )
    chain_motion(
        parent,
        joint_type,
        v_index,
        work_rotation,
        work_position,
        work_axis,
        v,
        np.zeros(v.shape[0]),
        work_omega,
        work_omega_dot,
        work_velocity,
        work_drift,
    )
    for k in range(frame_joint.shape[0]):
        joint = frame_joint[k]
        frame_jacobian(
            parent,
            joint_type,
            v_index,
            work_rotation,
            work_position,
            work_axis,
            joint,
            frame_rotation[k],
            frame_translation[k],
            rotation[k],
            position[k],
            jacobian[k],
        )
        px, py, pz = position[k, 0], position[k, 1], position[k, 2]
        point_drift(work_position, work_omega, work_omega_dot, work_drift, joint, px, py, pz, drift[k])
    mass = chain_centroidal(
        parent,
        joint_type,
        v_index,
        work_rotation,
        work_position,
        work_axis,
        body_mass,
        body_com,
        body_inertia,
        work_composite,
        com,
        centroidal[:3],
        centroidal[3:],
    )
    for r in range(3):
        for c in range(centroidal.shape[1]):
            centroidal[r, c] *= mass
    chain_centroidal_drift(
        work_rotation,
        work_position,
        body_mass,
        body_com,
        body_inertia,
        work_omega,
        work_omega_dot,
        work_drift,
        com,
        centroidal_drift,
    )
    return mass


@njit(**JIT)
def chain_rnea(
    parent,
    joint_type,
    v_index,
    rotation,
    position,
    world_axis,
    body_mass,
    body_com,
    body_inertia,
    armature,
    gravity,
    v,
    a,
    omega,
    omega_dot,
    velocity,
    acceleration,
    force,
    moment,
    tau,
):
    """``tau = M(q) a + h(q, v)`` (nv) by the recursive Newton-Euler algorithm after :func:`chain_forward` at ``q``,
    as ``pinocchio.rnea`` (the armature's ``armature * a`` included; ``gravity`` the world's (3) [m/s^2]); a free
    flyer's six entries are the spatial force on it in its own frame at its origin (force, then moment).

    Forward: :func:`chain_motion` with ``a`` into ``omega``, ``omega_dot``, ``velocity`` and ``acceleration``
    (J, 3). Backward: ``force`` and ``moment`` (J, 3) receive each subtree's wrench about the world origin,
    ``sum m_i (a_i - g)`` and ``sum c_i x m_i (a_i - g) + I_i omega_dot_i + omega_i x I_i omega_i`` (``a_i`` the
    body CoM's acceleration, ``I_i`` its world inertia); a revolute joint's torque is its world axis times the
    moment about its origin, a prismatic one's its axis times the force."""
    nj = parent.shape[0]
    chain_motion(
        parent, joint_type, v_index, rotation, position, world_axis, v, a, omega, omega_dot, velocity, acceleration
    )
    for j in range(nj):
        cx, cy, cz, fx, fy, fz, nx, ny, nz = _body_wrench(
            rotation,
            position,
            body_mass,
            body_com,
            body_inertia,
            omega,
            omega_dot,
            acceleration,
            j,
            gravity[0],
            gravity[1],
            gravity[2],
        )
        force[j, 0], force[j, 1], force[j, 2] = fx, fy, fz
        moment[j, 0] = cy * fz - cz * fy + nx
        moment[j, 1] = cz * fx - cx * fz + ny
        moment[j, 2] = cx * fy - cy * fx + nz
    for j in range(nj - 1, -1, -1):
        c = v_index[j]
        fx, fy, fz = force[j, 0], force[j, 1], force[j, 2]
        ox, oy, oz = position[j, 0], position[j, 1], position[j, 2]
        # the subtree's moment about the joint origin
        nx = moment[j, 0] - (oy * fz - oz * fy)
        ny = moment[j, 1] - (oz * fx - ox * fz)
        nz = moment[j, 2] - (ox * fy - oy * fx)
        if joint_type[j] == FREE:
            for i in range(3):
                tau[c + i] = rotation[j, 0, i] * fx + rotation[j, 1, i] * fy + rotation[j, 2, i] * fz
                tau[c + i] += armature[c + i] * a[c + i]
                tau[c + 3 + i] = rotation[j, 0, i] * nx + rotation[j, 1, i] * ny + rotation[j, 2, i] * nz
                tau[c + 3 + i] += armature[c + 3 + i] * a[c + 3 + i]
        elif joint_type[j] == PRISMATIC:
            tau[c] = world_axis[j, 0] * fx + world_axis[j, 1] * fy + world_axis[j, 2] * fz + armature[c] * a[c]
        else:
            tau[c] = world_axis[j, 0] * nx + world_axis[j, 1] * ny + world_axis[j, 2] * nz + armature[c] * a[c]
        p = parent[j]
        if p >= 0:
            for r in range(3):
                force[p, r] += force[j, r]
                moment[p, r] += moment[j, r]


@njit(**JIT)
def chain_difference(joint_type, q_index, v_index, q0, q1, out):
    """``out = q1 (-) q0``, the tangent vector with ``integrate(q0, out, 1) = q1``, as ``pinocchio.difference``: a
    free flyer's ``log6(M0^-1 M1)`` (``[v; omega]``, the rotation by the relative quaternion's shorter arc), 1-DoF
    joints ``q1 - q0``."""
    for j in range(joint_type.shape[0]):
        k = q_index[j]
        c = v_index[j]
        if joint_type[j] != FREE:
            out[c] = q1[k] - q0[k]
            continue
        ax, ay, az, aw = q0[k + 3], q0[k + 4], q0[k + 5], q0[k + 6]
        bx, by, bz, bw = q1[k + 3], q1[k + 4], q1[k + 5], q1[k + 6]
        # relative rotation conj(a) * b, on the hemisphere w >= 0 (the shorter arc)
        rw = aw * bw + ax * bx + ay * by + az * bz
        rx = aw * bx - ax * bw - ay * bz + az * by
        ry = aw * by + ax * bz - ay * bw - az * bx
        rz = aw * bz - ax * by + ay * bx - az * bw
        if rw < 0.0:
            rw, rx, ry, rz = -rw, -rx, -ry, -rz
        s = np.sqrt(rx * rx + ry * ry + rz * rz)
        theta = 2.0 * np.arctan2(s, rw)
        # omega = theta * axis: theta / s, whose limit at s -> 0 is 2 / rw
        scale = theta / s if s > 1e-12 else 2.0 / rw
        wx, wy, wz = scale * rx, scale * ry, scale * rz
        # p = R0^T (p1 - p0), with R0 from the first quaternion
        dx, dy, dz = q1[k] - q0[k], q1[k + 1] - q0[k + 1], q1[k + 2] - q0[k + 2]
        px = (1.0 - 2.0 * (ay * ay + az * az)) * dx + 2.0 * (ax * ay + az * aw) * dy + 2.0 * (ax * az - ay * aw) * dz
        py = 2.0 * (ax * ay - az * aw) * dx + (1.0 - 2.0 * (ax * ax + az * az)) * dy + 2.0 * (ay * az + ax * aw) * dz
        pz = 2.0 * (ax * az + ay * aw) * dx + 2.0 * (ay * az - ax * aw) * dy + (1.0 - 2.0 * (ax * ax + ay * ay)) * dz
        # v = V^-1 p, V^-1 = I - [w]x / 2 + b [w]x^2, b = (1 - theta sin(theta) / (2 (1 - cos(theta)))) / theta^2
        t2 = theta * theta
        if theta < 1e-2:  # its series (the closed form cancels: 1e-10 off at 1e-3 rad), exact to round-off there
            b = 1.0 / 12.0 + t2 / 720.0 + t2 * t2 / 30240.0
        else:
            b = (1.0 - theta * np.sin(theta) / (2.0 * (1.0 - np.cos(theta)))) / t2
        cx, cy, cz = wy * pz - wz * py, wz * px - wx * pz, wx * py - wy * px
        ex, ey, ez = wy * cz - wz * cy, wz * cx - wx * cz, wx * cy - wy * cx
        out[c], out[c + 1], out[c + 2] = px - 0.5 * cx + b * ex, py - 0.5 * cy + b * ey, pz - 0.5 * cz + b * ez
        out[c + 3], out[c + 4], out[c + 5] = wx, wy, wz

"""Compiled forward and adjoint integration of the predictive IK's optimal control problem (monograph 5.6).

The nullspace input ``u_k`` (one per sample, held over the sample time ``dt``) drives the joint motion

    qdot_k = f(q_k, u_k) = J# wdot_k + (I - J# J) u_k = u_k + J^T y_k,   y_k = A^-1 (wdot_k - J u_k),
    A = J J^T + rho I,                                                                      (5.100), (5.102)

integrated explicitly, ``q_{k+1} = q_k + dt qdot_k`` (5.112). The cost (5.101), (5.130) is
``Phi = sum_k dt [w_v qdot_k^T qdot_k (5.131) + H_jl(q_k) (5.58) + H_c(q_k) (5.49)]``. Its exact gradient
for this discretization comes from the adjoint recursion (5.113), (5.115)

    lambda_N = 0,   lambda_k = lambda_{k+1} + dt [dH/dq + (df/dq)^T (lambda_{k+1} + 2 w_v qdot_k)],
    dPhi/du_k = dt (df/du)^T (lambda_{k+1} + 2 w_v qdot_k) = dt N (lambda_{k+1} + 2 w_v qdot_k)   (5.119), (A.54)

with ``(df/dq)^T v`` formed without the derivative of the pseudoinverse as a matrix (A.53), (A.59): with
``mu = A^-1 J v``, ``[(df/dq)^T v]_i = y^T (dJ/dq_i) (v - J^T mu) - mu^T (dJ/dq_i) qdot + mu^T dwdot/dq_i``,
and ``(dJ/dq_i) a`` = the derivative of the task velocity ``J a`` along joint ``i``, in closed form along the
kinematic path (O(n) per joint).

:func:`pik_optimize` runs the whole of algorithm 11 (the loop of ``PredictiveIk.optimize``) in one call for the
receding horizon: the adjoint pass reads what the accepted forward pass kept (kinematics, task Jacobian, Cholesky
factor, potential gradient of every sample), line-search trials stop once their partial cost exceeds the Armijo
threshold, and no gradient is formed at the last iterate, where no direction uses it.

Tasks: selected rows of a frame's position (``kind`` 0, :class:`~redundancy_gym.controllers.FramePositionTask`)
or a frame's position plus the direction of one of its axes (``kind`` 1,
:class:`~redundancy_gym.controllers.FrameAxisTask`: rows ``u^T J_R``, ``v^T J_R`` and feedforward
``u.omega_d``, ``v.omega_d`` in the axes ``u, v`` normal to the tool axis).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...geometry.potentials import piecewise_potential_kernel
from ...kernel_options import BORROW, JIT
from ...model.chain_kernels import FREE, PRISMATIC, chain_forward, chain_jacobian
from ..kernels.linalg import cholesky_factor, cholesky_solve
from ..objectives.collision_kernels import collision_potential

__all__ = [
    "CONVERGED",
    "MAX_ITERATIONS",
    "METHODS",
    "NO_DECREASE",
    "OVERFLOW",
    "SINGULAR",
    "SLOTS",
    "STATUS",
    "pik_command",
    "pik_gradient",
    "pik_optimize",
    "pik_rollout",
    "slot_size",
]

# The per-sample functions (and the forward and adjoint passes over a slot) only borrow their arrays: compiled
# without reference counting (BORROW), they skip an atomic incref/decref per array argument and per view, hundreds
# per sample. The entry points allocate, so they keep it (JIT).


@njit(**BORROW)
def _task(chain_f, chain_i, task_i, task_f, q, wdot, rotation, position, world_axis, jac6, jac, b, frame):
    """Kinematics at ``q``; the task Jacobian ``jac`` (m x n), task velocity ``b`` (m) from the reference
    ``wdot`` and the task frame's rotation and origin ``frame`` (12: R row-major, p).

    Runs once per sample of every rollout, so it indexes the flat arrays instead of taking reshaped views
    (each view costs reference counting, about a third of this function's time otherwise)."""
    placement_rotation, placement_translation, axis = chain_f
    parent, joint_type, q_index, v_index = chain_i
    kind, joint, tool_axis = task_i[0], task_i[1], task_i[2]
    chain_forward(
        parent, placement_rotation, placement_translation, axis, joint_type, q_index, q, rotation, position, world_axis
    )
    # the task frame M_joint * (R_local, p_local) (place_frame's arithmetic)
    for r in range(3):
        if joint < 0:
            frame[9 + r] = task_f[9 + r]
            for c in range(3):
                frame[3 * r + c] = task_f[3 * r + c]
            continue
        frame[9 + r] = (
            position[joint, r]
            + rotation[joint, r, 0] * task_f[9]
            + rotation[joint, r, 1] * task_f[10]
            + rotation[joint, r, 2] * task_f[11]
        )
        for c in range(3):
            frame[3 * r + c] = (
                rotation[joint, r, 0] * task_f[c]
                + rotation[joint, r, 1] * task_f[3 + c]
                + rotation[joint, r, 2] * task_f[6 + c]
            )
    chain_jacobian(
        parent, joint_type, v_index, rotation, position, world_axis, joint, frame[9], frame[10], frame[11], jac6
    )
    n = jac.shape[1]
    if kind == 0:
        for r in range(jac.shape[0]):
            row = task_i[3 + r]
            for k in range(n):
                jac[r, k] = jac6[row, k]
            b[r] = wdot[r]
        return
    for r in range(3):
        for k in range(n):
            jac[r, k] = jac6[r, k]
        b[r] = wdot[r]
    for s in range(2):
        c = (tool_axis + 1 + s) % 3
        ux, uy, uz = frame[c], frame[3 + c], frame[6 + c]
        for k in range(n):  # a loop, not an array expression: that allocates a row per call
            jac[3 + s, k] = ux * jac6[3, k] + uy * jac6[4, k] + uz * jac6[5, k]
        b[3 + s] = ux * wdot[3] + uy * wdot[4] + uz * wdot[5]


@njit(**BORROW)
def _velocity(jac, b, u, rho, a, low, y, qdot):
    """``qdot = u + J^T y`` with ``y = (J J^T + rho I)^-1 (b - J u)``; the factor stays in ``low``."""
    m, n = jac.shape
    for r in range(m):
        for c in range(r + 1):
            acc = 0.0
            for k in range(n):
                acc += jac[r, k] * jac[c, k]
            a[r, c] = acc
            a[c, r] = acc
        a[r, r] += rho
    if not cholesky_factor(a, m, low) > 0.0:
        return False
    for r in range(m):
        acc = b[r]
        for k in range(n):
            acc -= jac[r, k] * u[k]
        y[r] = acc
    cholesky_solve(low, m, y)
    for k in range(n):
        acc = u[k]
        for r in range(m):
            acc += jac[r, k] * y[r]
        qdot[k] = acc
    return True


@njit(**BORROW)
def _limits(q, lower, upper, lp, gradient):
    """(5.58) on the distance to each limit; adds the gradient (when given) and returns the value."""
    da, slope, ratio, weight = lp[0], lp[1], lp[2], lp[3]
    value = 0.0
    if weight == 0.0:
        return value
    for k in range(q.shape[0]):
        h0, d0, _ = piecewise_potential_kernel(q[k] - lower[k], da, slope, ratio)
        h1, d1, _ = piecewise_potential_kernel(upper[k] - q[k], da, slope, ratio)
        value += weight * (h0 + h1)
        gradient[k] += weight * (d0 - d1)
    return value


@njit(**BORROW)
def _collision(coll_i, coll_f, coll_p, chain_i, rotation, position, world_axis, gradient, scratch):
    """(5.49) over the collision pairs, gradient added (the arrays of :func:`collision_fields`)."""
    parent, joint_type, _, v_index = chain_i
    chain = (parent, joint_type, v_index, rotation, position, world_axis)
    value, _ = collision_potential(coll_i, coll_f, coll_p, chain, gradient, scratch)
    return value


@njit(**JIT)
def _vjp_scratch(nj):
    """The work arrays of :func:`_vjp` for a chain of ``nj`` joints: the path, suffix sums, ``dv``, ``dw``."""
    return (np.empty(nj, dtype=np.int64), np.empty((nj + 1, 2, 3)), np.empty((nj + 1, 2, 3)), np.empty(3), np.empty(3))


@njit(**BORROW)
def _vjp(chain_i, task_i, position, world_axis, frame, wdot, y, a1, mu, a2, out, scratch):
    """``out[i] += y^T (dJ/dq_i) a1 - mu^T (dJ/dq_i) a2 + mu^T d wdot/dq_i`` along the task frame's path.
    ``scratch`` is :func:`_vjp_scratch` (allocated once per kernel call: this runs once per sample)."""
    parent, joint_type, _, v_index = chain_i
    kind, joint, tool_axis = task_i[0], task_i[1], task_i[2]
    rows = task_i[3:]
    px, py, pz = frame[9], frame[10], frame[11]
    path, vs, ws, dv, dw = scratch
    # the path from the root to the task joint, root first
    length = 0
    k = joint
    while k >= 0:
        length += 1
        k = parent[k]
    k = joint
    for idx in range(length - 1, -1, -1):
        path[idx] = k
        k = parent[k]
    # suffix sums of each joint's linear velocity contribution and angular velocities, for a1 and a2
    for r in range(3):
        for s in range(2):
            vs[length, s, r] = 0.0
            ws[length, s, r] = 0.0
    for idx in range(length - 1, -1, -1):
        j = path[idx]
        c = v_index[j]
        zx, zy, zz = world_axis[j, 0], world_axis[j, 1], world_axis[j, 2]
        rx, ry, rz = px - position[j, 0], py - position[j, 1], pz - position[j, 2]
        for s in range(2):
            aj = a1[c] if s == 0 else a2[c]
            if joint_type[j] == PRISMATIC:
                vs[idx, s, 0] = vs[idx + 1, s, 0] + aj * zx
                vs[idx, s, 1] = vs[idx + 1, s, 1] + aj * zy
                vs[idx, s, 2] = vs[idx + 1, s, 2] + aj * zz
                for r in range(3):
                    ws[idx, s, r] = ws[idx + 1, s, r]
            else:
                vs[idx, s, 0] = vs[idx + 1, s, 0] + aj * (zy * rz - zz * ry)
                vs[idx, s, 1] = vs[idx + 1, s, 1] + aj * (zz * rx - zx * rz)
                vs[idx, s, 2] = vs[idx + 1, s, 2] + aj * (zx * ry - zy * rx)
                ws[idx, s, 0] = ws[idx + 1, s, 0] + aj * zx
                ws[idx, s, 1] = ws[idx + 1, s, 1] + aj * zy
                ws[idx, s, 2] = ws[idx + 1, s, 2] + aj * zz
    m = rows.shape[0] if kind == 0 else 5
    for idx in range(length):
        j = path[idx]
        if joint_type[j] == FREE:
            continue
        c = v_index[j]
        zx, zy, zz = world_axis[j, 0], world_axis[j, 1], world_axis[j, 2]
        acc = 0.0
        for s in range(2):
            weights = y if s == 0 else mu
            sign = 1.0 if s == 0 else -1.0
            # angular velocity of the joints before j: total minus the suffix from j
            ox = ws[0, s, 0] - ws[idx, s, 0]
            oy = ws[0, s, 1] - ws[idx, s, 1]
            oz = ws[0, s, 2] - ws[idx, s, 2]
            if joint_type[j] == PRISMATIC:
                # d v_p / dq_j = omega_before x z_j; the angular velocity does not change
                dv[0], dv[1], dv[2] = oy * zz - oz * zy, oz * zx - ox * zz, ox * zy - oy * zx
                dw[0] = dw[1] = dw[2] = 0.0
            else:
                # d v_p / dq_j = z_j x V_j + omega_before x (z_j x (p - o_j));
                # d omega / dq_j = z_j x omega_after
                rx, ry, rz = px - position[j, 0], py - position[j, 1], pz - position[j, 2]
                cx, cy, cz = zy * rz - zz * ry, zz * rx - zx * rz, zx * ry - zy * rx
                vx, vy, vz = vs[idx, s, 0], vs[idx, s, 1], vs[idx, s, 2]
                dv[0] = zy * vz - zz * vy + oy * cz - oz * cy
                dv[1] = zz * vx - zx * vz + oz * cx - ox * cz
                dv[2] = zx * vy - zy * vx + ox * cy - oy * cx
                ax, ay, az = ws[idx + 1, s, 0], ws[idx + 1, s, 1], ws[idx + 1, s, 2]
                dw[0], dw[1], dw[2] = zy * az - zz * ay, zz * ax - zx * az, zx * ay - zy * ax
            if kind == 0:
                for r in range(m):
                    acc += sign * weights[r] * dv[rows[r]]
                continue
            for r in range(3):
                acc += sign * weights[r] * dv[r]
            tx, ty, tz = ws[0, s, 0], ws[0, s, 1], ws[0, s, 2]  # the whole angular velocity J_R a
            for t in range(2):
                col = (tool_axis + 1 + t) % 3
                ux, uy, uz = frame[col], frame[3 + col], frame[6 + col]
                # d(u . omega)/dq_j = (z_j x u) . omega + u . d omega/dq_j (u turns with the frame)
                du = 0.0
                if joint_type[j] != PRISMATIC:
                    du = (zy * uz - zz * uy) * tx + (zz * ux - zx * uz) * ty + (zx * uy - zy * ux) * tz
                acc += sign * weights[3 + t] * (du + ux * dw[0] + uy * dw[1] + uz * dw[2])
        if kind == 1 and joint_type[j] != PRISMATIC:
            for t in range(2):  # d(u . omega_d)/dq_j of the feedforward
                col = (tool_axis + 1 + t) % 3
                ux, uy, uz = frame[col], frame[3 + col], frame[6 + col]
                acc += mu[3 + t] * (
                    (zy * uz - zz * uy) * wdot[3] + (zz * ux - zx * uz) * wdot[4] + (zx * uy - zy * ux) * wdot[5]
                )
        out[c] += acc


@njit(**JIT)
def _workspace(chain_i, task_i, n):
    """Task size and the per-step arrays: joint frames, Jacobians, task velocity, frame, ``A``, its factor, ``y``."""
    m = task_i.shape[0] - 3 if task_i[0] == 0 else 5
    nj = chain_i[0].shape[0]
    return (
        m,
        np.empty((nj, 3, 3)),
        np.empty((nj, 3)),
        np.empty((nj, 3)),
        np.empty((6, n)),
        np.empty((m, n)),
        np.empty(m),
        np.empty(12),
        np.empty((m, m)),
        np.zeros((m, m)),
        np.empty(m),
    )


@njit(**JIT)
def pik_rollout(
    problem,
    q0,
    u,
    wdot,
    dt,
    q_out,
    qdot_out,
    cost_out,
):
    """Integrate (5.112) from ``q0`` under the inputs ``u`` (N x n) and references ``wdot`` (N x 6) into
    ``q_out`` (N + 1 x n) and ``qdot_out`` (N x n); the cost terms (velocity, joint limits, collision) into
    ``cost_out`` (3). ``objective_f`` is ``[rho, w_v, lower (n), upper (n), d_a, slope, ratio, weight]``.
    Returns False when ``J J^T + rho I`` is not positive definite somewhere (the outputs are then partial).
    ``problem``: ``(chain_f, chain_i, task_i, task_f, objective_f, coll_i, coll_f, coll_p, collision)``, as
    :meth:`PredictiveIk._problem <redundancy_gym.controllers.PredictiveIk>` gives it."""
    chain_f, chain_i, task_i, task_f, objective_f, coll_i, coll_f, coll_p, collision = problem
    steps, n = u.shape
    m, rotation, position, world_axis, jac6, jac, b, frame, a, low, y = _workspace(chain_i, task_i, n)
    rho, wv = objective_f[0], objective_f[1]
    lower, upper, lp = objective_f[2 : 2 + n], objective_f[2 + n : 2 + 2 * n], objective_f[2 + 2 * n : 6 + 2 * n]
    scratch, dummy = np.empty(16), np.zeros(n)
    cost_out[:] = 0.0
    q_out[0, :] = q0
    for k in range(steps):
        q = q_out[k]
        _task(chain_f, chain_i, task_i, task_f, q, wdot[k], rotation, position, world_axis, jac6, jac, b, frame)
        if not _velocity(jac, b, u[k], rho, a, low, y, qdot_out[k]):
            return False
        speed = 0.0
        for i in range(n):
            speed += qdot_out[k, i] * qdot_out[k, i]
            q_out[k + 1, i] = q[i] + dt * qdot_out[k, i]
        cost_out[0] += dt * wv * speed
        cost_out[1] += dt * _limits(q, lower, upper, lp, dummy)
        if collision:
            cost_out[2] += dt * _collision(
                coll_i, coll_f, coll_p, chain_i, rotation, position, world_axis, dummy, scratch
            )
    return True


@njit(**JIT)
def pik_gradient(problem, q_traj, u, wdot, dt, grad_u, lam0):
    """The adjoint recursion (5.113), (5.115) backward along ``q_traj`` (from :func:`pik_rollout`): the exact
    gradient of the cost with respect to every ``u_k`` into ``grad_u`` (N x n), and ``lambda_0`` into ``lam0``.
    Returns False when ``J J^T + rho I`` is not positive definite somewhere (``problem``: as :func:`pik_rollout`)."""
    chain_f, chain_i, task_i, task_f, objective_f, coll_i, coll_f, coll_p, collision = problem
    steps, n = u.shape
    m, rotation, position, world_axis, jac6, jac, b, frame, a, low, y = _workspace(chain_i, task_i, n)
    rho, wv = objective_f[0], objective_f[1]
    lower, upper, lp = objective_f[2 : 2 + n], objective_f[2 + n : 2 + 2 * n], objective_f[2 + 2 * n : 6 + 2 * n]
    mu = np.empty(m)
    qdot, v, nv, grad_q, scratch = np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(16)
    vjp_scratch = _vjp_scratch(rotation.shape[0])
    lam = np.zeros(n)
    for k in range(steps - 1, -1, -1):
        q = q_traj[k]
        _task(chain_f, chain_i, task_i, task_f, q, wdot[k], rotation, position, world_axis, jac6, jac, b, frame)
        if not _velocity(jac, b, u[k], rho, a, low, y, qdot):
            return False
        for i in range(n):
            v[i] = lam[i] + 2.0 * wv * qdot[i]
        for r in range(m):
            acc = 0.0
            for i in range(n):
                acc += jac[r, i] * v[i]
            mu[r] = acc
        cholesky_solve(low, m, mu)
        for i in range(n):
            acc = v[i]
            for r in range(m):
                acc -= jac[r, i] * mu[r]
            nv[i] = acc
            grad_u[k, i] = dt * acc
            grad_q[i] = 0.0
        _limits(q, lower, upper, lp, grad_q)
        if collision:
            _collision(coll_i, coll_f, coll_p, chain_i, rotation, position, world_axis, grad_q, scratch)
        _vjp(chain_i, task_i, position, world_axis, frame, wdot[k], y, nv, mu, qdot, grad_q, vjp_scratch)
        for i in range(n):
            lam[i] += dt * grad_q[i]
    lam0[:] = lam
    return True


@njit(**JIT)
def pik_command(chain_f, chain_i, task_i, task_f, rho, q, u, wdot, target, gain, qdot_out, error_out):
    """The CLIK command with the nullspace input ``u``: ``qdot = J# (wdot + K e) + N u`` at ``q`` (5.5), (5.100),
    with the task error ``e`` into ``error_out`` (m). ``target`` is the task's rows (position task) or
    ``[p_d, a_d]`` (tool-axis task). Returns False when ``J J^T + rho I`` is singular."""
    m, rotation, position, world_axis, jac6, jac, b, frame, a, low, y = _workspace(chain_i, task_i, q.shape[0])
    _task(chain_f, chain_i, task_i, task_f, q, wdot, rotation, position, world_axis, jac6, jac, b, frame)
    if task_i[0] == 0:
        rows = task_i[3:]
        for r in range(m):
            error_out[r] = target[r] - frame[9 + rows[r]]
    else:
        for r in range(3):
            error_out[r] = target[r] - frame[9 + r]
        ax, ay, az = target[3], target[4], target[5]
        norm = np.sqrt(ax * ax + ay * ay + az * az)
        col = task_i[2]
        tx, ty, tz = frame[col], frame[3 + col], frame[6 + col]  # the tool axis
        cx, cy, cz = (ty * az - tz * ay) / norm, (tz * ax - tx * az) / norm, (tx * ay - ty * ax) / norm
        for s in range(2):
            c = (col + 1 + s) % 3
            error_out[3 + s] = frame[c] * cx + frame[3 + c] * cy + frame[6 + c] * cz
    for r in range(m):
        b[r] += gain * error_out[r]
    return _velocity(jac, b, u, rho, a, low, y, qdot_out)


# ---------------------------------------------------------------------------------------------- algorithm 11, fused
CONVERGED, MAX_ITERATIONS, NO_DECREASE = 0, 1, 2
"""Status codes of :func:`pik_optimize` (the order of ``PredictiveResult.status``'s names in :data:`STATUS`)."""
SINGULAR, OVERFLOW = -1, -2
"""Failure codes of :func:`pik_optimize`: ``J J^T + rho I`` singular along a rollout; the first rollout overflowed."""
STATUS = ("converged", "max_iterations", "no_decrease")
"""``PredictiveResult.status`` of each status code."""
METHODS = ("fletcher_reeves", "polak_ribiere", "steepest_descent")
"""Descent direction codes of :func:`pik_optimize` (their index)."""
_OK, _ABOVE = 0, 2
"""Codes of :func:`_rollout_slot` besides ``SINGULAR`` and ``OVERFLOW``: done; stopped above the limit."""
SLOTS = 3
"""Rollouts the workspace of :func:`pik_optimize` holds at once: the current iterate, the Armijo trial and the
parabolic step's trial."""


@njit(**JIT)
def slot_size(steps, n, nj, m):
    """Floats of one rollout slot of the workspace (see :func:`_slot`) for ``steps`` samples, ``n`` joints, ``nj``
    chain joints and a task of ``m`` rows."""
    return steps * (5 * n + 6 * nj + 12 + m * n + m + m * m) + n


@njit(**JIT)
def _slot(work, index, steps, n, nj, m):
    """Views of rollout slot ``index`` of the flat workspace ``work``: the decision variables ``params`` (N, n), the
    inputs ``u`` (N, n), ``q`` (N + 1, n), ``qdot`` (N, n), and what the adjoint pass needs of each sample, kept by
    the forward pass so that it is not recomputed: the potentials' gradient ``dH_jl/dq + dH_c/dq`` (N, n), the
    joint origins and world axes (N, nj, 3), the task frame (N, 12), the task Jacobian (N, m, n), ``y`` (N, m) and
    the Cholesky factor of ``J J^T + rho I`` (N, m, m)."""
    size = slot_size(steps, n, nj, m)
    w = work[index * size : (index + 1) * size]
    o = 0
    params = w[o : o + steps * n].reshape((steps, n))
    o += steps * n
    u = w[o : o + steps * n].reshape((steps, n))
    o += steps * n
    q = w[o : o + (steps + 1) * n].reshape((steps + 1, n))
    o += (steps + 1) * n
    qdot = w[o : o + steps * n].reshape((steps, n))
    o += steps * n
    grad_h = w[o : o + steps * n].reshape((steps, n))
    o += steps * n
    position = w[o : o + steps * nj * 3].reshape((steps, nj, 3))
    o += steps * nj * 3
    world_axis = w[o : o + steps * nj * 3].reshape((steps, nj, 3))
    o += steps * nj * 3
    frame = w[o : o + steps * 12].reshape((steps, 12))
    o += steps * 12
    jac = w[o : o + steps * m * n].reshape((steps, m, n))
    o += steps * m * n
    y = w[o : o + steps * m].reshape((steps, m))
    o += steps * m
    low = w[o : o + steps * m * m].reshape((steps, m, m))
    return params, u, q, qdot, grad_h, position, world_axis, frame, jac, y, low


@njit(**BORROW)
def _total(terms):
    """The cost of a slot's terms (velocity, joint limits, collision, input rate), summed in the order of
    ``PredictiveIk._rollout``."""
    return terms[0] + terms[1] + terms[2] + terms[3]


@njit(**BORROW)
def _rollout_slot(problem, run, slot, limit, terms, temps):
    """:func:`pik_rollout` of the problem ``(chain_f, chain_i, task_i, task_f, objective_f, coll_i, coll_f,
    coll_p, collision)`` from ``run``: ``(q0, wdot, dt, augmented, u_b, input_weight)`` (:func:`pik_optimize`'s
    arguments) on the slot's ``params`` (the inputs ``u`` formed from them when ``augmented``:
    ``u_k = u_b + dt sum_{l<k} udot_l`` (5.121)), keeping each sample's kinematics and potential gradient in the
    slot for :func:`_adjoint_slot`; the cost terms into ``terms`` (4).

    Returns ``_OK``, ``SINGULAR``, ``OVERFLOW`` (a joint velocity or configuration, or the cost, is not finite:
    the cost is infinite) or ``_ABOVE``: the cost so far exceeds ``limit`` and the rest is not integrated. Every
    term is >= 0 (squares and potentials (5.58), (5.49) with weights >= 0), so the partial sum only grows: a trial
    stopped above the line search's threshold would have been rejected with its whole cost too.

    ``temps``: ``(rotation, jac6, b, a, scratch, running)``, the work arrays of :func:`pik_optimize`.
    """
    chain_f, chain_i, task_i, task_f, objective_f, coll_i, coll_f, coll_p, collision = problem
    q0, wdot, dt, augmented, u_b, input_weight = run
    rotation, jac6, b, a, scratch, running = temps
    params, u, q, qdot, grad_h, position, world_axis, frame, jac, y, low = slot
    steps, n = params.shape
    rho, wv = objective_f[0], objective_f[1]
    lower, upper, lp = objective_f[2 : 2 + n], objective_f[2 + n : 2 + 2 * n], objective_f[2 + 2 * n : 6 + 2 * n]
    may_stop = lp[3] >= 0.0 and (not collision or coll_p[3] >= 0.0)
    rate = 0.0
    if augmented:
        for k in range(steps):
            for i in range(n):
                rate += params[k, i] * params[k, i]
        rate = dt * input_weight * rate
        for i in range(n):
            running[i] = 0.0
            u[0, i] = u_b[i]
        for k in range(1, steps):
            for i in range(n):
                running[i] += params[k - 1, i]
                u[k, i] = u_b[i] + dt * running[i]
    else:
        for k in range(steps):
            for i in range(n):
                u[k, i] = params[k, i]
    terms[0] = terms[1] = terms[2] = 0.0
    terms[3] = rate
    for i in range(n):
        q[0, i] = q0[i]
    for k in range(steps):
        qk = q[k]
        _task(
            chain_f,
            chain_i,
            task_i,
            task_f,
            qk,
            wdot[k],
            rotation,
            position[k],
            world_axis[k],
            jac6,
            jac[k],
            b,
            frame[k],
        )
        if not _velocity(jac[k], b, u[k], rho, a, low[k], y[k], qdot[k]):
            return SINGULAR
        speed = 0.0
        finite = True
        for i in range(n):
            speed += qdot[k, i] * qdot[k, i]
            q[k + 1, i] = qk[i] + dt * qdot[k, i]
            finite = finite and np.isfinite(q[k + 1, i])
        if not (finite and np.isfinite(speed)):
            return OVERFLOW
        g = grad_h[k]
        for i in range(n):
            g[i] = 0.0
        terms[0] += dt * wv * speed
        terms[1] += dt * _limits(qk, lower, upper, lp, g)
        if collision:
            terms[2] += dt * _collision(
                coll_i, coll_f, coll_p, chain_i, rotation, position[k], world_axis[k], g, scratch
            )
        if may_stop and _total(terms) > limit:
            return _ABOVE
    if not np.isfinite(_total(terms)):
        return OVERFLOW
    return _OK


@njit(**BORROW)
def _adjoint_slot(
    chain_i, task_i, slot, wdot, dt, wv, augmented, input_weight, grad, lam, v, nv, mu, grad_q, vjp_scratch
):
    """:func:`pik_gradient` from the kinematics a :func:`_rollout_slot` kept: the adjoint recursion (5.113),
    (5.115) backward, the gradient with respect to the slot's ``params`` into ``grad`` (N, n). When ``augmented``
    it is the gradient with respect to ``udot``: ``u_k`` depends on ``udot_l`` for ``l < k`` (5.121), so the
    adjoint of ``u`` (5.126) is the reverse cumulative sum, plus ``2 dt w_a udot_k`` (A.62)."""
    params, u, q, qdot, grad_h, position, world_axis, frame, jac, y, low = slot
    steps, n = params.shape
    m = y.shape[1]
    for i in range(n):
        lam[i] = 0.0
    for k in range(steps - 1, -1, -1):
        jk = jac[k]
        for i in range(n):
            v[i] = lam[i] + 2.0 * wv * qdot[k, i]
        for r in range(m):
            acc = 0.0
            for i in range(n):
                acc += jk[r, i] * v[i]
            mu[r] = acc
        cholesky_solve(low[k], m, mu)
        for i in range(n):
            acc = v[i]
            for r in range(m):
                acc -= jk[r, i] * mu[r]
            nv[i] = acc
            grad[k, i] = dt * acc
            grad_q[i] = grad_h[k, i]
        _vjp(chain_i, task_i, position[k], world_axis[k], frame[k], wdot[k], y[k], nv, mu, qdot[k], grad_q, vjp_scratch)
        for i in range(n):
            lam[i] += dt * grad_q[i]
    if not augmented:
        return
    rate = 2.0 * dt * input_weight
    for i in range(n):
        v[i] = 0.0  # sum_{l > k} dPhi/du_l
    for k in range(steps - 1, -1, -1):
        for i in range(n):
            later = v[i]
            v[i] += grad[k, i]
            grad[k, i] = dt * later + rate * params[k, i]


@njit(**JIT)
def pik_optimize(
    problem,
    q0,
    wdot,
    dt,
    augmented,
    u_b,
    input_weight,
    initial,
    max_iterations,
    tolerance,
    method,
    step,
    work,
    costs,
    params_out,
    u_out,
    q_out,
    qdot_out,
    terms_out,
):
    """Algorithm 11 in one call: ``PredictiveIk.optimize``'s Python loop (the same descent directions, Armijo
    backtracking, parabolic step and stopping rules) on the compiled rollout and adjoint.

    What the Python loop repeats per call, this does once per update: the adjoint pass reads the kinematics, task
    Jacobians, Cholesky factors and potential gradients the accepted rollout kept (``work``: :data:`SLOTS` slots
    of :func:`slot_size`) instead of recomputing them; a line-search trial stops integrating once its cost exceeds
    the threshold it has to meet; and the gradient at the last iterate, which no direction uses, is not formed.

    Args:
        problem: as :func:`pik_rollout`.
        initial: the first decision variables (N, n); method: index into :data:`METHODS`; step: first trial
            step size; costs: (max_iterations + 1) the cost after each iteration, the initial cost first.
        params_out, u_out, q_out, qdot_out: the final iterate (N, n), its inputs, configurations (N + 1, n) and
            joint velocities; terms_out: its cost terms (velocity, joint limits, collision, input rate).

    Returns:
        ``(code, iterations, step, rollouts)``: a status code (``CONVERGED``, ``MAX_ITERATIONS``, ``NO_DECREASE``)
        or a failure code (``SINGULAR``, ``OVERFLOW``), the descent steps taken, the step size the next line
        search would try first, and the forward integrations started (those stopped early included).
    """
    chain_i, task_i, objective_f = problem[1], problem[2], problem[4]
    steps, n = initial.shape
    nj = chain_i[0].shape[0]
    m = task_i.shape[0] - 3 if task_i[0] == 0 else 5
    wv = objective_f[1]
    rotation, jac6, b, a, scratch = np.empty((nj, 3, 3)), np.empty((6, n)), np.empty(m), np.empty((m, m)), np.empty(16)
    grad, ham, direction = np.empty((steps, n)), np.empty((steps, n)), np.empty((steps, n))
    lam, v, nv, mu, grad_q, running = np.empty(n), np.empty(n), np.empty(n), np.empty(m), np.empty(n), np.empty(n)
    vjp_scratch = _vjp_scratch(nj)
    terms = np.zeros((SLOTS, 4))
    run = (q0, wdot, dt, augmented, u_b, input_weight)
    temps = (rotation, jac6, b, a, scratch, running)
    cur, trial, other = 0, 1, 2
    slot = _slot(work, cur, steps, n, nj, m)
    slot[0][:, :] = initial
    code = _rollout_slot(problem, run, slot, np.inf, terms[cur], temps)
    rollouts = 1
    if code != _OK:
        return code, 0, step, rollouts
    cost = _total(terms[cur])
    _adjoint_slot(
        chain_i, task_i, slot, wdot, dt, wv, augmented, input_weight, grad, lam, v, nv, mu, grad_q, vjp_scratch
    )
    costs[0] = cost
    previous_norm = 0.0
    for k in range(steps):
        for i in range(n):
            h = grad[k, i] / dt  # dH/du: the function-space gradient (5.119)
            ham[k, i] = h
            direction[k, i] = -h
            previous_norm += h * h
    previous_norm = dt * previous_norm  # <g, g> as the integral of algorithm 11
    alpha = step
    status = MAX_ITERATIONS
    iterations = 0
    for j in range(max_iterations):
        slope = 0.0
        for k in range(steps):
            for i in range(n):
                slope += grad[k, i] * direction[k, i]
        if not slope < 0.0:  # not a descent direction (round-off): restart along the gradient
            slope = 0.0
            for k in range(steps):
                for i in range(n):
                    direction[k, i] = -ham[k, i]
                    slope += grad[k, i] * direction[k, i]
            if not slope < 0.0:
                status = CONVERGED
                break
        current = _slot(work, cur, steps, n, nj, m)[0]
        trial_cost = np.inf
        accepted = False
        for _ in range(30):  # backtracking with the Armijo condition
            slot = _slot(work, trial, steps, n, nj, m)
            candidate = slot[0]
            for k in range(steps):
                for i in range(n):
                    candidate[k, i] = current[k, i] + alpha * direction[k, i]
            threshold = cost + 1e-4 * alpha * slope
            code = _rollout_slot(problem, run, slot, threshold, terms[trial], temps)
            rollouts += 1
            if code == SINGULAR:
                return SINGULAR, iterations, alpha, rollouts
            if code == _OK:
                trial_cost = _total(terms[trial])
                if trial_cost <= threshold:
                    accepted = True
                    break
            alpha *= 0.5
        if not accepted:
            status = NO_DECREASE
            break
        # the minimum of the parabola through the cost at 0 and alpha with the slope at 0
        curvature = trial_cost - cost - slope * alpha
        if curvature > 0.0:
            best = -slope * alpha * alpha / (2.0 * curvature)
            if 0.0 < best < 4.0 * alpha and abs(best - alpha) > 1e-3 * alpha:
                slot = _slot(work, other, steps, n, nj, m)
                candidate = slot[0]
                for k in range(steps):
                    for i in range(n):
                        candidate[k, i] = current[k, i] + best * direction[k, i]
                code = _rollout_slot(problem, run, slot, trial_cost, terms[other], temps)
                rollouts += 1
                if code == SINGULAR:
                    return SINGULAR, iterations, alpha, rollouts
                if code == _OK and _total(terms[other]) < trial_cost:
                    trial, other = other, trial
                    trial_cost, alpha = _total(terms[trial]), best
        decrease = (cost - trial_cost) / max(abs(cost), 1e-300)
        cur, trial = trial, cur
        cost = trial_cost
        iterations = j + 1
        costs[iterations] = cost
        alpha *= 2.0  # start the next search a little further out
        if decrease < tolerance:
            status = CONVERGED
            break
        if j == max_iterations - 1:
            break  # the next direction would be the only use of this gradient
        _adjoint_slot(
            chain_i,
            task_i,
            _slot(work, cur, steps, n, nj, m),
            wdot,
            dt,
            wv,
            augmented,
            input_weight,
            grad,
            lam,
            v,
            nv,
            mu,
            grad_q,
            vjp_scratch,
        )
        norm = 0.0
        change = 0.0
        for k in range(steps):
            for i in range(n):
                h = grad[k, i] / dt
                change += h * (h - ham[k, i])
                norm += h * h
                ham[k, i] = h
        norm = dt * norm
        beta = 0.0
        if method == 0 and previous_norm > 0.0:
            beta = norm / previous_norm
        elif method == 1 and previous_norm > 0.0:  # PR+, restarts by itself
            beta = max(0.0, dt * change / previous_norm)
        for k in range(steps):
            for i in range(n):
                direction[k, i] = -ham[k, i] + beta * direction[k, i]
        previous_norm = norm
    params, u, q, qdot = _slot(work, cur, steps, n, nj, m)[:4]
    params_out[:, :] = params
    u_out[:, :] = u
    q_out[:, :] = q
    qdot_out[:, :] = qdot
    terms_out[:] = terms[cur]
    return status, iterations, alpha, rollouts

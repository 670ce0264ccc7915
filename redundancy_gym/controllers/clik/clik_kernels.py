"""The fused, compiled CLIK control step behind :class:`~redundancy_gym.controllers.CompiledClik`.

One kernel call does what :meth:`Clik.build` + :meth:`Clik.solve` do through some two hundred small NumPy and
pinocchio calls: forward kinematics of the chain, the task error, Jacobian and feedforward, the joint-limit,
posture and collision objectives with their gradients (5.58)-(5.61), and the weighted (damped) minimum-norm
solution with nullspace projection of Algorithm 10 / (5.14) / (5.22).

Everything the kernel reads or writes lives in two flat buffers, one float64 and one int64 (a NumPy array
argument costs numba about 0.4 us to box, so a step passes two instead of thirty). :func:`pack_buffers` lays
them out: the int64 buffer starts with an ``(offset, size)`` entry per field of :data:`FLOAT_FIELDS` and
:data:`INT_FIELDS`; the kernel takes views by field index.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numba import njit
from numpy.typing import NDArray

from ...geometry.potentials import piecewise_potential_kernel
from ...kernel_options import BORROW
from ...model.chain_kernels import frame_jacobian
from ..kernels import chain_fields as _chain
from ..kernels.buffers import borrowed_float_field, borrowed_int_field, pack_fields
from ..kernels.chain_fields import chain_indices, chain_views, field_index, forward_chain
from ..kernels.linalg import cholesky_factor, cholesky_solve
from ..objectives import collision_kernels as _collision
from ..objectives import objective_fields as _objective_fields
from ..objectives.collision_kernels import close_pair_rows, collision_potential, collision_views
from ..objectives.objective_fields import LIMIT_LOWER, LIMIT_PARAMETERS, LIMIT_UPPER, POSTURE_REFERENCE, POSTURE_WEIGHTS
from .redundancy_resolution import BOUND_ROUND_OFF, MAX_COORDINATE

__all__ = [
    "DIMS",
    "FLOAT_FIELDS",
    "INT_FIELDS",
    "METHOD_CODES",
    "SCALARS",
    "STATUS_NAMES",
    "clik_close_pairs",
    "clik_fields",
    "clik_step",
    "clik_step_arrays",
    "pack_buffers",
]

FLOAT_FIELDS: tuple[str, ...] = (
    *_chain.CHAIN_PLACEMENT_FIELDS,
    *_chain.CHAIN_STATE_FIELDS,
    "task_rotation",
    "task_translation",
    "gain",
    "inverse_weights",
    "scalars",
    *_objective_fields.OBJECTIVE_FLOAT_FIELDS,
    *_collision.COLLISION_FLOAT_FIELDS,
    "inputs",
    "outputs",
    "jacobian6",
    "jacobian",
    "gradient",
    "scratch",
    "max_velocity",
    "position_lower",
    "position_upper",
)
INT_FIELDS: tuple[str, ...] = (
    "dims",
    *_chain.CHAIN_INT_FIELDS,
    "task_rows",
    *_collision.COLLISION_INT_FIELDS,
    "position_q_index",
    "position_v_index",
)
# entries of the "dims" field
DIMS: tuple[str, ...] = (
    "joints",
    "nv",
    "nq",
    "task_dim",
    *_objective_fields.OBJECTIVE_DIMS,
    *_collision.COLLISION_COUNTS,
    "task_kind",
    "task_joint",
    "task_axis",
    "method",
    "collision",
    "objectives",
    "bounded_joints",
)
METHOD_CODES: dict[str, int] = {"pseudoinverse": 0, "dls": 1, "transpose": 2}
STATUS_NAMES: tuple[str, ...] = ("ok", "damped", "singular")
SCRATCH_SIZE = 160
# result entries after qdot (nv) and the task error (task_dim) in "outputs"
OUTPUT_EXTRA = 8  # |e|, sigma_min, damping, H, status code, smallest collision distance seen [m], limited (0/1),
# stepped (1: the last call succeeded, so the buffers hold its kinematics and placed volumes)
STEPPED = 7  # index of the stepped flag among the extra outputs
# entries of the "scalars" field
SCALARS: tuple[str, ...] = ("nullspace_gain", "singular_threshold", "dls_threshold", "dls_max_damping", "period")

_F = field_index(FLOAT_FIELDS)
_F_TASK_ROTATION = _F["task_rotation"]
_F_TASK_TRANSLATION = _F["task_translation"]
_F_GAIN = _F["gain"]
_F_INVERSE_WEIGHTS = _F["inverse_weights"]
_F_SCALARS = _F["scalars"]
_F_INPUTS = _F["inputs"]
_F_OUTPUTS = _F["outputs"]
_F_JACOBIAN6 = _F["jacobian6"]
_F_JACOBIAN = _F["jacobian"]
_F_GRADIENT = _F["gradient"]
_F_SCRATCH = _F["scratch"]
_F_MAX_VELOCITY = _F["max_velocity"]
_F_POSITION_LOWER = _F["position_lower"]
_F_POSITION_UPPER = _F["position_upper"]
_F_OBJECTIVES = _F[_objective_fields.OBJECTIVE_FLOAT_FIELDS[0]]  # the objectives' block: + LIMIT_LOWER, ...
_F_COLLISION = _F[_collision.COLLISION_FLOAT_FIELDS[0]]  # the collision block (collision_views takes it)
_I = field_index(INT_FIELDS, len(FLOAT_FIELDS))
_I_DIMS = _I["dims"]
_I_TASK_ROWS = _I["task_rows"]
_I_POSITION_Q_INDEX = _I["position_q_index"]
_I_POSITION_V_INDEX = _I["position_v_index"]
_I_COLLISION = _I[_collision.COLLISION_INT_FIELDS[0]]  # and its int block
_CHAIN_FLOATS, _CHAIN_INTS = chain_indices(FLOAT_FIELDS, INT_FIELDS)  # in the order of kernels.chain_fields

# return codes of clik_step
OK, BAD_CONFIGURATION, BAD_TARGET, ZERO_AXIS, BAD_VELOCITY, BAD_INPUT = range(6)

# The kernels index the buffers by these module-level ints, which numba folds into constants.
(
    _D_JOINTS,
    _D_NV,
    _D_NQ,
    _D_TASK_DIM,
    _D_LIMIT_OBJECTIVES,
    _D_POSTURE_OBJECTIVES,
    _D_SEGMENTS,
    _D_VOLUMES,
    _D_PAIRS,
    _D_VOLUME_PAIRS,
    _D_TASK_KIND,
    _D_TASK_JOINT,
    _D_TASK_AXIS,
    _D_METHOD,
    _D_COLLISION,
    _D_OBJECTIVES,
    _D_BOUNDED_JOINTS,
) = range(len(DIMS))
_DLS, _TRANSPOSE = METHOD_CODES["dls"], METHOD_CODES["transpose"]
# the status codes as the float outputs hold them
_STATUS_OK, _STATUS_DAMPED, _STATUS_SINGULAR = (
    float(STATUS_NAMES.index(name)) for name in ("ok", "damped", "singular")
)
_NULLSPACE_GAIN, _SINGULAR_THRESHOLD, _DLS_THRESHOLD, _DLS_MAX_DAMPING, _PERIOD = range(len(SCALARS))
# the extra outputs after qdot and the task error (OUTPUT_EXTRA of them, the last STEPPED)
_X_ERROR_NORM, _X_SIGMA, _X_DAMPING, _X_OBJECTIVE, _X_STATUS, _X_MIN_DISTANCE, _X_LIMITED = range(STEPPED)
# offsets of the "scratch" field: its first 12 entries are collision_potential's
_S_FRAME_ROTATION = 12  # the task frame's rotation (3 x 3)
_S_FRAME_POSITION = _S_FRAME_ROTATION + 9  # and origin (3)
_S_RHS = _S_FRAME_POSITION + 3  # the effective task velocity wdot_d + K e (at most 6 rows)
_S_GRAM = _S_RHS + 6  # J W^-1 J^T (+ damping), 6 x 6
_S_EIGEN = _S_GRAM + 36  # the Jacobi rotations' matrix of _min_eigenvalue (6 x 6)
_S_LAMBDA = _S_EIGEN + 36  # the multipliers (6)
_S_FACTOR = _S_LAMBDA + 6  # the Cholesky factor of the Gram matrix (6 x 6)
assert _S_FACTOR + 36 <= SCRATCH_SIZE

# every kernel here only borrows the buffers' arrays: compiled with BORROW (no reference counting)


def pack_buffers(
    floats: Mapping[str, NDArray[np.float64]], ints: Mapping[str, NDArray[np.int64]]
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """The kernel's two buffers from every field of :data:`FLOAT_FIELDS` and :data:`INT_FIELDS` (flattened)."""
    return pack_fields(floats, ints, FLOAT_FIELDS, INT_FIELDS)


_fv = borrowed_float_field
_iv = borrowed_int_field


@njit(**BORROW)
def _min_eigenvalue(b, m, a):
    """Smallest eigenvalue of the symmetric m x m matrix ``b`` by cyclic Jacobi rotations (``a``: m*m scratch)."""
    for r in range(m):
        for c in range(m):
            a[r * m + c] = b[r, c]
    scale = 0.0
    for k in range(m * m):
        scale += a[k] * a[k]
    for _ in range(60):
        off = 0.0
        for r in range(m):
            for c in range(r + 1, m):
                off += a[r * m + c] * a[r * m + c]
        if off <= 1e-32 * scale:
            break
        for p in range(m):
            for q in range(p + 1, m):
                apq = a[p * m + q]
                if apq == 0.0:
                    continue
                theta = (a[q * m + q] - a[p * m + p]) / (2.0 * apq)
                t = (1.0 if theta >= 0.0 else -1.0) / (abs(theta) + np.sqrt(theta * theta + 1.0))
                c = 1.0 / np.sqrt(t * t + 1.0)
                s = t * c
                for k in range(m):  # columns p, q
                    akp = a[k * m + p]
                    akq = a[k * m + q]
                    a[k * m + p] = c * akp - s * akq
                    a[k * m + q] = s * akp + c * akq
                for k in range(m):  # rows p, q
                    apk = a[p * m + k]
                    aqk = a[q * m + k]
                    a[p * m + k] = c * apk - s * aqk
                    a[q * m + k] = s * apk + c * aqk
    smallest = a[0]
    for r in range(1, m):
        smallest = min(smallest, a[r * m + r])
    return smallest


@njit(inline="always", **BORROW)  # inlined: it returns views (see kernels.buffers.borrowed_float_field)
def _collision_views(f, i, dims):
    """:func:`~.collision_kernels.collision_views` of the buffer's collision fields."""
    return collision_views(f, i, _F_COLLISION, _I_COLLISION, dims[_D_SEGMENTS], dims[_D_VOLUMES], dims[_D_PAIRS])


@njit(**BORROW)
def clik_close_pairs(f, i, limit, distances, rows):
    """:func:`~.collision_kernels.close_pair_rows` at the configuration of the last :func:`clik_step` (which placed
    the volumes and computed the kinematics in the buffers); returns how many pairs it filled."""
    dims = _iv(i, _I_DIMS)
    coll_i, coll_f, _ = _collision_views(f, i, dims)
    chain = chain_views(f, i, dims[_D_JOINTS], _CHAIN_FLOATS, _CHAIN_INTS)
    return close_pair_rows(coll_i, coll_f, chain, limit, distances, rows)


@njit(**BORROW)
def _task(
    f, i, dims, has_velocity, q_rotation, position, world_axis, parent, joint_type, v_index, error, rhs, jac, scratch
):
    """Task error, Jacobian and effective velocity ``wdot_d + K e`` (5.5); returns a clik_step code."""
    nv, nq, m = dims[_D_NV], dims[_D_NQ], dims[_D_TASK_DIM]
    kind, joint, ax = dims[_D_TASK_KIND], dims[_D_TASK_JOINT], dims[_D_TASK_AXIS]
    inputs = _fv(f, i, _F_INPUTS)
    target = inputs[nq : nq + 6]
    velocity = inputs[nq + 6 : nq + 12]
    gain = _fv(f, i, _F_GAIN)
    jac6 = _fv(f, i, _F_JACOBIAN6).reshape((6, nv))
    rot = scratch[_S_FRAME_ROTATION:_S_FRAME_POSITION].reshape((3, 3))
    pos = scratch[_S_FRAME_POSITION : _S_FRAME_POSITION + 3]
    frame_jacobian(
        parent,
        joint_type,
        v_index,
        q_rotation,
        position,
        world_axis,
        joint,
        _fv(f, i, _F_TASK_ROTATION).reshape((3, 3)),
        _fv(f, i, _F_TASK_TRANSLATION),
        rot,
        pos,
        jac6,
    )
    width = 6 if kind == 1 else m
    for k in range(width):
        if not np.isfinite(target[k]):
            return BAD_TARGET
        if has_velocity and not np.isfinite(velocity[k]):
            return BAD_VELOCITY
    if kind == 0:  # selected world coordinates of the frame origin
        rows = _iv(i, _I_TASK_ROWS)
        for r in range(m):
            error[r] = target[r] - pos[rows[r]]
            rhs[r] = gain[r] * error[r] + (velocity[r] if has_velocity else 0.0)
            for c in range(nv):
                jac[r, c] = jac6[rows[r], c]
        return OK
    # position and tool axis (FrameAxisTask): [p_d - p, u.(a x a_d), v.(a x a_d)]
    norm = np.sqrt(target[3] * target[3] + target[4] * target[4] + target[5] * target[5])
    if norm < 1e-9:
        return ZERO_AXIS
    u1 = (ax + 1) % 3
    u2 = (ax + 2) % 3
    a = (rot[0, ax], rot[1, ax], rot[2, ax])
    u = (rot[0, u1], rot[1, u1], rot[2, u1])
    v = (rot[0, u2], rot[1, u2], rot[2, u2])
    g = (target[3] / norm, target[4] / norm, target[5] / norm)
    cross = (a[1] * g[2] - a[2] * g[1], a[2] * g[0] - a[0] * g[2], a[0] * g[1] - a[1] * g[0])
    for r in range(3):
        error[r] = target[r] - pos[r]
        rhs[r] = gain[r] * error[r] + (velocity[r] if has_velocity else 0.0)
        for c in range(nv):
            jac[r, c] = jac6[r, c]
    error[3] = u[0] * cross[0] + u[1] * cross[1] + u[2] * cross[2]
    error[4] = v[0] * cross[0] + v[1] * cross[1] + v[2] * cross[2]
    rhs[3] = gain[3] * error[3]
    rhs[4] = gain[4] * error[4]
    if has_velocity:
        rhs[3] += u[0] * velocity[3] + u[1] * velocity[4] + u[2] * velocity[5]
        rhs[4] += v[0] * velocity[3] + v[1] * velocity[4] + v[2] * velocity[5]
    for c in range(nv):
        jac[3, c] = u[0] * jac6[3, c] + u[1] * jac6[4, c] + u[2] * jac6[5, c]
        jac[4, c] = v[0] * jac6[3, c] + v[1] * jac6[4, c] + v[2] * jac6[5, c]
    return OK


@njit(**BORROW)
def _bound(f, i, nv, nb, q, x):
    """:meth:`~.redundancy_resolution.JointBounds.apply` in place on ``x``: hold each bounded joint inside its
    range (``q + x period`` inside with a period, else no velocity further out of a limit it has reached), then
    scale the whole ``x`` into the speed limits; returns whether anything changed by more than round-off
    (:data:`~.redundancy_resolution.BOUND_ROUND_OFF` of the largest component, or of 1)."""
    limited = False
    largest = 1.0
    for k in range(nv):
        largest = max(largest, abs(x[k]))
    tolerance = BOUND_ROUND_OFF * largest
    period = _fv(f, i, _F_SCALARS)[_PERIOD]
    lower = _fv(f, i, _F_POSITION_LOWER)
    upper = _fv(f, i, _F_POSITION_UPPER)
    q_index = _iv(i, _I_POSITION_Q_INDEX)
    v_index = _iv(i, _I_POSITION_V_INDEX)
    for b in range(nb):
        qk = q[q_index[b]]
        if period > 0.0:
            low = min((lower[b] - qk) / period, 0.0)
            high = max((upper[b] - qk) / period, 0.0)
        else:
            low = -np.inf if qk > lower[b] else 0.0
            high = np.inf if qk < upper[b] else 0.0
        v = x[v_index[b]]
        bounded = min(max(v, low), high)
        if bounded != v:
            x[v_index[b]] = bounded
            if abs(bounded - v) > tolerance:
                limited = True
    vmax = _fv(f, i, _F_MAX_VELOCITY)
    peak = 0.0
    for k in range(nv):
        peak = max(peak, abs(x[k]) / vmax[k])
    if peak > 1.0:
        for k in range(nv):
            x[k] = min(max(x[k] / peak, -vmax[k]), vmax[k])
        limited = True
    return limited


@njit(inline="always", **BORROW)  # inlined: it returns views (see kernel_buffers.borrowed_float_field)
def clik_fields(f, i):
    """``(inputs, outputs, nq, nv, task_dim)`` of the buffers: the views and sizes that a compiled caller of
    :func:`clik_step` fills and reads (``inputs``: q, target (6), target velocity (6), nullspace input (nv);
    ``outputs``: qdot, task error, :data:`OUTPUT_EXTRA` diagnostics)."""
    dims = _iv(i, _I_DIMS)
    return _fv(f, i, _F_INPUTS), _fv(f, i, _F_OUTPUTS), dims[_D_NQ], dims[_D_NV], dims[_D_TASK_DIM]


@njit(inline="always", **BORROW)
def _recorded_step(f, i, has_velocity, has_input):
    """:func:`_step`, with the outputs' :data:`STEPPED` flag set where it succeeded. Inlined, so that each entry
    point calls :func:`_step` itself: numba compiles a kernel together with every kernel it calls, and one
    wrapper level less is one compilation of the whole step less (about 5 % of the quick start's cold compile)."""
    dims = _iv(i, _I_DIMS)
    flag = dims[_D_NV] + dims[_D_TASK_DIM] + STEPPED
    outputs = _fv(f, i, _F_OUTPUTS)
    outputs[flag] = 0.0  # a failed step leaves the kinematics half done: close pairs must not read them
    code = _step(f, i, has_velocity, has_input)
    if code == OK:
        outputs[flag] = 1.0
    return code


@njit(**BORROW)
def clik_step(f, i, has_velocity, has_input):
    """One CLIK step on the buffers of :func:`pack_buffers`: reads ``inputs`` (q, target (6), target velocity
    (6), nullspace input ``u`` of (5.100) (nv), used where ``has_input``) and writes ``outputs`` (qdot, bounded
    by :func:`_bound`, error, then :data:`OUTPUT_EXTRA` diagnostics, the last of them :data:`STEPPED`);
    returns a code (0 ok, 1 non-finite q, 2 non-finite target, 3 zero target axis, 4 non-finite target
    velocity, 5 non-finite nullspace input)."""
    return _recorded_step(f, i, has_velocity, has_input)


@njit(**BORROW)
def clik_step_arrays(f, i, q, target, velocity, has_velocity):
    """:func:`clik_step` (no nullspace input) on ``q`` (nq), ``target`` and ``velocity`` (the task's target
    width: 6 for a :class:`FrameAxisTask`, else its rows; ``velocity`` read where ``has_velocity``), copied into
    ``inputs`` here: one call instead of three NumPy slice assignments and the step."""
    dims = _iv(i, _I_DIMS)
    nq = dims[_D_NQ]
    inputs = _fv(f, i, _F_INPUTS)
    for k in range(nq):
        inputs[k] = q[k]
    for k in range(target.shape[0]):
        inputs[nq + k] = target[k]
    if has_velocity:
        for k in range(velocity.shape[0]):
            inputs[nq + 6 + k] = velocity[k]
    return _recorded_step(f, i, has_velocity, False)


@njit(**BORROW)
def _step(f, i, has_velocity, has_input):
    """The body of :func:`clik_step` (which records whether it succeeded)."""
    dims = _iv(i, _I_DIMS)
    nj, nv, nq, m = dims[_D_JOINTS], dims[_D_NV], dims[_D_NQ], dims[_D_TASK_DIM]
    n_limits, n_postures = dims[_D_LIMIT_OBJECTIVES], dims[_D_POSTURE_OBJECTIVES]
    method, collision, objectives = dims[_D_METHOD], dims[_D_COLLISION], dims[_D_OBJECTIVES]
    inputs = _fv(f, i, _F_INPUTS)
    q = inputs[:nq]
    for k in range(nq):
        if not abs(q[k]) <= MAX_COORDINATE:  # NaN, inf or beyond the coordinates a controller accepts
            return BAD_CONFIGURATION
    chain = forward_chain(f, i, nj, q, _CHAIN_FLOATS, _CHAIN_INTS)
    parent, joint_type, v_index, rotation, position, world_axis = chain
    scratch = _fv(f, i, _F_SCRATCH)
    outputs = _fv(f, i, _F_OUTPUTS)
    x = outputs[:nv]
    error = outputs[nv : nv + m]
    extra = outputs[nv + m :]
    rhs = scratch[_S_RHS:_S_GRAM]
    jac = _fv(f, i, _F_JACOBIAN).reshape((m, nv))
    code = _task(
        f, i, dims, has_velocity, rotation, position, world_axis, parent, joint_type, v_index, error, rhs, jac, scratch
    )
    if code != OK:
        return code
    # nullspace objectives: H and (dH/dq)^T
    gradient = _fv(f, i, _F_GRADIENT)
    gradient[:] = 0.0
    value = 0.0
    lower = _fv(f, i, _F_OBJECTIVES + LIMIT_LOWER)
    upper = _fv(f, i, _F_OBJECTIVES + LIMIT_UPPER)
    lp = _fv(f, i, _F_OBJECTIVES + LIMIT_PARAMETERS)
    for o in range(n_limits):  # (5.58) on the distance to each limit
        da, slope, ratio, weight = lp[4 * o], lp[4 * o + 1], lp[4 * o + 2], lp[4 * o + 3]
        for k in range(nq):
            h0, d0, _ = piecewise_potential_kernel(q[k] - lower[o * nq + k], da, slope, ratio)
            h1, d1, _ = piecewise_potential_kernel(upper[o * nq + k] - q[k], da, slope, ratio)
            value += weight * (h0 + h1)
            gradient[k] += weight * (d0 - d1)
    reference = _fv(f, i, _F_OBJECTIVES + POSTURE_REFERENCE)
    pw = _fv(f, i, _F_OBJECTIVES + POSTURE_WEIGHTS)
    for o in range(n_postures):
        for k in range(nq):
            delta = q[k] - reference[o * nq + k]
            value += 0.5 * pw[o * nq + k] * delta * delta
            gradient[k] += pw[o * nq + k] * delta
    smallest = np.inf
    if collision:
        coll_i, coll_f, params = _collision_views(f, i, dims)
        h, smallest = collision_potential(coll_i, coll_f, params, chain, gradient, scratch)
        value += h
    # weighted minimum norm with nullspace vector z = alpha dH/dq (Algorithm 10, (5.14), (5.22))
    scalars = _fv(f, i, _F_SCALARS)
    alpha, singular_threshold = scalars[_NULLSPACE_GAIN], scalars[_SINGULAR_THRESHOLD]
    dls_threshold, dls_max = scalars[_DLS_THRESHOLD], scalars[_DLS_MAX_DAMPING]
    winv = _fv(f, i, _F_INVERSE_WEIGHTS)
    b = scratch[_S_GRAM:_S_EIGEN].reshape((6, 6))
    for r in range(m):
        for c in range(r + 1):
            acc = 0.0
            for k in range(nv):
                acc += jac[r, k] * winv[k] * jac[c, k]
            b[r, c] = acc
            b[c, r] = acc
    sigma = np.sqrt(max(_min_eigenvalue(b, m, scratch[_S_EIGEN:_S_LAMBDA]), 0.0))
    damping = 0.0
    status = _STATUS_OK
    e2 = 0.0
    for r in range(m):
        e2 += error[r] * error[r]
    extra[_X_ERROR_NORM] = np.sqrt(e2)
    extra[_X_OBJECTIVE] = value
    extra[_X_MIN_DISTANCE] = smallest
    extra[_X_LIMITED] = 0.0
    x[:] = 0.0
    if method == _TRANSPOSE:  # transpose (5.24): x = W^-1 J^T rhs, objectives ignored
        finite = True
        for k in range(nv):
            acc = 0.0
            for r in range(m):
                acc += jac[r, k] * rhs[r]
            x[k] = winv[k] * acc
            finite = finite and np.isfinite(x[k])
        if not finite:
            x[:] = 0.0
            status = _STATUS_SINGULAR
        extra[_X_SIGMA], extra[_X_DAMPING], extra[_X_STATUS] = sigma, 0.0, status
        if finite and _bound(f, i, nv, dims[_D_BOUNDED_JOINTS], q, x):
            extra[_X_LIMITED] = 1.0
        return OK
    if method == _DLS:
        if sigma < dls_threshold:
            damping = dls_max * (1.0 - (sigma / dls_threshold) ** 2)
            status = _STATUS_DAMPED
        for r in range(m):
            b[r, r] += damping
    elif not sigma >= singular_threshold:
        extra[_X_SIGMA], extra[_X_DAMPING], extra[_X_STATUS] = sigma, 0.0, _STATUS_SINGULAR
        return OK
    # z = alpha dH/dq - W u: the nullspace term -N W^-1 z is the objectives' descent plus N u (5.100)
    u = inputs[nq + 12 : nq + 12 + nv]
    if has_input:
        for k in range(nv):
            if not np.isfinite(u[k]):
                return BAD_INPUT
    nullspace = objectives or has_input
    lam = scratch[_S_LAMBDA:_S_FACTOR]
    for r in range(m):
        lam[r] = rhs[r]
        if nullspace:
            acc = 0.0
            for k in range(nv):
                z = alpha * gradient[k] if objectives else 0.0
                if has_input:
                    z -= u[k] / winv[k]
                acc += jac[r, k] * winv[k] * z
            lam[r] += acc
    low = scratch[_S_FACTOR : _S_FACTOR + m * m].reshape((m, m))
    if not cholesky_factor(b, m, low) > 0.0:
        extra[_X_SIGMA], extra[_X_DAMPING], extra[_X_STATUS] = sigma, damping, _STATUS_SINGULAR
        return OK
    cholesky_solve(low, m, lam)
    finite = True
    for k in range(nv):
        acc = 0.0
        for r in range(m):
            acc += jac[r, k] * lam[r]
        if objectives:
            acc -= alpha * gradient[k]
        if has_input:
            acc += u[k] / winv[k]
        x[k] = winv[k] * acc
        finite = finite and np.isfinite(x[k])
    if not finite:
        x[:] = 0.0
        status = _STATUS_SINGULAR
    extra[_X_SIGMA], extra[_X_DAMPING], extra[_X_STATUS] = sigma, damping, status
    if finite and _bound(f, i, nv, dims[_D_BOUNDED_JOINTS], q, x):
        extra[_X_LIMITED] = 1.0
    return OK

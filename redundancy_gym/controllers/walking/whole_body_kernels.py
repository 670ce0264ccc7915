"""The fused, compiled step of the whole-body IK behind :class:`~.CompiledWholeBodyIk`.

One kernel call does what :meth:`WholeBodyIk.step` does through some hundred pinocchio and NumPy calls:
floating-base kinematics (:mod:`redundancy_gym.model.chain_kernels`), the CoM and ``J_Lz`` from composite
rigid bodies, the sole and torso task Jacobians and errors, the joint-limit (5.58), posture and
self-collision (5.49)-(5.61) gradients, the solve with ``W = gamma I + J_Lz^T J_Lz`` (5.62) by
Sherman-Morrison-Woodbury, the integration over the period and the Newton correction at its end.

The arrays live in two flat buffers (:mod:`..kernel_buffers`); :data:`FLOAT_FIELDS`, :data:`INT_FIELDS` and
:data:`DIMS` name them. A reference is packed as :data:`REFERENCE_LAYOUT`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...geometry.potentials import piecewise_potential_kernel
from ...kernel_options import JIT
from ...model.chain_kernels import chain_centroidal, chain_integrate, frame_jacobian
from ..kernels import chain_fields as _chain
from ..kernels.buffers import float_field, int_field
from ..kernels.chain_fields import chain_indices, chain_views, field_index, forward_chain
from ..kernels.linalg import rotation_error_into
from ..objectives import collision_kernels as _collision
from ..objectives import objective_fields as _objective_fields
from ..objectives.collision_kernels import collision_potential, collision_views
from ..objectives.objective_fields import LIMIT_LOWER, LIMIT_PARAMETERS, LIMIT_UPPER, POSTURE_REFERENCE, POSTURE_WEIGHTS
from .ik_kernels import weighted_solve

__all__ = [
    "DIMS",
    "FLOAT_FIELDS",
    "INT_FIELDS",
    "OUTPUT_EXTRA",
    "REFERENCE_LAYOUT",
    "REFERENCE_SIZE",
    "BAD_INPUT",
    "OK",
    "whole_body_step",
]

FLOAT_FIELDS: tuple[str, ...] = (
    *_chain.CHAIN_PLACEMENT_FIELDS,
    "body_mass",
    "body_com",
    "body_inertia",
    *_chain.CHAIN_STATE_FIELDS,
    "composite",
    "frame_rotation",
    "frame_translation",
    *_objective_fields.OBJECTIVE_FLOAT_FIELDS,
    *_collision.COLLISION_FLOAT_FIELDS,
    "scalars",
    "inputs",
    "outputs",
    "jacobian",
    "jacobian6",
    "jacobian_com",
    "jacobian_angular",
    "error",
    "rhs",
    "gradient",
    "scratch",
)
INT_FIELDS: tuple[str, ...] = (
    "dims",
    *_chain.CHAIN_INT_FIELDS,
    "frame_joint",
    *_collision.COLLISION_INT_FIELDS,
)
DIMS: tuple[str, ...] = (
    "joints",
    "nq",
    "nv",
    "base_nq",
    "base_nv",
    *_objective_fields.OBJECTIVE_DIMS,
    *_collision.COLLISION_COUNTS,
    "collision",
    "momentum_minimization",
)
REFERENCE_LAYOUT: dict[str, slice] = {
    "com": slice(0, 3),
    "com_velocity": slice(3, 6),
    "feet_position": slice(6, 12),
    "feet_rotation": slice(12, 30),
    "feet_velocity": slice(30, 42),
    "torso_rotation": slice(42, 51),
    "torso_angular_velocity": slice(51, 54),
}
"""Where each :class:`~.WholeBodyReference` field lies in a packed reference (flattened, row-major)."""
REFERENCE_SIZE = 54
SCALARS: tuple[str, ...] = (
    "gain",
    "gamma",
    "beta",
    "nullspace_gain",
    "damping",
    "singular_threshold",
    "max_velocity",
    "dt",
)
# after q_next (nq) and qdot (nv) in "outputs"
OUTPUT_EXTRA = 7  # task error, lz, sigma_min, success, smallest collision distance seen [m], objective value,
# limited
SCRATCH_SIZE = 16
OK, BAD_INPUT = 0, 1

_M = 18
_F = field_index(FLOAT_FIELDS)
_F_BODY_MASS = _F["body_mass"]
_F_BODY_COM = _F["body_com"]
_F_BODY_INERTIA = _F["body_inertia"]
_F_COMPOSITE = _F["composite"]
_F_FRAME_ROTATION = _F["frame_rotation"]
_F_FRAME_TRANSLATION = _F["frame_translation"]
_F_SCALARS = _F["scalars"]
_F_INPUTS = _F["inputs"]
_F_OUTPUTS = _F["outputs"]
_F_JACOBIAN = _F["jacobian"]
_F_JACOBIAN6 = _F["jacobian6"]
_F_JACOBIAN_COM = _F["jacobian_com"]
_F_JACOBIAN_ANGULAR = _F["jacobian_angular"]
_F_ERROR = _F["error"]
_F_RHS = _F["rhs"]
_F_GRADIENT = _F["gradient"]
_F_SCRATCH = _F["scratch"]
_F_OBJECTIVES = _F[_objective_fields.OBJECTIVE_FLOAT_FIELDS[0]]  # the objectives' block: + LIMIT_LOWER, ...
_F_COLLISION = _F[_collision.COLLISION_FLOAT_FIELDS[0]]  # the collision block (collision_views takes it)
_I = field_index(INT_FIELDS, len(FLOAT_FIELDS))
_I_DIMS = _I["dims"]
_I_FRAME_JOINT = _I["frame_joint"]
_I_COLLISION = _I[_collision.COLLISION_INT_FIELDS[0]]  # and its int block
_CHAIN_FLOATS, _CHAIN_INTS = chain_indices(FLOAT_FIELDS, INT_FIELDS)  # in the order of kernels.chain_fields
_I_PARENT, _I_JOINT_TYPE, _I_Q_INDEX, _I_V_INDEX = _CHAIN_INTS


@njit(**JIT)
def _build(f, i, dims, q, reference):
    """Task Jacobian, error (reference - actual) and ``J_Lz`` at ``q`` into the buffer
    (as :meth:`WholeBodyIk.build`)."""
    nj = dims[0]
    chain = forward_chain(f, i, nj, q, _CHAIN_FLOATS, _CHAIN_INTS)
    parent, joint_type, v_index, rotation, position, world_axis = chain
    nv = dims[2]
    jac = float_field(f, i, _F_JACOBIAN).reshape((_M, nv))
    jac6 = float_field(f, i, _F_JACOBIAN6).reshape((6, nv))
    jac_com = float_field(f, i, _F_JACOBIAN_COM).reshape((3, nv))
    jac_angular = float_field(f, i, _F_JACOBIAN_ANGULAR).reshape((3, nv))
    err = float_field(f, i, _F_ERROR)
    scratch = float_field(f, i, _F_SCRATCH)
    com = scratch[0:3]
    chain_centroidal(
        *chain,
        float_field(f, i, _F_BODY_MASS),
        float_field(f, i, _F_BODY_COM).reshape((nj, 3)),
        float_field(f, i, _F_BODY_INERTIA).reshape((nj, 3, 3)),
        float_field(f, i, _F_COMPOSITE).reshape((nj, 13)),
        com,
        jac_com,
        jac_angular,
    )
    for r in range(3):
        jac[r, :] = jac_com[r, :]
        err[r] = reference[r] - com[r]
    frame_joint = int_field(i, _I_FRAME_JOINT)
    frame_rotation = float_field(f, i, _F_FRAME_ROTATION).reshape((3, 3, 3))
    frame_translation = float_field(f, i, _F_FRAME_TRANSLATION).reshape((3, 3))
    rot = scratch[3:12].reshape((3, 3))
    pos = scratch[12:15]
    feet_position = reference[6:12].reshape((2, 3))
    feet_rotation = reference[12:30].reshape((2, 3, 3))
    for side in range(3):  # right sole, left sole, torso
        frame_jacobian(
            parent,
            joint_type,
            v_index,
            rotation,
            position,
            world_axis,
            frame_joint[side],
            frame_rotation[side],
            frame_translation[side],
            rot,
            pos,
            jac6,
        )
        if side < 2:
            row = 3 + 6 * side
            for r in range(6):
                jac[row + r, :] = jac6[r, :]
            for r in range(3):
                err[row + r] = feet_position[side, r] - pos[r]
            rotation_error_into(feet_rotation[side], rot, err[row + 3 : row + 6])
        else:
            for r in range(3):
                jac[15 + r, :] = jac6[3 + r, :]
            rotation_error_into(reference[42:51].reshape((3, 3)), rot, err[15:18])


@njit(**JIT)
def _objectives(f, i, dims, q, gradient):
    """Joint-limit (5.58), posture and self-collision (5.49) gradients at ``q`` (after :func:`_build` at ``q``)
    into ``gradient``; returns ``(value, smallest collision distance computed)``."""
    nv, base_nq, base_nv = dims[2], dims[3], dims[4]
    n_limits, n_postures, collision = dims[5], dims[6], dims[11]
    na = nv - base_nv
    gradient[:] = 0.0
    value = 0.0
    lower = float_field(f, i, _F_OBJECTIVES + LIMIT_LOWER)
    upper = float_field(f, i, _F_OBJECTIVES + LIMIT_UPPER)
    lp = float_field(f, i, _F_OBJECTIVES + LIMIT_PARAMETERS)
    for o in range(n_limits):
        da, slope, ratio, weight = lp[4 * o], lp[4 * o + 1], lp[4 * o + 2], lp[4 * o + 3]
        for k in range(na):
            x = q[base_nq + k]
            h0, d0, _ = piecewise_potential_kernel(x - lower[o * na + k], da, slope, ratio)
            h1, d1, _ = piecewise_potential_kernel(upper[o * na + k] - x, da, slope, ratio)
            value += weight * (h0 + h1)
            gradient[base_nv + k] += weight * (d0 - d1)
    reference = float_field(f, i, _F_OBJECTIVES + POSTURE_REFERENCE)
    pw = float_field(f, i, _F_OBJECTIVES + POSTURE_WEIGHTS)
    for o in range(n_postures):
        for k in range(na):
            delta = q[base_nq + k] - reference[o * na + k]
            value += 0.5 * pw[o * na + k] * delta * delta
            gradient[base_nv + k] += pw[o * na + k] * delta
    smallest = np.inf
    if collision:
        nj, ns, nvol, npairs = dims[0], dims[7], dims[8], dims[9]
        coll_i, coll_f, params = collision_views(f, i, _F_COLLISION, _I_COLLISION, ns, nvol, npairs)
        chain = chain_views(f, i, nj, _CHAIN_FLOATS, _CHAIN_INTS)
        h, smallest = collision_potential(coll_i, coll_f, params, chain, gradient, float_field(f, i, _F_SCRATCH))
        value += h
    return value, smallest


@njit(**JIT)
def whole_body_step(f, i):
    """One :meth:`WholeBodyIk.step` on the buffers: reads ``inputs`` (q, the start and the end reference) and
    writes ``outputs`` (q at the end of the period, qdot, then :data:`OUTPUT_EXTRA` diagnostics); returns
    :data:`OK` or :data:`BAD_INPUT` (a non-finite input, nothing written)."""
    dims = int_field(i, _I_DIMS)
    nq, nv, momentum = dims[1], dims[2], dims[12]
    inputs = float_field(f, i, _F_INPUTS)
    for k in range(inputs.shape[0]):
        if not np.isfinite(inputs[k]):
            return BAD_INPUT
    q = inputs[:nq]
    start = inputs[nq : nq + REFERENCE_SIZE]
    end = inputs[nq + REFERENCE_SIZE : nq + 2 * REFERENCE_SIZE]
    scalars = float_field(f, i, _F_SCALARS)
    gain, gamma, beta, alpha, damping, threshold = (
        scalars[0],
        scalars[1],
        scalars[2],
        scalars[3],
        scalars[4],
        scalars[5],
    )
    max_velocity, dt = scalars[6], scalars[7]
    outputs = float_field(f, i, _F_OUTPUTS)
    q_next = outputs[:nq]
    qdot = outputs[nq : nq + nv]
    extra = outputs[nq + nv :]
    jac = float_field(f, i, _F_JACOBIAN).reshape((_M, nv))
    jac_angular = float_field(f, i, _F_JACOBIAN_ANGULAR).reshape((3, nv))
    err = float_field(f, i, _F_ERROR)
    rhs = float_field(f, i, _F_RHS)
    gradient = float_field(f, i, _F_GRADIENT)
    _build(f, i, dims, q, start)
    value, smallest = _objectives(f, i, dims, q, gradient)
    for r in range(_M):
        rhs[r] = gain * err[r]
    for r in range(3):  # wdot_d: CoM velocity, sole twists, torso angular velocity
        rhs[r] += start[3 + r]
        rhs[15 + r] += start[51 + r]
    for r in range(12):
        rhs[3 + r] += start[30 + r]
    scale = alpha / beta
    for k in range(nv):
        gradient[k] *= scale
    j_lz = jac_angular[2].copy()
    x, sigma, ok = weighted_solve(jac, rhs, j_lz, gradient, gamma, momentum != 0, damping)
    ok = ok and sigma >= threshold
    finite = True
    for k in range(nv):
        finite = finite and np.isfinite(x[k])
    extra[2], extra[4], extra[5], extra[6] = sigma, smallest, value, 0.0
    if not (ok and finite):
        worst = 0.0
        for r in range(_M):
            worst = max(worst, abs(err[r]))
        q_next[:] = q
        qdot[:] = 0.0
        extra[0], extra[1], extra[3] = worst, 0.0, 0.0
        return OK
    peak = 0.0
    for k in range(nv):
        peak = max(peak, abs(x[k]))
    shrink = 1.0
    if peak > max_velocity:  # near a singularity: keep the direction, bound the speed
        shrink = max_velocity / peak
        extra[6] = 1.0
    lz = 0.0
    for k in range(nv):
        qdot[k] = x[k] * shrink
        lz += j_lz[k] * qdot[k]
    joint_type = int_field(i, _I_JOINT_TYPE)
    q_index = int_field(i, _I_Q_INDEX)
    v_index = int_field(i, _I_V_INDEX)
    chain_integrate(joint_type, q_index, v_index, q, qdot, dt, q_next)
    # Newton correction on the end-of-period error (no nullspace motion)
    _build(f, i, dims, q_next, end)
    worst = 0.0
    for r in range(_M):
        worst = max(worst, abs(err[r]))
    j_lz = jac_angular[2].copy()
    gradient[:] = 0.0
    correction, sigma_end, ok = weighted_solve(jac, err, j_lz, gradient, gamma, momentum != 0, damping)
    finite = ok and sigma_end >= threshold
    peak = 0.0
    for k in range(nv):
        finite = finite and np.isfinite(correction[k])
        peak = max(peak, abs(correction[k]))
    if finite:
        if peak > max_velocity * dt:
            correction *= max_velocity * dt / peak
            extra[6] = 1.0
        chain_integrate(joint_type, q_index, v_index, q_next, correction, 1.0, q_next)
    extra[0], extra[1], extra[3] = worst, lz, 1.0
    return OK

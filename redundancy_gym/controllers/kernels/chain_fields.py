"""The serial chain's fields in a fused kernel's flat buffers (:func:`~.buffers.pack_fields`): their views and the
forward kinematics on them, for the kernels that carry a chain (:mod:`~redundancy_gym.controllers.clik.clik_kernels`,
:mod:`~redundancy_gym.controllers.walking.whole_body_kernels`)."""

from __future__ import annotations

from numba import njit

from ...kernel_options import BORROW
from ...model.chain_kernels import chain_forward
from .buffers import borrowed_float_field, borrowed_int_field

__all__ = ["chain_views", "forward_chain"]


@njit(inline="always", **BORROW)  # inlined: it returns views (see buffers.borrowed_float_field)
def chain_views(f, i, nj, floats, ints):  # pragma: no cover - compiled
    """``(parent, joint_type, v_index, rotation, position, world_axis)``: the chain's kinematics of ``nj`` joints
    in the buffers, the layout :func:`~redundancy_gym.controllers.objectives.collision_kernels.collision_potential`
    takes. ``floats`` are the field indices of ``(placement_rotation, placement_translation, axis, rotation,
    position, world_axis)``, ``ints`` of ``(parent, joint_type, q_index, v_index)``."""
    return (
        borrowed_int_field(i, ints[0]),
        borrowed_int_field(i, ints[1]),
        borrowed_int_field(i, ints[3]),
        borrowed_float_field(f, i, floats[3]).reshape((nj, 3, 3)),
        borrowed_float_field(f, i, floats[4]).reshape((nj, 3)),
        borrowed_float_field(f, i, floats[5]).reshape((nj, 3)),
    )


@njit(inline="always", **BORROW)  # inlined: it returns views
def forward_chain(f, i, nj, q, floats, ints):  # pragma: no cover - compiled
    """:func:`~redundancy_gym.model.chain_kernels.chain_forward` at ``q`` on the buffers' chain fields (indices
    as :func:`chain_views`); returns :func:`chain_views`, the kinematics it wrote."""
    chain = chain_views(f, i, nj, floats, ints)
    parent, joint_type, _, rotation, position, world_axis = chain
    chain_forward(
        parent,
        borrowed_float_field(f, i, floats[0]).reshape((nj, 3, 3)),
        borrowed_float_field(f, i, floats[1]).reshape((nj, 3)),
        borrowed_float_field(f, i, floats[2]).reshape((nj, 3)),
        joint_type,
        borrowed_int_field(i, ints[2]),
        q,
        rotation,
        position,
        world_axis,
    )
    return chain

"""The serial chain's fields in a fused kernel's flat buffers (:func:`~.buffers.pack_fields`): their views and the
forward kinematics on them, for the kernels that carry a chain (:mod:`~redundancy_gym.controllers.clik.clik_kernels`,
:mod:`~redundancy_gym.controllers.walking.whole_body_kernels`)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numba import njit
from numpy.typing import NDArray

from ...kernel_options import BORROW
from ...model import SerialChain
from ...model.chain_kernels import chain_forward
from .buffers import borrowed_float_field, borrowed_int_field

__all__ = [
    "CHAIN_INT_FIELDS",
    "CHAIN_PLACEMENT_FIELDS",
    "CHAIN_STATE_FIELDS",
    "chain_arrays",
    "chain_indices",
    "chain_views",
    "field_index",
    "forward_chain",
]

CHAIN_PLACEMENT_FIELDS: tuple[str, ...] = ("placement_rotation", "placement_translation", "axis")
"""The chain's constant float fields (its joints' placements and axes), in buffer order."""
CHAIN_STATE_FIELDS: tuple[str, ...] = ("rotation", "position", "world_axis")
"""The float fields the forward kinematics writes (each joint's world rotation, origin and axis), in buffer order."""
CHAIN_INT_FIELDS: tuple[str, ...] = ("parent", "joint_type", "q_index", "v_index")
"""The chain's int fields, in buffer order."""


def chain_arrays(chain: SerialChain) -> tuple[dict[str, NDArray[np.float64]], dict[str, NDArray[np.int64]]]:
    """The fields of :data:`CHAIN_PLACEMENT_FIELDS`, :data:`CHAIN_STATE_FIELDS` (zeros) and
    :data:`CHAIN_INT_FIELDS` of ``chain``, as :func:`~.buffers.pack_fields` takes them."""
    nj = chain.num_joints
    floats = {
        "placement_rotation": chain.placement_rotation,
        "placement_translation": chain.placement_translation,
        "axis": chain.axis,
        "rotation": np.zeros((nj, 3, 3)),
        "position": np.zeros((nj, 3)),
        "world_axis": np.zeros((nj, 3)),
    }
    ints = {"parent": chain.parent, "joint_type": chain.joint_type, "q_index": chain.q_index, "v_index": chain.v_index}
    return floats, ints


def chain_indices(float_fields: Sequence[str], int_fields: Sequence[str]) -> tuple[tuple[int, ...], tuple[int, ...]]:
    """``(floats, ints)``: the field indices of the chain in buffers of ``float_fields`` and ``int_fields``, in the
    order :func:`chain_views` and :func:`forward_chain` take them."""
    f, i = field_index(float_fields), field_index(int_fields, len(float_fields))
    return (
        tuple(f[name] for name in (*CHAIN_PLACEMENT_FIELDS, *CHAIN_STATE_FIELDS)),
        tuple(i[name] for name in CHAIN_INT_FIELDS),
    )


def field_index(fields: Sequence[str], start: int = 0) -> dict[str, int]:
    """Each field's index in the buffers' header (:func:`~.buffers.pack_fields`): ``start`` plus its position in
    ``fields`` (``start``: the number of float fields, for the int fields)."""
    return {name: start + k for k, name in enumerate(fields)}


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

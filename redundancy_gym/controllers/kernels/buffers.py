"""Two flat buffers (float64, int64) that carry every array of a fused control-step kernel.

Boxing a NumPy array costs numba about 0.4 us per argument, so a kernel with thirty inputs would spend
more on its call than on its work; the fused kernels (:mod:`.clik_kernels`,
:mod:`.walking.whole_body_kernels`) take two buffers instead. :func:`pack_fields` lays them out: the int64
buffer starts with an ``(offset, size)`` entry per float field then per int field, and the kernel takes views
by field index with :func:`float_field` and :func:`int_field`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from numba import njit
from numpy.typing import NDArray

from ...kernel_options import BORROW, JIT

__all__ = [
    "BORROW",
    "borrowed_float_field",
    "borrowed_int_field",
    "buffer_view",
    "float_field",
    "int_field",
    "pack_fields",
]

# BORROW (re-exported): the numba options of a fused kernel that only borrows arrays (never allocates, keeps or
# returns one to a caller that counts references). With reference counting, every call between compiled functions
# paid an atomic NRT_incref and NRT_decref per array argument and per view taken, a few hundred per CLIK step: the
# AgriReach CLIK kernel took 9.1 us with them and 4.5 us without (2-core machine shared with other processes).


def pack_fields(
    floats: Mapping[str, NDArray[np.float64]],
    ints: Mapping[str, NDArray[np.int64]],
    float_fields: Sequence[str],
    int_fields: Sequence[str],
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """The two buffers holding every field of ``float_fields`` and ``int_fields`` (flattened, in that order)."""
    header = 2 * (len(float_fields) + len(int_fields))
    fsizes = [np.asarray(floats[name]).size for name in float_fields]
    isizes = [np.asarray(ints[name]).size for name in int_fields]
    f = np.zeros(max(sum(fsizes), 1))
    i = np.zeros(header + sum(isizes), dtype=np.int64)
    offset = 0
    for k, (name, size) in enumerate(zip(float_fields, fsizes, strict=False)):
        i[2 * k], i[2 * k + 1] = offset, size
        f[offset : offset + size] = np.asarray(floats[name], dtype=np.float64).reshape(-1)
        offset += size
    offset = header
    for k, (name, size) in enumerate(zip(int_fields, isizes, strict=False), start=len(float_fields)):
        i[2 * k], i[2 * k + 1] = offset, size
        i[offset : offset + size] = np.asarray(ints[name], dtype=np.int64).reshape(-1)
        offset += size
    return f, i


def buffer_view(
    f: NDArray[np.float64], i: NDArray[np.int64], float_fields: Sequence[str], name: str
) -> NDArray[np.float64]:
    """The view of float field ``name`` of a packed buffer (writes reach the kernel)."""
    k = float_fields.index(name)
    offset, size = int(i[2 * k]), int(i[2 * k + 1])
    return f[offset : offset + size]


@njit(**JIT)
def float_field(f, i, k):  # pragma: no cover - compiled
    """View of float field ``k`` (its index in the float field list)."""
    o = i[2 * k]
    return f[o : o + i[2 * k + 1]]


@njit(**JIT)
def int_field(i, k):  # pragma: no cover - compiled
    """View of int field ``k`` (the number of float fields plus its index in the int field list)."""
    o = i[2 * k]
    return i[o : o + i[2 * k + 1]]


# inlined into the caller's IR: a function compiled without reference counting cannot return a view
@njit(inline="always", **BORROW)
def borrowed_float_field(f, i, k):  # pragma: no cover - compiled
    """:func:`float_field` for kernels compiled with :data:`BORROW` (the view is not reference counted, so it
    must not outlive the call, nor be returned to a kernel that counts references)."""
    o = i[2 * k]
    return f[o : o + i[2 * k + 1]]


@njit(inline="always", **BORROW)
def borrowed_int_field(i, k):  # pragma: no cover - compiled
    """:func:`int_field` for kernels compiled with :data:`BORROW`."""
    o = i[2 * k]
    return i[o : o + i[2 * k + 1]]

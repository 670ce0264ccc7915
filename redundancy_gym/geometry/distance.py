"""SSV distance queries (monograph 5.2.3): one pair, or many pairs in one compiled call."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..kernel_options import LazyEntryPoint
from .exceptions import GeometryError
from .primitives import SSV
from .ssv_kernels import GROUP_OF, cull_pairs_at, near_pairs_at, smallest_pair_at, ssv_pairs_at, ssv_pairs_grouped

__all__ = ["PackedVolumes", "PairBatch", "SSVDistance", "SSVDistances", "distance", "distances", "indexed_distances"]


class SSVDistance(NamedTuple):
    """Result of :func:`distance`.

    Attributes:
        distance: distance of the generating primitives minus both radii [m]; negative when the volumes
            overlap, ``-(r_a + r_b)`` when the primitives intersect.
        point_a: witness point on ``a``'s generating primitive [m].
        point_b: witness point on ``b``'s generating primitive [m]; ``|point_b - point_a| - r_a - r_b``
            equals ``distance``.
        normal: unit vector from ``point_a`` to ``point_b``; when the primitives touch, the direction between
            their centroids (``+z`` if those coincide too).
    """

    distance: float
    point_a: NDArray[np.float64]
    point_b: NDArray[np.float64]
    normal: NDArray[np.float64]


class SSVDistances(NamedTuple):
    """Results of :func:`distances` / :func:`indexed_distances`: ``distance`` (K,), the others (K, 3)."""

    distance: NDArray[np.float64]
    point_a: NDArray[np.float64]
    point_b: NDArray[np.float64]
    normal: NDArray[np.float64]


@dataclass(frozen=True)
class PackedVolumes:
    """Volumes in the kernels' layout: ``vertices`` (M, 3, 3) [m], ``radii`` (M,) [m], ``kinds`` (M,)."""

    vertices: NDArray[np.float64]
    radii: NDArray[np.float64]
    kinds: NDArray[np.int64]

    def __post_init__(self) -> None:
        """Check shapes, kinds and finiteness once, here (the kernels do not): a NaN vertex would give NaN
        distances. Arrays of another dtype are converted (float64 vertices and radii, int64 kinds)."""
        for name, dtype in (("vertices", np.float64), ("radii", np.float64), ("kinds", np.int64)):
            value = getattr(self, name)
            if not isinstance(value, np.ndarray) or value.dtype != dtype:
                given = np.asarray(value)
                if given.dtype.kind not in ("iu" if name == "kinds" else "iuf"):
                    raise GeometryError(
                        f"PackedVolumes {name} must be an array of "
                        f"{'ints' if name == 'kinds' else 'real numbers'}, got dtype {given.dtype}"
                    )
                object.__setattr__(self, name, given.astype(dtype))
        m = self.vertices.shape[0] if self.vertices.ndim == 3 else -1
        if self.vertices.shape != (m, 3, 3):
            raise GeometryError(f"PackedVolumes vertices must have shape (M, 3, 3), got {self.vertices.shape}")
        for name in ("radii", "kinds"):
            if getattr(self, name).shape != (m,):
                raise GeometryError(
                    f"PackedVolumes {name} must have shape ({m},) like the vertices, got {getattr(self, name).shape}"
                )
        check_packed_volumes(self)

    @classmethod
    def from_volumes(cls, volumes: Sequence[SSV]) -> PackedVolumes:
        """Pack a sequence of :class:`PSS`/:class:`LSS`/:class:`TSS`."""
        for i, v in enumerate(volumes):
            if not isinstance(v, SSV):
                raise GeometryError(f"volume {i} is {type(v).__name__}, expected PSS, LSS or TSS")
        n = len(volumes)
        vertices = np.empty((n, 3, 3))
        for i, v in enumerate(volumes):
            vertices[i] = v.vertices
        radii = np.array([v.radius for v in volumes], dtype=np.float64).reshape(n)
        kinds = np.array([v.kind for v in volumes], dtype=np.int64).reshape(n)
        return cls._checked(vertices, radii, kinds)

    @classmethod
    def _checked(
        cls, vertices: NDArray[np.float64], radii: NDArray[np.float64], kinds: NDArray[np.int64]
    ) -> PackedVolumes:
        """Arrays already known valid (from checked volumes), without checking them again."""
        packed = object.__new__(cls)
        for name, value in (("vertices", vertices), ("radii", radii), ("kinds", kinds)):
            object.__setattr__(packed, name, value)
        return packed

    def __len__(self) -> int:
        return int(self.radii.shape[0])


def check_packed_volumes(volumes: PackedVolumes) -> None:
    """Raise :class:`GeometryError` naming the first volume with a non-finite vertex or radius, a negative
    radius or an unknown kind (the arrays may have been written in place since they were packed)."""
    v, r, k = volumes.vertices, volumes.radii, volumes.kinds
    if not len(volumes) or (
        math.isfinite(float(v.sum()) + float(r.sum())) and r.min() >= 0.0 and k.min() >= 0 and k.max() <= 2
    ):
        return
    bad = ~np.isfinite(volumes.vertices).reshape(len(volumes), 9).all(axis=1)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise GeometryError(f"PackedVolumes vertices must be finite; volume {i} has {volumes.vertices[i].tolist()}")
    bad = ~(np.isfinite(volumes.radii) & (volumes.radii >= 0.0))
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise GeometryError(f"PackedVolumes radii must be finite and >= 0; volume {i} has {volumes.radii[i]!r}")
    bad = (volumes.kinds < 0) | (volumes.kinds > 2)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise GeometryError(
            f"PackedVolumes kinds must be 0 (PSS), 1 (LSS) or 2 (TSS); volume {i} has {int(volumes.kinds[i])}"
        )


def distance(a: SSV, b: SSV) -> SSVDistance:
    """Distance and witness points of two swept-sphere volumes (5.36).

    >>> from redundancy_gym.geometry import PSS, LSS
    >>> round(distance(PSS([0, 0, 1], 0.1), LSS([-1, 0, 0], [1, 0, 0], 0.2)).distance, 12)
    0.7
    """
    if not isinstance(a, SSV) or not isinstance(b, SSV):
        raise GeometryError(f"distance expects PSS, LSS or TSS, got {type(a).__name__}, {type(b).__name__}")
    out = indexed_distances(PackedVolumes.from_volumes((a, b)), [0], [1])
    return SSVDistance(float(out.distance[0]), out.point_a[0], out.point_b[0], out.normal[0])


class _Layout(NamedTuple):
    """Pairs sorted by type for :func:`ssv_pairs_grouped` (lower kind first, original row in ``slot``)."""

    index_a: NDArray[np.int64]
    index_b: NDArray[np.int64]
    slot: NDArray[np.int64]
    swap: NDArray[np.int64]
    starts: NDArray[np.int64]


def _layout(kinds: NDArray[np.int64], index_a: ArrayLike, index_b: ArrayLike) -> _Layout:
    """Check the pair indices and sort the pairs into the kernel's six type groups."""
    ia = np.asarray(index_a, dtype=np.int64).reshape(-1)
    ib = np.asarray(index_b, dtype=np.int64).reshape(-1)
    if ia.shape != ib.shape:
        raise GeometryError(f"index arrays must have equal length, got {ia.size} and {ib.size}")
    m = kinds.size
    if ia.size and (min(ia.min(), ib.min()) < 0 or max(ia.max(), ib.max()) >= m):
        raise GeometryError(f"pair indices must lie in [0, {m})")
    swap = kinds[ia] > kinds[ib]
    lo = np.where(swap, ib, ia)
    hi = np.where(swap, ia, ib)
    group = GROUP_OF[kinds[lo], kinds[hi]]
    order = np.argsort(group, kind="stable")
    return _Layout(
        np.ascontiguousarray(lo[order]),
        np.ascontiguousarray(hi[order]),
        order.astype(np.int64),
        swap[order].astype(np.int64),
        np.searchsorted(group[order], np.arange(7)).astype(np.int64),
    )


def indexed_distances(volumes: PackedVolumes, index_a: ArrayLike, index_b: ArrayLike) -> SSVDistances:
    """Distances of the pairs ``(volumes[index_a[k]], volumes[index_b[k]])`` in one compiled call.

    Raises:
        GeometryError: ``volumes`` is not a :class:`PackedVolumes`, holds a non-finite vertex or radius (checked
            again here: the arrays may have been written since packing), or an index is out of range.
    """
    if not isinstance(volumes, PackedVolumes):
        raise GeometryError(f"indexed_distances expects PackedVolumes, got {type(volumes).__name__}")
    layout = _layout(volumes.kinds, index_a, index_b)
    k = layout.slot.size
    out = SSVDistances(np.empty(k), np.empty((k, 3)), np.empty((k, 3)), np.empty((k, 3)))
    ssv_pairs_grouped(
        volumes.vertices,
        volumes.radii,
        volumes.kinds,
        *layout,
        np.ones(k, dtype=np.int64),
        *out,
        np.empty(k, dtype=np.int64),
    )
    if not math.isfinite(float(out.distance.sum())):  # a non-finite input written after packing: say which
        check_packed_volumes(volumes)
    return out


def distances(a: Sequence[SSV] | PackedVolumes, b: Sequence[SSV] | PackedVolumes) -> SSVDistances:
    """Elementwise :func:`distance` of two equally long sequences of volumes (one compiled call)."""
    pa = a if isinstance(a, PackedVolumes) else PackedVolumes.from_volumes(a)
    pb = b if isinstance(b, PackedVolumes) else PackedVolumes.from_volumes(b)
    if len(pa) != len(pb):
        raise GeometryError(f"distances needs equally many volumes, got {len(pa)} and {len(pb)}")
    both = PackedVolumes._checked(
        np.concatenate([pa.vertices, pb.vertices]),
        np.concatenate([pa.radii, pb.radii]),
        np.concatenate([pa.kinds, pb.kinds]),
    )
    n = len(pa)
    return indexed_distances(both, np.arange(n), np.arange(n, 2 * n))


class PairBatch:
    """A fixed set of volume pairs evaluated again and again (a control loop's collision queries).

    The pairs are sorted by type once, so that :meth:`compute` runs one tight compiled loop per pair type,
    and the kernel is entered with the addresses of buffers this object owns (a NumPy array argument costs
    numba about 0.4 us to box). Move the volumes by writing into :attr:`vertices` in place; :meth:`compute`
    then returns the distances in the original pair order, in buffers that the next call overwrites.

    Args:
        volumes: the volumes; their arrays are copied into buffers owned by the batch.
        index_a, index_b: (K,) volume indices of each pair.
        moving: how many leading volumes move; :meth:`compute_near` takes the volumes from index ``moving`` on
            as fixed (their bounding spheres are computed here, and by :meth:`cull`). Default: all move.
    """

    def __init__(
        self, volumes: PackedVolumes | Sequence[SSV], index_a: ArrayLike, index_b: ArrayLike, moving: int | None = None
    ) -> None:
        packed = volumes if isinstance(volumes, PackedVolumes) else PackedVolumes.from_volumes(volumes)
        self.vertices = np.ascontiguousarray(packed.vertices, dtype=np.float64).copy()
        self.radii = np.ascontiguousarray(packed.radii, dtype=np.float64).copy()
        self.kinds = np.ascontiguousarray(packed.kinds, dtype=np.int64).copy()
        layout = _layout(self.kinds, index_a, index_b)
        self._slot = layout.slot
        m = len(packed)
        if moving is None:
            moving = m
        if not isinstance(moving, (int, np.integer)) or not 0 <= moving <= m:
            raise GeometryError(f"moving must be an int in [0, {m}], got {moving!r}")
        self._moving = int(moving)
        k = layout.slot.size
        self._active = np.ones(k, dtype=np.int64)
        self.result = SSVDistances(np.empty(k), np.empty((k, 3)), np.empty((k, 3)), np.empty((k, 3)))
        self._todo = np.empty(k, dtype=np.int64)
        # the buffers stay referenced by self (layout included), so the addresses below stay valid
        self._layout = layout
        self._centers = np.empty((m, 3))
        self._bounds = np.empty(m)
        buffers = (self.vertices, self.radii, self.kinds, *layout, self._active, *self.result, self._todo)
        self._header = np.array(
            [b.ctypes.data for b in buffers] + [m, k, self._centers.ctypes.data, self._bounds.ctypes.data],
            dtype=np.int64,
        )
        self._header_address = int(self._header.ctypes.data)
        # every volume's bounding sphere, which compute_near keeps for the fixed ones (the small broad phase
        # compiles here; the narrow phases at their first call, so a batch never queried compiles nothing more)
        self._cull_kernel = LazyEntryPoint(self, "_cull_kernel", cull_pairs_at)
        self._cull_kernel(self._header_address, 0.0)
        self._active[:] = 1  # the broad phase above wrote the mask
        self._kernel = LazyEntryPoint(self, "_kernel", ssv_pairs_at)
        self._near_kernel = LazyEntryPoint(self, "_near_kernel", near_pairs_at)
        self._frames: tuple[NDArray[np.float64], ...] | None = None
        self._frames_address = 0

    def __len__(self) -> int:
        return int(self._slot.size)

    def set_active(self, mask: ArrayLike) -> None:
        """Compute only the pairs where ``mask`` (in the original pair order) is true; the others get +inf."""
        m = np.asarray(mask, dtype=bool).reshape(-1)
        if m.size != len(self):
            raise GeometryError(f"mask must have {len(self)} entries, got {m.size}")
        self._active[:] = m[self._slot]

    def cull(self, margin: float) -> int:
        """Compute (in the next :meth:`compute`) only the pairs whose bounding spheres are at most ``margin`` [m]
        apart, for the current :attr:`vertices`; returns how many. Culled pairs get +inf, and their SSV distance
        is known to exceed ``margin`` (a broad phase; replaces any :meth:`set_active` mask)."""
        return int(self._cull_kernel(self._header_address, float(margin)))

    def attach_frames(
        self, positions: NDArray[np.float64], rotations: NDArray[np.float64], half_lengths: ArrayLike
    ) -> None:
        """Let :meth:`compute_near` place volumes ``0..n`` from frames first: volume ``i`` becomes the segment
        ``positions[i] -/+ half_lengths[i] * z_i`` (``z_i`` the third column of the row-major rotation
        ``rotations[i]``), or the point ``positions[i]`` where the half length is 0; radii and kinds stay.

        The arrays are read in place on every call (for example row slices of MuJoCo's ``geom_xpos`` and
        ``geom_xmat``), so they must be C-contiguous float64 of shapes (n, 3) and (n, 9), and stay alive and
        at the same address while attached; the volumes' kinds must match (LSS where the half length is > 0).
        """
        p = np.asarray(positions)
        r = np.asarray(rotations)
        h = np.ascontiguousarray(half_lengths, dtype=np.float64).reshape(-1).copy()
        n = h.size
        for name, a, shape in (("positions", p, (n, 3)), ("rotations", r, (n, 9))):
            if a.dtype != np.float64 or a.shape != shape or not a.flags.c_contiguous:
                raise GeometryError(
                    f"{name} must be a C-contiguous float64 array of shape {shape}, got {a.dtype} {a.shape}"
                )
        if (
            n > self._moving
            or np.any(h < 0.0)
            or np.any((h > 0.0) != (self.kinds[:n] == 1))
            or np.any((h == 0.0) != (self.kinds[:n] == 0))
        ):
            raise GeometryError(
                f"half_lengths must give an LSS (h > 0) or PSS (h = 0) for each of the first "
                f"volumes, at most moving={self._moving} of them"
            )
        self._frames = (p, r, h, np.array([p.ctypes.data, r.ctypes.data, h.ctypes.data, n], dtype=np.int64))
        self._frames_address = int(self._frames[3].ctypes.data)

    def compute_near(self, margin: float) -> float:
        """Broad and narrow phase in one compiled pass: the pairs whose bounding spheres are at most ``margin``
        [m] apart get their exact distance in :attr:`result`, the others +inf (their witnesses are stale);
        returns the smallest distance [m] (+inf when no pair is near). Faster than :meth:`cull` + :meth:`compute`
        when few pairs are near.
        Only the first ``moving`` volumes (constructor) may have moved since the last :meth:`cull` or
        construction; attached frames (:meth:`attach_frames`) are read first."""
        return float(self._near_kernel(self._header_address, float(margin), self._moving, self._frames_address))

    def smallest(self, margin: float) -> float:
        """The smallest distance of all pairs [m], exactly, computing only the pairs near it: a
        :meth:`compute_near` with ``margin`` [m] (a guess of the answer, such as the last step's), repeated with
        a doubled margin while its minimum lies beyond the margin (a pair farther than the margin may then be
        nearer than that minimum); beyond 1e6 m every pair is computed. A non-finite vertex gives NaN or +inf
        back, as :meth:`compute` would. One compiled call (``ssv_kernels.smallest_pair_at``)."""
        return float(smallest_pair_at(self._header_address, float(margin), self._moving, self._frames_address))

    @property
    def address(self) -> tuple[int, int, int]:
        """``(header address, moving, frames address)``: the arguments with which a kernel queries this batch
        through :func:`~redundancy_gym.geometry.ssv_kernels.smallest_pair_at` (valid while the batch lives and its
        frames stay attached)."""
        return self._header_address, self._moving, self._frames_address

    def compute(self) -> SSVDistances:
        """Distances of all pairs for the current :attr:`vertices` (buffers reused by the next call)."""
        self._kernel(self._header_address)
        return self.result

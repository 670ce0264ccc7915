"""SSV distance queries (monograph 5.2.3): one pair, or many pairs in one compiled call."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .exceptions import GeometryError
from .primitives import SSV
from .ssv_kernels import ssv_pair, ssv_pairs_indexed

__all__ = ["PackedVolumes", "SSVDistance", "SSVDistances", "distance", "distances", "indexed_distances"]


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
        return cls(vertices, radii, kinds)

    def __len__(self) -> int:
        return int(self.radii.shape[0])


def distance(a: SSV, b: SSV) -> SSVDistance:
    """Distance and witness points of two swept-sphere volumes (5.36).

    >>> from redundancy_gym.geometry import PSS, LSS
    >>> round(distance(PSS([0, 0, 1], 0.1), LSS([-1, 0, 0], [1, 0, 0], 0.2)).distance, 12)
    0.7
    """
    if not isinstance(a, SSV) or not isinstance(b, SSV):
        raise GeometryError(f"distance expects PSS, LSS or TSS, got {type(a).__name__}, {type(b).__name__}")
    pa = np.empty(3)
    pb = np.empty(3)
    n = np.empty(3)
    d = ssv_pair(a.vertices, a.radius, a.kind, b.vertices, b.radius, b.kind, pa, pb, n)
    return SSVDistance(float(d), pa, pb, n)


def indexed_distances(volumes: PackedVolumes, index_a: ArrayLike, index_b: ArrayLike) -> SSVDistances:
    """Distances of the pairs ``(volumes[index_a[k]], volumes[index_b[k]])`` in one compiled call."""
    ia = np.ascontiguousarray(index_a, dtype=np.int64)
    ib = np.ascontiguousarray(index_b, dtype=np.int64)
    if ia.shape != ib.shape or ia.ndim != 1:
        raise GeometryError(f"index arrays must be 1-D of equal length, got {ia.shape} and {ib.shape}")
    m = len(volumes)
    if ia.size and (min(ia.min(), ib.min()) < 0 or max(ia.max(), ib.max()) >= m):
        raise GeometryError(f"pair indices must lie in [0, {m})")
    k = ia.size
    out = SSVDistances(np.empty(k), np.empty((k, 3)), np.empty((k, 3)), np.empty((k, 3)))
    ssv_pairs_indexed(volumes.vertices, volumes.radii, volumes.kinds, ia, ib, *out)
    return out


def distances(a: Sequence[SSV] | PackedVolumes, b: Sequence[SSV] | PackedVolumes) -> SSVDistances:
    """Elementwise :func:`distance` of two equally long sequences of volumes (one compiled call)."""
    pa = a if isinstance(a, PackedVolumes) else PackedVolumes.from_volumes(a)
    pb = b if isinstance(b, PackedVolumes) else PackedVolumes.from_volumes(b)
    if len(pa) != len(pb):
        raise GeometryError(f"distances needs equally many volumes, got {len(pa)} and {len(pb)}")
    both = PackedVolumes(np.concatenate([pa.vertices, pb.vertices]), np.concatenate([pa.radii, pb.radii]),
                         np.concatenate([pa.kinds, pb.kinds]))
    n = len(pa)
    return indexed_distances(both, np.arange(n), np.arange(n, 2 * n))

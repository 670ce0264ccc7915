"""Swept-sphere geometry and distance potentials (monograph 5.2, 5.3).

Plain numpy and numba: never imports gymnasium, mujoco, envs or eval.
"""

from .distance import PackedVolumes, PairBatch, SSVDistance, SSVDistances, distance, distances, indexed_distances
from .exceptions import GeometryError
from .potentials import PiecewisePotential, PotentialValue
from .primitives import KIND_NAMES, LSS, PSS, SSV, TSS

__all__ = [
    "KIND_NAMES",
    "LSS",
    "PSS",
    "SSV",
    "TSS",
    "GeometryError",
    "PackedVolumes",
    "PairBatch",
    "PiecewisePotential",
    "PotentialValue",
    "SSVDistance",
    "SSVDistances",
    "distance",
    "distances",
    "indexed_distances",
]

"""Swept-sphere geometry and distance potentials (monograph 5.2, 5.3).

Plain numpy and numba: never imports gymnasium, mujoco, envs or eval.
"""

from .collision_model import CollisionLayout, CollisionModel, CollisionState, Kinematics, Segment, bounding_lss
from .distance import PackedVolumes, PairBatch, SSVDistance, SSVDistances, distance, distances, indexed_distances
from .exceptions import GeometryError
from .grasp_path import GraspPath, GraspPathTiming, grasp_path_durations
from .potentials import (
    CubicPotential,
    PiecewisePotential,
    PotentialValue,
    QuadraticPotential,
    piecewise_potential_kernel,
)
from .primitives import KIND_NAMES, LSS, PSS, SSV, TSS

__all__ = [
    "KIND_NAMES",
    "LSS",
    "PSS",
    "SSV",
    "TSS",
    "CollisionLayout",
    "CollisionModel",
    "CollisionState",
    "CubicPotential",
    "GeometryError",
    "GraspPath",
    "GraspPathTiming",
    "Kinematics",
    "PackedVolumes",
    "PairBatch",
    "PiecewisePotential",
    "PotentialValue",
    "QuadraticPotential",
    "SSVDistance",
    "SSVDistances",
    "Segment",
    "bounding_lss",
    "distance",
    "distances",
    "grasp_path_durations",
    "indexed_distances",
    "piecewise_potential_kernel",
]

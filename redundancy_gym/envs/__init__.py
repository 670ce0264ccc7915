"""Gymnasium environments on MuJoCo for redundant robots, one class per file (ids registered in
:mod:`redundancy_gym.registration`)."""

from .agri_reach import AgriReachEnv
from .biped_obstacles import BipedObstaclesEnv
from .biped_terrain import BipedTerrainEnv
from .biped_walk import BipedWalkEnv
from .exceptions import EnvConfigError, InvalidActionError
from .planar_reach import PlanarReachEnv

__all__ = [
    "AgriReachEnv",
    "BipedObstaclesEnv",
    "BipedTerrainEnv",
    "BipedWalkEnv",
    "EnvConfigError",
    "InvalidActionError",
    "PlanarReachEnv",
]

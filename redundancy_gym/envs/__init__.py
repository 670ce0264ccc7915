"""Gymnasium environments on MuJoCo for redundant robots, one class per file (ids registered in
:mod:`redundancy_gym.registration`).

The env classes load when first named (``from redundancy_gym.envs import AgriReachEnv``), not with the package:
``gym.make`` of one env imports its own module only (each brings its scene, kernels and collision model).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from .exceptions import EnvConfigError, InvalidActionError

if TYPE_CHECKING:
    from .agri_reach import AgriReachEnv
    from .biped_obstacles import BipedObstaclesEnv
    from .biped_terrain import BipedTerrainEnv
    from .biped_walk import BipedWalkEnv
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

_MODULES = {
    "AgriReachEnv": "agri_reach",
    "BipedObstaclesEnv": "biped_obstacles",
    "BipedTerrainEnv": "biped_terrain",
    "BipedWalkEnv": "biped_walk",
    "PlanarReachEnv": "planar_reach",
}


def __getattr__(name: str) -> Any:
    if name in _MODULES:
        value = getattr(importlib.import_module(f".{_MODULES[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))

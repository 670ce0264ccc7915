"""Swept-sphere geometry and distance potentials (monograph 5.2, 5.3).

Plain numpy: never imports gymnasium, mujoco, envs or eval.
"""

from .exceptions import GeometryError
from .potentials import PiecewisePotential, PotentialValue

__all__ = ["GeometryError", "PiecewisePotential", "PotentialValue"]

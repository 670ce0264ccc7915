"""Inverse Kineto-Dynamics (monograph 5.5): joint trajectories for hybrid tasks of prescribed forces and task
coordinates."""

from .general_ikd import GeneralIkd, GeneralIkdResult

__all__ = ["GeneralIkd", "GeneralIkdResult"]

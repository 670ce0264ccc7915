"""Inverse Kineto-Dynamics (monograph 5.5): joint trajectories for hybrid tasks of prescribed forces and task
coordinates."""

from .biped_ikd import BipedIkd, BipedIkdReference, BipedIkdResult
from .general_ikd import WEIGHTINGS, GeneralIkd, GeneralIkdResult

__all__ = ["WEIGHTINGS", "BipedIkd", "BipedIkdReference", "BipedIkdResult", "GeneralIkd", "GeneralIkdResult"]

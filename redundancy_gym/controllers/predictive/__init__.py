"""Predictive inverse kinematics (monograph 5.6): Algorithm 11 (:class:`PredictiveIk`) in a receding horizon
(Algorithm 12, :class:`RecedingHorizon`)."""

from .predictive_ik import DESCENT_METHODS, PredictiveIk, PredictiveResult, PredictiveRollout
from .receding_horizon import HorizonUpdate, RecedingHorizon

__all__ = [
    "DESCENT_METHODS",
    "HorizonUpdate",
    "PredictiveIk",
    "PredictiveResult",
    "PredictiveRollout",
    "RecedingHorizon",
]

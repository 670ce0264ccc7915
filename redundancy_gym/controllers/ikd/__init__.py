"""Inverse Kineto-Dynamics (monograph 5.5): joint trajectories for hybrid tasks of prescribed forces and task
coordinates."""

from .biped_ikd import BipedIkd, BipedIkdReference, BipedIkdResult
from .error_compensation import ErrorCompensation, ErrorCompensationOutput
from .general_ikd import WEIGHTINGS, GeneralIkd, GeneralIkdResult
from .plan_stabilizer import PlanStabilizer, PlanStabilizerOutput
from .walking_ikd import WalkingIkd, WalkingIkdConfig, WalkingIkdStep

__all__ = ["WEIGHTINGS", "BipedIkd", "BipedIkdReference", "BipedIkdResult", "ErrorCompensation",
           "ErrorCompensationOutput", "GeneralIkd", "GeneralIkdResult",
           "PlanStabilizer", "PlanStabilizerOutput", "WalkingIkd", "WalkingIkdConfig", "WalkingIkdStep"]

"""Nullspace objectives (monograph 5.3): a value and its gradient, with the collision potential's compiled fields."""

from .actuated_objective import ActuatedObjective
from .collision_objective import CollisionObjective
from .joint_limit_objective import JointLimitObjective
from .objective import Objective, ObjectiveValue, sum_objectives
from .posture_objective import PostureObjective

__all__ = [
    "ActuatedObjective",
    "CollisionObjective",
    "JointLimitObjective",
    "Objective",
    "ObjectiveValue",
    "PostureObjective",
    "sum_objectives",
]

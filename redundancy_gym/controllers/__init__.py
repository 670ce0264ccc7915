"""Model-based controllers of monograph chapter 5 (numpy + pinocchio; no simulator inside).

The core never imports gymnasium, mujoco, envs, policies, wrappers or eval: :mod:`redundancy_gym.policies` and
:mod:`redundancy_gym.wrappers` join controllers and envs.
"""

from .acceleration_clik import AccelerationClik, AccelerationClikResult
from .clik import Clik, ClikProblem, ClikResult
from .collision_objective import CollisionObjective
from .compiled_clik import CompiledClik
from .exceptions import ControllerError
from .frame_axis_task import FrameAxisTask
from .frame_position_task import FramePositionTask
from .joint_limit_objective import JointLimitObjective
from .objective import Objective, ObjectiveValue, sum_objectives
from .posture_objective import PostureObjective
from .predictive_ik import DESCENT_METHODS, PredictiveIk, PredictiveResult, PredictiveRollout
from .redundancy_resolution import METHODS, Resolution, WeightMatrix, resolve
from .task import Task

__all__ = [
    "DESCENT_METHODS",
    "METHODS",
    "AccelerationClik",
    "AccelerationClikResult",
    "Clik",
    "ClikProblem",
    "ClikResult",
    "CollisionObjective",
    "CompiledClik",
    "ControllerError",
    "FrameAxisTask",
    "FramePositionTask",
    "JointLimitObjective",
    "Objective",
    "ObjectiveValue",
    "PostureObjective",
    "PredictiveIk",
    "PredictiveResult",
    "PredictiveRollout",
    "Resolution",
    "Task",
    "WeightMatrix",
    "resolve",
    "sum_objectives",
]

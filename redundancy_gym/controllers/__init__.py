"""Model-based controllers of monograph chapter 5 (numpy + pinocchio; no simulator inside).

The core never imports gymnasium, mujoco, envs, policies, wrappers or eval: :mod:`redundancy_gym.policies` and
:mod:`redundancy_gym.wrappers` join controllers and envs.
"""

from .clik.acceleration_clik import AccelerationClik, AccelerationClikResult
from .clik.clik import Clik, ClikProblem, ClikResult
from .clik.compiled_clik import CompiledClik
from .clik.redundancy_resolution import METHODS, Resolution, WeightMatrix, resolve
from .exceptions import ControllerError
from .objectives.collision_objective import CollisionObjective
from .objectives.joint_limit_objective import JointLimitObjective
from .objectives.objective import Objective, ObjectiveValue, sum_objectives
from .objectives.posture_objective import PostureObjective
from .predictive.predictive_ik import DESCENT_METHODS, PredictiveIk, PredictiveResult, PredictiveRollout
from .tasks.frame_axis_task import FrameAxisTask
from .tasks.frame_position_task import FramePositionTask
from .tasks.task import Task

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

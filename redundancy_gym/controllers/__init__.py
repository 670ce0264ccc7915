"""Model-based controllers of monograph chapter 5 (numpy + pinocchio; no simulator inside).

The core never imports gymnasium, mujoco, envs or eval; :mod:`.policies` joins controllers and envs by duck
typing and is imported on demand (``redundancy_gym.make_policy``).
"""

from .acceleration_clik import AccelerationClik, AccelerationClikResult
from .clik import Clik, ClikProblem, ClikResult
from .collision_objective import CollisionObjective
from .compiled_clik import CompiledClik
from .exceptions import ControllerError, PolicyError
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
    "PolicyError",
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

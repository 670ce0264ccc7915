"""Model-based controllers of monograph chapter 5 (numpy + pinocchio; no simulator inside).

The core never imports gymnasium, mujoco, envs, policies, wrappers or eval: :mod:`redundancy_gym.policies` and
:mod:`redundancy_gym.wrappers` join controllers and envs.
"""

from .clik import *  # noqa: F403 - the parent re-exports every name of clik (listed once: clik/__init__.py)
from .clik import __all__ as _clik_names
from .exceptions import ControllerError
from .objectives.collision_objective import CollisionObjective
from .objectives.joint_limit_objective import JointLimitObjective
from .objectives.objective import Objective, ObjectiveValue, sum_objectives
from .objectives.posture_objective import PostureObjective
from .predictive.predictive_ik import DESCENT_METHODS, PredictiveIk, PredictiveResult, PredictiveRollout
from .tasks.frame_axis_task import FrameAxisTask
from .tasks.frame_position_task import FramePositionTask
from .tasks.task import Task

# every name of the clik subpackage, then the others (listed once: clik/__init__.py)
__all__ = [
    *_clik_names,
    "DESCENT_METHODS",
    "CollisionObjective",
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
    "Task",
    "sum_objectives",
]

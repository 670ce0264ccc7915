"""The controller's robot model (pinocchio, built from the same MJCF MuJoCo simulates).

Never imports gymnasium, mujoco, envs or eval.
"""

from .exceptions import ModelError, UnknownFrameError
from .robot_model import JacobianKind, RobotModel

__all__ = ["JacobianKind", "ModelError", "RobotModel", "UnknownFrameError"]

"""The controller's robot model (pinocchio, built from the same MJCF MuJoCo simulates).

Never imports gymnasium, mujoco, envs or eval.
"""

from .collision_geometry import CollisionGeometry, box_volumes, collision_geometry_from_mjcf, collision_model_from_mjcf
from .exceptions import ModelError, UnknownFrameError
from .robot_model import AccelerationTerms, JacobianKind, RobotModel
from .serial_chain import SerialChain

__all__ = [
    "AccelerationTerms",
    "CollisionGeometry",
    "JacobianKind",
    "ModelError",
    "RobotModel",
    "SerialChain",
    "UnknownFrameError",
    "box_volumes",
    "collision_geometry_from_mjcf",
    "collision_model_from_mjcf",
]

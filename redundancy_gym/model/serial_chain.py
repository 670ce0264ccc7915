"""A robot's kinematic tree of 1-DoF joints as flat arrays, for the compiled kernels of :mod:`.chain_kernels`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .chain_kernels import chain_forward, chain_jacobian
from .exceptions import ModelError

__all__ = ["SerialChain"]


@dataclass(frozen=True)
class SerialChain:
    """Joints of a fixed-base tree of revolute and prismatic joints, exported once by
    :meth:`~redundancy_gym.model.RobotModel.serial_chain` (indices are 0-based joints; the world is -1).

    Joint ``j``'s world frame is ``M_parent[j] * (placement_rotation[j], placement_translation[j]) *
    exp(axis[j] q[q_index[j]])``, a rotation about ``axis`` for a revolute joint and a translation along it for
    a prismatic one; its column in a Jacobian is ``v_index[j]``.

    Attributes:
        joint_names: (J,) names, in model order (parents first).
        parent: (J,) parent joint, -1 for the world.
        placement_rotation: (J, 3, 3) and placement_translation: (J, 3) [m] of the joint frame in its parent's.
        axis: (J, 3) unit axis in the joint frame.
        prismatic: (J,) 1 for a prismatic joint, 0 for a revolute one.
        q_index, v_index: (J,) index into the configuration and the velocity.
    """

    joint_names: tuple[str, ...]
    parent: NDArray[np.int64]
    placement_rotation: NDArray[np.float64]
    placement_translation: NDArray[np.float64]
    axis: NDArray[np.float64]
    prismatic: NDArray[np.int64]
    q_index: NDArray[np.int64]
    v_index: NDArray[np.int64]

    @property
    def num_joints(self) -> int:
        """Number of joints ``J`` (= nq = nv)."""
        return len(self.joint_names)

    def forward(self, q: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """World rotations (J, 3, 3) and positions (J, 3) [m] of the joint frames at ``q``."""
        rotation, position, _ = self._forward(q)
        return rotation, position

    def point_jacobian(self, q: ArrayLike, joint: int, point: ArrayLike) -> NDArray[np.float64]:
        """World-aligned ``[J_T; J_R]`` (6 x nv) of the world point ``point`` [m] moving with ``joint`` at ``q``."""
        if not -1 <= int(joint) < self.num_joints:
            raise ModelError(f"joint must lie in [-1, {self.num_joints}), got {joint}")
        _, position, world_axis = self._forward(q)
        p = np.asarray(point, dtype=np.float64)
        out = np.zeros((6, self.num_joints))
        chain_jacobian(self.parent, self.prismatic, self.v_index, position, world_axis, int(joint), float(p[0]),
                       float(p[1]), float(p[2]), out)
        return out

    def _forward(self, q: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """Joint rotations, positions and world axes at a checked ``q``."""
        q = np.ascontiguousarray(q, dtype=np.float64)
        if q.shape != (self.num_joints,) or not np.all(np.isfinite(q)):
            raise ModelError(f"q must be finite with shape ({self.num_joints},), got {q.shape}")
        n = self.num_joints
        rotation, position, world_axis = np.empty((n, 3, 3)), np.empty((n, 3)), np.empty((n, 3))
        chain_forward(self.parent, self.placement_rotation, self.placement_translation, self.axis, self.prismatic,
                      self.q_index, q, rotation, position, world_axis)
        return rotation, position, world_axis

"""A robot's kinematic tree as flat arrays, for the compiled kernels of :mod:`.chain_kernels`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .chain_kernels import FREE, chain_centroidal, chain_forward, chain_integrate, chain_jacobian
from .exceptions import ModelError

__all__ = ["SerialChain"]


@dataclass(frozen=True)
class SerialChain:
    """Joints of a tree of revolute and prismatic joints, on a fixed base or a free-flying root, exported once
    by :meth:`~redundancy_gym.model.RobotModel.serial_chain` (indices are 0-based joints; the world is -1).

    Joint ``j``'s world frame is ``M_parent[j] * (placement_rotation[j], placement_translation[j]) *
    exp(axis[j] q[q_index[j]])``, a rotation about ``axis`` for a revolute joint and a translation along it for
    a prismatic one; a free flyer (:data:`~.chain_kernels.FREE`, the root of a floating-base robot) reads
    ``q[q_index : q_index + 7] = [p; quat (x, y, z, w)]`` and has six velocity columns from ``v_index``
    (``[v; omega]`` in its own frame, as pinocchio's free flyer).

    Attributes:
        joint_names: (J,) names, in model order (parents first).
        parent: (J,) parent joint, -1 for the world.
        placement_rotation: (J, 3, 3) and placement_translation: (J, 3) [m] of the joint frame in its parent's.
        axis: (J, 3) unit axis in the joint frame (zero for a free flyer).
        joint_type: (J,) :data:`~.chain_kernels.REVOLUTE`, :data:`~.chain_kernels.PRISMATIC` or
            :data:`~.chain_kernels.FREE`.
        q_index, v_index: (J,) first index into the configuration and the velocity.
        body_mass: (J,) [kg], body_com: (J, 3) [m] and body_inertia: (J, 3, 3) [kg m^2] about the body's CoM,
            of the body each joint carries, in the joint frame.
        nq, nv: configuration and velocity sizes.
    """

    joint_names: tuple[str, ...]
    parent: NDArray[np.int64]
    placement_rotation: NDArray[np.float64]
    placement_translation: NDArray[np.float64]
    axis: NDArray[np.float64]
    joint_type: NDArray[np.int64]
    q_index: NDArray[np.int64]
    v_index: NDArray[np.int64]
    body_mass: NDArray[np.float64]
    body_com: NDArray[np.float64]
    body_inertia: NDArray[np.float64]
    nq: int
    nv: int

    @property
    def num_joints(self) -> int:
        """Number of joints ``J`` (= nq = nv on a fixed base)."""
        return len(self.joint_names)

    def kernel_arrays(self) -> tuple[NDArray[np.generic], ...]:
        """``(parent, placement_rotation, placement_translation, axis, joint_type, q_index, v_index, body_mass,
        body_com, body_inertia)``: the chain's arrays in the order the dynamics kernels of :mod:`.chain_kernels`
        take them (:func:`~.chain_kernels.chain_acceleration_terms` and the kernels built on it)."""
        return (
            self.parent,
            self.placement_rotation,
            self.placement_translation,
            self.axis,
            self.joint_type,
            self.q_index,
            self.v_index,
            self.body_mass,
            self.body_com,
            self.body_inertia,
        )

    @property
    def floating_base(self) -> bool:
        """Whether the root is a free flyer."""
        return bool(np.any(self.joint_type == FREE))

    def forward(self, q: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """World rotations (J, 3, 3) and positions (J, 3) [m] of the joint frames at ``q``."""
        rotation, position, _ = self._forward(q)
        return rotation, position

    def point_jacobian(self, q: ArrayLike, joint: int, point: ArrayLike) -> NDArray[np.float64]:
        """World-aligned ``[J_T; J_R]`` (6 x nv) of the world point ``point`` [m] moving with ``joint`` at ``q``."""
        if not -1 <= int(joint) < self.num_joints:
            raise ModelError(f"joint must lie in [-1, {self.num_joints}), got {joint}")
        frames = self._frames(q)
        p = np.asarray(point, dtype=np.float64)
        out = np.zeros((6, self.nv))
        chain_jacobian(*frames, int(joint), float(p[0]), float(p[1]), float(p[2]), out)
        return out

    def centroidal(self, q: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """``(c, J_c, A_L)`` at ``q``: CoM [m], its Jacobian (3 x nv) and the angular rows of the centroidal
        momentum matrix (3 x nv, ``L_G = A_L qdot`` [kg m^2/s] about the CoM)."""
        frames = self._frames(q)
        com, jac_com, jac_angular = np.zeros(3), np.zeros((3, self.nv)), np.zeros((3, self.nv))
        chain_centroidal(
            *frames,
            self.body_mass,
            self.body_com,
            self.body_inertia,
            np.zeros((self.num_joints, 13)),
            com,
            jac_com,
            jac_angular,
        )
        return com, jac_com, jac_angular

    def integrate(self, q: ArrayLike, v: ArrayLike, dt: float) -> NDArray[np.float64]:
        """The configuration reached from ``q`` moving with ``v`` for ``dt`` [s] (as ``pinocchio.integrate``)."""
        q = self._check(q, self.nq, "q")
        v = self._check(v, self.nv, "v")
        out = np.empty(self.nq)
        chain_integrate(self.joint_type, self.q_index, self.v_index, q, v, float(dt), out)
        return out

    @staticmethod
    def _check(x: ArrayLike, n: int, name: str) -> NDArray[np.float64]:
        x = np.ascontiguousarray(x, dtype=np.float64)
        if x.shape != (n,) or not np.all(np.isfinite(x)):
            raise ModelError(f"{name} must be finite with shape ({n},), got {x.shape}")
        return x

    def _frames(
        self, q: ArrayLike
    ) -> tuple[
        NDArray[np.int64],
        NDArray[np.int64],
        NDArray[np.int64],
        NDArray[np.float64],
        NDArray[np.float64],
        NDArray[np.float64],
    ]:
        """The leading arguments of the kernels that read the frames (:func:`chain_jacobian`,
        :func:`chain_centroidal`): parent, joint type and velocity index, then :meth:`_forward` at ``q``."""
        return (self.parent, self.joint_type, self.v_index, *self._forward(q))

    def _forward(self, q: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """Joint rotations, positions and world axes at a checked ``q``."""
        q = self._check(q, self.nq, "q")
        n = self.num_joints
        rotation, position, world_axis = np.empty((n, 3, 3)), np.empty((n, 3)), np.empty((n, 3))
        chain_forward(
            self.parent,
            self.placement_rotation,
            self.placement_translation,
            self.axis,
            self.joint_type,
            self.q_index,
            q,
            rotation,
            position,
            world_axis,
        )
        return rotation, position, world_axis

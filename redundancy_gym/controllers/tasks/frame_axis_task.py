"""Task: a frame's position plus the direction of one of its axes (a tool pointing along an approach line)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ...model import RobotModel
from ..exceptions import ControllerError

__all__ = ["FrameAxisTask"]


class FrameAxisTask:
    """``w`` = the frame origin [m] and the direction of its ``axis`` (5 coordinates: rotation about the axis is
    left free, a fifth redundant direction for a tool whose roll does not matter).

    The target is ``[p_d (3), a_d (3)]`` with ``a_d`` a unit vector. The position error is ``p_d - p``; the
    axis error is ``a x a_d`` expressed in two unit directions ``u, v`` orthogonal to the current axis ``a``
    (its magnitude is ``sin`` of the angle between the axes), with Jacobian rows ``u^T J_R`` and ``v^T J_R``
    since ``da/dt = omega x a``. A target velocity ``[v_d (3), omega_d (3)]`` maps to ``[v_d, u.omega_d,
    v.omega_d]`` (:meth:`feedforward`).

    Args:
        frame: the frame (e.g. the TCP site).
        axis: which local axis is the tool axis: 0 (x), 1 (y) or 2 (z).
    """

    dim = 5

    def __init__(self, frame: str, axis: int = 0) -> None:
        if axis not in (0, 1, 2):
            raise ControllerError(f"axis must be 0, 1 or 2, got {axis!r}")
        self.frame = frame
        self.axis = int(axis)

    def _basis(self, model: RobotModel) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        rot = model.frame_rotation(self.frame)
        a = rot[:, self.axis]
        return a, rot[:, (self.axis + 1) % 3], rot[:, (self.axis + 2) % 3]

    def value(self, model: RobotModel) -> NDArray[np.float64]:
        """Frame position [m] and tool axis (6 numbers; the task itself has 5 coordinates)."""
        a, _, _ = self._basis(model)
        return np.concatenate([model.frame_position(self.frame), a])

    def error(self, model: RobotModel, target: NDArray[np.float64]) -> NDArray[np.float64]:
        """``[p_d - p, u.(a x a_d), v.(a x a_d)]``."""
        target = np.asarray(target, dtype=np.float64)
        if target.shape != (6,) or not np.all(np.isfinite(target)):
            raise ControllerError(f"target must be finite [p_d, a_d] with shape (6,), got {target.shape}")
        a_d = target[3:]
        norm = float(np.linalg.norm(a_d))
        if norm < 1e-9:
            raise ControllerError("the target axis must not be zero")
        a, u, v = self._basis(model)
        c = np.cross(a, a_d / norm)
        return np.concatenate([target[:3] - model.frame_position(self.frame), [u @ c, v @ c]])

    def jacobian(self, model: RobotModel) -> NDArray[np.float64]:
        """``[J_T; u^T J_R; v^T J_R]`` (5 x nv)."""
        _, u, v = self._basis(model)
        jac = model.frame_jacobian(self.frame, "full")
        return np.vstack([jac[:3], u @ jac[3:], v @ jac[3:]])

    def feedforward(self, model: RobotModel, target_velocity: NDArray[np.float64]) -> NDArray[np.float64]:
        """Task-coordinate velocity of ``[v_d, omega_d]`` (6) at the current configuration (5)."""
        w = np.asarray(target_velocity, dtype=np.float64)
        if w.shape != (6,) or not np.all(np.isfinite(w)):
            raise ControllerError(f"target_velocity must be finite [v_d, omega_d] with shape (6,), got {w.shape}")
        _, u, v = self._basis(model)
        return np.concatenate([w[:3], [u @ w[3:], v @ w[3:]]])

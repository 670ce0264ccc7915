"""Task: selected world coordinates of a frame origin (e.g. the TCP's x and z for a planar arm)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from ...model import RobotModel
from ..exceptions import ControllerError

__all__ = ["FramePositionTask"]

_AXES = {"x": 0, "y": 1, "z": 2}


class FramePositionTask:
    """``w(q)`` = the chosen world coordinates of a frame origin [m]; ``J_w`` = the matching rows of ``J_T``.

    Args:
        frame: frame name in the model (an MJCF site, body or joint).
        axes: which world coordinates, as a string such as ``"xz"`` or indices; default all three.
    """

    def __init__(self, frame: str, axes: str | Sequence[int] = "xyz") -> None:
        if isinstance(axes, str):
            unknown = set(axes) - set(_AXES)
            if unknown or not axes:
                raise ControllerError(f"axes must be letters from 'xyz', got {axes!r}")
            rows = [_AXES[a] for a in axes]
        else:
            rows = [int(a) for a in axes]
            if not rows or any(r not in (0, 1, 2) for r in rows):
                raise ControllerError(f"axis indices must be in 0, 1, 2, got {list(axes)!r}")
        if len(set(rows)) != len(rows):
            raise ControllerError(f"axes must not repeat, got {axes!r}")
        self.frame = frame
        self.rows = np.array(rows, dtype=np.intp)
        self.dim = len(rows)

    def value(self, model: RobotModel) -> NDArray[np.float64]:
        """Selected coordinates of the frame origin [m]."""
        return model.frame_position(self.frame)[self.rows]

    def error(self, model: RobotModel, target: NDArray[np.float64]) -> NDArray[np.float64]:
        """``w_d - w(q)`` [m]."""
        target = np.asarray(target, dtype=np.float64)
        if target.shape != (self.dim,):
            raise ControllerError(f"target must have shape ({self.dim},), got {target.shape}")
        return target - self.value(model)

    def jacobian(self, model: RobotModel) -> NDArray[np.float64]:
        """Rows of the world-aligned translational Jacobian (dim x nv)."""
        return model.frame_jacobian(self.frame, "translational")[self.rows]

    def drift(self, model: RobotModel, q: NDArray[np.float64], qdot: NDArray[np.float64]) -> NDArray[np.float64]:
        """``Jdot_w qdot`` [m/s^2] of (5.18); leaves the model updated at ``q``."""
        return model.frame_jacobian_derivative_times_velocity(q, qdot, self.frame, "translational")[self.rows]

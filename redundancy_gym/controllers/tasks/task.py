"""The interface shared by tasks ``w(q)``: a value, an error against a target and a Jacobian."""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from ...model import RobotModel

__all__ = ["Task"]


@runtime_checkable
class Task(Protocol):
    """A task-space coordinate ``w(q)`` of dimension ``dim`` with Jacobian ``J_w = dw/dq`` (5.3).

    Methods are called after ``model.update(q)``.
    """

    dim: int

    def value(self, model: RobotModel) -> NDArray[np.float64]:
        """``w(q)``."""
        ...

    def error(self, model: RobotModel, target: NDArray[np.float64]) -> NDArray[np.float64]:
        """``e_w = w_d - w(q)`` (5.5)."""
        ...

    def jacobian(self, model: RobotModel) -> NDArray[np.float64]:
        """``J_w`` (dim x nv)."""
        ...

"""Lifts an objective on the actuated joints to the full configuration of a floating-base model."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ...model import RobotModel
from .objective import Objective, ObjectiveValue

__all__ = ["ActuatedObjective"]


class ActuatedObjective:
    """``H(q) = H_a(q_a)`` where ``q_a`` are the joint coordinates after the base's (the base is left free).

    The gradient has zeros on the base velocities, so (5.14) never pushes the base itself. With a fixed-base
    model the objective passes through unchanged.

    Args:
        objective: an objective on the actuated joints (e.g. :class:`JointLimitObjective`, :class:`PostureObjective`).
        model: the model whose base coordinates are skipped.
    """

    def __init__(self, objective: Objective, model: RobotModel) -> None:
        self.objective = objective
        self._nq, self._nv = model.base_dofs

    def evaluate(self, model: RobotModel, q: NDArray[np.float64]) -> ObjectiveValue:
        """Value and gradient (length nv) at the full configuration ``q``."""
        value, gradient = self.objective.evaluate(model, np.asarray(q, dtype=np.float64)[self._nq :])
        return ObjectiveValue(value, np.concatenate([np.zeros(self._nv), gradient]))

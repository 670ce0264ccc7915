"""The interface shared by nullspace objectives ``H(q)`` of (5.7): a value and its gradient."""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from ...model import RobotModel

__all__ = ["Objective", "ObjectiveValue", "sum_objectives"]


class ObjectiveValue(NamedTuple):
    """``H(q)`` and ``(dH/dq)^T`` (length nv)."""

    value: float
    gradient: NDArray[np.float64]


@runtime_checkable
class Objective(Protocol):
    """A scalar cost ``H(q)`` minimised in the nullspace of the task (5.7), (5.14).

    ``evaluate`` is called after ``model.update(q)``, so objectives that need frames or Jacobians read them
    from the model's cache.
    """

    def evaluate(self, model: RobotModel, q: NDArray[np.float64]) -> ObjectiveValue:
        """Value and gradient at ``q``."""
        ...


def sum_objectives(objectives: Sequence[Objective], model: RobotModel, q: NDArray[np.float64]) -> ObjectiveValue:
    """``H = sum H_i`` and its gradient (zeros when there are no objectives)."""
    value = 0.0
    gradient = np.zeros(model.nv)
    for objective in objectives:
        v, g = objective.evaluate(model, q)
        value += v
        gradient += g
    return ObjectiveValue(value, gradient)

"""Posture objective: a quadratic pull towards a preferred configuration."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...model import RobotModel
from ..exceptions import ControllerError
from .objective import ObjectiveValue

__all__ = ["PostureObjective"]


class PostureObjective:
    """``H = 1/2 (q - q_ref)^T diag(weights) (q - q_ref)``; gradient ``diag(weights) (q - q_ref)``.

    Args:
        reference: preferred configuration ``q_ref`` [rad or m].
        weights: per-joint weights (scalar or length nq), >= 0.
    """

    def __init__(self, reference: ArrayLike, weights: ArrayLike | float = 1.0) -> None:
        self.reference = np.asarray(reference, dtype=np.float64).copy()
        if self.reference.ndim != 1 or not np.all(np.isfinite(self.reference)):
            raise ControllerError("reference must be a finite 1-D configuration")
        self.weights = np.broadcast_to(np.asarray(weights, dtype=np.float64), self.reference.shape).copy()
        if np.any(self.weights < 0.0) or not np.all(np.isfinite(self.weights)):
            raise ControllerError("weights must be finite and >= 0")

    def evaluate(self, model: RobotModel | None, q: NDArray[np.float64]) -> ObjectiveValue:
        """Value and gradient at ``q`` (the model is not needed and may be ``None``)."""
        delta = np.asarray(q, dtype=np.float64) - self.reference
        if delta.shape != self.reference.shape:
            raise ControllerError(f"q must have shape {self.reference.shape}, got {delta.shape}")
        gradient = self.weights * delta
        return ObjectiveValue(0.5 * float(delta @ gradient), gradient)

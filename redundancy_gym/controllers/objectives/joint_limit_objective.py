"""Joint-limit avoidance: the C2 potential ``H_c23`` (5.58) on the distance of each joint to each of its limits."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...geometry import PiecewisePotential
from ...model import RobotModel
from ..exceptions import ControllerError
from .objective import ObjectiveValue

__all__ = ["JointLimitObjective"]


class JointLimitObjective:
    """``H = weight * sum_i [H_c23(q_i - q_min,i) + H_c23(q_max,i - q)]`` (5.58), gradient from (5.59).

    The monograph (5.3) pairs collision avoidance with "potentials similar to the one described above, when d
    is taken as the distance to a joint limit"; this is that potential. It is zero while every joint is more
    than ``activation_distance`` from its limits.

    Args:
        lower: lower limits [rad or m] (length nq).
        upper: upper limits [rad or m].
        activation_distance: ``d_a`` [rad or m], > 0.
        slope: ``|H'(0)|`` of the potential at the limit, > 0.
        switch_ratio: ``t`` of (5.58), in (0, 1).
        weight: scale of the whole objective, >= 0.
    """

    def __init__(
        self,
        lower: ArrayLike,
        upper: ArrayLike,
        *,
        activation_distance: float = 0.35,
        slope: float = 1.0,
        switch_ratio: float = 0.5,
        weight: float = 1.0,
    ) -> None:
        self.lower = np.asarray(lower, dtype=np.float64).copy()
        self.upper = np.asarray(upper, dtype=np.float64).copy()
        if self.lower.shape != self.upper.shape or self.lower.ndim != 1:
            raise ControllerError(
                f"lower and upper must be 1-D of equal length, got {self.lower.shape}, {self.upper.shape}"
            )
        if np.any(self.lower >= self.upper):
            raise ControllerError("every lower limit must be below its upper limit")
        if not np.isfinite(weight) or weight < 0.0:
            raise ControllerError(f"weight must be finite and >= 0, got {weight!r}")
        self.weight = float(weight)
        self.potential = PiecewisePotential(activation_distance, slope, switch_ratio)

    @classmethod
    def from_model(cls, model: RobotModel, **kwargs: float) -> JointLimitObjective:
        """Use the model's joint limits."""
        return cls(model.lower_limits, model.upper_limits, **kwargs)

    def margins(self, q: ArrayLike) -> NDArray[np.float64]:
        """Distance of each joint to its nearer limit [rad or m] (negative outside the range)."""
        q = np.asarray(q, dtype=np.float64)
        return np.minimum(q - self.lower, self.upper - q)

    def evaluate(self, model: RobotModel | None, q: NDArray[np.float64]) -> ObjectiveValue:
        """Value and gradient at ``q`` (the model is not needed and may be ``None``)."""
        q = np.asarray(q, dtype=np.float64)
        if q.shape != self.lower.shape:
            raise ControllerError(f"q must have shape {self.lower.shape}, got {q.shape}")
        n = q.size
        both = self.potential.evaluate(np.concatenate([q - self.lower, self.upper - q]))
        value = self.weight * float(both.value.sum())
        gradient = self.weight * (both.slope[:n] - both.slope[n:])
        return ObjectiveValue(value, gradient)

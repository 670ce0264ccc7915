"""Nullspace collision avoidance (monograph 5.3, (5.49)-(5.61)): ``H_c = sum_i H_c23(d_i)``."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ...geometry import CollisionModel, CollisionState, PiecewisePotential
from ...model import RobotModel
from ..exceptions import ControllerError
from .objective import ObjectiveValue

__all__ = ["CollisionObjective"]


class CollisionObjective:
    """``H = weight * sum_i H_c23(d_i)`` over the collision pairs (5.49), gradient ``H'(d_i) dd_i/dq`` (5.60),
    (5.61).

    Only pairs closer than the activation distance contribute, so the Jacobians of the witness points are
    formed for those pairs alone. The last :class:`CollisionState` is kept in :attr:`last_state` (the
    clearance the controller saw).

    Args:
        collision_model: the segments and pairs.
        activation_distance: ``d_a`` [m], > 0.
        slope: ``|H'(0)|`` [1/m], > 0.
        switch_ratio: ``t`` of (5.58), in (0, 1).
        weight: scale of the objective, >= 0.
    """

    def __init__(
        self,
        collision_model: CollisionModel,
        *,
        activation_distance: float = 0.1,
        slope: float = 1.0,
        switch_ratio: float = 0.5,
        weight: float = 1.0,
    ) -> None:
        if not isinstance(collision_model, CollisionModel):
            raise ControllerError(f"collision_model must be a CollisionModel, got {type(collision_model).__name__}")
        if not np.isfinite(weight) or weight < 0.0:
            raise ControllerError(f"weight must be finite and >= 0, got {weight!r}")
        self.collision_model = collision_model
        self.potential = PiecewisePotential(activation_distance, slope, switch_ratio)
        self.weight = float(weight)
        self.last_state: CollisionState | None = None

    def evaluate(self, model: RobotModel, q: NDArray[np.float64]) -> ObjectiveValue:
        """Value and gradient at ``q`` (``model`` must have been updated to ``q``)."""
        state = self.collision_model.evaluate(model)
        self.last_state = state
        gradient = np.zeros(model.nv)
        near = np.flatnonzero(state.distance < self.potential.activation_distance)
        if near.size == 0:
            return ObjectiveValue(0.0, gradient)
        pot = self.potential.evaluate(state.distance[near])
        jac = self.collision_model.distance_gradient(model, state, near)
        gradient = self.weight * (pot.slope @ jac)
        return ObjectiveValue(self.weight * float(pot.value.sum()), gradient)

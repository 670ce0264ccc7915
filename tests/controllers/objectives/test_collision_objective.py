"""Nullspace collision avoidance (5.49)-(5.61): gradient, activation, and PlanarReach solved without collision."""

from __future__ import annotations

import numpy as np
import pytest

from redundancy_gym.controllers import CollisionObjective, ControllerError
from redundancy_gym.geometry import PSS, Segment
from redundancy_gym.model import RobotModel, collision_model_from_mjcf


def test_gradient_matches_finite_differences(planar_model: RobotModel, rng: np.random.Generator) -> None:
    model = collision_model_from_mjcf(planar_model, [Segment("obstacle", (PSS([0.55, 0.0, -0.2], 0.1),))])
    objective = CollisionObjective(model, activation_distance=0.4, slope=3.0)
    h = 1e-7
    active = 0
    for _ in range(30):
        q = rng.uniform(0.8 * planar_model.lower_limits, 0.8 * planar_model.upper_limits)
        planar_model.update(q)
        value, grad = objective.evaluate(planar_model, q)
        if value == 0.0 or np.any(objective.last_state.distance < 0.01):
            continue
        active += 1
        fd = np.zeros(planar_model.nv)
        for k in range(planar_model.nv):
            dq = np.zeros(planar_model.nv)
            dq[k] = h
            planar_model.update(q + dq)
            plus = objective.evaluate(planar_model, q + dq).value
            planar_model.update(q - dq)
            minus = objective.evaluate(planar_model, q - dq).value
            fd[k] = (plus - minus) / (2 * h)
        np.testing.assert_allclose(grad, fd, atol=1e-5)
    assert active >= 5


def test_inactive_far_from_obstacles(planar_model: RobotModel) -> None:
    model = collision_model_from_mjcf(
        planar_model, [Segment("obstacle", (PSS([5.0, 0.0, 0.0], 0.1),))], self_collision=False
    )
    objective = CollisionObjective(model, activation_distance=0.1)
    q = np.zeros(planar_model.nv)
    planar_model.update(q)
    value, grad = objective.evaluate(planar_model, q)
    assert value == 0.0 and not np.any(grad)


def test_rejects_bad_arguments(planar_model: RobotModel) -> None:
    with pytest.raises(ControllerError, match="CollisionModel"):
        CollisionObjective("not a model")  # type: ignore[arg-type]
    with pytest.raises(ControllerError, match="weight"):
        CollisionObjective(collision_model_from_mjcf(planar_model), weight=-1.0)


def test_planar_reach_with_obstacle_is_solved_without_collision() -> None:
    """Plain CLIK hits the obstacle; with the collision objective (default when the obstacle is on) it passes."""
    from redundancy_gym.eval.evaluate import evaluate

    env_id = "redundancy_gym/PlanarReach-v0"
    plain = evaluate(
        env_id, "clik", episodes=2, seed=0, policy_kwargs={"collision_avoidance": "off"}, progress=False
    ).to_json()
    avoid = evaluate(env_id, "clik", episodes=3, seed=0, progress=False).to_json()
    assert plain["collision_rate"] == 1.0
    assert avoid["collision_rate"] == 0.0 and avoid["success_rate"] == 1.0
    assert avoid["min_clearance"] > 0.005

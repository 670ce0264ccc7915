"""NullspaceAction: the learner's u moves only the nullspace; u = 0 is the bare tracker, the reference's
objectives as u avoid the obstacle."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import redundancy_gym  # noqa: F401  (registers the ids)
from redundancy_gym.wrappers import NullspaceAction, WrapperError

PLANAR = "redundancy_gym/PlanarReach-Nullspace-v0"


def _episode(env: gym.Env, seed: int, actions: np.random.Generator | None = None) -> dict:
    env.reset(seed=seed)
    shape = env.action_space.shape
    assert shape is not None
    while True:
        a = np.zeros(shape) if actions is None else actions.uniform(-1, 1, shape)
        _, _, terminated, truncated, info = env.step(a.astype(np.float32))
        if terminated or truncated:
            return info


def test_u_zero_collides_and_the_reference_objectives_avoid_the_obstacle() -> None:
    bare = _episode(gym.make(PLANAR), seed=5)
    assert bare["collision"] and not bare["is_success"]
    with_objectives = _episode(gym.make(PLANAR, objectives=True), seed=5)
    assert not with_objectives["collision"] and with_objectives["is_success"]


@pytest.mark.parametrize("seed", [301, 302, 303, 304])
def test_random_bounded_u_keeps_the_tracking_within_the_success_tolerance(seed: int) -> None:
    env = gym.make(PLANAR, obstacle=False)
    info = _episode(env, seed, np.random.default_rng(seed))
    assert info["line_finished"] and info["max_tracking_error"] <= 1e-3  # the env's success_tolerance
    assert info["is_success"]


def test_u_changes_the_joint_motion_but_not_the_task_velocity() -> None:
    env = gym.make(PLANAR, obstacle=False)
    env.reset(seed=0)
    inner = env
    while not isinstance(inner, NullspaceAction):
        inner = inner.env
    u = np.array([0.3, -0.2, 0.1, 0.25])
    plain, _ = inner.command(np.zeros(4))
    moved, fraction = inner.command(u)
    assert fraction == 1.0
    model = inner.reference.model
    assert inner._obs is not None
    model.update(inner._obs[:4])  # OBSERVATION_LAYOUT["q"]
    jacobian = inner.reference.controller.clik.task.jacobian(model)
    assert np.abs(moved.qdot - plain.qdot).max() > 0.05
    assert np.abs(jacobian @ (moved.qdot - plain.qdot)).max() < 1e-9


def test_bad_options_raise_naming_them() -> None:
    env = gym.make("redundancy_gym/PlanarReach-v0")
    with pytest.raises(WrapperError, match="max_nullspace_speed"):
        NullspaceAction(env, max_nullspace_speed=2.0)
    not_a_bool: Any = "yes"
    with pytest.raises(WrapperError, match="objectives"):
        NullspaceAction(env, objectives=not_a_bool)

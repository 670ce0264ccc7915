"""Every action wrapper times its controller per step (its controller_time_us attribute), and eval counts it as the
policy's: a wrapped learner's step time is the whole policy's. info stays deterministic (check_env compares it)."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import redundancy_gym  # noqa: F401  (registers the env ids)
from redundancy_gym.eval.evaluate import run_episode
from redundancy_gym.policies import make_policy
from redundancy_gym.registration import WRAPPED_ENV_IDS
from redundancy_gym.wrappers.action_check import CONTROLLER_TIME_ATTRIBUTE


@pytest.mark.parametrize("env_id", WRAPPED_ENV_IDS)
def test_each_wrapped_step_times_its_controller_outside_info(env_id: str) -> None:
    env = gym.make(env_id)
    try:
        env.reset(seed=0)
        for _ in range(5):
            _, _, terminated, truncated, info = env.step(np.zeros(env.action_space.shape, dtype=np.float32))
            elapsed = env.get_wrapper_attr(CONTROLLER_TIME_ATTRIBUTE)
            assert math.isfinite(elapsed) and elapsed > 0.0
            assert CONTROLLER_TIME_ATTRIBUTE not in info
            assert not (terminated or truncated)
    finally:
        env.close()


class _SlowController(gym.Wrapper):
    """Claims a controller that took one second per step, without taking it."""

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        self.controller_time_us = 0.0

    def step(self, action):
        self.controller_time_us = 1e6
        return self.env.step(action)


def test_eval_adds_the_wrappers_controller_time_to_the_policys() -> None:
    env = _SlowController(gym.make("redundancy_gym/PlanarReach-v0", max_episode_steps=20))
    _, plain = run_episode(env.env, make_policy("zero", env.env), 0)
    _, wrapped = run_episode(env, make_policy("zero", env), 0)
    assert np.all(plain.step_time_us < 1e5)
    assert np.all(wrapped.step_time_us >= 1e6) and np.all(wrapped.step_time_us < 1e6 + 1e5)

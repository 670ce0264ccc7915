"""ResidualAction: a = 0 is the reference policy, bit for bit; the residual is bounded and observed."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import redundancy_gym
from redundancy_gym.policies import make_policy
from redundancy_gym.wrappers import ResidualAction, WrapperActionError, WrapperError

CASES = [
    ("redundancy_gym/PlanarReach-v0", "clik", {}),
    ("redundancy_gym/AgriReach-v0", "clik", {}),
    ("redundancy_gym/BipedWalk-v0", "walking", {"max_episode_steps": 1000}),
]


def _reference_episode(env_id: str, policy: str, make_kwargs: dict, seed: int) -> tuple[list, list]:
    env = gym.make(env_id, **make_kwargs)
    pi = make_policy(policy, env)
    obs, _ = env.reset(seed=seed)
    actions, rewards = [], []
    while True:
        action, _ = pi.predict(obs)
        obs, reward, terminated, truncated, _ = env.step(action)
        actions.append(action)
        rewards.append(reward)
        if terminated or truncated:
            return actions, rewards


@pytest.mark.parametrize(
    "env_id, policy, make_kwargs", CASES, ids=lambda v: v.split("/")[-1] if isinstance(v, str) else ""
)
def test_zero_residual_is_the_reference_policy_bitwise(env_id: str, policy: str, make_kwargs: dict) -> None:
    wrapped_id = env_id.replace("-v0", "-Residual-v0")
    expected_actions, expected_rewards = _reference_episode(env_id, policy, make_kwargs, seed=11)
    env = gym.make(wrapped_id, **make_kwargs)
    env.reset(seed=11)
    assert env.action_space.shape is not None
    zero = np.zeros(env.action_space.shape, dtype=np.float32)
    actions, rewards = [], []
    while True:
        _, reward, terminated, truncated, info = env.step(zero)
        actions.append(info["reference_action"])
        rewards.append(reward)
        if terminated or truncated:
            break
    assert len(actions) == len(expected_actions) > 50
    for got, want in zip(actions, expected_actions, strict=True):
        assert np.array_equal(got, want)
    assert rewards == expected_rewards


def test_residual_moves_the_applied_action_by_scale_and_is_clipped() -> None:
    env = gym.make("redundancy_gym/PlanarReach-Residual-v0", scale=0.25)
    env.reset(seed=0)
    _, _, _, _, info = env.step(np.ones(4, dtype=np.float32))
    reference = info["reference_action"]
    applied = reference + info["residual_action"]
    assert np.allclose(applied, np.clip(reference + 0.25, -1.0, 1.0), atol=1e-6)


def test_observe_reference_appends_the_reference_action() -> None:
    env = gym.make("redundancy_gym/PlanarReach-Residual-v0", observe_reference=True)
    base = gym.make("redundancy_gym/PlanarReach-v0")
    obs, _ = env.reset(seed=3)
    raw, _ = base.reset(seed=3)
    assert obs.shape == (raw.size + 4,) and env.observation_space.contains(obs)
    expected, _ = make_policy("clik", base).predict(raw)
    assert np.array_equal(obs[raw.size :], expected.astype(obs.dtype))


def test_bad_options_and_actions_raise_naming_them() -> None:
    env = gym.make("redundancy_gym/PlanarReach-v0")
    with pytest.raises(WrapperError, match="scale"):
        ResidualAction(env, scale=0.0)
    with pytest.raises(WrapperError, match="walking"):
        ResidualAction(env, policy="walking")
    not_a_dict: Any = [1, 2]
    with pytest.raises(WrapperError, match="policy_kwargs must be a dict"):  # found by tests/fuzz
        ResidualAction(env, policy_kwargs=not_a_dict)
    wrapped = ResidualAction(env)
    with pytest.raises(WrapperError, match="reset"):
        wrapped.step(np.zeros(4))
    wrapped.reset(seed=0)
    with pytest.raises(WrapperActionError, match="finite"):
        wrapped.step(np.array([0.0, np.nan, 0.0, 0.0]))
    assert redundancy_gym  # the ids are registered on import

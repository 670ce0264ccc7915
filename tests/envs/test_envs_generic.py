"""Checks every registered env must pass: the raw envs and the wrapped ones (``<Env>-<Wrapper>-v0``)."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env

import redundancy_gym
from redundancy_gym.envs import EnvConfigError, InvalidActionError

ENV_IDS = redundancy_gym.ENV_IDS
_MAKE_WRAPPERS = (gym.wrappers.TimeLimit, gym.wrappers.OrderEnforcing, gym.wrappers.PassiveEnvChecker)


def _checked(env: gym.Env) -> gym.Env:
    """The env under gymnasium's ``make`` wrappers: the raw env, or the action wrapper of a wrapped id."""
    while isinstance(env, _MAKE_WRAPPERS):
        env = env.env
    return env


def _action_shape(env: gym.Env) -> tuple[int, ...]:
    """The shape of the env's ``Box`` action space (every env and wrapped env has one)."""
    assert isinstance(env.action_space, gym.spaces.Box), env.action_space
    return env.action_space.shape


def _rollout(env: gym.Env, seed: int, steps: int) -> tuple[list[np.ndarray], list[float], list[dict[str, Any]]]:
    rng = np.random.default_rng(seed)
    obs, info = env.reset(seed=seed)
    observations: list[np.ndarray] = [obs]
    rewards: list[float] = []
    infos = [info]
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(rng.uniform(-1, 1, _action_shape(env)))
        observations.append(obs)
        rewards.append(float(reward))
        infos.append(info)
        if terminated or truncated:
            break
    return observations, rewards, infos


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_gymnasium_check_env(env_id: str) -> None:
    env = gym.make(env_id)
    gym_check_env(_checked(env), skip_render_check=True)
    env.close()


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_sb3_check_env(env_id: str) -> None:
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    env = gym.make(env_id)
    sb3_check_env(env, warn=True)
    env.close()


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_randomized_plant_passes_check_env(env_id: str) -> None:
    """The same checks on a plant drawn by the dynamics randomization (level 0.2, two periods of latency)."""
    env = gym.make(env_id, dynamics=0.2)
    gym_check_env(_checked(env), skip_render_check=True)
    env.close()


@pytest.mark.parametrize("env_id", ENV_IDS)
@pytest.mark.parametrize("dynamics", [None, 0.2])
def test_same_seed_same_episode(env_id: str, dynamics: float | None) -> None:
    a = _rollout(gym.make(env_id, dynamics=dynamics), seed=7, steps=60)
    b = _rollout(gym.make(env_id, dynamics=dynamics), seed=7, steps=60)
    assert all(np.all(np.isfinite(o)) for o in a[0]) and all(np.isfinite(a[1]))
    assert len(a[0]) == len(b[0])
    for x, y in zip(a[0], b[0], strict=True):
        assert np.array_equal(x, y)
    assert a[1] == b[1]
    c = _rollout(gym.make(env_id, dynamics=dynamics), seed=8, steps=5)
    assert not np.array_equal(a[0][0], c[0][0])  # the seed matters


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_reward_is_sum_of_terms_and_finite(env_id: str) -> None:
    observations, rewards, infos = _rollout(gym.make(env_id), seed=3, steps=100)
    for obs in observations:
        assert np.all(np.isfinite(obs))
    for reward, info in zip(rewards, infos[1:], strict=True):
        terms = [v for k, v in info.items() if k.startswith("reward_")]
        assert terms and reward == pytest.approx(sum(terms), abs=1e-12)
        assert np.isfinite(reward)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_non_finite_or_misshaped_actions_raise(env_id: str) -> None:
    env = gym.make(env_id)
    env.reset(seed=0)
    shape = _action_shape(env)
    bad = np.zeros(shape)
    bad[0] = np.nan
    with pytest.raises(InvalidActionError):
        env.step(bad)
    with pytest.raises(InvalidActionError):
        env.step(np.zeros(shape[0] + 1))


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_unknown_kwarg_names_valid_ones(env_id: str) -> None:
    with pytest.raises(EnvConfigError, match="valid"):
        gym.make(env_id, not_an_option=1)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_rgb_render_headless(env_id: str) -> None:
    env = gym.make(env_id, render_mode="rgb_array", width=64, height=48)
    env.reset(seed=0)
    frame = env.render()
    assert frame.shape == (48, 64, 3) and frame.dtype == np.uint8 and frame.std() > 0
    env.close()

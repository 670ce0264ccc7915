"""Every env and wrapped env runs in Gymnasium's vector envs (sync and async) and in SB3's SubprocVecEnv; the async
envs step exactly as the sync ones."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import redundancy_gym  # noqa: F401  (registers the env ids)
from redundancy_gym.registration import ENV_IDS


def _rollout(env_id: str, mode: str, steps: int = 3) -> list[np.ndarray]:
    envs = gym.make_vec(env_id, num_envs=2, vectorization_mode=mode)
    try:
        obs, _ = envs.reset(seed=11)  # the sub-envs get seeds 11 and 12
        space = envs.single_observation_space
        assert isinstance(space, gym.spaces.Box)
        envs.action_space.seed(5)
        out = [obs]
        for _ in range(steps):
            obs, reward, terminated, truncated, _ = envs.step(envs.action_space.sample())
            assert obs.shape == (2, *space.shape) and np.all(np.isfinite(obs))
            assert reward.shape == (2,) and np.all(np.isfinite(reward))
            out.append(obs)
        return out
    finally:
        envs.close()


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_sync_vector_env_steps(env_id: str) -> None:
    _rollout(env_id, "sync")


@pytest.mark.parametrize(
    "env_id",
    [
        "redundancy_gym/PlanarReach-v0",
        "redundancy_gym/AgriReach-Nullspace-v0",
        "redundancy_gym/BipedWalk-WalkingCommand-v0",
    ],
)
def test_async_steps_as_sync(env_id: str) -> None:
    for a, b in zip(_rollout(env_id, "sync"), _rollout(env_id, "async"), strict=True):
        np.testing.assert_array_equal(a, b)


def test_sb3_subproc_vec_env_on_a_wrapped_id() -> None:
    pytest.importorskip("stable_baselines3")
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import SubprocVecEnv

    # SB3 starts its workers with forkserver: "module:id" makes gym.make import the package (and register the ids)
    # in each worker
    envs = make_vec_env(
        "redundancy_gym:redundancy_gym/PlanarReach-Residual-v0", n_envs=2, seed=0, vec_env_cls=SubprocVecEnv
    )
    try:
        envs.reset()
        obs, reward, done, info = envs.step(np.zeros((2, 4), dtype=np.float32))
        assert obs.shape == (2, 20) and np.all(np.isfinite(reward)) and len(info) == 2
    finally:
        envs.close()

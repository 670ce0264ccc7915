import warnings

import gymnasium as gym
import numpy as np
import pytest

from redundancy_gym.envs import EnvConfigError, PlanarReachEnv
from redundancy_gym.envs.planar_reach import default_config

ENV_ID = "redundancy_gym/PlanarReach-v0"


def test_start_on_line_with_varied_posture() -> None:
    env = gym.make(ENV_ID)
    layout = PlanarReachEnv.OBSERVATION_LAYOUT
    postures = []
    for seed in range(5):
        obs, info = env.reset(seed=seed)
        assert np.allclose(obs[layout["tcp"]], default_config()["line_start"], atol=1e-9)
        assert info["tracking_error"] < 1e-9 and not info["goal_reached"]
        assert np.all(obs[layout["qdot"]] == 0)
        postures.append(obs[layout["q"]])
    assert np.ptp(np.array(postures), axis=0).max() > 0.01  # the redundant posture varies with the seed


def test_reference_is_rest_to_rest_quintic() -> None:
    env = PlanarReachEnv(duration=2.0)
    start, end = np.array(default_config()["line_start"]), np.array(default_config()["line_end"])
    p0, v0, s0 = env.reference(0.0)
    p1, v1, s1 = env.reference(2.0)
    pm, vm, _ = env.reference(1.0)
    assert np.allclose(p0, start) and np.allclose(p1, end) and np.allclose(v0, 0) and np.allclose(v1, 0)
    assert s0 == 0.0 and s1 == 1.0
    assert np.allclose(pm, (start + end) / 2) and np.allclose(vm, 1.875 * (end - start) / 2.0)
    h = 1e-6
    fd = (env.reference(0.7 + h)[0] - env.reference(0.7 - h)[0]) / (2 * h)
    assert np.allclose(env.reference(0.7)[1], fd, atol=1e-6)


def test_zero_action_holds_posture_and_accumulates_error() -> None:
    env = gym.make(ENV_ID, obstacle=False)
    obs0, _ = env.reset(seed=0)
    for _ in range(100):
        obs, reward, terminated, truncated, info = env.step(np.zeros(4))
    assert np.allclose(obs[:4], obs0[:4], atol=1e-3)  # gravity compensated, servo holds
    assert info["min_clearance"] == float("inf") and not info["collision"]
    assert info["tracking_error"] > 0.1 and not info["is_success"]
    assert info["goal_error"] == pytest.approx(
        np.linalg.norm(np.subtract(default_config()["line_end"], default_config()["line_start"])), abs=2e-3
    )


def test_collision_terminates() -> None:
    """An obstacle centred on the line: the TCP link runs into it."""
    env = gym.make(ENV_ID, obstacle_center=(0.9, 0.2), obstacle_radius=0.05)
    from redundancy_gym import make_policy

    policy = make_policy("clik", env)
    obs, info = env.reset(seed=0)
    assert info["min_clearance"] > 0
    for _ in range(250):
        obs, reward, terminated, truncated, info = env.step(policy.predict(obs)[0])
        if terminated or truncated:
            break
    assert terminated and info["collision"] and info["min_clearance"] <= 0.0
    assert info["reward_collision"] == -default_config()["collision_penalty"]
    assert not info["is_success"]


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(duration=0.0), "duration"),
        (dict(line_start=(1.5, 0.5)), "reach"),
        (dict(obstacle_radius=-1), "radius"),
        (dict(line_end=(0.9,)), "line_end"),
        (dict(frame_skip=0), "frame_skip"),
        (dict(initial_configuration=(0, 0, 0)), "initial_configuration"),
    ],
)
def test_invalid_kwargs(kwargs: dict, match: str) -> None:
    with pytest.raises(EnvConfigError, match=match):
        gym.make(ENV_ID, **kwargs)


def test_a_task_longer_than_the_time_limit_warns_at_reset() -> None:
    env = gym.make(ENV_ID, duration=3.0)  # 3 s line, registered limit 250 steps = 2.5 s
    with pytest.warns(UserWarning, match="max_episode_steps=300"):
        env.reset(seed=0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        env.reset(seed=1)  # once per env
        gym.make(ENV_ID, duration=2.4).reset(seed=0)  # fits

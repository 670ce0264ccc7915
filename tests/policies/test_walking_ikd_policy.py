"""The ``walking`` policy with ``ik="ikd"``: the IKD's joint trajectory as the servo targets walks BipedWalk-v0."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import redundancy_gym
from redundancy_gym.controllers.walking import WalkingIkdStep
from redundancy_gym.policies import PolicyError


@pytest.mark.parametrize("speed", [0.5, 0.7])
def test_the_ikd_walker_walks_at_the_commanded_speed_with_its_zmp_realized_in_the_support(speed):
    env = gym.make("redundancy_gym/BipedWalk-v0", target_speed=speed, max_episode_steps=1000)  # 4 s
    policy = redundancy_gym.make_policy("walking", env, ik="ikd")
    obs, _ = env.reset(seed=11)
    start = env.unwrapped.data.qpos[0]
    steps, inside = 0, []
    while True:
        action, _ = policy.predict(obs, episode_start=np.array([steps == 0]))
        step = policy.last_command.ik
        assert isinstance(step, WalkingIkdStep) and step.success
        inside.append(bool(np.all(step.zmp >= step.support[0] - 1e-9) and np.all(step.zmp <= step.support[1] + 1e-9)))
        obs, _, terminated, truncated, info = env.step(action)
        steps += 1
        if terminated or truncated:
            break
    env.close()
    assert steps == 1000 and not info["fell"] and not info["collision"]
    # the start takes 0.4 s of standing, so the mean over 4 s is below the walking speed
    assert (env.unwrapped.data.qpos[0] - start) / 4.0 > 0.75 * speed
    assert all(inside)


def test_an_unknown_ik_is_refused_with_the_choices():
    env = gym.make("redundancy_gym/BipedWalk-v0")
    with pytest.raises(PolicyError, match="clik, ikd"):
        redundancy_gym.make_policy("walking", env, ik="idk")
    env.close()

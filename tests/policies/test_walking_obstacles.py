"""The walking reference on BipedObstacles-v0: it reads the obstacles from the observation, steps over a low beam
in physics without touching it, and needs its SSTA layer to do so."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import redundancy_gym  # noqa: F401 - registers the ids
from redundancy_gym import make_policy
from redundancy_gym.policies.walking_policy import obstacle_volumes

ENV_ID = "redundancy_gym/BipedObstacles-v0"
LOW_BEAM = [{"shape": "box", "center": [1.2, 0.0, 0.04], "size": [0.08, 0.5, 0.08]}]


def walk(policy_kwargs: dict, obstacles: list = LOW_BEAM, seed: int = 0, limit: int = 2500) -> dict:
    env = gym.make(ENV_ID, obstacles=obstacles)
    policy = make_policy("walking", env, **policy_kwargs)
    obs, _ = env.reset(seed=seed)
    contacts = 0
    info: dict[str, Any] = {}
    for _ in range(limit):
        action, _ = policy.predict(obs)
        obs, _, terminated, truncated, info = env.step(action)
        contacts += int(info["obstacle_contact"])
        if terminated or truncated:
            break
    env.close()
    return {**info, "contacts": contacts, "policy": policy}


def test_the_observation_rows_give_back_the_course_volumes():
    env = gym.make(ENV_ID, course="triangle")
    obs, _ = env.reset(seed=0)
    rows = obs[env.unwrapped.OBSERVATION_LAYOUT["obstacles"]]
    assert obstacle_volumes(rows) == list(env.unwrapped.obstacle_volumes)
    assert obstacle_volumes(np.zeros_like(rows)) == []


def test_the_reference_steps_over_a_low_beam_without_touching_it():
    result = walk({})
    assert result["is_success"] and not result["fell"]
    assert result["contacts"] == 0
    pattern = result["policy"].controller.pattern
    kinds = {m.kind for k in range(12) if (m := pattern.swing_modification(k)) is not None}
    assert kinds == {"over"}


@pytest.mark.parametrize("layer", ["ssta"])
def test_without_ssta_the_feet_walk_into_the_beam(layer):
    result = walk({layer: False})
    assert result["contacts"] > 0 or result["fell"]
    assert not result["is_success"]


def test_a_wall_stops_the_walk_and_the_policy_says_why():
    wall = [{"shape": "box", "center": [1.2, 0.0, 0.5], "size": [0.1, 1.5, 1.0]}]
    result = walk({}, obstacles=wall, limit=600)
    reason = result["policy"].stop_reason
    assert reason is not None and reason.startswith("too_large before foothold")
    assert "class too_large" in reason and "> max_step_over_height" in reason
    assert result["contacts"] == 0 and not result["fell"]
    assert walk({}, limit=300)["policy"].stop_reason is None  # the low beam is stepped over

"""The walking reference on BipedTerrain-v0, in the physics: onto and off a low platform, reading the terrain
from the height scan only."""

from __future__ import annotations

import gymnasium as gym
import numpy as np

import redundancy_gym  # noqa: F401 - registers the ids
from redundancy_gym.policies import make_policy


def test_the_walker_steps_onto_and_off_a_low_platform() -> None:
    env = gym.make(
        "redundancy_gym/BipedTerrain-v0",
        segments=[{"kind": "platform", "height": 0.08, "length": 1.0}],
        first_segment_distance=1.0,
    )
    policy = make_policy("walking", env)
    obs, info = env.reset(seed=4100)
    heights, supports = [], []
    for _ in range(3000):
        action, _ = policy.predict(obs)
        obs, _, terminated, truncated, info = env.step(action)
        heights.append(info["terrain_height"])
        supports.append(info["support_fraction"])
        if terminated or truncated:
            break
    assert info["is_success"] and not info["fell"], info
    # every landing on the platform's top or the ground: the last one on the top may overhang its far end by the toe
    # (0.87 here: the search window, 0.25 m back from the nominal foothold, holds no spot with the whole margin)
    assert info["unsupported_steps"] == 0 and info["min_support_fraction"] >= 0.8
    assert max(heights) == np.float64(0.08)  # the pelvis passed over the platform
    assert info["touchdowns"] >= 8
    # the pattern placed footholds on the platform's top (the map read from the scan)
    pattern = policy.controller.pattern
    tops = [float(pattern.foothold(j)[2]) for j in range(2, 12)]
    assert any(abs(z - 0.08) < 1e-9 for z in tops) and tops[-1] == 0.0


def test_sole_tilt_is_on_with_a_height_scan_and_leaves_a_walk_without_rough_footholds_bit_for_bit() -> None:
    env = gym.make(
        "redundancy_gym/BipedTerrain-v0",
        segments=[{"kind": "platform", "height": 0.08, "length": 1.0}],
        first_segment_distance=1.0,
    )
    on, off = make_policy("walking", env), make_policy("walking", env, sole_tilt=False)
    assert on.controller.sole_tilt is not None and off.controller.sole_tilt is None
    assert make_policy("walking", gym.make("redundancy_gym/BipedWalk-v0")).controller.sole_tilt is None
    taken: list[list[bytes]] = []
    for policy in (on, off):
        obs, _ = env.reset(seed=4100)
        actions = []
        for _ in range(1500):  # onto the platform and along it
            action, _ = policy.predict(obs)
            actions.append(action.tobytes())
            obs, _, terminated, truncated, _ = env.step(action)
            if terminated or truncated:
                break
        taken.append(actions)
    assert len(taken[0]) == 1500 and taken[0] == taken[1]

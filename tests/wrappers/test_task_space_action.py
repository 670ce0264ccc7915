"""TaskSpaceAction: the action moves the TCP; avoidance and joint ranges hold whatever the learner commands."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import redundancy_gym  # noqa: F401  (registers the ids)
from redundancy_gym.wrappers import TaskSpaceAction, WrapperError
from redundancy_gym.wrappers.task_space_action import _perpendicular_basis, _tool_axis

AGRI = "redundancy_gym/AgriReach-TaskSpace-v0"


def test_a_constant_action_moves_the_tcp_along_it_at_max_speed() -> None:
    env = gym.make("redundancy_gym/PlanarReach-TaskSpace-v0", obstacle=False, max_speed=0.2)
    obs, _ = env.reset(seed=0)
    start = obs[8:10].copy()  # OBSERVATION_LAYOUT["tcp"]
    for _ in range(30):
        obs, *_ = env.step(np.array([0.0, -1.0], dtype=np.float32))
    moved = obs[8:10] - start
    assert moved[1] == pytest.approx(-0.2 * 0.3, rel=0.15)  # 30 steps of 10 ms at 0.2 m/s, less the start lag
    assert abs(moved[0]) < 0.01


def _agri_episode(seed: int, hold: int) -> tuple[bool, float, float]:
    """(collided, smallest clearance [m], smallest joint-limit margin) of an episode of random actions, each held
    for ``hold`` steps."""
    env = gym.make(AGRI)
    env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    collided, clearance, margin = False, np.inf, np.inf
    k = 0
    while True:
        if k % hold == 0:
            action = rng.uniform(-1, 1, 5).astype(np.float32)
        k += 1
        _, _, terminated, truncated, info = env.step(action)
        collided |= bool(info["collision"])
        clearance = min(clearance, info["min_obstacle_clearance"], info["min_self_clearance"])
        margin = min(margin, info["joint_limit_margin"])
        if terminated or truncated:
            return collided, clearance, margin


@pytest.mark.parametrize("seed", range(4000, 4020))
def test_random_actions_never_collide_nor_leave_the_joint_ranges(seed: int) -> None:
    collided, clearance, margin = _agri_episode(seed, hold=1)
    assert not collided and clearance > 0.0 and margin >= 0.0


@pytest.mark.parametrize("seed", [2001, 2005, 2009])
def test_held_full_speed_commands_stop_short_of_the_plants(seed: int) -> None:
    """Commands held for 0.5 s drive the TCP into stems (seeds that did so with nullspace avoidance alone)."""
    env = gym.make(AGRI)
    env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    k, collided, margin = 0, False, np.inf
    while True:
        if k % 50 == 0:
            action = rng.uniform(-1, 1, 5)
            action[:3] = np.sign(action[:3])
        k += 1
        _, _, terminated, truncated, info = env.step(action.astype(np.float32))
        collided |= bool(info["collision"])
        margin = min(margin, info["joint_limit_margin"])
        if terminated or truncated:
            break
    assert not collided and margin >= 0.0


@pytest.mark.parametrize("difficulty", ["easy", "hard"])
def test_a_proportional_law_on_the_observation_grasps_through_it(difficulty: str) -> None:
    """What a learner must find through this action space: TCP velocity proportional to the grasp point's offset,
    turn rate to the tool axis' error (both from the observation, in the wrapper's basis orthogonal to the axis).
    The wrapper's avoidance keeps it out of the plants, so on these seeds it grasps every time."""
    env = gym.make(AGRI, difficulty=difficulty, observed_obstacles=0)
    layout = env.unwrapped.observation_layout
    successes = 0
    for seed in range(123000, 123006):
        obs, _ = env.reset(seed=seed)
        terminated = truncated = False
        while not (terminated or truncated):
            axis = _tool_axis(obs[layout["tcp_quaternion"]])
            u, v = _perpendicular_basis(axis)
            turn = 3.0 * np.cross(axis, obs[layout["approach"]])  # [rad/s], max_turn_rate 1
            velocity = 4.0 * (obs[layout["grasp_position"]] - obs[layout["tcp_position"]]) / 0.3  # max_speed 0.3
            action = np.clip(np.r_[velocity, turn @ u, turn @ v], -1.0, 1.0)
            obs, _, terminated, truncated, info = env.step(action.astype(np.float32))
        assert not info["collision"]
        successes += bool(info["is_success"])
    assert successes == 6


def test_bad_options_raise_naming_them() -> None:
    env = gym.make("redundancy_gym/AgriReach-v0")
    with pytest.raises(WrapperError, match="max_speed"):
        TaskSpaceAction(env, max_speed=-1.0)
    with pytest.raises(WrapperError, match="stop_distance"):
        TaskSpaceAction(env, guard_distance=0.02, stop_distance=0.03)

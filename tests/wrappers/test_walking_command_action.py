"""WalkingCommandAction: the biped walks at the commanded velocity and turns at the commanded yaw rate, and random
commands do not make it fall."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import redundancy_gym  # noqa: F401  (registers the ids)
from redundancy_gym.wrappers import WalkingCommandAction, WrapperError

ID = "redundancy_gym/BipedWalk-WalkingCommand-v0"


def _walk(env: gym.Env, seed: int, actions) -> tuple[bool, int, np.ndarray]:
    env.reset(seed=seed)
    steps = 0
    while True:
        _, _, terminated, truncated, info = env.step(actions(steps).astype(np.float32))
        steps += 1
        if terminated or truncated:
            return terminated, steps, env.unwrapped.data.qpos[:2].copy()


def _heading(qpos: np.ndarray) -> float:
    """The base's yaw [rad] (MuJoCo quaternion w, x, y, z)."""
    w, x, y, z = qpos[3:7]
    return float(np.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z)))


@pytest.mark.parametrize("speed", [0.5, 0.3])
def test_a_constant_command_walks_ten_seconds_at_that_speed(speed: float) -> None:
    env = gym.make(ID)
    action = np.array([2.0 * (speed - 0.2) / 0.4 - 1.0, 0.0, 0.0])  # default forward range [0.2, 0.6] m/s
    fell, steps, position = _walk(env, 0, lambda k: action)
    assert not fell and steps == 2500
    assert position[0] / 10.0 == pytest.approx(speed, abs=0.05)  # less the standing start and the first step


def test_sideways_commands_walk_sideways() -> None:
    fell, _, position = _walk(gym.make(ID), 0, lambda k: np.array([-1.0, 1.0, 0.0]))
    assert not fell and position[1] > 0.3  # 0.05 m/s to the left for about 9 s


def test_a_yaw_rate_command_turns_the_walker() -> None:
    """0.4 m/s forward at 0.2 rad/s (default bounds: forward 0.2-0.6 m/s, yaw rate +-0.3 rad/s)."""
    env = gym.make(ID)
    env.reset(seed=0)
    action = np.array([0.0, 0.0, 0.2 / 0.3], dtype=np.float32)
    headings = []
    for _ in range(2500):
        _, _, terminated, truncated, info = env.step(action)
        headings.append(_heading(env.unwrapped.data.qpos))
        assert not terminated
    assert truncated and info["commanded_yaw_rate"] == pytest.approx(0.2, rel=1e-6)
    # the first turned foothold is the first landing, after the 0.4 s start; measured 1.82 rad of 1.92
    assert np.unwrap(headings)[-1] == pytest.approx(0.2 * (10.0 - 0.4), abs=0.15)
    x, y = env.unwrapped.data.qpos[:2]
    assert y > 2.0 and np.hypot(x, y) == pytest.approx(2 * 0.4 / 0.2 * np.sin(0.96), abs=0.3)  # the arc's chord


@pytest.mark.parametrize("seed", range(600, 610))
def test_random_commands_changed_every_step_do_not_make_it_fall(seed: int) -> None:
    rng = np.random.default_rng(seed)
    fell, steps, _ = _walk(gym.make(ID), seed, lambda k: rng.uniform(-1, 1, 3))
    assert not fell and steps == 2500


@pytest.mark.parametrize("seed", range(600, 610))
def test_random_commands_held_for_a_step_do_not_make_it_fall(seed: int) -> None:
    rng = np.random.default_rng(seed)
    held: dict[int, np.ndarray] = {}
    fell, steps, _ = _walk(
        gym.make(ID),
        seed,
        lambda k: held[k // 200] if k // 200 in held else held.setdefault(k // 200, rng.uniform(-1, 1, 3)),
    )
    assert not fell and steps == 2500  # 200 periods: 0.8 s


def test_bad_options_raise_naming_them() -> None:
    env = gym.make("redundancy_gym/BipedWalk-v0")
    with pytest.raises(WrapperError, match="max_forward_speed"):
        WalkingCommandAction(env, max_forward_speed=0.9)
    with pytest.raises(WrapperError, match="min_forward_speed"):
        WalkingCommandAction(env, min_forward_speed=0.5, max_forward_speed=0.4)
    with pytest.raises(WrapperError, match="max_yaw_rate"):
        WalkingCommandAction(env, max_yaw_rate=0.6)
    with pytest.raises(WrapperError, match="command_period"):
        WalkingCommandAction(env, command_period=0)


def test_a_held_command_keeps_the_ten_second_episode() -> None:
    env = gym.make(ID, command_period=4)
    env.reset(seed=0)
    steps, total = 0, 0.0
    while True:
        _, reward, terminated, truncated, info = env.step(np.array([0.5, 0.0, 0.0], dtype=np.float32))
        steps += 1
        total += float(reward)
        if terminated or truncated:
            break
    assert truncated and not terminated and steps == 625 and info["time"] == pytest.approx(10.0)


def test_a_held_command_reports_its_periods_together() -> None:
    """With command_period 4, info sums the per-period pseudoenergy and reward terms and keeps the worst peak speed
    and clearance of the four periods: the same numbers as four single-period steps of the same command."""
    action = np.array([0.3, 0.2, -0.1], dtype=np.float32)
    single, held = gym.make(ID), gym.make(ID, command_period=4)
    single.reset(seed=3)
    held.reset(seed=3)
    periods = [single.step(action)[4] for _ in range(8)]
    for k in range(2):
        info = held.step(action)[4]
        part = periods[4 * k : 4 * k + 4]
        assert info["pseudoenergy"] == pytest.approx(sum(p["pseudoenergy"] for p in part), rel=1e-12)
        assert info["reward_speed"] == pytest.approx(sum(p["reward_speed"] for p in part), rel=1e-12)
        assert info["peak_joint_speed"] == max(p["peak_joint_speed"] for p in part)
        assert info["min_self_clearance"] == min(p["min_self_clearance"] for p in part)
        assert info["fell"] is False and info["time"] == part[-1]["time"]
    single.close()
    held.close()

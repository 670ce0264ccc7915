"""BipedWalk-v0: standing statics, the observation layout, the walking policy for a few steps, bad input."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import redundancy_gym  # noqa: F401 - registers the ids
from redundancy_gym import make_policy
from redundancy_gym.envs import EnvConfigError, InvalidActionError
from redundancy_gym.model import RobotModel


def test_standing_zmp_is_under_the_com_and_the_feet_carry_the_weight() -> None:
    env = gym.make("redundancy_gym/BipedWalk-v0")
    env.reset(seed=0)
    for _ in range(1000):  # 4 s: the soft contact settles slowly
        _, _, terminated, _, info = env.step(np.zeros(22))
        assert not terminated
    assert np.allclose(info["zmp"], info["com"][:2], atol=3e-3)  # statics: the ZMP is the CoM's projection
    assert info["normal_force"].sum() == pytest.approx(60.0 * 9.81, rel=0.02)
    assert np.allclose(info["cop"].mean(axis=0), info["zmp"], atol=0.02)
    assert info["min_self_clearance"] > 0.01 and not info["fell"]


def test_observation_holds_mujoco_state_and_the_model_round_trip() -> None:
    env = gym.make("redundancy_gym/BipedWalk-v0")
    obs, _ = env.reset(seed=1)
    base = env.unwrapped
    layout = base.OBSERVATION_LAYOUT
    assert np.allclose(obs[: base.model.nq], base.data.qpos)
    assert np.allclose(obs[layout["command"]], 0.5)
    model = RobotModel.from_mjcf(base.ROBOT_XML)
    base.data.qvel[:] = np.random.default_rng(0).normal(size=base.model.nv)
    q, v = model.from_mujoco_state(base.data.qpos, base.data.qvel)
    assert np.allclose(model.to_mujoco_qpos(q), base.data.qpos)
    # pinocchio's base velocity is in the base frame: the pelvis world velocity must match MuJoCo's
    model.update(q)
    jac = model.frame_jacobian("pelvis_site", "translational")
    assert np.allclose(jac @ v, base.data.qvel[:3], atol=1e-10)


def test_walking_policy_walks_a_few_steps_without_falling() -> None:
    env = gym.make("redundancy_gym/BipedWalk-v0", target_speed=0.5)
    policy = make_policy("walking", env)
    obs, _ = env.reset(seed=0)
    start = True
    for _ in range(int(3.2 / env.unwrapped.dt)):
        action, _ = policy.predict(obs, episode_start=np.array([start]))
        start = False
        obs, _, terminated, _, info = env.step(action)
        assert not terminated, info
    assert info["distance"] > 0.8  # about four steps of 0.4 m after the weight shift
    assert abs(info["com"][1]) < 0.15


def test_bad_arguments_and_actions_raise() -> None:
    with pytest.raises(EnvConfigError, match="valid"):
        gym.make("redundancy_gym/BipedWalk-v0", target_sped=1.0)
    with pytest.raises(EnvConfigError, match="target_speed"):
        gym.make("redundancy_gym/BipedWalk-v0", target_speed=-1.0)
    env = gym.make("redundancy_gym/BipedWalk-v0")
    env.reset(seed=0)
    with pytest.raises(InvalidActionError):
        env.step(np.full(22, np.nan))


def test_an_unloaded_foot_has_a_flagged_finite_centre_of_pressure() -> None:
    """No NaN in info (Gymnasium's check_env compares infos, and NaN never equals itself): an unloaded foot's CoP
    is 0 and ``cop_valid`` says so."""
    env = gym.make("redundancy_gym/BipedWalk-v0")
    policy = make_policy("walking", env)
    obs, _ = env.reset(seed=0)
    unloaded = 0
    for _ in range(500):
        action, _ = policy.predict(obs)
        obs, _, _, _, info = env.step(action)
        assert np.all(np.isfinite(info["cop"])) and np.all(np.isfinite(info["zmp"]))
        unloaded += int(not info["cop_valid"].all())
        assert np.all(info["cop"][~info["cop_valid"]] == 0.0)
        assert info["zmp_valid"]
    assert unloaded > 100  # single supports

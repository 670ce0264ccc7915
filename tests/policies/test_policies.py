import gymnasium as gym
import numpy as np
import pytest

import redundancy_gym
from redundancy_gym.policies import ClikPolicy, Policy, PolicyError

ENV_ID = "redundancy_gym/PlanarReach-v0"


def test_policies_share_the_sb3_signature() -> None:
    env = gym.make(ENV_ID)
    obs, _ = env.reset(seed=0)
    for name in ("clik", "zero", "random"):
        policy = redundancy_gym.make_policy(name, env)
        assert isinstance(policy, Policy)
        action, state = policy.predict(obs, state=None, episode_start=np.array([True]), deterministic=True)
        assert action.shape == env.action_space.shape and env.action_space.contains(action)
        assert state is None


def test_random_policy_is_seeded() -> None:
    env = gym.make(ENV_ID)
    obs, _ = env.reset(seed=0)
    a = [redundancy_gym.make_policy("random", env, seed=3).predict(obs)[0] for _ in range(2)]
    assert np.array_equal(a[0], a[1])
    assert not np.array_equal(a[0], redundancy_gym.make_policy("random", env, seed=4).predict(obs)[0])


def test_clik_policy_tracks_the_line() -> None:
    env = gym.make(ENV_ID, obstacle=False)
    policy = redundancy_gym.make_policy("clik", env)
    assert isinstance(policy, ClikPolicy)
    obs, _ = env.reset(seed=1)
    while True:
        obs, reward, terminated, truncated, info = env.step(policy.predict(obs)[0])
        assert policy.last_result is not None and policy.last_result.success
        if terminated or truncated:
            break
    assert info["is_success"] and info["max_tracking_error"] <= 1e-3


@pytest.mark.parametrize(
    "name, kwargs, match",
    [
        ("nope", {}, "clik, walking, predictive, global, zero, random"),
        ("clik", {"gian": 1}, "valid"),
        ("clik", {"method": "svd"}, "dls"),
        ("zero", {"x": 1}, "no options"),
        ("missing.zip", {}, "not found"),
    ],
)
def test_policy_errors(name: str, kwargs: dict, match: str) -> None:
    with pytest.raises(PolicyError, match=match):
        redundancy_gym.make_policy(name, gym.make(ENV_ID), **kwargs)


def test_clik_policy_rejects_unsupported_env() -> None:
    with pytest.raises(PolicyError, match="lacks"):
        redundancy_gym.make_policy("clik", gym.make("CartPole-v1"))


@pytest.mark.parametrize("env_id", [ENV_ID, "redundancy_gym/AgriReach-v0"])
def test_compiled_and_python_backends_give_the_same_episode(env_id: str) -> None:
    """The default compiled controller and the Python Clik command the same actions along a whole episode."""
    env = gym.make(env_id)
    obs, _ = env.reset(seed=2)
    compiled = redundancy_gym.make_policy("clik", env)
    python = redundancy_gym.make_policy("clik", env, backend="python")
    steps = 0
    while True:
        action = compiled.predict(obs)[0]
        np.testing.assert_allclose(action, python.predict(obs)[0], atol=1e-5)  # float32 actions
        assert compiled.last_result.status == python.last_result.status
        obs, _, terminated, truncated, info = env.step(action)
        steps += 1
        if terminated or truncated:
            break
    assert steps > 50 and info["is_success"]


def test_sb3_model_of_another_env_is_refused_at_load(tmp_path) -> None:
    from stable_baselines3 import PPO

    agri = gym.make("redundancy_gym/AgriReach-v0")
    path = tmp_path / "agri.zip"
    PPO("MlpPolicy", agri, n_steps=64, batch_size=64, device="cpu").save(str(path))
    assert redundancy_gym.make_policy(str(path), agri).predict(agri.reset(seed=0)[0])[0].shape == (9,)
    with pytest.raises(PolicyError, match=r"observation shape \(530,\).*PlanarReach-v0 has \(20,\)"):
        redundancy_gym.make_policy(str(path), gym.make("redundancy_gym/PlanarReach-v0"))


def test_walking_action_is_the_clipped_normalized_joint_targets() -> None:
    """The action is ``clip((targets - nominal) / scale, -1, 1)`` in float32 (NaN passes through, as in np.clip)."""
    env = gym.make("redundancy_gym/BipedWalk-v0")
    policy = redundancy_gym.make_policy("walking", env)
    obs, _ = env.reset(seed=0)
    action, _ = policy.predict(obs, episode_start=np.array([True]))
    command = policy.last_command
    nominal, scale = policy._nominal, policy._scale
    np.testing.assert_array_equal(action, np.clip((command.joint_targets - nominal) / scale, -1, 1).astype(np.float32))
    targets = nominal + scale * np.linspace(-3.0, 3.0, nominal.size)
    targets[0] = np.nan
    policy.controller.step_mujoco = lambda *args: command._replace(joint_targets=targets.copy())
    action = policy.command(obs)
    expected = np.clip((targets - nominal) / scale, -1.0, 1.0).astype(np.float32)
    assert action.dtype == np.float32 and np.isnan(action[0])
    np.testing.assert_array_equal(action, expected)
    assert np.nanmin(action) == -1.0 and np.nanmax(action) == 1.0
    env.close()

"""Hard cases of the environments: episodes of one step, resets mid-episode and without a seed, long horizons with
saturated actions, rendering before the first reset, and a negative zero where a scale >= 0 is asked for.

Each case names the property it protects: the observation is finite and where the robot can be, the episode ends
where the time limit says, and a seed gives the same episode however the env got there.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import redundancy_gym  # noqa: F401 - registers the ids
from redundancy_gym.assets import PLANAR_ARM_XML
from redundancy_gym.model import RobotModel

PLANAR = "redundancy_gym/PlanarReach-v0"
AGRI = "redundancy_gym/AgriReach-v0"
BIPED = "redundancy_gym/BipedWalk-v0"
ENV_IDS = [PLANAR, AGRI, BIPED]
SHORT = {PLANAR: "planar", AGRI: "agri", BIPED: "biped"}


def _box(env: gym.Env) -> gym.spaces.Box:
    """The env's action space, a ``Box`` for every env here."""
    assert isinstance(env.action_space, gym.spaces.Box), env.action_space
    return env.action_space


def _zero(env: gym.Env) -> np.ndarray:
    return np.zeros(_box(env).shape, dtype=_box(env).dtype)


def _finite_step(env: gym.Env, action: np.ndarray) -> tuple:
    obs, reward, terminated, truncated, info = env.step(action)
    assert obs.shape == env.observation_space.shape and np.all(np.isfinite(obs)), obs
    assert np.isfinite(float(reward))
    return obs, reward, terminated, truncated, info


# ------------------------------------------------------------------------------------------ zero-length episodes
@pytest.mark.parametrize("env_id", ENV_IDS, ids=SHORT.get)
def test_max_episode_steps_one_truncates_at_the_first_step(env_id: str) -> None:
    env = gym.make(env_id, max_episode_steps=1)
    try:
        for seed in (0, 1):  # and again after a reset: the limit counts per episode
            env.reset(seed=seed)
            _, _, terminated, truncated, _ = _finite_step(env, _zero(env))
            assert truncated or terminated
            assert truncated  # the zero action does not end any of these tasks in one step by itself
    finally:
        env.close()


@pytest.mark.parametrize("env_id", ENV_IDS, ids=SHORT.get)
def test_max_episode_steps_zero_is_rejected_by_name(env_id: str) -> None:
    with pytest.raises(ValueError, match="max_episode_steps"):
        gym.make(env_id, max_episode_steps=0)


# ------------------------------------------------------------------------------------------------ resets and seeds
@pytest.mark.parametrize("env_id", ENV_IDS, ids=SHORT.get)
def test_reset_mid_episode_gives_the_fresh_reset_observation(env_id: str) -> None:
    fresh = gym.make(env_id)
    used = gym.make(env_id)
    try:
        expected, _ = fresh.reset(seed=11)
        used.reset(seed=3)
        used.action_space.seed(0)
        for _ in range(7):
            obs, _, terminated, truncated, _ = _finite_step(used, used.action_space.sample())
            if terminated or truncated:
                break
        again, _ = used.reset(seed=11)
        np.testing.assert_array_equal(again, expected)
        # and the episodes go on alike: the simulator state was reset, not only the observation
        a = _finite_step(fresh, _zero(fresh))[0]
        b = _finite_step(used, _zero(used))[0]
        np.testing.assert_array_equal(b, a)
    finally:
        fresh.close()
        used.close()


@pytest.mark.parametrize("env_id", ENV_IDS, ids=SHORT.get)
def test_unseeded_resets_after_a_seeded_reset_follow_the_generator(env_id: str) -> None:
    """``reset()`` without a seed draws from the generator the last seed set up: two envs seeded alike give the
    same sequence of episodes, and the episodes differ from each other (the generator moves on)."""
    envs = [gym.make(env_id), gym.make(env_id)]
    try:
        sequences = []
        for env in envs:
            first, _ = env.reset(seed=5)
            sequences.append([first] + [env.reset()[0] for _ in range(2)])
        for a, b in zip(*sequences, strict=False):
            np.testing.assert_array_equal(a, b)
        assert not np.array_equal(sequences[0][0], sequences[0][1])
        assert not np.array_equal(sequences[0][1], sequences[0][2])
    finally:
        for env in envs:
            env.close()


@pytest.mark.parametrize("env_id", ENV_IDS, ids=SHORT.get)
def test_negative_zero_reset_noise_scale_resets_like_zero(env_id: str) -> None:
    """Was: ``reset_noise_scale=-0.0`` passed the ``>= 0`` check, then ``uniform(0.0, -0.0)`` raised NumPy's
    ``ValueError: high - low < 0`` at the first reset (nightly fuzz)."""
    envs = [gym.make(env_id, reset_noise_scale=scale) for scale in (-0.0, 0.0)]
    try:
        a, b = (env.reset(seed=2)[0] for env in envs)
        np.testing.assert_array_equal(a, b)
    finally:
        for env in envs:
            env.close()


# ------------------------------------------------------------------------------------------------- long horizons
def test_planar_20k_steps_of_saturated_actions_stay_finite_and_inside_the_joint_ranges() -> None:
    """200 s of the arm driven into its limits (+1 then -1 on every joint, no obstacle): finite observations and
    rewards, q within the joint ranges to the simulator's soft-limit give, phase in [0, 1], and the episode ends
    by the time limit at exactly step 20,000."""
    env = gym.make(PLANAR, obstacle=False, duration=250.0, max_episode_steps=20_000)
    model = RobotModel.from_mjcf(PLANAR_ARM_XML)
    layout = env.unwrapped.OBSERVATION_LAYOUT
    try:
        env.reset(seed=0)
        qs, qdots, phases = [], [], []
        steps, truncated = 0, False
        for sign in (1.0, -1.0):
            action = np.full(_box(env).shape, sign, dtype=_box(env).dtype)
            for _ in range(10_000):
                obs, _, terminated, truncated, info = _finite_step(env, action)
                steps += 1
                assert not terminated
                qs.append(obs[layout["q"]])
                qdots.append(obs[layout["qdot"]])
                phases.append(obs[layout["phase"]][0])
        assert steps == 20_000 and truncated
        assert info["time"] == pytest.approx(200.0, abs=1e-6)
        q = np.array(qs)
        give = 0.1  # [rad] MuJoCo's soft joint limits let a joint driven into its stop in by a few centiradians
        assert np.all(q >= model.lower_limits - give) and np.all(q <= model.upper_limits + give)
        assert np.any(q.max(axis=0) > model.upper_limits - 0.05)  # the +1 phase did reach the upper stops
        assert np.any(q.min(axis=0) < model.lower_limits + 0.05)  # and the -1 phase the lower ones
        assert np.max(np.abs(qdots)) < 2.0 * env.unwrapped.max_joint_speed  # rebounds off the stops, no blow-up
        assert 0.0 <= min(phases) and max(phases) <= 1.0
    finally:
        env.close()


@pytest.mark.parametrize("env_id", [AGRI, BIPED], ids=SHORT.get)
def test_saturated_actions_over_many_episodes_stay_finite(env_id: str) -> None:
    """+1 / -1 on every actuator ends an episode within a few dozen steps (a collision, a fall); 1,500 steps of
    that, resetting each time, keep every observation and reward finite and every reset clean."""
    env = gym.make(env_id)
    try:
        env.reset(seed=0)
        episodes, sign = 0, 1.0
        for _ in range(1500):
            action = np.full(_box(env).shape, sign, dtype=_box(env).dtype)
            _, _, terminated, truncated, _ = _finite_step(env, action)
            if terminated or truncated:
                obs, _ = env.reset()
                assert np.all(np.isfinite(obs))
                episodes += 1
                sign = -sign
        assert episodes >= 5
    finally:
        env.close()


# ------------------------------------------------------------------------------------------- render before reset
@pytest.mark.parametrize("env_id", ENV_IDS, ids=SHORT.get)
def test_render_before_reset(env_id: str) -> None:
    """The wrapped env refuses (Gymnasium's order enforcing, naming the way out); the env itself renders its
    initial state as an image of the asked size."""
    env = gym.make(env_id, render_mode="rgb_array", width=64, height=48)
    try:
        with pytest.raises(gym.error.ResetNeeded, match="reset"):
            env.render()
        frame = env.unwrapped.render()
        assert frame.shape == (48, 64, 3) and frame.dtype == np.uint8
        assert frame.std() > 0.0  # a scene, not a blank buffer
        env.reset(seed=0)
        assert env.render().shape == (48, 64, 3)
    finally:
        env.close()

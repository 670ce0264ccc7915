"""Hard cases of the reference policies' ``predict`` on observations that are no state of the robot.

Found by the nightly fuzz (``tests/fuzz/test_fuzz_policies.py``): the ``walking`` policy let the model's
``ModelError`` out for a NaN joint or base velocity and for a zero base quaternion. Every such observation is now a
:class:`PolicyError` naming what is wrong, like a non-numeric one; a good observation afterwards still acts.
"""

from __future__ import annotations

from collections.abc import Iterator

import gymnasium as gym
import numpy as np
import pytest

import redundancy_gym
from redundancy_gym.controllers import ControllerError
from redundancy_gym.policies import PolicyError

PLANAR = "redundancy_gym/PlanarReach-v0"
BIPED = "redundancy_gym/BipedWalk-v0"


@pytest.fixture(scope="module")
def biped() -> Iterator[tuple[gym.Env, np.ndarray]]:
    env = gym.make(BIPED)
    obs, _ = env.reset(seed=0)
    yield env, obs
    env.close()


@pytest.mark.parametrize(
    "slot, index, value, match",
    [
        ("base_linear_velocity", 0, np.nan, "velocity contains non-finite values"),
        ("qdot", 3, np.inf, "velocity contains non-finite values"),
        ("base_position", 0, np.nan, "configuration contains non-finite values"),
        ("q", 5, -np.inf, "configuration contains non-finite values"),
        ("base_quaternion", None, 0.0, "quaternion of qpos is zero"),
    ],
    ids=["nan-base-velocity", "inf-joint-velocity", "nan-base-position", "inf-joint-angle", "zero-quaternion"],
)
def test_walking_policy_invalid_robot_state_is_a_policy_error(
    biped, slot: str, index: int | None, value: float, match: str
) -> None:
    env, obs = biped
    policy = redundancy_gym.make_policy("walking", env)
    layout = env.unwrapped.OBSERVATION_LAYOUT
    bad = obs.copy()
    entries = np.arange(layout[slot].start, layout[slot].stop)
    bad[entries if index is None else entries[index]] = value
    with pytest.raises(PolicyError, match=rf"^invalid robot state in the observation: .*{match}"):
        policy.predict(bad, deterministic=True)
    with pytest.raises(PolicyError, match=match):  # in a batch too
        policy.predict(np.stack([obs, bad]), episode_start=np.array([True, True]))
    action, _ = policy.predict(obs, episode_start=np.array([True]))
    assert action.shape == env.action_space.shape and np.all(np.isfinite(action))


@pytest.mark.parametrize("name", ["clik", "predictive"])
def test_planar_policies_name_a_non_finite_joint_angle(name: str) -> None:
    """The arm policies hand q to their controller, which names it (ControllerError); the action space is never
    left with a NaN."""
    env = gym.make(PLANAR)
    try:
        obs, _ = env.reset(seed=0)
        policy = redundancy_gym.make_policy(name, env)
        bad = obs.copy()
        bad[env.unwrapped.OBSERVATION_LAYOUT["q"].start + 1] = np.nan
        with pytest.raises((ControllerError, PolicyError), match="finite"):
            policy.predict(bad, episode_start=np.array([True]))
        action, _ = policy.predict(obs, episode_start=np.array([True]))
        assert np.all(np.isfinite(action)) and np.all(np.abs(action) <= 1.0)
    finally:
        env.close()


def test_planar_clik_policy_far_outside_the_joint_ranges_is_rejected_naming_q() -> None:
    """A joint angle of 1e300 rad (no sensor reads that) made the two CLIK backends return different noise; the
    controller now rejects |q| > 1e6 like a NaN."""
    env = gym.make(PLANAR)
    try:
        obs, _ = env.reset(seed=0)
        policy = redundancy_gym.make_policy("clik", env)
        bad = obs.copy()
        bad[env.unwrapped.OBSERVATION_LAYOUT["q"].start] = 1e300
        with pytest.raises(ControllerError, match=r"^q must be finite, with every \|entry\| <= 1e\+06"):
            policy.predict(bad, episode_start=np.array([True]))
    finally:
        env.close()


def test_empty_batch_gives_no_actions() -> None:
    env = gym.make(PLANAR)
    try:
        obs, _ = env.reset(seed=0)
        actions, _ = redundancy_gym.make_policy("clik", env).predict(obs[None, :][:0])
        assert actions.shape[0] == 0 and actions.shape[1:] == env.action_space.shape
    finally:
        env.close()


@pytest.mark.parametrize(
    "name, kwargs, match",
    [
        ("clik", {"gain": -1.0}, "gain"),
        (
            "clik",
            {"dls_max_damping": 0.0},
            r"^invalid option for the clik policy: dls_max_damping",
        ),  # was ControllerError
        ("clik", {"no_such_option": 1}, "no_such_option"),
        ("predictive", {"horizon": 0.0}, "horizon"),
        ("predictive", {"sample_time": 0.015}, "sample_time"),
        ("predictive", {"descent": "newton"}, "descent"),
        ("random", {"seed": "x"}, "seed"),
        ("zero", {"gain": 1.0}, "gain"),
        ("no_such_policy", {}, "no_such_policy"),
    ],
)
def test_make_policy_bad_options_name_the_option(name: str, kwargs: dict, match: str) -> None:
    env = gym.make(PLANAR)
    try:
        with pytest.raises(PolicyError, match=match):
            redundancy_gym.make_policy(name, env, **kwargs)
    finally:
        env.close()

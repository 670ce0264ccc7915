"""Fuzz policy.predict with generated observations (a real one, perturbed, batched, hostile): finite actions
inside the action space, or PolicyError."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import redundancy_gym
from redundancy_gym.controllers import ControllerError
from redundancy_gym.policies import PolicyError

from .strategies import ANY_FLOATS

CASES = [
    ("redundancy_gym/PlanarReach-v0", "clik"),
    ("redundancy_gym/PlanarReach-v0", "zero"),
    ("redundancy_gym/PlanarReach-v0", "random"),
    ("redundancy_gym/AgriReach-v0", "clik"),
    ("redundancy_gym/AgriReach-v0", "zero"),
    ("redundancy_gym/BipedWalk-v0", "walking"),
]
IDS = [
    "PlanarReach-clik",
    "PlanarReach-zero",
    "PlanarReach-random",
    "AgriReach-clik",
    "AgriReach-zero",
    "BipedWalk-walking",
]


@pytest.fixture(scope="module")
def policies() -> dict:
    return {}


@pytest.fixture()
def setup(policies, env_id, name):
    """One env and policy per case for the module (gym.make of AgriReach takes ~0.2 s)."""
    if (env_id, name) not in policies:
        policies[env_id, name] = _build(env_id, name)
    return policies[env_id, name]


def _build(env_id: str, name: str):
    env = gym.make(env_id)
    obs, _ = env.reset(seed=0)
    return env, redundancy_gym.make_policy(name, env), obs


def observations(obs: np.ndarray) -> st.SearchStrategy:
    n = obs.size
    noise = st.lists(st.floats(-1.0, 1.0), min_size=n, max_size=n).map(np.array)
    return st.one_of(
        st.just(obs.copy()),
        st.tuples(noise, st.sampled_from([1e-3, 0.1, 1.0])).map(lambda t: obs + t[1] * t[0]),  # perturbed
        st.tuples(st.integers(0, n - 1), ANY_FLOATS).map(lambda t: _with(obs, *t)),  # one entry NaN/inf/huge
        noise.map(lambda e: np.stack([obs, obs + 0.01 * e])),  # a batch of two
        st.integers(0, n + 2).filter(lambda k: k != n).map(lambda k: np.zeros(k)),  # wrong size
    )


def _with(obs: np.ndarray, i: int, value: float) -> np.ndarray:
    out = obs.copy()
    out[i] = value
    return out


@pytest.mark.parametrize(("env_id", "name"), CASES, ids=IDS)
@given(data=st.data())
def test_predict_is_finite_within_bounds_or_raises(setup, data) -> None:
    env, policy, obs = setup
    observation = data.draw(observations(obs), label="observation")
    try:
        action, _ = policy.predict(observation, deterministic=True)
    except (PolicyError, ControllerError):  # the package's own (clik names a non-finite q as ControllerError)
        return
    action = np.asarray(action)
    assert action.shape[-1:] == env.action_space.shape
    assert np.all(np.isfinite(action)), action
    assert np.all(action >= env.action_space.low - 1e-6) and np.all(action <= env.action_space.high + 1e-6), action


@pytest.mark.parametrize(("env_id", "name"), CASES, ids=IDS)
@pytest.mark.parametrize("observation", [{}, np.array(["a", "b", "c"])], ids=["dict", "strings"])
def test_predict_with_non_numeric_observation_raises_policy_error(setup, observation) -> None:
    env, policy, _ = setup
    try:
        policy.predict(observation, deterministic=True)
    except PolicyError:
        pass

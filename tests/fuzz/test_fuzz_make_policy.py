"""Fuzz ``make_policy`` with generated options (each field of the policy's options dataclass, mutated as in
``test_fuzz_envs``, plus unknown names): a policy or PolicyError; the cheap policies also act once, giving a finite
action inside the action space or the package's error."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import MISSING, fields

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import redundancy_gym
from redundancy_gym.controllers import ControllerError
from redundancy_gym.policies import ClikPolicyConfig, PolicyError
from redundancy_gym.policies.grasp_clik_policy import GraspClikConfig
from redundancy_gym.policies.predictive_policy import PredictivePolicyConfig
from redundancy_gym.policies.walking_policy import WalkingPolicyConfig

from .strategies import ANY_FLOATS, JUNK
from .test_fuzz_envs import mutations

PLANAR = "redundancy_gym/PlanarReach-v0"
AGRI = "redundancy_gym/AgriReach-v0"
BIPED = "redundancy_gym/BipedWalk-v0"
# (env, policy name, options dataclass, whether one predict is cheap enough to run per example)
CASES = [
    (PLANAR, "clik", ClikPolicyConfig, True),
    (AGRI, "clik", GraspClikConfig, True),
    (PLANAR, "predictive", PredictivePolicyConfig, False),
    (AGRI, "global", PredictivePolicyConfig, False),
    (BIPED, "walking", WalkingPolicyConfig, False),
]
IDS = [f"{env.split('/')[1].split('-')[0]}-{name}" for env, name, _, _ in CASES]


@pytest.fixture(scope="module")
def envs() -> Iterator[dict]:
    made = {}
    for env_id in (PLANAR, AGRI, BIPED):
        env = gym.make(env_id)
        made[env_id] = (env, env.reset(seed=0)[0])
    yield made
    for env, _ in made.values():
        env.close()


def _default(field) -> object:
    if field.default is not MISSING:
        return field.default
    if field.default_factory is not MISSING:
        return field.default_factory()
    return None


def options(config) -> st.SearchStrategy:
    """1-3 fields of ``config``, each mutated (same type scaled / hostile, or another type), sometimes an unknown
    option besides."""
    defaults = {f.name: _default(f) for f in fields(config)}
    keys = sorted(defaults)
    chosen = st.lists(st.sampled_from(keys), min_size=1, max_size=3, unique=True).flatmap(
        lambda names: st.fixed_dictionaries({k: mutations(defaults[k]) for k in names})
    )
    unknown = st.dictionaries(
        st.sampled_from(["speed", "gains", "Method", "horizon_s", "x"]), st.one_of(ANY_FLOATS, JUNK), max_size=1
    )
    return st.tuples(chosen, unknown).map(lambda t: {**t[1], **t[0]})


def _act(env, obs, policy) -> None:
    try:
        action, _ = policy.predict(obs, deterministic=True)
    except (PolicyError, ControllerError):
        return
    action = np.asarray(action)
    assert action.shape == env.action_space.shape and np.all(np.isfinite(action)), action
    assert np.all(action >= env.action_space.low - 1e-6) and np.all(action <= env.action_space.high + 1e-6)


@pytest.mark.parametrize(("env_id", "name", "config", "cheap"), CASES, ids=IDS)
@given(data=st.data())
def test_make_policy_with_fuzzed_options_is_valid_or_policy_error(envs, env_id, name, config, cheap, data) -> None:
    env, obs = envs[env_id]
    kwargs = data.draw(options(config), label="options")
    try:
        policy = redundancy_gym.make_policy(name, env, **kwargs)
    except PolicyError:
        return
    for key in kwargs:  # accepted: only known options
        assert key in {f.name for f in fields(config)} | {"mode"}, key
    if cheap:
        _act(env, obs, policy)


@given(seed=st.one_of(st.integers(-3, 2**64), ANY_FLOATS, JUNK), env_id=st.sampled_from([PLANAR, AGRI, BIPED]))
def test_random_policy_seed_is_valid_or_policy_error(envs, seed, env_id) -> None:
    env, obs = envs[env_id]
    try:
        policy = redundancy_gym.make_policy("random", env, seed=seed)
    except PolicyError:
        return
    _act(env, obs, policy)


@given(
    name=st.one_of(st.text(max_size=8), st.sampled_from(["CLIK", "clik ", "walk", "global2", "", "zip"])),
    env_id=st.sampled_from([PLANAR, AGRI, BIPED]),
)
def test_unknown_policy_name_is_a_policy_error(envs, name, env_id) -> None:
    env, _ = envs[env_id]
    if name in ("clik", "predictive", "global", "walking", "zero", "random") or name.endswith(".zip"):
        return
    with pytest.raises(PolicyError):
        redundancy_gym.make_policy(name, env)

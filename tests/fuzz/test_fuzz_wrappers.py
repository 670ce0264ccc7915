"""Fuzz the action wrappers: generated options (each field of the wrapper's options dataclass mutated as in
``test_fuzz_envs``, plus unknown names) give a wrapper or a WrapperError; generated actions (hostile vectors) give
a finite step or the env's InvalidActionError, never a crash or a silent NaN."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import fields
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import redundancy_gym  # noqa: F401  (registers the ids)
from redundancy_gym.envs import InvalidActionError
from redundancy_gym.registration import WRAPPED_ENV_IDS
from redundancy_gym.wrappers import (
    NullspaceAction,
    NullspaceActionConfig,
    ResidualAction,
    ResidualActionConfig,
    TaskSpaceAction,
    TaskSpaceActionConfig,
    WalkingCommandAction,
    WalkingCommandActionConfig,
    WrapperError,
)

from .strategies import ANY_FLOATS, JUNK, hostile_vectors
from .test_fuzz_envs import mutations

PLANAR = "redundancy_gym/PlanarReach-v0"
AGRI = "redundancy_gym/AgriReach-v0"
BIPED = "redundancy_gym/BipedWalk-v0"
# (base env, wrapper, options dataclass, whether a reset and a step are cheap enough to run per example: the
# walker's reset estimates its ZMP correction by rollouts, a second per new controller)
CASES = [
    (PLANAR, TaskSpaceAction, TaskSpaceActionConfig, True),
    (AGRI, TaskSpaceAction, TaskSpaceActionConfig, True),
    (PLANAR, NullspaceAction, NullspaceActionConfig, True),
    (AGRI, NullspaceAction, NullspaceActionConfig, True),
    (PLANAR, ResidualAction, ResidualActionConfig, True),
    (BIPED, WalkingCommandAction, WalkingCommandActionConfig, False),
]
IDS = [f"{env.split('/')[1].split('-')[0]}-{cls.__name__}" for env, cls, _, _ in CASES]


@pytest.fixture(scope="module")
def bases() -> Iterator[dict]:
    made = {env_id: gym.make(env_id) for env_id in (PLANAR, AGRI, BIPED)}
    yield made
    for env in made.values():
        env.close()


def options(config) -> st.SearchStrategy:
    """1-3 fields of ``config`` mutated (``policy_kwargs`` as junk or an empty dict), sometimes an unknown name."""
    defaults: dict[str, Any] = {f.name: (f.default if f.name != "policy_kwargs" else {}) for f in fields(config)}
    keys = sorted(defaults)

    def mutate(name: str) -> st.SearchStrategy:
        if name == "policy_kwargs":
            return st.one_of(st.just({}), st.just(None), JUNK)
        if name == "policy":
            return st.one_of(st.sampled_from([None, "clik", "walking", "zero", "nope"]), JUNK)
        return mutations(defaults[name])

    chosen = st.lists(st.sampled_from(keys), min_size=1, max_size=3, unique=True).flatmap(
        lambda names: st.fixed_dictionaries({k: mutate(k) for k in names})
    )
    unknown = st.dictionaries(st.sampled_from(["speed", "Scale", "u", "gain"]), st.one_of(ANY_FLOATS, JUNK), max_size=1)
    return st.tuples(chosen, unknown).map(lambda t: {**t[1], **t[0]})


@pytest.mark.parametrize(("env_id", "wrapper", "config", "cheap"), CASES, ids=IDS)
@given(data=st.data())
def test_wrapper_with_fuzzed_options_is_valid_or_wrapper_error(bases, env_id, wrapper, config, cheap, data) -> None:
    kwargs = data.draw(options(config), label="options")
    try:
        env = wrapper(bases[env_id], **kwargs)
    except (WrapperError, TypeError) as exc:  # TypeError: an unknown keyword, as Python reports it for a class
        assert isinstance(exc, WrapperError) or "unexpected keyword" in str(exc), exc
        return
    for key in kwargs:  # accepted: only known options
        assert key in {f.name for f in fields(config)}, key
    if cheap:
        obs, _ = env.reset(seed=0)
        obs, reward, *_ = env.step(np.zeros(env.action_space.shape, dtype=np.float32))
        assert np.all(np.isfinite(obs)) and np.isfinite(reward)


@pytest.fixture(scope="module")
def wrapped() -> Iterator[dict]:
    made = {}
    for env_id in WRAPPED_ENV_IDS:
        env = gym.make(env_id)
        env.reset(seed=0)
        made[env_id] = env
    yield made
    for env in made.values():
        env.close()


@pytest.mark.parametrize("env_id", WRAPPED_ENV_IDS, ids=lambda i: i.split("/")[1])
@given(data=st.data())
def test_hostile_actions_step_or_raise_invalid_action(wrapped, env_id, data) -> None:
    env = wrapped[env_id]
    action = data.draw(hostile_vectors(env.action_space.shape[0]), label="action")
    try:
        obs, reward, terminated, truncated, info = env.step(action)
    except InvalidActionError:
        return
    assert np.all(np.isfinite(obs)) and np.isfinite(reward), (obs, reward)
    for key, value in info.items():
        if isinstance(value, (float, np.floating, np.ndarray)) and np.asarray(value).dtype.kind == "f":
            assert np.all(np.isfinite(value)), (key, value)
    if terminated or truncated:
        env.reset(seed=1)

"""Every action wrapper records its constructor arguments (``gymnasium.utils.RecordConstructorArgs``): Gymnasium's
``check_env`` accepts it applied by hand, and ``gym.make(env.spec)`` rebuilds the same stack, options included.

The (wrapper, env) pairs come from the registry of :mod:`redundancy_gym.policies` (each base env is built once at
collection to ask :func:`missing_capabilities`), so a new built-in wrapper or base env id is covered too.
"""

from __future__ import annotations

import dataclasses
import json
import pathlib
import pickle
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.envs.registration import EnvSpec
from gymnasium.utils.env_checker import check_env

import redundancy_gym  # noqa: F401  (registers the env ids)
from redundancy_gym.policies import WRAPPER_NAMES, env_capabilities, lookup, missing_capabilities
from redundancy_gym.registration import BASE_ENV_IDS, WRAPPED_ENV_IDS
from redundancy_gym.wrappers import ResidualAction, WrapperError

# non-default options each wrapper must record (a nested policy_kwargs among them): each one changes the first
# steps on every env the wrapper supports (asserted below), so a rebuild that dropped any would not reproduce them
NON_DEFAULT_OPTIONS: dict[str, dict[str, Any]] = {
    "task_space": {"max_speed": 0.15, "policy_kwargs": {"gain": 5.0}},
    "nullspace": {"max_nullspace_speed": 0.3, "policy_kwargs": {"gain": 5.0}},
    "residual": {"scale": 0.5, "observe_reference": True},
    "walking_command": {"command_period": 2, "max_yaw_rate": 0.2},
}
STEPS = 4  # a few steps: the bipeds' are slow, and a dropped option shows from the first
SEED = 3

# check_env's advice to check the unwrapped env: the wrapped stack is what is checked here
pytestmark = pytest.mark.filterwarnings("ignore:.*is different from the unwrapped version.*:UserWarning")


def _supported_pairs() -> list[tuple[str, str]]:
    """(wrapper name, base env id) for every built-in wrapper and every base env id it supports."""
    pairs = []
    for env_id in BASE_ENV_IDS:
        env = gym.make(env_id)
        try:
            pairs += [(name, env_id) for name in WRAPPER_NAMES if not missing_capabilities(name, env, "wrapper")]
        finally:
            env.close()
    return pairs


PAIRS = _supported_pairs()


def _pair_id(pair: tuple[str, str]) -> str:
    return f"{pair[0]}-{pair[1].split('/')[-1]}"


def _wrapper_class(name: str, env: gym.Env) -> type[gym.Wrapper]:
    """The class the registry builds for the wrapper ``name`` on ``env``."""
    impl = lookup(name, "wrapper").implementation_for(env_capabilities(env))
    assert impl is not None
    cls = impl.load()
    assert isinstance(cls, type) and issubclass(cls, gym.Wrapper)
    return cls


def _hand_wrapped(name: str, env_id: str, **options: Any) -> gym.Env:
    """``Wrapper(gym.make(env_id), **options)``: the wrapper applied by hand, not through a wrapped id."""
    env = gym.make(env_id)
    return _wrapper_class(name, env)(env, **options)


def _wrapper_types(env: gym.Env) -> list[type]:
    """The classes of ``env``'s wrapper chain, outermost first, down to the unwrapped env."""
    types = []
    while isinstance(env, gym.Wrapper):
        types.append(type(env))
        env = env.env
    return [*types, type(env)]


def _rollout(env: gym.Env) -> tuple[list[np.ndarray], list[float]]:
    """Observations and rewards of the first :data:`STEPS` steps from :data:`SEED` under seeded random actions."""
    rng = np.random.default_rng(SEED)
    obs, _ = env.reset(seed=SEED)
    observations, rewards = [np.array(obs)], []
    for _ in range(STEPS):
        obs, reward, terminated, truncated, _ = env.step(rng.uniform(-1, 1, env.action_space.shape).astype(np.float32))
        observations.append(np.array(obs))
        rewards.append(float(reward))
        if terminated or truncated:
            break
    return observations, rewards


def _same(a: tuple[list[np.ndarray], list[float]], b: tuple[list[np.ndarray], list[float]]) -> bool:
    return (
        len(a[0]) == len(b[0])
        and all(x.shape == y.shape and np.array_equal(x, y) for x, y in zip(a[0], b[0], strict=True))
        and a[1] == b[1]
    )


def test_every_wrapper_has_supported_envs_and_non_default_options() -> None:
    """Every built-in wrapper is covered: it supports some base env, and this file knows options to rebuild."""
    assert sorted({name for name, _ in PAIRS}) == sorted(WRAPPER_NAMES)
    assert sorted(NON_DEFAULT_OPTIONS) == sorted(WRAPPER_NAMES)


@pytest.mark.parametrize("pair", PAIRS, ids=_pair_id)
def test_check_env_passes_on_the_hand_wrapped_env(pair: tuple[str, str]) -> None:
    env = _hand_wrapped(*pair)
    check_env(env, skip_render_check=True)  # its close check rebuilds the env from env.spec
    env.close()


@pytest.mark.parametrize("pair", PAIRS, ids=_pair_id)
def test_the_spec_records_the_checked_options_not_the_env(pair: tuple[str, str]) -> None:
    name, env_id = pair
    options = NON_DEFAULT_OPTIONS[name]
    env = _hand_wrapped(name, env_id, **options)
    assert env.spec is not None
    recorded = env.spec.additional_wrappers[-1]
    assert recorded.kwargs is not None
    assert recorded.entry_point == f"{type(env).__module__}:{type(env).__name__}"
    config = env.config  # the wrapper's checked options (a ...Config dataclass)
    # exactly the constructor's keyword arguments (the fields of its options dataclass), with the given values
    assert recorded.kwargs == {f.name: getattr(config, f.name) for f in dataclasses.fields(config)}
    assert "env" not in recorded.kwargs
    assert {k: recorded.kwargs[k] for k in options} == options
    # JSON and pickle friendly: the spec survives both round trips unchanged
    assert EnvSpec.from_json(env.spec.to_json()) == env.spec
    assert pickle.loads(pickle.dumps(env.spec)) == env.spec
    json.dumps(recorded.kwargs)
    env.close()


@pytest.mark.parametrize("pair", PAIRS, ids=_pair_id)
def test_make_of_the_spec_rebuilds_the_same_stack_and_episode(pair: tuple[str, str]) -> None:
    name, env_id = pair
    options = NON_DEFAULT_OPTIONS[name]
    env = _hand_wrapped(name, env_id, **options)
    assert env.spec is not None
    episode = _rollout(env)
    # from the spec itself and from its JSON form (what a saved run keeps)
    for spec in (env.spec, EnvSpec.from_json(env.spec.to_json())):
        rebuilt = gym.make(spec)
        assert _wrapper_types(rebuilt) == _wrapper_types(env)
        assert rebuilt.spec == env.spec
        assert rebuilt.observation_space == env.observation_space
        assert rebuilt.action_space == env.action_space
        assert _same(_rollout(rebuilt), episode)
        rebuilt.close()
    # each option matters to these steps: a rebuild that lost any one (its default) gives another episode
    for dropped in options:
        rest = {k: v for k, v in options.items() if k != dropped}
        assert not _same(_rollout(_hand_wrapped(name, env_id, **rest)), episode), dropped
    env.close()


@pytest.mark.parametrize("env_id", WRAPPED_ENV_IDS, ids=lambda v: v.split("/")[-1])
def test_registered_wrapped_ids_pass_check_env_and_rebuild_from_their_spec(env_id: str) -> None:
    wrapper = gym.spec(env_id).kwargs["wrapper"]
    options = NON_DEFAULT_OPTIONS[wrapper]
    env = gym.make(env_id, **options)
    check_env(env, skip_render_check=True)
    assert env.spec is not None
    # the entry point's own wrapper, recorded with the options gym.make passed to it
    (recorded,) = env.spec.additional_wrappers
    assert recorded.kwargs is not None
    assert {k: recorded.kwargs[k] for k in options} == options
    rebuilt = gym.make(env.spec)  # gym.make compares the rebuilt wrapper's record with the spec's
    assert _wrapper_types(rebuilt) == _wrapper_types(env)
    assert _same(_rollout(rebuilt), _rollout(env))
    for e in (env, rebuilt):
        e.close()


def test_residual_records_a_path_policy_as_its_name_and_rejects_an_object() -> None:
    env = gym.make("redundancy_gym/PlanarReach-v0")
    wrapped = ResidualAction(env, policy=pathlib.Path("clik"))
    assert wrapped.spec is not None
    assert wrapped.spec.additional_wrappers[-1].kwargs == {
        "scale": 0.2,
        "policy": "clik",
        "policy_kwargs": {},
        "observe_reference": False,
    }
    with pytest.raises(WrapperError, match="policy must be a registered policy name.*got <object"):
        ResidualAction(env, policy=object())  # type: ignore[arg-type]  # the wrong type on purpose
    env.close()

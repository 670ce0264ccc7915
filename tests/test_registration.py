"""Every env id's card (what `redundancy-gym list` and the policy registry read without building an env) equals what
its built default env offers: spaces, control period, capabilities."""

from __future__ import annotations

import gymnasium as gym
import pytest

from redundancy_gym.policies.registry import env_capabilities
from redundancy_gym.registration import ENV_CARDS, ENV_IDS, EnvCard


def test_every_env_id_has_a_card() -> None:
    assert list(ENV_CARDS) == list(ENV_IDS)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_the_card_is_the_built_env(env_id: str) -> None:
    env = gym.make(env_id)
    try:
        built = EnvCard(
            tuple(env.observation_space.shape or ()),
            tuple(env.action_space.shape or ()),
            float(env.unwrapped.dt),
            env_capabilities(env),
        )
    finally:
        env.close()
    assert ENV_CARDS[env_id] == built

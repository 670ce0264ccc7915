"""The one registry of policies and wrappers: what make_policy, make_wrapper and the errors read."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces

import redundancy_gym  # noqa: F401  (registers the ids)
from redundancy_gym.policies import (
    CAPABILITY_ATTRIBUTES,
    POLICY_NAMES,
    WRAPPER_NAMES,
    Implementation,
    PolicyError,
    env_capabilities,
    make_policy,
    register,
    registered,
    supported_env_ids,
    supported_policies,
)
from redundancy_gym.registration import WRAPPED_ENV_IDS
from redundancy_gym.wrappers import WrapperError, make_wrapper


def test_every_name_is_registered_once_with_known_capabilities() -> None:
    assert POLICY_NAMES == ("clik", "walking", "predictive", "global", "zero", "random")
    assert WRAPPER_NAMES == ("task_space", "nullspace", "residual", "walking_command")
    for entry in registered("policy") + registered("wrapper"):
        for impl in entry.implementations:
            assert impl.capabilities <= set(CAPABILITY_ATTRIBUTES)
            assert callable(impl.load())  # the entry point imports


def test_envs_declare_what_the_policies_read() -> None:
    caps = {
        env_id: env_capabilities(gym.make(env_id))
        for env_id in ("redundancy_gym/PlanarReach-v0", "redundancy_gym/AgriReach-v0", "redundancy_gym/BipedWalk-v0")
    }
    assert caps["redundancy_gym/PlanarReach-v0"] >= {"tcp_tracking", "tcp_reference", "bounded_action"}
    assert "grasp_task" in caps["redundancy_gym/AgriReach-v0"]
    assert "biped" in caps["redundancy_gym/BipedWalk-v0"]
    assert supported_env_ids("walking") == (
        "redundancy_gym/BipedWalk-v0",
        "redundancy_gym/BipedObstacles-v0",
        "redundancy_gym/BipedTerrain-v0",
    )
    assert set(supported_env_ids("task_space", "wrapper")) == {
        "redundancy_gym/PlanarReach-v0",
        "redundancy_gym/AgriReach-v0",
    }


def test_a_wrapped_env_offers_no_reference_policy_that_would_misread_its_action() -> None:
    for env_id in WRAPPED_ENV_IDS:
        env = gym.make(env_id)
        assert supported_policies(env) == ("zero", "random"), env_id
        with pytest.raises(PolicyError, match="supports"):
            make_policy("clik", env)


def test_unknown_and_unsupported_names_list_the_valid_choices() -> None:
    planar = gym.make("redundancy_gym/PlanarReach-v0")
    with pytest.raises(PolicyError, match="valid: clik, walking, predictive, global, zero, random"):
        make_policy("mpc", planar)
    with pytest.raises(PolicyError, match="supports redundancy_gym/BipedWalk-v0.*lacks the capabilities biped"):
        make_policy("walking", planar)
    with pytest.raises(WrapperError, match="valid: task_space, nullspace, residual, walking_command"):
        make_wrapper("joint", planar)
    biped = gym.make("redundancy_gym/BipedWalk-v0")
    with pytest.raises(WrapperError, match="supports redundancy_gym/PlanarReach-v0, redundancy_gym/AgriReach-v0"):
        make_wrapper("nullspace", biped)
    with pytest.raises(WrapperError, match="unknown option.*valid: max_nullspace_speed, objectives, policy_kwargs"):
        make_wrapper("nullspace", planar, speed=1.0)


class _Arm(gym.Env):
    """An env of one's own that declares a capability without the attributes it promises."""

    CAPABILITIES = frozenset({"tcp_tracking"})
    observation_space = spaces.Box(-1.0, 1.0, (3,))
    action_space = spaces.Box(-1.0, 1.0, (2,))
    ROBOT_XML = "arm.xml"


def test_a_declared_capability_without_its_attributes_is_named() -> None:
    with pytest.raises(PolicyError, match="declares tcp_tracking but lacks OBSERVATION_LAYOUT, TCP_FRAME"):
        make_policy("clik", _Arm())


def test_a_registered_policy_of_ones_own_is_built_and_listed() -> None:
    class Hold:
        def __init__(self, env: gym.Env, gain: float = 1.0) -> None:
            self.gain = gain

        def predict(self, observation, state=None, episode_start=None, deterministic=True):
            return np.zeros(2), state

    import sys
    import types

    module = types.ModuleType("_own_policies")
    module.Hold = Hold
    sys.modules["_own_policies"] = module
    try:
        register("hold", "policy", (Implementation(frozenset({"box_action"}), "_own_policies:Hold"),), "hold still")
        assert "hold" in supported_policies(_Arm())
        assert isinstance(make_policy("hold", _Arm()), Hold)
        with pytest.raises(PolicyError, match="takes no options"):
            make_policy("hold", _Arm(), gain=2.0)
        with pytest.raises(PolicyError, match="unknown capability"):
            register("bad", "policy", (Implementation(frozenset({"wings"}), "_own_policies:Hold"),), "")
    finally:
        from redundancy_gym.policies import registry

        registry._REGISTRY.pop("hold", None)
        sys.modules.pop("_own_policies", None)


def test_errors_on_a_wrapped_env_say_it_is_wrapped() -> None:
    wrapped = gym.make("redundancy_gym/PlanarReach-Nullspace-v0")
    with pytest.raises(PolicyError, match="in the action wrapper NullspaceAction.*takes zero, random or an SB3 .zip"):
        make_policy("clik", wrapped)
    with pytest.raises(WrapperError, match="in the action wrapper NullspaceAction"):
        make_wrapper("task_space", wrapped)


def test_wrapped_ids_name_the_wrapper_options_on_a_typo_and_want_a_dict() -> None:
    from redundancy_gym.envs import EnvConfigError

    with pytest.raises(EnvConfigError, match="or an option of the task_space wrapper: .*max_speed"):
        gym.make("redundancy_gym/AgriReach-TaskSpace-v0", max_sped=0.2)
    with pytest.raises(WrapperError, match="wrapper_kwargs must be a dict of residual options"):
        gym.make("redundancy_gym/PlanarReach-Residual-v0", wrapper_kwargs=[("scale", 0.1)])

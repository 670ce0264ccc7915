"""The ``backend`` option of the reference policies: one switch (the choices and the default of
:mod:`redundancy_gym.kernel_options`) that picks the compiled twin or the Python reference of every controller."""

from __future__ import annotations

from dataclasses import fields

import gymnasium as gym
import numpy as np
import pytest

import redundancy_gym
from redundancy_gym.controllers import Clik, CompiledClik
from redundancy_gym.controllers.walking import CompiledWholeBodyIk, WholeBodyIk
from redundancy_gym.kernel_options import BACKENDS, DEFAULT_BACKEND
from redundancy_gym.policies import PolicyError
from redundancy_gym.policies.clik_policy import ClikPolicyConfig
from redundancy_gym.policies.grasp_clik_policy import GraspClikConfig
from redundancy_gym.policies.options import config_from_options, option_rule
from redundancy_gym.policies.walking_policy import WalkingPolicyConfig

CONFIGS = (ClikPolicyConfig, GraspClikConfig, WalkingPolicyConfig)


@pytest.mark.parametrize("config", CONFIGS, ids=lambda c: c.__name__)
def test_every_backend_option_has_the_shared_choices_and_default(config: type) -> None:
    assert {f.name: f.default for f in fields(config)}["backend"] == DEFAULT_BACKEND
    rule = option_rule(config, "backend")
    assert rule is not None and rule.choices == BACKENDS
    with pytest.raises(PolicyError, match=r"backend must be one of compiled, python; got 'gpu'"):
        config_from_options(config, {"backend": "gpu"})
    with pytest.raises(PolicyError, match=r"backend must be one of compiled, python; got None"):
        config_from_options(config, {"backend": None})


def test_no_other_policy_config_has_a_twin_switch() -> None:
    """The predictive policies choose per mode (the horizon compiled, the global plan on the reference loop), so
    no option of theirs is a backend; if one appears it must be one of CONFIGS above."""
    from redundancy_gym.policies.predictive_policy import PredictivePolicyConfig  # noqa: PLC0415

    assert "backend" not in {f.name for f in fields(PredictivePolicyConfig)}


@pytest.mark.parametrize("backend", BACKENDS)
def test_the_clik_policy_builds_the_chosen_twin(backend: str) -> None:
    policy = redundancy_gym.make_policy("clik", gym.make("redundancy_gym/PlanarReach-v0"), backend=backend)
    assert type(policy.controller) is (CompiledClik if backend == "compiled" else Clik)


@pytest.mark.parametrize("backend", BACKENDS)
def test_the_grasp_policy_builds_the_chosen_twin(backend: str) -> None:
    env = gym.make("redundancy_gym/AgriReach-v0")
    obs, _ = env.reset(seed=0)
    policy = redundancy_gym.make_policy("clik", env, backend=backend)
    action = policy.predict(obs)[0]
    assert type(policy.controller) is (CompiledClik if backend == "compiled" else Clik)
    assert (policy._fused is not None) == (backend == "compiled")  # the one-call step only on the compiled twin
    assert np.all(np.isfinite(action))


@pytest.mark.parametrize("backend", BACKENDS)
def test_the_walking_policy_runs_the_chosen_twins(backend: str) -> None:
    """One option for both of the walking controller's twins: the whole-body IK and the measurement."""
    env = gym.make("redundancy_gym/BipedWalk-v0")
    obs, _ = env.reset(seed=0)
    policy = redundancy_gym.make_policy("walking", env, backend=backend)
    policy.predict(obs)
    controller = policy.controller
    assert controller.ik_config.backend == backend
    assert type(controller.solver) is (CompiledWholeBodyIk if backend == "compiled" else WholeBodyIk)
    assert (controller._measurement is not None) == (backend == "compiled")

"""Policies with the stable-baselines3 ``predict`` signature over the controllers, and the one registry of
policies and action wrappers (:func:`make_policy`, :func:`register`).

This package joins controllers and envs (docs/architecture.md): a policy reads what it needs from the env by duck typing
(the attributes its capabilities promise, :data:`CAPABILITY_ATTRIBUTES`) and never imports mujoco, so the same
policy object can drive a robot fed with the same observation. The policy classes load when first used.
"""

from __future__ import annotations

from typing import Any

from .exceptions import PolicyError
from .options import config_from_options, env_name
from .per_env_policy import PerEnvPolicy, Policy, observation_time_index
from .registry import (
    CAPABILITY_ATTRIBUTES,
    GENERIC_POLICIES,
    KINDS,
    POLICY_NAMES,
    WRAPPER_NAMES,
    Implementation,
    RegistryEntry,
    capability_problems,
    env_capabilities,
    lookup,
    make_policy,
    missing_capabilities,
    policy_supports,
    reference_policy,
    register,
    registered,
    supported_env_ids,
    supported_names,
    supported_policies,
)

__all__ = [
    "CAPABILITY_ATTRIBUTES",
    "KINDS",
    "POLICY_NAMES",
    "WRAPPER_NAMES",
    "ClikPolicy",
    "ClikPolicyConfig",
    "GraspClikConfig",
    "GraspClikPolicy",
    "Implementation",
    "MlpInference",
    "PerEnvPolicy",
    "Policy",
    "PolicyError",
    "PredictivePolicy",
    "PredictivePolicyConfig",
    "RandomPolicy",
    "RandomPolicyConfig",
    "RegistryEntry",
    "Sb3Policy",
    "WalkingPolicy",
    "WalkingPolicyConfig",
    "ZeroPolicy",
    "capability_problems",
    "config_from_options",
    "env_capabilities",
    "env_name",
    "lookup",
    "make_policy",
    "missing_capabilities",
    "observation_time_index",
    "policy_supports",
    "GENERIC_POLICIES",
    "reference_policy",
    "register",
    "registered",
    "supported_env_ids",
    "supported_names",
    "supported_policies",
]

# the policy classes import the controllers (numba kernels, pinocchio): loaded on first access
_LAZY = {
    "ClikPolicy": "clik_policy",
    "ClikPolicyConfig": "clik_policy",
    "GraspClikPolicy": "grasp_clik_policy",
    "GraspClikConfig": "grasp_clik_policy",
    "MlpInference": "mlp_inference",
    "PredictivePolicy": "predictive_policy",
    "PredictivePolicyConfig": "predictive_policy",
    "RandomPolicy": "random_policy",
    "RandomPolicyConfig": "random_policy",
    "Sb3Policy": "sb3_policy",
    "WalkingPolicy": "walking_policy",
    "WalkingPolicyConfig": "walking_policy",
    "ZeroPolicy": "zero_policy",
}


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    import importlib

    return getattr(importlib.import_module(f".{module}", __name__), name)

"""Checks shared by the reference policies: options against their config dataclass, and what the env must expose."""

from __future__ import annotations

from dataclasses import fields
from typing import Any, TypeVar

from .exceptions import PolicyError
from .redundancy_resolution import METHODS

__all__ = ["BACKENDS", "config_from_options", "env_with_attributes"]

C = TypeVar("C")
# how a CLIK policy runs its controller: one fused compiled kernel (CompiledClik) or the Python Clik
BACKENDS: tuple[str, ...] = ("compiled", "python")


def config_from_options(config_type: type[C], options: dict[str, Any]) -> C:
    """``config_type(**options)``, with a :class:`PolicyError` naming the valid options or redundancy methods."""
    valid = {f.name for f in fields(config_type)}  # type: ignore[arg-type]
    unknown = set(options) - valid
    if unknown:
        raise PolicyError(f"unknown option(s) of {config_type.__name__}: {', '.join(sorted(unknown))}; valid: {', '.join(sorted(valid))}")
    config = config_type(**options)
    method = getattr(config, "method", METHODS[0])
    if method not in METHODS:
        raise PolicyError(f"unknown method {method!r}; valid methods: {', '.join(METHODS)}")
    backend = getattr(config, "backend", BACKENDS[0])
    if backend not in BACKENDS:
        raise PolicyError(f"unknown backend {backend!r}; valid: {', '.join(BACKENDS)}")
    return config


def env_with_attributes(env: Any, required: tuple[str, ...], policy: str) -> Any:
    """The unwrapped env, after checking that it has every attribute in ``required``.

    :func:`~redundancy_gym.controllers.policies.make_policy` checks support first and names the registered envs a
    policy supports; this is the check of a policy class built directly.
    """
    base = getattr(env, "unwrapped", env)
    missing = [name for name in required if not hasattr(base, name)]
    if missing:
        spec = getattr(env, "spec", None) or getattr(base, "spec", None)
        name = getattr(spec, "id", None) or type(base).__name__
        raise PolicyError(f"policy {policy!r} does not support {name} "
                          f"(for an env of your own: {type(base).__name__} lacks {', '.join(missing)})")
    return base

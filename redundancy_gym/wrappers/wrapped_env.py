"""Building wrappers by name from the one registry, and the ``gym.make`` entry point of the wrapped env ids."""

from __future__ import annotations

from typing import Any

import gymnasium as gym

from ..envs.exceptions import EnvConfigError
from ..policies.registry import build, lookup
from .exceptions import WrapperError

__all__ = ["make_wrapped_env", "make_wrapper", "wrapper_option_names"]


def make_wrapper(name: str, env: gym.Env, **kwargs: Any) -> gym.Wrapper:
    """Wrap ``env`` in the registered action wrapper ``name`` (``redundancy-gym list`` shows them).

    Args:
        name: ``"task_space"`` (:class:`~redundancy_gym.wrappers.TaskSpaceAction`), ``"nullspace"``
            (:class:`~redundancy_gym.wrappers.NullspaceAction`), ``"residual"``
            (:class:`~redundancy_gym.wrappers.ResidualAction`) or another registered wrapper.
        env: the env to wrap.
        **kwargs: the wrapper's options (the fields of its ``...Config`` dataclass).

    Raises:
        WrapperError: unknown name or option, or an env the wrapper does not support (naming the registered env
            ids it supports).
    """
    return build(name, "wrapper", env, kwargs, error=WrapperError)


def wrapper_option_names(name: str) -> tuple[str, ...]:
    """The option names of the registered wrapper ``name``."""
    entry = lookup(name, "wrapper", WrapperError)
    names: list[str] = []
    for impl in entry.implementations:
        names += [n for n in impl.option_names() if n not in names]
    return tuple(names)


def make_wrapped_env(env_id: str, wrapper: str, wrapper_kwargs: dict[str, Any] | None = None, **kwargs: Any) -> gym.Env:
    """The entry point of a wrapped env id (``redundancy_gym/AgriReach-Nullspace-v0``): the env ``env_id`` built
    from its registered entry point (without its ``gym.make`` wrappers: the wrapped id's own time limit and
    checks go around the whole) and wrapped in ``wrapper``.

    Keyword arguments named like an option of the wrapper go to the wrapper (as do ``wrapper_kwargs``); the rest
    go to the env, so ``gym.make("redundancy_gym/PlanarReach-TaskSpace-v0", max_speed=0.2, obstacle=False)``
    sets one of each.
    """
    options = set(wrapper_option_names(wrapper))
    if wrapper_kwargs is not None and not isinstance(wrapper_kwargs, dict):
        raise WrapperError(
            f"wrapper_kwargs must be a dict of {wrapper} options ({', '.join(sorted(options))}), "
            f"got {type(wrapper_kwargs).__name__}"
        )
    own = {k: v for k, v in kwargs.items() if k in options}
    clash = sorted(set(own) & set(wrapper_kwargs or {}))
    if clash:
        raise WrapperError(f"{', '.join(clash)} given both as a keyword and in wrapper_kwargs")
    env_kwargs = {k: v for k, v in kwargs.items() if k not in options}
    spec = gym.spec(env_id)
    if spec.entry_point is None:
        raise WrapperError(f"env_id {env_id!r} is registered without an entry point: it cannot be built")
    creator = (
        gym.envs.registration.load_env_creator(spec.entry_point)
        if isinstance(spec.entry_point, str)
        else spec.entry_point
    )
    try:
        env = creator(**{**spec.kwargs, **env_kwargs})
    except EnvConfigError as exc:
        if "unknown keyword" in str(exc):  # a typo may have meant a wrapper option: name those too
            raise EnvConfigError(f"{exc}; or an option of the {wrapper} wrapper: {', '.join(sorted(options))}") from exc
        raise
    if not isinstance(env, gym.Env):  # an entry point may return anything; the wrappers need one gymnasium.Env
        raise WrapperError(f"the entry point of {env_id} made a {type(env).__name__}, not a gymnasium.Env")
    env.spec = spec  # the base env's spec, so that make_policy and messages name the env it is
    return make_wrapper(wrapper, env, **{**own, **(wrapper_kwargs or {})})

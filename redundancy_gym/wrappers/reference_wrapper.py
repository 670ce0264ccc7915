"""The base of the action wrappers that drive a reference policy's controller (NullspaceAction, TaskSpaceAction,
WalkingCommandAction): what they declare and record alike."""

from __future__ import annotations

from dataclasses import asdict
from typing import Any

import gymnasium as gym

__all__ = ["ReferenceActionWrapper"]


class ReferenceActionWrapper(gym.Wrapper, gym.utils.RecordConstructorArgs):
    """An action wrapper whose action drives the controller of a reference policy (:attr:`reference`).

    The wrapper records its arguments (``gymnasium.utils.RecordConstructorArgs``), checked and with their defaults
    filled in (``policy_kwargs=None`` as ``{}``), not the env: ``env.spec`` lists them, so ``gym.make(env.spec)``
    rebuilds the whole stack and Gymnasium's ``check_env`` accepts the wrapper applied by hand.
    """

    # the action is no longer the env's joint command: no reference policy reads it (redundancy_gym.policies)
    CAPABILITIES: frozenset[str] = frozenset()

    # the reference policy this wrapper drives, used by duck typing as the registry builds it (each subclass says
    # which)
    reference: Any

    controller_time_us: float
    """Compute time of this wrapper's controller in the last step [us] (``CONTROLLER_TIME_ATTRIBUTE``)."""

    def _wrap(self, env: gym.Env) -> None:
        """Wrap ``env``; no controller time spent yet."""
        gym.Wrapper.__init__(self, env)
        self.controller_time_us = 0.0

    def _record(self, config: Any) -> None:
        """Record the validated options (the dataclass ``config``), not the env: ``env.spec`` lists them, so
        ``gym.make(env.spec)`` rebuilds this wrapper."""
        gym.utils.RecordConstructorArgs.__init__(self, _disable_deepcopy=True, **asdict(config))

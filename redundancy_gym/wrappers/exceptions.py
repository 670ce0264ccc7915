"""Exceptions of :mod:`redundancy_gym.wrappers`."""

from __future__ import annotations

from ..envs.exceptions import InvalidActionError

__all__ = ["WrapperActionError", "WrapperError"]


class WrapperError(ValueError):
    """A wrapper that cannot be built or stepped: unknown name or option, an env it does not support, an action
    that is not finite or has the wrong shape (the message names the valid choices)."""


class WrapperActionError(WrapperError, InvalidActionError):
    """An action a wrapper rejects (not finite, a wrong shape): an :class:`InvalidActionError` as the envs raise."""

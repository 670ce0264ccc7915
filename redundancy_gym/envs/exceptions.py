"""Exceptions of :mod:`redundancy_gym.envs`."""

from __future__ import annotations

__all__ = ["EnvConfigError", "InvalidActionError"]


class EnvConfigError(ValueError):
    """An invalid environment keyword argument (the message names the valid choices or range)."""


class InvalidActionError(ValueError):
    """An action of the wrong shape or with non-finite entries."""

"""Exceptions of :mod:`redundancy_gym.policies`."""

from __future__ import annotations

__all__ = ["PolicyError"]


class PolicyError(ValueError):
    """A policy that cannot be built or fed: unknown name or option, unsupported environment, unreadable model
    file, an observation that is no state of the env (the message names the valid choices)."""

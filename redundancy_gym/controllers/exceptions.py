"""Exceptions of :mod:`redundancy_gym.controllers`."""

from __future__ import annotations

__all__ = ["ControllerError", "PolicyError"]


class ControllerError(ValueError):
    """Invalid controller parameters or inputs (the message names the valid choices)."""


class PolicyError(ValueError):
    """A policy that cannot be built: unknown name, unsupported environment, unreadable model file."""

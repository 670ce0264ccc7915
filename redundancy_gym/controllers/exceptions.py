"""Exceptions of :mod:`redundancy_gym.controllers`."""

from __future__ import annotations

__all__ = ["ControllerError"]


class ControllerError(ValueError):
    """Invalid controller parameters or inputs (the message names the valid choices)."""

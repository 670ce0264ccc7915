"""Exceptions of :mod:`redundancy_gym.eval`."""

from __future__ import annotations

__all__ = ["EvalError"]


class EvalError(ValueError):
    """Invalid evaluation, training or demo input (unknown env id, bad JSON, bad episode count)."""

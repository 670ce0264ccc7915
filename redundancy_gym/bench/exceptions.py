"""Exceptions of :mod:`redundancy_gym.bench`."""

from __future__ import annotations

from ..eval.exceptions import EvalError

__all__ = ["BenchError"]


class BenchError(EvalError):
    """Invalid benchmark input (unknown bench, bad round count, a candidate without samples).

    A subclass of :class:`~redundancy_gym.eval.EvalError`, so ``except EvalError`` catches it too."""

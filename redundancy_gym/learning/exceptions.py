"""Exceptions of :mod:`redundancy_gym.learning`."""

from __future__ import annotations

from ..eval.exceptions import EvalError

__all__ = ["LearningError"]


class LearningError(EvalError):
    """Invalid training, behaviour-cloning or baselines input (unknown algorithm, bad config, missing record).

    A subclass of :class:`~redundancy_gym.eval.EvalError`, so ``except EvalError`` catches it too."""

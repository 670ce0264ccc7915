"""Exceptions of :mod:`redundancy_gym.studies`."""

from __future__ import annotations

from ..eval.exceptions import EvalError

__all__ = ["StudyError"]


class StudyError(EvalError):
    """Invalid input to a monograph-figure study (unknown case, bad horizon).

    A subclass of :class:`~redundancy_gym.eval.EvalError`, so ``except EvalError`` catches it too."""

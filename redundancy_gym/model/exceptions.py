"""Exceptions of :mod:`redundancy_gym.model`."""

from __future__ import annotations

__all__ = ["ModelError", "UnknownFrameError"]


class ModelError(ValueError):
    """Invalid model input: wrong configuration size, non-finite values, unreadable description."""


class UnknownFrameError(ModelError, KeyError):
    """A frame name that the model does not have; the message lists the valid names."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else ""

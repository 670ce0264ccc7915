"""Checks of env keyword arguments shared by the env classes (each raises :class:`EnvConfigError`)."""

from __future__ import annotations

import numpy as np

from .exceptions import EnvConfigError

__all__ = ["non_negative", "positive"]


def positive(value: float, name: str) -> float:
    """``value`` as a float when it is a finite number > 0."""
    if not isinstance(value, (int, float, np.number)) or not np.isfinite(value) or value <= 0:
        raise EnvConfigError(f"{name} must be a finite number > 0, got {value!r}")
    return float(value)


def non_negative(value: float, name: str) -> float:
    """``value`` as a float when it is a finite number >= 0."""
    if not isinstance(value, (int, float, np.number)) or not np.isfinite(value) or value < 0:
        raise EnvConfigError(f"{name} must be a finite number >= 0, got {value!r}")
    return float(value)

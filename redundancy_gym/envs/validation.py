"""Checks of env keyword arguments shared by the env classes (each raises :class:`EnvConfigError`)."""

from __future__ import annotations

import numpy as np

from ..rendering_backend import require_render_backend
from .exceptions import EnvConfigError

__all__ = ["check_render_backend", "non_negative", "positive"]


def check_render_backend(render_mode: str | None) -> None:
    """Fail at ``gym.make`` (not at the first frame) when an offscreen ``render_mode`` has no OpenGL backend.

    Raises :class:`redundancy_gym.rendering_backend.RenderBackendError` naming the library to install.
    """
    if render_mode in ("rgb_array", "depth_array"):
        require_render_backend()


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

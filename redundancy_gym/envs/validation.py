"""Checks of env keyword arguments shared by the env classes (each raises :class:`EnvConfigError`)."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from ..rendering_backend import can_open_window, require_render_backend, require_window
from .exceptions import EnvConfigError

__all__ = ["check_render_backend", "non_negative", "positive", "render_modes", "warn_if_time_limit_short"]


def render_modes(*offscreen: str) -> list[str]:
    """The render modes an env offers here: ``"human"`` (a window) only where a display exists, then
    ``offscreen``. Gymnasium's ``check_env`` renders every listed mode; listing ``"human"`` on a headless machine
    would abort the process in GLFW."""
    return (["human"] if can_open_window() else []) + list(offscreen)


def warn_if_time_limit_short(env: Any, needed: float, what: str) -> bool:
    """Warn (once per env) when the registered time limit ends episodes before ``needed`` seconds of env time.

    ``gym.make`` wraps the env in a ``TimeLimit`` of the registered ``max_episode_steps``; a kwarg that lengthens
    the task (a slower ``duration``, a longer path) would otherwise be cut silently. The env cannot see a limit
    passed to ``gym.make`` itself (Gymnasium keeps it in the wrapper), so the warning names the registered one
    and the value that fits. Returns whether it warned.
    """
    spec = getattr(env, "spec", None)
    if spec is None or getattr(env, "_warned_time_limit", False) or spec.id not in gym.registry:
        return False
    limit = gym.registry[spec.id].max_episode_steps
    if limit is None or limit * env.dt >= needed - 1e-9:
        return False
    env._warned_time_limit = True
    steps = int(np.ceil(needed / env.dt - 1e-9))
    gym.logger.warn(f"{spec.id}: {what} needs {needed:.2f} s, but the registered max_episode_steps={limit} ends "
                    f"episodes at {limit * env.dt:.2f} s; pass max_episode_steps={steps} or more to gym.make")
    return True


def check_render_backend(render_mode: str | None) -> None:
    """Fail at ``gym.make`` (not at the first frame) when an offscreen ``render_mode`` has no OpenGL backend, or
    ``"human"`` has no display.

    Raises :class:`redundancy_gym.rendering_backend.RenderBackendError` naming what to install or use instead.
    """
    if render_mode in ("rgb_array", "depth_array"):
        require_render_backend()
    elif render_mode == "human":
        require_window()


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

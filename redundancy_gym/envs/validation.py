"""Checks of env keyword arguments shared by the env classes (each raises :class:`EnvConfigError`).

The type, finiteness and range checks are those of :mod:`redundancy_gym.validation` (shared with the policies
and the geometry), bound here to :class:`EnvConfigError`; they run in the constructors only.

Each env writes its keyword arguments and their defaults once, in its explicit ``__init__`` signature;
:func:`constructor_defaults` reads its ``default_config()`` from there, :func:`constructor_arguments` what
``EzPickle`` records, and :func:`check_known_arguments` the valid names of the unknown-argument error.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Mapping
from functools import partial
from typing import Any, Unpack

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from .. import validation as _checks
from ..rendering_backend import can_open_window, require_render_backend, require_window
from .exceptions import EnvConfigError, InvalidActionError

__all__ = [
    "MAX_FRAME_SKIP",
    "RENDER_ARGUMENTS",
    "RENDER_MODES",
    "check_backend",
    "check_bool",
    "check_choice",
    "check_int",
    "check_known_arguments",
    "check_noise",
    "check_range_pair",
    "check_real",
    "check_real_array",
    "check_render_arguments",
    "check_render_backend",
    "constructor_arguments",
    "constructor_defaults",
    "non_finite_action",
    "non_negative",
    "positive",
    "render_modes",
    "warn_if_time_limit_short",
]


MAX_FRAME_SKIP = 1000
"""Largest ``frame_skip`` of every env: physics steps per control step (a control period of seconds; beyond, one
``step`` would run for minutes)."""


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
    gym.logger.warn(
        f"{spec.id}: {what} needs {needed:.2f} s, but the registered max_episode_steps={limit} ends "
        f"episodes at {limit * env.dt:.2f} s; pass max_episode_steps={steps} or more to gym.make"
    )
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


def init_mujoco_env(
    env: Any,
    xml: str,
    frame_skip: int,
    timestep: float,
    observation_size: int,
    rendering: tuple[str | None, int, int, str | None],
) -> None:
    """Gymnasium's ``MujocoEnv.__init__`` for ``env`` on the model ``xml``: ``metadata`` (offscreen render modes,
    frames per second of the control period ``timestep * frame_skip`` [s]) and an unbounded float64 observation
    space of ``observation_size``. ``rendering``: ``(render_mode, width, height, camera_name)``, checked by
    :func:`check_render_arguments` (the camera is passed only when rendering)."""
    from gymnasium import spaces
    from gymnasium.envs.mujoco.mujoco_env import MujocoEnv

    render_mode, width, height, camera_name = rendering
    env.metadata = {
        "render_modes": render_modes("rgb_array", "depth_array"),
        "render_fps": int(np.round(1.0 / (timestep * frame_skip))),
    }
    MujocoEnv.__init__(
        env,
        xml,
        int(frame_skip),
        observation_space=spaces.Box(-np.inf, np.inf, shape=(observation_size,), dtype=np.float64),
        render_mode=render_mode,
        width=width,
        height=height,
        camera_name=camera_name if render_mode is not None else None,
    )


def as_action(action: Any, size: int, *, finite: bool = True) -> NDArray[np.float64]:
    """``action`` as a float64 vector of ``size`` entries, else :class:`InvalidActionError` saying why; with
    ``finite`` (the default) its entries must be finite too (a compiled step that checks them itself passes False
    and raises :func:`non_finite_action`)."""
    try:
        array = np.asarray(action, dtype=np.float64)
    except (TypeError, ValueError) as exc:  # a dict, strings, None: not an action
        raise InvalidActionError(f"action must be an array of numbers, got {type(action).__name__}") from exc
    if array.shape != (size,):
        raise InvalidActionError(f"action must have shape ({size},), got {array.shape}")
    if finite and not np.all(np.isfinite(array)):
        raise non_finite_action(array)
    return array


def non_finite_action(action: NDArray[np.float64]) -> InvalidActionError:
    """The error of an action with a non-finite entry."""
    return InvalidActionError(f"action must be finite, got {action}")


def check_real(name: str, value: Any, **bounds: Unpack[_checks.RealRange]) -> float:
    """``value`` as a float when it is a finite real number inside the range, else :class:`EnvConfigError`
    (:func:`redundancy_gym.validation.check_real`; no env argument takes None where a number is asked for)."""
    return _checks.check_required_real(name, value, error=EnvConfigError, **bounds)


def check_int(name: str, value: Any, **bounds: Unpack[_checks.IntRange]) -> int:
    """``value`` as an int when it is an int inside ``[low, high]``, else :class:`EnvConfigError`
    (:func:`redundancy_gym.validation.check_int`)."""
    return _checks.check_required_int(name, value, error=EnvConfigError, **bounds)


def positive(value: float, name: str) -> float:
    """``value`` as a float when it is a finite real number > 0 (see :func:`redundancy_gym.validation.check_real`)."""
    return check_real(name, value, low=0.0, low_open=True)


def non_negative(value: float, name: str) -> float:
    """``value`` as a float when it is a finite real number >= 0."""
    return check_real(name, value, low=0.0)


# the shared checks of redundancy_gym.validation, raising EnvConfigError
check_bool = partial(_checks.check_bool, error=EnvConfigError)
check_choice = partial(_checks.check_choice, error=EnvConfigError)
check_backend = partial(_checks.check_backend, error=EnvConfigError)
check_range_pair = partial(_checks.check_range_pair, error=EnvConfigError)
check_real_array = partial(_checks.check_real_array, error=EnvConfigError)


def check_noise(
    name: str,
    value: Any,
    groups: dict[str, tuple[slice, ...]],
    default_groups: tuple[str, ...],
    unit: str | None = None,
) -> tuple[np.ndarray, np.ndarray] | None:
    """An observation-noise argument (``sensor_noise``, ``obs_noise``) as ``(indices, stds)``, or None when off.

    ``value`` is None or 0 (off), a float std >= 0 for every group of ``default_groups``, or a dict from group
    names (keys of ``groups``, each naming its observation slices) to stds >= 0 (groups not named get none).
    Only entries with a std > 0 are returned, so a noise of 0 everywhere is off.
    """
    if value is None:
        return None
    if isinstance(value, dict):
        unknown = sorted(str(k) for k in value if k not in groups)
        if unknown:
            raise EnvConfigError(
                f"{name} has unknown channel group(s) {', '.join(unknown)}; valid: {', '.join(groups)}"
            )
        stds = {k: check_real(f"{name}[{k!r}]", v, low=0.0, unit=unit) for k, v in value.items()}
    else:
        std = check_real(
            name,
            value,
            low=0.0,
            unit=unit,
            note="None or 0: off; a float: the std of every sensor channel; a dict: a std per "
            f"channel group of {', '.join(groups)}",
        )
        stds = {k: std for k in default_groups}
    index: list[int] = []
    scale: list[float] = []
    for group, std in stds.items():
        if std and std > 0.0:
            for part in groups[group]:
                idx = range(part.start, part.stop)
                index.extend(idx)
                scale.extend([std] * len(idx))
    if not index:
        return None
    return np.array(index, dtype=np.intp), np.array(scale)


RENDER_MODES: tuple[str, ...] = ("human", "rgb_array", "depth_array")
"""Every render mode an env may name (``"human"`` needs a display: :func:`check_render_backend`)."""


def check_render_arguments(
    render_mode: str | None,
    width: int,
    height: int,
    camera_name: str | None,
    render_modes: tuple[str, ...] = RENDER_MODES,
) -> tuple[int, int]:
    """Check the rendering arguments every env takes; returns ``(width, height)`` as ints.

    ``render_mode``: None or one of ``render_modes``; ``width``, ``height``: ints >= 1 [pixels];
    ``camera_name``: None or a string (whether the camera exists is the env's check).
    """
    if render_mode is not None:
        check_choice("render_mode", render_mode, render_modes)
    w = check_int("width", width, low=1)
    h = check_int("height", height, low=1)
    if camera_name is not None and not isinstance(camera_name, str):
        raise EnvConfigError(
            f"camera_name must be None or a camera's name (a str), got {camera_name!r} ({type(camera_name).__name__})"
        )
    check_render_backend(render_mode)
    return w, h


RENDER_ARGUMENTS: tuple[str, ...] = ("render_mode", "width", "height", "camera_name")
"""The rendering keyword arguments every env takes, as Gymnasium's MuJoCo envs do; they are no part of an env's
``default_config()`` (they change what is drawn, not the task)."""


def _named_parameters(init: Callable[..., Any]) -> list[inspect.Parameter]:
    """The parameters of an env constructor that take an argument by name (``self`` and ``**kwargs`` left out)."""
    kinds = (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)
    return [p for p in list(inspect.signature(init).parameters.values())[1:] if p.kind in kinds]


def constructor_defaults(init: Callable[..., Any]) -> dict[str, Any]:
    """The defaults of the env constructor ``init``'s keyword arguments, the :data:`RENDER_ARGUMENTS` left out: each
    env's ``default_config()``.

    The explicit signature is the one place an env writes its defaults (it stays explicit for IDE help and
    ``help()``, as Gymnasium's v5 envs do); ``default_config()`` and the pickled arguments
    (:func:`constructor_arguments`) are read from it.
    """
    return {p.name: p.default for p in _named_parameters(init) if p.name not in RENDER_ARGUMENTS}


def constructor_arguments(init: Callable[..., Any], local_vars: Mapping[str, Any]) -> dict[str, Any]:
    """The arguments of one call of the env constructor ``init``, by name, read from its ``locals()``: what
    ``gymnasium.utils.EzPickle`` records, so that unpickling makes the env again with every argument it was given.

    Pass ``locals()`` before the constructor rebinds an argument (``frame_skip = check_int(...)``): the record must
    hold what the caller passed.
    """
    return {p.name: local_vars[p.name] for p in _named_parameters(init)}


def check_known_arguments(kwargs: Mapping[str, Any], init: Callable[..., Any]) -> None:
    """Raise :class:`EnvConfigError` when the env constructor ``init`` got keyword arguments it does not take
    (``kwargs``, its ``**kwargs``), naming them and the valid ones; a ``TypeError`` would name no valid choice."""
    if kwargs:
        valid = ", ".join(sorted(constructor_defaults(init)) + list(RENDER_ARGUMENTS))
        raise EnvConfigError(f"unknown keyword argument(s) {', '.join(sorted(kwargs))}; valid: {valid}")

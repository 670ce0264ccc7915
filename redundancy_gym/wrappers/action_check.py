"""The checks every wrapper applies to its input: the learner's action before it reaches a controller, and the
reference policy's options."""

from __future__ import annotations

import math
from typing import Any, Unpack

import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from .. import validation
from .exceptions import WrapperActionError, WrapperError
from .glue_kernels import clipped_finite

__all__ = [
    "CONTROLLER_TIME_ATTRIBUTE",
    "check_action",
    "check_bool",
    "check_int",
    "check_policy_kwargs",
    "check_real",
    "normalized_box",
]

CONTROLLER_TIME_ATTRIBUTE = "controller_time_us"
"""The wrapper attribute holding its own compute time in the last step [us]: its controller turning the learner's
action into the env's (the env's simulation excluded). ``eval`` adds it to the learner's time, so that a wrapped
learner's step time is that of the whole policy. An attribute, not an ``info`` key: ``info`` stays a deterministic
function of the seed and the actions (Gymnasium's ``check_env`` compares it across runs)."""


def normalized_box(dim: int) -> spaces.Box:
    """The action space of a wrapper: ``[-1, 1]^dim`` (float32); each wrapper scales it by its bounds."""
    return spaces.Box(-1.0, 1.0, shape=(dim,), dtype=np.float32)


_COMPILED_DTYPES = (np.dtype(np.float32), np.dtype(np.float64))  # the actions clipped_finite is compiled for


def check_action(action: Any, space: spaces.Space[Any], wrapper: str) -> NDArray[np.float64]:
    """``action`` as float64 after checking it is an array of ``space``'s shape with finite entries; entries
    outside ``[-1, 1]`` (every wrapper's box, :func:`normalized_box`) are clipped into it, as the envs clip
    theirs.

    Raises:
        WrapperActionError: not numbers, a wrong shape, or a NaN/inf entry (naming the wrapper and the shape).
    """
    if type(action) is np.ndarray and action.shape == space.shape and action.dtype.kind == "f":  # the hot path
        if action.ndim == 1 and action.dtype in _COMPILED_DTYPES:
            clipped, finite = clipped_finite(action)
            if finite:
                return clipped
        else:
            a = action.astype(np.float64)
            if math.isfinite(float(a.sum())):  # finite entries sum to a finite number (or overflow: checked below)
                return a.clip(-1.0, 1.0)
    try:
        a = np.asarray(action, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise WrapperActionError(f"{wrapper}: action must be an array of numbers, got {type(action).__name__}") from exc
    if a.shape != space.shape:
        raise WrapperActionError(f"{wrapper}: action must have shape {space.shape}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise WrapperActionError(f"{wrapper}: action must be finite, got {a.tolist()}")
    return a.clip(-1.0, 1.0)


def check_policy_kwargs(value: Any, wrapper: str) -> dict[str, Any]:
    """``policy_kwargs`` as a dict (None: empty), else :class:`WrapperError` naming it."""
    if value is None:
        return {}
    if not isinstance(value, dict) or not all(isinstance(k, str) for k in value):
        raise WrapperError(
            f"{wrapper}: policy_kwargs must be a dict of the reference policy's options, got "
            f"{value!r} ({type(value).__name__})"
        )
    return dict(value)


def check_bool(name: str, value: Any) -> bool:
    """``value`` when it is a bool, else :class:`WrapperError` (:func:`redundancy_gym.validation.check_bool`)."""
    return validation.check_bool(name, value, error=WrapperError)


def check_real(name: str, value: Any, **bounds: Unpack[validation.RealRange]) -> float:
    """``value`` as a float when it is a finite real number inside the range, else :class:`WrapperError`
    (:func:`redundancy_gym.validation.check_real`; no wrapper option takes None where a number is asked for)."""
    return validation.check_required_real(name, value, error=WrapperError, **bounds)


def check_int(name: str, value: Any, **bounds: Unpack[validation.IntRange]) -> int:
    """``value`` as an int when it is an int inside ``[low, high]``, else :class:`WrapperError`
    (:func:`redundancy_gym.validation.check_int`)."""
    return validation.check_required_int(name, value, error=WrapperError, **bounds)

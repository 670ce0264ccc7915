"""Argument checks shared by every layer: envs, policies, controllers and geometry constructors.

One way to check a constructor argument, so that every package says the same thing about the same mistake:

- a bool is a bool (``"no"`` is not ``True``), a number is a real number (``"480"``, ``True`` and ``None`` are
  not), an int is an int (``3.0`` is not);
- a real number is finite (NaN and inf raise) and inside its range, with closed or open bounds;
- the message names the argument, the value (and its type when the type is wrong) and the valid range or
  choices: ``target_speed must be a finite real number in [0, 1] [m/s] (...), got 10``.

Each function raises the exception class the caller passes as ``error`` (``EnvConfigError``, ``PolicyError``,
``GeometryError``, ...), so each package keeps its own exceptions. The module imports only numpy, so any layer
may import it without breaking the dependency direction (``geometry <- model <- controllers <- eval``; envs).
The checks are meant for constructors, not for per-step hot paths.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence
from typing import Any, TypedDict, Unpack

import numpy as np
from numpy.typing import NDArray

from .kernel_options import BACKENDS

__all__ = [
    "IntRange",
    "RealRange",
    "as_real_array",
    "check_backend",
    "check_bool",
    "check_choice",
    "check_int",
    "check_range_pair",
    "check_real",
    "check_real_array",
    "check_required_int",
    "check_required_real",
    "describe_range",
    "is_real",
]

ErrorType = type[Exception]


class RealRange(TypedDict, total=False):
    """The range of a real argument, as :func:`check_real` and :func:`check_range_pair` take it (keywords)."""

    low: float | None
    """Lower bound (None: unbounded)."""
    high: float | None
    """Upper bound (None: unbounded)."""
    low_open: bool
    """Exclude ``low`` itself (``> low`` instead of ``>= low``)."""
    high_open: bool
    """Exclude ``high`` itself."""
    unit: str | None
    """Unit of the bounds in the message (``"m"``, ``"m/s"``)."""
    note: str | None
    """Why the range is what it is, said in parentheses after the range."""


class IntRange(TypedDict, total=False):
    """The range of an int argument, as :func:`check_int` takes it (keywords)."""

    low: int | None
    """Lower bound, included (None: unbounded)."""
    high: int | None
    """Upper bound, included (None: unbounded)."""
    note: str | None
    """Why the range is what it is, said in parentheses after the range."""


def _show(value: Any) -> str:
    """``repr`` of a value (shortened beyond 100 characters), with its type where the repr alone could hide it
    (``[1, 'a'] (list)``, ``0.5 (float32)``)."""
    if isinstance(value, np.generic) and value.ndim == 0:
        text = repr(value.item())
    else:
        text = repr(value)
    if len(text) > 100:
        text = text[:97] + "..."
    if type(value) in (bool, int, float, str, type(None)):
        return text
    return f"{text} ({type(value).__name__})"


def _fmt(x: float) -> str:
    return f"{x:g}"


def describe_range(
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
    unit: str | None = None,
) -> str:
    """The range in words: ``"> 0"``, ``">= 0"``, ``"in [0, 1]"``, ``"in (0, 0.92)"``, ``"<= 1"``; empty without
    bounds; ``unit`` appended in brackets (``"> 0 [1/s]"``)."""
    if low is not None and high is not None:
        text = f"in {'(' if low_open else '['}{_fmt(low)}, {_fmt(high)}{')' if high_open else ']'}"
    elif low is not None:
        text = f"{'>' if low_open else '>='} {_fmt(low)}"
    elif high is not None:
        text = f"{'<' if high_open else '<='} {_fmt(high)}"
    else:
        return ""
    return f"{text} [{unit}]" if unit else text


def _within(x: float, low: float | None, high: float | None, low_open: bool, high_open: bool) -> bool:
    if low is not None and (x <= low if low_open else x < low):
        return False
    return not (high is not None and (x >= high if high_open else x > high))


def is_real(value: Any) -> bool:
    """Whether ``value`` is a real number: an int or float (numpy's too), not a bool, a string or a complex."""
    kind = type(value)
    if kind is float or kind is int:
        return True
    return isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_))


def _finite_float(value: Any) -> float | None:
    """``float(value)`` for a finite real number, else None (an int too large for a float included). A negative
    zero comes back as ``0.0``: ``-0.0`` passes ``>= 0`` but is no valid bound of ``uniform(-x, x)`` (NumPy
    rejects ``high - low = -0.0``), and no argument means anything else by it."""
    if not is_real(value):
        return None
    try:
        x = float(value)
    except (OverflowError, ValueError, TypeError):
        return None
    return x + 0.0 if math.isfinite(x) else None


def _suffix(note: str | None) -> str:
    return f" ({note})" if note else ""


def check_bool(name: str, value: Any, *, error: ErrorType = ValueError) -> bool:
    """``value`` when it is a bool (``numpy.bool_`` too); otherwise ``error`` (``"no"``, ``1``, ``None`` are not)."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise error(f"{name} must be a bool (True or False), got {_show(value)}")


def check_real(
    name: str,
    value: Any,
    *,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
    unit: str | None = None,
    optional: bool = False,
    note: str | None = None,
    error: ErrorType = ValueError,
) -> float | None:
    """``value`` as a float when it is a finite real number inside the range; otherwise ``error``.

    Args:
        name: the argument's name, first word of the message.
        value: what was passed.
        low, high: bounds (None: unbounded on that side).
        low_open, high_open: exclude the bound itself (``> low`` instead of ``>= low``).
        unit: unit of the bounds in the message (``"m"``, ``"m/s"``).
        optional: ``None`` is valid (and returned).
        note: why the range is what it is, said in parentheses after the range.
        error: the exception class to raise.
    """
    if value is None and optional:
        return None
    x = _finite_float(value)
    if x is not None and _within(x, low, high, low_open, high_open):
        return x
    bounds = describe_range(low, high, low_open, high_open, unit)
    what = f"{'None or ' if optional else ''}a finite real number{' ' + bounds if bounds else ''}"
    raise error(f"{name} must be {what}{_suffix(note)}, got {_show(value)}")


def check_int(
    name: str,
    value: Any,
    *,
    low: int | None = None,
    high: int | None = None,
    optional: bool = False,
    note: str | None = None,
    error: ErrorType = ValueError,
) -> int | None:
    """``value`` as an int when it is an int (numpy's too; not a bool, not ``3.0``) inside ``[low, high]``."""
    if value is None and optional:
        return None
    if (
        isinstance(value, (int, np.integer))
        and not isinstance(value, (bool, np.bool_))
        and _within(int(value), low, high, False, False)
    ):
        return int(value)
    bounds = describe_range(low, high)
    what = f"{'None or ' if optional else ''}an int{' ' + bounds if bounds else ''}"
    raise error(f"{name} must be {what}{_suffix(note)}, got {_show(value)}")


def check_required_real(name: str, value: Any, *, error: ErrorType, **bounds: Unpack[RealRange]) -> float:
    """:func:`check_real` of an argument that has no None: always a float, else ``error`` (for the packages that
    bind their own exception class)."""
    x = check_real(name, value, error=error, **bounds)
    if x is None:  # cannot happen without optional=True; narrows the Optional result
        raise error(f"{name} must be a finite real number, got None")
    return x


def check_required_int(name: str, value: Any, *, error: ErrorType, **bounds: Unpack[IntRange]) -> int:
    """:func:`check_int` of an argument that has no None: always an int, else ``error``."""
    n = check_int(name, value, error=error, **bounds)
    if n is None:  # cannot happen without optional=True; narrows the Optional result
        raise error(f"{name} must be an int, got None")
    return n


def check_choice(name: str, value: Any, choices: Sequence[Any], *, error: ErrorType = ValueError) -> Any:
    """``value`` when it is one of ``choices`` (compared by equality and kind: ``1`` is not ``True``, ``"1"`` not
    ``1``). The message lists string choices without quotes: ``mode must be one of a, b; got 'c'``."""
    for choice in choices:
        same_kind = isinstance(value, type(choice)) and isinstance(value, bool) == isinstance(choice, bool)
        if same_kind and value == choice:
            return value
    listed = ", ".join(c if isinstance(c, str) else repr(c) for c in choices)
    raise error(f"{name} must be one of {listed}; got {_show(value)}")


def check_backend(name: str, value: Any, *, error: ErrorType = ValueError) -> str:
    """``value`` when it is one of :data:`~redundancy_gym.kernel_options.BACKENDS` (``"compiled"``: the compiled
    twin; ``"python"``: its readable reference); otherwise ``error``: ``backend must be one of compiled, python; got
    'gpu'``. Every controller and policy option that picks a twin checks it here, so all say the same."""
    return str(check_choice(name, value, BACKENDS, error=error))


def check_real_array(
    name: str,
    value: Any,
    *,
    shape: tuple[int, ...] | None = None,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
    unit: str | None = None,
    what: str | None = None,
    error: ErrorType = ValueError,
) -> NDArray[np.float64]:
    """``value`` as a new float64 array when all its entries are finite real numbers (not strings or bools) in
    the range, with ``shape`` when given.

    ``what`` is what the message says the value must be (``"an (x, z) pair of finite real numbers [m]"``); by
    default it is said from the shape.
    """
    arr: NDArray[Any] | None
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError):  # a ragged sequence
        arr = None
    ok = arr is not None and arr.dtype.kind in "iuf" and (shape is None or arr.shape == shape)
    if ok:
        out = np.array(arr, dtype=np.float64) + 0.0  # + 0.0: no negative zeros (see _finite_float)
        if np.all(np.isfinite(out)) and (
            out.size == 0
            or _within(float(out.min()), low, None, low_open, False)
            and _within(float(out.max()), None, high, False, high_open)
        ):
            return out
    if what is None:
        count = (
            "" if shape is None else (f"{shape[0]} " if len(shape) == 1 else f"a {'x'.join(map(str, shape))} array of ")
        )
        what = f"{count}finite real numbers"
    bounds = describe_range(low, high, low_open, high_open, unit)
    raise error(f"{name} must be {what}{' ' + bounds if bounds else ''}, got {_show(value)}")


def as_real_array(name: str, value: Any, *, error: ErrorType = ValueError) -> NDArray[np.float64]:
    """``value`` as a float64 array when it holds real numbers (bools and ints too; finiteness is not checked,
    so hot paths can check it their own cheap way); otherwise ``error`` (strings, None, mappings, complex
    numbers, ragged sequences)."""
    try:
        given = np.asarray(value)
    except ValueError:  # a ragged sequence
        raise error(f"{name} must be an array of real numbers, got {value!r}") from None
    if given.dtype.kind not in "biuf":
        raise error(f"{name} must be an array of real numbers, got {value!r}")
    return np.asarray(given, dtype=np.float64)


def check_range_pair(
    name: str, value: Any, *, integer: bool = False, error: ErrorType = ValueError, **bounds: Unpack[RealRange]
) -> tuple[float, float] | tuple[int, int]:
    """``(low, high)`` of a range argument: two finite real numbers (ints with ``integer``) with
    ``value[0] <= value[1]``, both inside the bounds ``low``/``high`` (``bounds``: :class:`RealRange`)."""
    low, high = bounds.get("low"), bounds.get("high")
    low_open, high_open = bounds.get("low_open", False), bounds.get("high_open", False)
    pair: Sequence[Any] | None = None
    if isinstance(value, (Sequence, np.ndarray)) and not isinstance(value, (str, bytes)) and len(value) == 2:
        pair = list(value)
    if pair is not None:
        if integer:
            good = all(isinstance(v, (int, np.integer)) and not isinstance(v, (bool, np.bool_)) for v in pair)
        else:
            good = all(_finite_float(v) is not None for v in pair)
        if good:
            a, b = (int(v) for v in pair) if integer else (float(v) + 0.0 for v in pair)  # no negative zeros
            if a <= b and _within(a, low, high, low_open, high_open) and _within(b, low, high, low_open, high_open):
                return (a, b)
    kind = "ints" if integer else "finite real numbers"
    described = describe_range(low, high, low_open, high_open, bounds.get("unit"))
    both = f", both {described}" if described else ""
    raise error(
        f"{name} must be a (low, high) pair of {kind} with low <= high{both}{_suffix(bounds.get('note'))}, "
        f"got {_show(value)}"
    )

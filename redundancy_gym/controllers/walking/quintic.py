"""Quintic polynomials between two states given to C2 (position, velocity, acceleration at both ends)."""

from __future__ import annotations

from bisect import bisect_right
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..exceptions import ControllerError

__all__ = ["PiecewiseQuintic", "Quintic"]


@dataclass(frozen=True)
class Quintic:
    """``p(s) = sum_k c_k s^k`` for ``s`` in ``[0, duration]`` meeting six boundary conditions.

    Values may be vectors: every coefficient row has the shape of the boundary values.

    Attributes:
        duration: length of the interval [s], > 0.
        coefficients: ``(6, ...)`` array, ``coefficients[k]`` multiplies ``s^k``.
    """

    duration: float
    coefficients: NDArray[np.float64]

    def __post_init__(self) -> None:
        # evaluate() runs several times per control period of the walking controller; on scalar or 2-vector values
        # it evaluates the polynomials on Python floats (the coefficients read once, on first use: the arrays are not
        # written after construction). numpy's per-call overhead on 2-vectors cost several times the arithmetic.
        object.__setattr__(self, "_rows", None)

    @classmethod
    def from_boundary(
        cls,
        duration: float,
        start: ArrayLike,
        end: ArrayLike,
        start_velocity: ArrayLike = 0.0,
        end_velocity: ArrayLike = 0.0,
        start_acceleration: ArrayLike = 0.0,
        end_acceleration: ArrayLike = 0.0,
    ) -> Quintic:
        """The unique quintic with the given position, velocity and acceleration at ``s = 0`` and ``s = duration``."""
        if not np.isfinite(duration) or duration < 1e-9:
            raise ControllerError(f"duration must be finite and >= 1e-9 s (its fifth power divides), got {duration!r}")
        p0, p1, v0, v1, a0, a1 = np.broadcast_arrays(
            *(
                np.asarray(x, dtype=np.float64)
                for x in (start, end, start_velocity, end_velocity, start_acceleration, end_acceleration)
            )
        )
        if not all(np.all(np.isfinite(x)) for x in (p0, p1, v0, v1, a0, a1)):
            raise ControllerError("boundary values must be finite")
        t = float(duration)
        # the three top coefficients solve the end conditions after the first three absorb the start
        d = p1 - p0 - v0 * t - 0.5 * a0 * t * t
        e = v1 - v0 - a0 * t
        f = a1 - a0
        c3 = (10.0 * d - 4.0 * e * t + 0.5 * f * t * t) / t**3
        c4 = (-15.0 * d + 7.0 * e * t - f * t * t) / t**4
        c5 = (6.0 * d - 3.0 * e * t + 0.5 * f * t * t) / t**5
        return cls(t, np.stack([p0, v0, 0.5 * a0, c3, c4, c5]))

    def evaluate(self, s: float) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """Position, velocity and acceleration at ``s`` [s], clamped into ``[0, duration]``."""
        values = self.values(s)
        if values is None:
            return self._evaluate_array(min(max(float(s), 0.0), self.duration))
        p, v, a = values
        if self.coefficients.ndim == 1:  # scalar values: NumPy scalars, as the array form gives
            return np.float64(p[0]), np.float64(v[0]), np.float64(a[0])  # type: ignore[return-value]
        return np.array(p), np.array(v), np.array(a)

    def values(self, s: float) -> tuple[list[float], list[float], list[float]] | None:
        """:meth:`evaluate` as lists of Python floats, one per value component (scalar values: one), for values that
        are scalars or vectors of up to three; None for other shapes (use :meth:`evaluate`)."""
        s = min(max(float(s), 0.0), self.duration)
        rows: list[list[float]] | None = self._rows  # type: ignore[attr-defined]
        if rows is None:
            c = self.coefficients
            # per value component, its six coefficients; other shapes (matrices of values) keep the array form
            rows = [c.tolist()] if c.ndim == 1 else c.T.tolist() if c.ndim == 2 and c.shape[1] <= 3 else []
            object.__setattr__(self, "_rows", rows)
        if not rows:
            return None
        # the array form's operations in its order, per component (elementwise IEEE arithmetic: the same floats)
        p, v, a = [], [], []
        for c0, c1, c2, c3, c4, c5 in rows:
            p.append(c0 + s * (c1 + s * (c2 + s * (c3 + s * (c4 + s * c5)))))
            v.append(c1 + s * (2.0 * c2 + s * (3.0 * c3 + s * (4.0 * c4 + s * 5.0 * c5))))
            a.append(2.0 * c2 + s * (6.0 * c3 + s * (12.0 * c4 + s * 20.0 * c5)))
        return p, v, a

    def _evaluate_array(self, s: float) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """:meth:`evaluate` on the coefficient array (values of any shape), ``s`` already clamped."""
        c = self.coefficients
        position = c[0] + s * (c[1] + s * (c[2] + s * (c[3] + s * (c[4] + s * c[5]))))
        velocity = c[1] + s * (2.0 * c[2] + s * (3.0 * c[3] + s * (4.0 * c[4] + s * 5.0 * c[5])))
        acceleration = 2.0 * c[2] + s * (6.0 * c[3] + s * (12.0 * c[4] + s * 20.0 * c[5]))
        return position, velocity, acceleration


class PiecewiseQuintic:
    """Quintic pieces joined end to start; C2 wherever neighbouring pieces share their boundary states.

    Args:
        pieces: the pieces in time order.
    """

    def __init__(self, pieces: Sequence[Quintic]) -> None:
        if not pieces:
            raise ControllerError("a piecewise quintic needs at least one piece")
        self.pieces = tuple(pieces)
        self.breaks = np.concatenate([[0.0], np.cumsum([p.duration for p in self.pieces])])
        self._inner = self.breaks[1:-1].tolist()
        self._starts = self.breaks[:-1].tolist()  # each piece's start [s] as a float, read per evaluation

    @property
    def duration(self) -> float:
        """Total duration [s]."""
        return float(self.breaks[-1])

    def evaluate(self, s: float) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """Position, velocity and acceleration at ``s`` [s] (clamped into the whole interval)."""
        index = bisect_right(self._inner, s)
        return self.pieces[index].evaluate(s - self._starts[index])

    def values(self, s: float) -> tuple[list[float], list[float], list[float]] | None:
        """:meth:`evaluate` as lists of Python floats (:meth:`Quintic.values`)."""
        index = bisect_right(self._inner, s)
        return self.pieces[index].values(s - self._starts[index])

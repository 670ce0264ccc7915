"""Repulsive distance potentials for nullspace avoidance (monograph 5.3, (5.50)-(5.59)).

A potential maps a scalar distance ``d`` [m or rad] to a cost that is zero for ``d >= d_a`` (the activation
distance) and grows as ``d`` shrinks. :class:`PiecewisePotential` is the C2 quadratic/cubic potential
``H_c23`` of (5.58) with gradient (5.59); it is used for joint-limit avoidance (``d`` = distance to a limit)
and for collision avoidance (``d`` = swept-sphere distance).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

from ..kernel_options import JIT_EXACT
from .exceptions import GeometryError

__all__ = ["CubicPotential", "PiecewisePotential", "PotentialValue", "QuadraticPotential", "piecewise_potential_kernel"]


@dataclass(frozen=True)
class PotentialValue:
    """Potential, first and second derivative with respect to the distance, elementwise."""

    value: NDArray[np.float64]
    slope: NDArray[np.float64]
    curvature: NDArray[np.float64]


@dataclass(frozen=True)
class PiecewisePotential:
    """The C2 piecewise quadratic/cubic potential ``H_c23`` (5.52)-(5.59).

    ``H(d) = H_2(d)`` for ``d < t d_a`` (quadratic, so the gradient keeps growing linearly when the distance
    becomes negative), ``H_3(d)`` for ``t d_a <= d <= d_a`` (cubic) and ``0`` beyond ``d_a``. The seven
    coefficients follow from ``H_2'(0) = s_0`` (5.55), C2 continuity at ``t d_a`` (5.56) and
    ``H_3 = H_3' = H_3'' = 0`` at ``d_a`` (5.57); the closed form is (5.58).

    The monograph's ``s_0`` is the slope at zero distance, which is negative for a repulsive potential; here
    ``slope`` is its magnitude, ``s_0 = -slope``, so that every parameter is positive.

    Args:
        activation_distance: ``d_a`` [m or rad], > 0; the potential vanishes beyond it.
        slope: ``|H'(0)|`` [1/m or 1/rad], > 0.
        switch_ratio: ``t`` in (0, 1); the quadratic branch starts below ``t d_a``.
    """

    activation_distance: float
    slope: float = 1.0
    switch_ratio: float = 0.5

    def __post_init__(self) -> None:
        if not np.isfinite(self.activation_distance) or self.activation_distance <= 0.0:
            raise GeometryError(f"activation_distance must be finite and > 0, got {self.activation_distance!r}")
        if not np.isfinite(self.slope) or self.slope <= 0.0:
            raise GeometryError(f"slope must be finite and > 0, got {self.slope!r}")
        if not 0.0 < self.switch_ratio < 1.0:
            raise GeometryError(f"switch_ratio must lie in (0, 1), got {self.switch_ratio!r}")

    def evaluate(self, distance: ArrayLike) -> PotentialValue:
        """Value, first and second derivative of (5.58) at each distance (elementwise, any shape)."""
        d = np.asarray(distance, dtype=np.float64)
        if not np.all(np.isfinite(d)):
            raise GeometryError("distances must be finite")
        da = self.activation_distance
        if d.size == 0 or d.min() > da:  # the common case in a control loop: nothing is near
            zero = np.zeros_like(d)
            return PotentialValue(zero, zero.copy(), zero.copy())
        if not d.flags.c_contiguous:  # flat views below, written in place (keeping a 0-d shape)
            d = d.copy(order="C")
        value, slope, curvature = np.empty(d.shape), np.empty(d.shape), np.empty(d.shape)
        _piecewise_potential_many(
            d.reshape(-1),
            da,
            self.slope,
            self.switch_ratio,
            value.reshape(-1),
            slope.reshape(-1),
            curvature.reshape(-1),
        )
        return PotentialValue(value, slope, curvature)

    def value(self, distance: ArrayLike) -> NDArray[np.float64]:
        """``H_c23(d)`` (5.58)."""
        return self.evaluate(distance).value

    def derivative(self, distance: ArrayLike) -> NDArray[np.float64]:
        """``dH_c23/dd`` (5.59)."""
        return self.evaluate(distance).slope


@njit(**JIT_EXACT)
def piecewise_potential_kernel(
    d: float, activation_distance: float, slope: float, switch_ratio: float
) -> tuple[float, float, float]:
    """``H_c23(d)`` (5.58), ``H_c23'(d)`` (5.59) and ``H_c23''(d)`` for one distance: the one implementation of
    :class:`PiecewisePotential`, also called inside compiled controllers."""
    da = activation_distance
    t = switch_ratio
    s0 = -slope
    if d > da:
        return 0.0, 0.0, 0.0
    if d < t * da:  # quadratic branch
        return (
            -s0 * d * d / (da * (t + 1.0)) + s0 * d - s0 * da * (t * t + t + 1.0) / (3.0 * (t + 1.0)),
            -2.0 * s0 * d / (da * (t + 1.0)) + s0,
            -2.0 * s0 / (da * (t + 1.0)),
        )
    rest = da - d  # cubic branch
    denom = da * da * (t * t - 1.0)
    return s0 * rest**3 / (3.0 * denom), -s0 * rest * rest / denom, 2.0 * s0 * rest / denom


@njit(**JIT_EXACT)
def _piecewise_potential_many(d, activation_distance, slope, switch_ratio, value, first, second):  # noqa: ANN001, ANN202
    """:func:`piecewise_potential_kernel` over a flat array."""
    for k in range(d.shape[0]):
        value[k], first[k], second[k] = piecewise_potential_kernel(d[k], activation_distance, slope, switch_ratio)


@dataclass(frozen=True)
class _PowerPotential:
    """``H(d) = s_0 |d - d_a|^k`` for ``d < d_a``, else 0, for the power ``k`` of the subclass."""

    POWER: ClassVar[int]
    activation_distance: float
    gain: float = 1.0

    def __post_init__(self) -> None:
        if not np.isfinite(self.activation_distance) or self.activation_distance <= 0.0:
            raise GeometryError(f"activation_distance must be finite and > 0, got {self.activation_distance!r}")
        if not np.isfinite(self.gain) or self.gain <= 0.0:
            raise GeometryError(f"gain must be finite and > 0, got {self.gain!r}")

    def evaluate(self, distance: ArrayLike) -> PotentialValue:
        """Value, first and second derivative at each distance."""
        d = np.asarray(distance, dtype=np.float64)
        if not np.all(np.isfinite(d)):
            raise GeometryError("distances must be finite")
        k = self.POWER
        # below d_a, x = d - d_a < 0, so s_0 |x|^k = s_0 (-1)^k x^k
        c = self.gain * (-1.0) ** k
        on = d < self.activation_distance
        x = np.where(on, d - self.activation_distance, 0.0)
        return PotentialValue(c * x**k, c * k * x ** (k - 1), np.where(on, c * k * (k - 1) * x ** (k - 2), 0.0))


@dataclass(frozen=True)
class QuadraticPotential(_PowerPotential):
    """``H_c2(d) = s_0 (d - d_a)^2`` for ``d < d_a``, else 0 (5.50): C1 at ``d_a`` (its curvature jumps).

    Args:
        activation_distance: ``d_a`` [m or rad], > 0.
        gain: ``s_0`` > 0.
    """

    POWER: ClassVar[int] = 2


@dataclass(frozen=True)
class CubicPotential(_PowerPotential):
    """``H_c3(d) = -s_0 (d - d_a)^3`` for ``d < d_a``, else 0: (5.51) with the sign that makes it repulsive
    for ``s_0 > 0`` (as printed, ``s_0 (d - d_a)^3`` is negative below ``d_a``); C2 at ``d_a``.

    Args:
        activation_distance: ``d_a`` [m or rad], > 0.
        gain: ``s_0`` > 0.
    """

    POWER: ClassVar[int] = 3

"""CoM reference from the linear inverted pendulum (LIPM) through its divergent component of motion (DCM).

With the CoM at constant height ``z_c`` the horizontal CoM ``x`` obeys ``xdd = omega^2 (x - r)`` with
``omega = sqrt(g / z_c)`` and ``r`` the ZMP (monograph 4.5.1). The DCM (capture point) ``xi = x + xd / omega``
splits it into a stable and an unstable first-order system:

    xid = omega (xi - r)        xd = omega (xi - x)

The unstable one is solved backwards in time from where the walk ends (``xi = r`` at rest), the stable one
forwards from the measured CoM. The ZMP reference is piecewise linear (constant under a foot or rolling
heel to toe, moving from foot to foot in double support), for which both have closed forms: on a segment
with ``r(s) = r_k + m s``,

    xi(s) = r(s) + m / omega + c e^{omega s},                 c = xi(0) - r_k - m / omega
    x(s)  = r(s) + c / 2 e^{omega s} + d e^{-omega s},         d = x(0) - r_k - c / 2

so the ZMP stays exactly on the planned reference, which is inside the support polygon by construction.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...constants import GRAVITY
from ..exceptions import ControllerError

__all__ = ["GRAVITY", "MAX_EXPONENT", "OMEGA_RANGE", "ComState", "DcmPlan", "DcmPlanner", "horizontal_point"]

OMEGA_RANGE = (0.1, 100.0)
"""``omega = sqrt(g / z_c)`` [1/s] the planner accepts: a CoM 0.1 mm to 1 km above the ground under Earth's gravity.
Outside it the exponentials of a step over- or underflow."""
MAX_EXPONENT = 700.0
"""Largest ``omega s`` evaluated (``e^700`` ~ 1e304): a plan sampled long after it diverged stays finite."""


def horizontal_point(name: str, value: ArrayLike) -> NDArray[np.float64]:
    """``value`` as a finite (x, y) [m]; ControllerError naming ``name`` otherwise."""
    try:
        point = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ControllerError(f"{name} must be a finite (x, y), got {value!r}") from None
    if point.shape != (2,) or not np.all(np.isfinite(point)):
        raise ControllerError(f"{name} must be a finite (x, y), got {value!r}")
    return point


def _divergent(c: NDArray[np.float64], exponent: float) -> NDArray[np.float64]:
    """``c e^exponent``, exactly zero where ``c`` is (no ``0 * inf``), the exponent capped at :data:`MAX_EXPONENT`."""
    return np.where(c != 0.0, c * np.exp(min(exponent, MAX_EXPONENT)), 0.0)


@dataclass(frozen=True)
class ComState:
    """Horizontal CoM state of the LIPM at one instant.

    Attributes:
        position: CoM ``(x, y)`` [m].
        velocity: CoM velocity [m/s].
        acceleration: CoM acceleration [m/s^2] (``omega^2 (x - r)``).
        dcm: divergent component of motion ``x + xd / omega`` [m].
        zmp: ZMP reference ``r`` [m].
    """

    position: NDArray[np.float64]
    velocity: NDArray[np.float64]
    acceleration: NDArray[np.float64]
    dcm: NDArray[np.float64]
    zmp: NDArray[np.float64]


@dataclass(frozen=True)
class DcmPlan:
    """A planned CoM motion over a piecewise-linear ZMP reference (built by :meth:`DcmPlanner.plan`).

    Attributes:
        omega: ``sqrt(g / z_c)`` [1/s].
        times: knot times [s], increasing, shape (n,).
        zmp: ZMP at the knots [m], shape (n, 2).
        dcm: DCM at the knots [m], shape (n, 2).
        com: CoM at the knots [m], shape (n, 2).
    """

    omega: float
    times: NDArray[np.float64]
    zmp: NDArray[np.float64]
    dcm: NDArray[np.float64]
    com: NDArray[np.float64]

    def __post_init__(self) -> None:
        # sample() runs several times per control period of the walking controller; it evaluates each segment from
        # Python floats computed once on the segment's first use (:meth:`_segment`). The cache relies on the plan's
        # arrays not being written after construction (the plan is frozen; nothing in the package writes them).
        object.__setattr__(self, "_knots", None)
        object.__setattr__(self, "_segments", {})

    def sample(self, t: float) -> ComState:
        """The LIPM state at time ``t`` [s]; before the first knot the first, after the last the resting state."""
        px, py, vx, vy, ax, ay, xx, xy, rx, ry = self.values(t)
        return ComState(
            np.array((px, py)), np.array((vx, vy)), np.array((ax, ay)), np.array((xx, xy)), np.array((rx, ry))
        )

    def values(self, t: float) -> tuple[float, float, float, float, float, float, float, float, float, float]:
        """:meth:`sample` as Python floats: CoM position, velocity, acceleration, DCM and ZMP, (x, y) each."""
        # Scalar math on x and y, with bisect on a list of knot times: on 2-vectors numpy's per-call overhead cost
        # several times the arithmetic, in the walking controller's per-period budget. The operations are those of
        # the vector form in the same order (the results agree to round-off; only exp may differ in the last bit).
        knots: list[float] | None = self._knots  # type: ignore[attr-defined]
        if knots is None:
            knots = self.times.tolist()
            object.__setattr__(self, "_knots", knots)
        if t >= knots[-1]:  # after the last knot: the rest (-1) with the ZMP at the last knot
            k, s = -1, t - knots[-1]
        else:
            k = min(max(bisect.bisect_right(knots, t) - 1, 0), len(knots) - 2)
            s = max(t - knots[k], 0.0)
        segments = self._segments  # type: ignore[attr-defined]
        segment = segments.get(k)
        zx, zy, mx, my, hcx, hcy, dx, dy = segment if segment is not None else self._segment(k)
        # r = r_k + m s; at rest r = r_k as it is (0 * s would be NaN for an infinite pause)
        rx, ry = (zx + mx * s, zy + my * s) if k >= 0 else (zx, zy)
        w = self.omega
        e_grow, e_decay = math.exp(min(w * s, MAX_EXPONENT)), math.exp(-w * s)
        # the divergent term is exactly zero where c is (at rest xi = r, however long the pause: no 0 * inf)
        gx = hcx * e_grow if hcx != 0.0 else 0.0
        gy = hcy * e_grow if hcy != 0.0 else 0.0
        ex, ey = dx * e_decay, dy * e_decay
        px, py = rx + gx + ex, ry + gy + ey
        vx, vy = mx + w * (gx - ex), my + w * (gy - ey)
        w2 = w**2
        return px, py, vx, vy, w2 * (px - rx), w2 * (py - ry), px + vx / w, py + vy / w, rx, ry

    def _segment(self, k: int) -> tuple[float, float, float, float, float, float, float, float]:
        """Coefficients of segment ``k`` (-1: the rest after the last knot) as Python floats, cached:
        ``(r_k x, r_k y, m x, m y, c x / 2, c y / 2, d x, d y)`` of the module docstring's closed form, the ZMP
        ``r_k`` [m] at its start, its slope ``m`` [m/s] (zero at rest) and the terms ``c / 2``, ``d`` [m]."""
        segments: dict[int, tuple[float, float, float, float, float, float, float, float]]
        segments = self._segments  # type: ignore[attr-defined]
        cached = segments.get(k)
        if cached is not None:
            return cached
        zx, zy = self.zmp[k].tolist()
        if k == -1:
            mx = my = 0.0
            # c = xi - r at rest
            cx, cy = self.dcm[-1, 0] - zx, self.dcm[-1, 1] - zy
        else:
            dt = float(self.times[k + 1] - self.times[k])
            mx, my = (self.zmp[k + 1] - self.zmp[k]).tolist()
            mx, my = mx / dt, my / dt
            # c = xi_k - r_k - m / omega
            cx, cy = self.dcm[k, 0] - zx - mx / self.omega, self.dcm[k, 1] - zy - my / self.omega
        hcx, hcy = float(0.5 * cx), float(0.5 * cy)
        # d = x_k - r_k - c / 2
        dx, dy = float(self.com[k, 0] - zx - hcx), float(self.com[k, 1] - zy - hcy)
        cached = (zx, zy, mx, my, hcx, hcy, dx, dy)
        segments[k] = cached
        return cached


class DcmPlanner:
    """Plans the LIPM CoM for a piecewise-linear ZMP reference via the DCM.

    Args:
        com_height: ``z_c`` [m], height of the CoM above the ground, > 0.
        gravity: [m/s^2], > 0.
    """

    def __init__(self, com_height: float, gravity: float = GRAVITY) -> None:
        for name, value in (("com_height", com_height), ("gravity", gravity)):
            if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
                raise ControllerError(f"{name} must be a real number, got {value!r} ({type(value).__name__})")
        if not np.isfinite(com_height) or com_height <= 0.0:
            raise ControllerError(f"com_height must be finite and > 0, got {com_height!r}")
        if not np.isfinite(gravity) or gravity <= 0.0:
            raise ControllerError(f"gravity must be finite and > 0, got {gravity!r}")
        self.com_height = float(com_height)
        self.omega = float(np.sqrt(gravity / com_height))
        if not OMEGA_RANGE[0] <= self.omega <= OMEGA_RANGE[1]:
            raise ControllerError(
                f"com_height={com_height!r} m and gravity={gravity!r} m/s^2 give omega="
                f"{self.omega:.3g} 1/s, outside {OMEGA_RANGE} (a physical LIPM)"
            )

    def dcm_at_knots(self, times: ArrayLike, zmp: ArrayLike) -> NDArray[np.float64]:
        """DCM at every knot by backward recursion from ``xi = r`` at the last knot (the walk ends at rest)."""
        times, zmp = self._check(times, zmp)
        dcm = np.empty_like(zmp)
        dcm[-1] = zmp[-1]
        for k in range(times.size - 2, -1, -1):
            dt = times[k + 1] - times[k]
            slope = (zmp[k + 1] - zmp[k]) / dt
            dcm[k] = (
                zmp[k] + slope / self.omega + (dcm[k + 1] - zmp[k + 1] - slope / self.omega) * np.exp(-self.omega * dt)
            )
        return dcm

    def first_dcm(self, times: ArrayLike, zmp: ArrayLike) -> NDArray[np.float64]:
        """The DCM at the first knot, as :meth:`dcm_at_knots` ``[0]`` but in closed form (no loop over knots).

        The recursion is ``xi_k = a_k + b_k xi_{k+1}`` with ``b_k = e^{-omega dt_k}``, so
        ``xi_0 = sum_j (prod_{i<j} b_i) a_j + (prod_i b_i) r_n``.
        """
        times, zmp = self._check(times, zmp)
        dt = np.diff(times)
        slope = np.diff(zmp, axis=0) / dt[:, None]
        decay = np.exp(-self.omega * dt)
        a = zmp[:-1] + slope / self.omega - (zmp[1:] + slope / self.omega) * decay[:, None]
        weights = np.concatenate([[1.0], np.cumprod(decay)])
        return weights[:-1] @ a + weights[-1] * zmp[-1]

    def plan(self, times: ArrayLike, zmp: ArrayLike, com: ArrayLike) -> DcmPlan:
        """The plan from the CoM ``com`` (x, y) [m] at the first knot; the DCM comes from :meth:`dcm_at_knots`."""
        times, zmp = self._check(times, zmp)
        com = horizontal_point("com", com)
        dcm = self.dcm_at_knots(times, zmp)
        x = np.empty_like(zmp)
        x[0] = com
        w = self.omega
        for k in range(times.size - 1):
            dt = times[k + 1] - times[k]
            slope = (zmp[k + 1] - zmp[k]) / dt
            c = dcm[k] - zmp[k] - slope / w
            d = x[k] - zmp[k] - 0.5 * c
            x[k + 1] = zmp[k + 1] + _divergent(0.5 * c, w * dt) + d * np.exp(-w * dt)
        return DcmPlan(w, times, zmp, dcm, x)

    def start_zmp(self, times: ArrayLike, zmp: ArrayLike, com: ArrayLike) -> NDArray[np.float64]:
        """The first ZMP knot for which the DCM starts at ``com``: a walk that starts from rest (``xd = 0``).

        The DCM at the first knot is affine in the first ZMP knot (``zmp[0]`` is ignored and replaced), so one
        division solves it.
        """
        times, zmp = self._check(times, zmp)
        zmp = zmp.copy()
        com = horizontal_point("com", com)
        zmp[0] = 0.0
        offset = self.dcm_at_knots(times, zmp)[0]
        zmp[0] = 1.0
        gain = self.dcm_at_knots(times, zmp)[0] - offset
        if not np.all(np.abs(gain) > 1e-9):
            raise ControllerError(
                f"the first ZMP knot hardly moves the DCM (gain {gain.tolist()}): the first "
                f"segment of {times[1] - times[0]!r} s is too short for a start from rest"
            )
        zmp[0] = (com - offset) / gain
        return zmp

    @staticmethod
    def _check(times: ArrayLike, zmp: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        times = np.asarray(times, dtype=np.float64)
        zmp = np.asarray(zmp, dtype=np.float64)
        if times.ndim != 1 or times.size < 2 or zmp.shape != (times.size, 2):
            raise ControllerError(f"need >= 2 knot times and a (n, 2) ZMP array, got {times.shape} and {zmp.shape}")
        if not (np.all(np.isfinite(times)) and np.all(np.isfinite(zmp))):
            raise ControllerError("knot times and ZMP must be finite")
        if np.any(np.diff(times) <= 0.0):
            raise ControllerError("knot times must increase strictly")
        return times, zmp

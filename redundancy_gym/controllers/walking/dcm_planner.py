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

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..exceptions import ControllerError

__all__ = ["GRAVITY", "ComState", "DcmPlan", "DcmPlanner"]

GRAVITY = 9.81
"""Gravitational acceleration [m/s^2] of the reduced model."""


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

    def sample(self, t: float) -> ComState:
        """The LIPM state at time ``t`` [s]; before the first knot the first, after the last the resting state."""
        times = self.times
        if t >= times[-1]:
            r = self.zmp[-1]
            x, xi = self.com[-1], self.dcm[-1]
            s = t - times[-1]
            c = xi - r
            d = x - r - 0.5 * c
            position = r + 0.5 * c * np.exp(self.omega * s) + d * np.exp(-self.omega * s)
            velocity = self.omega * (0.5 * c * np.exp(self.omega * s) - d * np.exp(-self.omega * s))
            return self._state(position, velocity, r)
        k = int(np.clip(np.searchsorted(times, t, side="right") - 1, 0, times.size - 2))
        s = max(t - times[k], 0.0)
        slope = (self.zmp[k + 1] - self.zmp[k]) / (times[k + 1] - times[k])
        r = self.zmp[k] + slope * s
        c = self.dcm[k] - self.zmp[k] - slope / self.omega
        d = self.com[k] - self.zmp[k] - 0.5 * c
        grow, decay = np.exp(self.omega * s), np.exp(-self.omega * s)
        position = r + 0.5 * c * grow + d * decay
        velocity = slope + self.omega * (0.5 * c * grow - d * decay)
        return self._state(position, velocity, r)

    def _state(self, position: NDArray[np.float64], velocity: NDArray[np.float64], r: NDArray[np.float64]) -> ComState:
        return ComState(position, velocity, self.omega**2 * (position - r), position + velocity / self.omega, r.copy())


class DcmPlanner:
    """Plans the LIPM CoM for a piecewise-linear ZMP reference via the DCM.

    Args:
        com_height: ``z_c`` [m], height of the CoM above the ground, > 0.
        gravity: [m/s^2], > 0.
    """

    def __init__(self, com_height: float, gravity: float = GRAVITY) -> None:
        if not np.isfinite(com_height) or com_height <= 0.0:
            raise ControllerError(f"com_height must be finite and > 0, got {com_height!r}")
        if not np.isfinite(gravity) or gravity <= 0.0:
            raise ControllerError(f"gravity must be finite and > 0, got {gravity!r}")
        self.com_height = float(com_height)
        self.omega = float(np.sqrt(gravity / com_height))

    def dcm_at_knots(self, times: ArrayLike, zmp: ArrayLike) -> NDArray[np.float64]:
        """DCM at every knot by backward recursion from ``xi = r`` at the last knot (the walk ends at rest)."""
        times, zmp = self._check(times, zmp)
        dcm = np.empty_like(zmp)
        dcm[-1] = zmp[-1]
        for k in range(times.size - 2, -1, -1):
            dt = times[k + 1] - times[k]
            slope = (zmp[k + 1] - zmp[k]) / dt
            dcm[k] = zmp[k] + slope / self.omega + (dcm[k + 1] - zmp[k + 1] - slope / self.omega) * np.exp(-self.omega * dt)
        return dcm

    def plan(self, times: ArrayLike, zmp: ArrayLike, com: ArrayLike) -> DcmPlan:
        """The plan from the CoM ``com`` (x, y) [m] at the first knot; the DCM comes from :meth:`dcm_at_knots`."""
        times, zmp = self._check(times, zmp)
        dcm = self.dcm_at_knots(times, zmp)
        x = np.empty_like(zmp)
        x[0] = np.asarray(com, dtype=np.float64)
        w = self.omega
        for k in range(times.size - 1):
            dt = times[k + 1] - times[k]
            slope = (zmp[k + 1] - zmp[k]) / dt
            c = dcm[k] - zmp[k] - slope / w
            d = x[k] - zmp[k] - 0.5 * c
            x[k + 1] = zmp[k + 1] + 0.5 * c * np.exp(w * dt) + d * np.exp(-w * dt)
        return DcmPlan(w, times, zmp, dcm, x)

    def start_zmp(self, times: ArrayLike, zmp: ArrayLike, com: ArrayLike) -> NDArray[np.float64]:
        """The first ZMP knot for which the DCM starts at ``com``: a walk that starts from rest (``xd = 0``).

        The DCM at the first knot is affine in the first ZMP knot (``zmp[0]`` is ignored and replaced), so one
        division solves it.
        """
        times, zmp = self._check(times, zmp)
        zmp = zmp.copy()
        com = np.asarray(com, dtype=np.float64)
        zmp[0] = 0.0
        offset = self.dcm_at_knots(times, zmp)[0]
        zmp[0] = 1.0
        gain = self.dcm_at_knots(times, zmp)[0] - offset
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

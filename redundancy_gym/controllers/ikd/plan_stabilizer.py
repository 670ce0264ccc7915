"""Stabilization of the IKD via planning (monograph 5.5.3, fig. 5.22): the LIPM plan restarted from the IKD's own
CoM state, with the contact moment modified by a shape function in double support only."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..exceptions import ControllerError

__all__ = ["PlanStabilizer", "PlanStabilizerOutput"]


class PlanStabilizerOutput(NamedTuple):
    """What :meth:`PlanStabilizer.advance` gives for one control period.

    Attributes:
        zmp_shift: the ZMP modification ``Delta p`` [m] (x, y) over the period (zero outside double support).
        com_offset: the restarted plan's CoM minus the original plan's [m] (x, y) at the period's start.
        com_offset_rate: its rate [m/s].
    """

    zmp_shift: NDArray[np.float64]
    com_offset: NDArray[np.float64]
    com_offset_rate: NDArray[np.float64]


class PlanStabilizer:
    """The CoM plan restarted from the IKD's state, its divergent component brought back to the original plan's
    by the end of the coming double support (monograph 5.5.3, "Stabilization via Planning").

    The kinematic IKD realizes the prescribed contact moment exactly, so its CoM drifts from the plan that the
    moment came from (the multi-body's own angular momentum, round-off): on the LIPM the deviation ``delta`` obeys
    ``delta'' = omega^2 (delta - Delta p)`` with ``Delta p`` the ZMP modification. :meth:`replan` restarts the plan
    from the IKD's CoM (``delta`` its deviation from the original plan) and picks the amplitude ``a`` of
    ``Delta p = a phi(t)``, ``phi`` a trapezoid over the double support ``[t_0, t_1]`` (ramps of ``ramp`` of its
    length), that brings the DCM deviation ``e = delta + delta' / omega`` to zero at ``t_1``::

        e(t_1) = e^{omega (t_1 - t)} e(t) - a int_{t_0}^{t_1} omega e^{omega (t_1 - s)} phi(s) ds = 0

    The modification happens while the support polygon is large (both feet down), never near the foot's edge in
    single support. Restarted at the double support's start, the deviation grows only over the double support
    (``e^{omega (t_1 - t_0)}``, about 1.7 for 0.16 s; restarted at the step's start it grows about 8-fold over the
    single support first, and a centimetre then needs 40 cm of ZMP shift). ``|a|`` is limited to ``max_shift``
    per axis; at ``t_1`` the restarted plan keeps only its convergent part (the DCM deviation that ``a`` could not
    remove is dropped, so the plan never diverges) and the contact-moment feedback (5.97) pulls the CoM to it
    (together: the hybrid stabilization of fig. 5.24). :meth:`advance` propagates the restarted plan's deviation
    over each period exactly (the ZMP shift held over the period).

    Args:
        omega: ``sqrt(g / z_c)`` [1/s] of the LIPM.
        ramp: share of the double support in each ramp of the trapezoid, in (0, 0.5].
        max_shift: largest ZMP modification [m] per axis.
    """

    def __init__(self, omega: float, *, ramp: float = 0.25, max_shift: float = 0.05) -> None:
        if not math.isfinite(omega) or omega <= 0.0:
            raise ControllerError(f"omega must be finite and > 0 [1/s], got {omega!r}")
        if not 0.0 < ramp <= 0.5:
            raise ControllerError(f"ramp must lie in (0, 0.5], got {ramp!r}")
        if not math.isfinite(max_shift) or max_shift < 0.0:
            raise ControllerError(f"max_shift must be finite and >= 0 [m], got {max_shift!r}")
        self.omega = float(omega)
        self.ramp = float(ramp)
        self.max_shift = float(max_shift)
        self.reset()

    def reset(self) -> None:
        """No deviation from the original plan, no modification planned."""
        self.offset = np.zeros(2)
        self.offset_rate = np.zeros(2)
        self.amplitude = np.zeros(2)
        self.window = (math.inf, math.inf)

    def shape(self, t: float) -> float:
        """``phi(t)`` in [0, 1]: the trapezoid over the planned double support (0 outside it)."""
        t0, t1 = self.window
        if not t0 < t < t1:
            return 0.0
        rise = self.ramp * (t1 - t0)
        return min(1.0, (t - t0) / rise, (t1 - t) / rise)

    def _influence(self, t0: float, t1: float) -> float:
        """``int_{t0}^{t1} omega e^{omega (t1 - s)} phi(s) ds`` in closed form (the trapezoid's three pieces)."""
        w = self.omega
        rise = self.ramp * (t1 - t0)

        def ramp_integral(a: float, b: float, up: bool) -> float:
            # int_a^b omega e^{omega (t1 - s)} l(s) ds, l linear from 0 to 1 (up) or 1 to 0 over [a, b], by parts
            ea, eb = math.exp(w * (t1 - a)), math.exp(w * (t1 - b))
            mean = (ea - eb) / (w * (b - a))
            return mean - eb if up else ea - mean

        rising = ramp_integral(t0, t0 + rise, up=True)
        flat = math.exp(w * (t1 - t0 - rise)) - math.exp(w * rise)
        falling = ramp_integral(t1 - rise, t1, up=False)
        return rising + flat + falling

    def replan(
        self, t: float, com_deviation: ArrayLike, com_velocity_deviation: ArrayLike, double_support: tuple[float, float]
    ) -> NDArray[np.float64]:
        """Restart the plan at ``t`` [s] from the IKD's CoM deviation from the original plan (``com_deviation``
        [m], ``com_velocity_deviation`` [m/s], horizontal) and plan the ZMP modification over ``double_support``
        ``(t_0, t_1)`` [s] (``t < t_1``; a window already begun starts at ``t``). Returns the amplitude ``a`` [m]
        (x, y)."""
        deviation = np.asarray(com_deviation, dtype=np.float64)
        rate = np.asarray(com_velocity_deviation, dtype=np.float64)
        if (
            deviation.shape != (2,)
            or rate.shape != (2,)
            or not (np.all(np.isfinite(deviation)) and np.all(np.isfinite(rate)))
        ):
            raise ControllerError("com_deviation and com_velocity_deviation must be finite (x, y)")
        t0, t1 = (float(v) for v in double_support)
        if not (math.isfinite(t) and math.isfinite(t0) and t < t1 < math.inf and t0 < t1):
            raise ControllerError(f"double_support must end after t={t!r} and have t_0 < t_1, got {double_support!r}")
        t0 = max(t0, t)
        self.offset, self.offset_rate = deviation.copy(), rate.copy()
        self.window = (t0, t1)
        divergent = deviation + rate / self.omega
        growth = math.exp(self.omega * (t1 - t))
        self.amplitude = np.clip(divergent * growth / self._influence(t0, t1), -self.max_shift, self.max_shift)
        return self.amplitude.copy()

    def advance(self, t: float, dt: float) -> PlanStabilizerOutput:
        """The modification over ``[t, t + dt]`` and the restarted plan's deviation at ``t``; then moves the
        deviation to ``t + dt`` (exact LIPM solution with the ZMP shift held at the period's mid-point value)."""
        shift_x, shift_y, offset_x, offset_y, rate_x, rate_y = self._advance(t, dt)
        return PlanStabilizerOutput(
            np.array([shift_x, shift_y]), np.array([offset_x, offset_y]), np.array([rate_x, rate_y])
        )

    def _advance(self, t: float, dt: float) -> tuple[float, float, float, float, float, float]:
        """:meth:`advance` as plain floats ``(zmp_shift, com_offset, com_offset_rate)`` (x, y each): the same
        arithmetic per axis as on the arrays, without their overhead."""
        phi = self.shape(t + 0.5 * dt)
        amplitude_x, amplitude_y = self.amplitude.tolist()
        offset_x, offset_y = self.offset.tolist()
        rate_x, rate_y = self.offset_rate.tolist()
        shift_x, shift_y = amplitude_x * phi, amplitude_y * phi
        w = self.omega
        c, s = math.cosh(w * dt), math.sinh(w * dt)
        ratio, gain = s / w, w * s
        relative_x, relative_y = offset_x - shift_x, offset_y - shift_y
        new_x = shift_x + relative_x * c + rate_x * ratio
        new_y = shift_y + relative_y * c + rate_y * ratio
        if t + dt >= self.window[1]:  # past the double support: the convergent part only (DCM deviation 0)
            self.offset_rate = np.array([-w * new_x, -w * new_y])
            self.amplitude = np.zeros(2)
            self.window = (math.inf, math.inf)
        else:
            self.offset_rate = np.array([relative_x * gain + rate_x * c, relative_y * gain + rate_y * c])
        self.offset = np.array([new_x, new_y])
        return shift_x, shift_y, offset_x, offset_y, rate_x, rate_y

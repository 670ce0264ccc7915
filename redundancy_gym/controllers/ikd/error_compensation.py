"""Dynamics error compensation (Takenaka et al. 2009b, monograph fig. 5.26 and (5.98)): the contact-moment error of
the full multi-body model drives an inverted-pendulum model whose CoM offset is added to the planned CoM, the
pendulum kept upright by a real PD controller that modifies the contact moment."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...constants import GRAVITY
from ..exceptions import ControllerError

__all__ = ["ErrorCompensation", "ErrorCompensationOutput"]


class ErrorCompensationOutput(NamedTuple):
    """What :meth:`ErrorCompensation.step` gives for one control period.

    Attributes:
        com_offset: the pendulum's CoM offset ``d`` [m] (x, y) at the period's start: add it to the planned CoM.
        com_offset_rate: its rate [m/s].
        moment_modification: ``Delta T = (Delta T_x, Delta T_y)`` [N m], the PD's modification of the contact
            moment over the period: the compensated motion needs ``T_ref + Delta T`` (to the pendulum model's
            accuracy) instead of ``T_ref``.
        saturated: whether the modification was clipped to ``max_moment`` on either axis.
    """

    com_offset: NDArray[np.float64]
    com_offset_rate: NDArray[np.float64]
    moment_modification: NDArray[np.float64]
    saturated: bool


class ErrorCompensation:
    """Feed-forward dynamics error compensation with an inverted-pendulum model (IPM), per horizontal axis.

    Takenaka's method as the monograph describes it (fig. 5.26): the contact moment that the full model's inverse
    dynamics give for the planned motion, ``T_full``, differs from the reference ``T_ref`` the simplified model was
    planned for. The difference drives an IPM (mass ``m`` at height ``z_c``); its CoM offset ``d`` is added to the
    planned CoM, so that the offset's own contact moment cancels the error. The IPM alone diverges, so a real PD
    controller (5.98), ``C(s) = K_R (T_R s + 1) / (T_d s + 1)``, modifies the contact moment by ``C d`` to keep it
    upright. Written with the "ZMP moment" ``u = (-T_y, T_x)`` (the vertical force times the ZMP, per axis x, y;
    ``T`` about the world's horizontal axes, as :class:`~redundancy_gym.controllers.ikd.BipedIkd` prescribes it)::

        m z_c d'' = m g d + e - u_c,     e = u_full - u_ref,     u_c = sat(C(s) d)

    The compensated motion's ZMP moment is ``u_ref + u_c`` (the pendulum's own, ``m g d - m z_c d''``, cancels
    ``e``). For a constant error the offset settles at ``d = e / (K_R - m g)`` and the modification at ``K_R e /
    (K_R - m g)``; errors faster than the closed loop (about 7 rad/s with the monograph's gains on a 60 kg robot)
    are cancelled, slower ones are not. The closed loop is stable when the characteristic polynomial ``m z_c T_d
    s^3 + m z_c s^2 + (K_R T_R - m g T_d) s + (K_R - m g)`` is Hurwitz (:attr:`closed_loop_stable`): in
    particular ``K_R > m g``.

    Discretization at the control period ``h``: the PD by Tustin's rule (bilinear, ``s = (2 / h) (z - 1) / (z +
    1)``, its frequency response exact at the pre-warped frequency ``(2 / h) tan(omega h / 2)``); the pendulum
    exactly for an input held over the period (zero-order hold: ``d + a / omega^2`` grows as ``cosh``/``sinh``).
    The PD reads the offset at the period's start (no algebraic loop). With ``max_moment`` the modification is
    clipped per axis to ``+-max_moment`` before it enters the pendulum; the filter's own state stays unclipped
    (it is a lead filter with no integrator to wind up).

    Args:
        mass: the robot's mass ``m`` [kg].
        com_height: the pendulum's height ``z_c`` [m].
        period: the control period ``h`` [s].
        gain: ``K_R`` [N m/m] (moment per metre of offset; the monograph's 3200 for Lola's 60 kg).
        lead: ``T_R`` [s].
        lag: ``T_d`` [s] (> 0: Tustin's rule on an ideal PD would ring at the Nyquist frequency).
        max_moment: the largest modification [N m] per axis (None: no saturation).
        gravity: ``g`` [m/s^2].
    """

    def __init__(
        self,
        mass: float,
        com_height: float,
        period: float,
        *,
        gain: float = 3200.0,
        lead: float = 0.2,
        lag: float = 0.02,
        max_moment: float | None = None,
        gravity: float = GRAVITY,
    ) -> None:
        for name, value, unit in (
            ("mass", mass, "kg"),
            ("com_height", com_height, "m"),
            ("period", period, "s"),
            ("lag", lag, "s"),
            ("gravity", gravity, "m/s^2"),
        ):
            if not _real(value) or not math.isfinite(value) or value <= 0.0:
                raise ControllerError(f"{name} must be finite and > 0 [{unit}], got {value!r}")
        for name, value, unit in (("gain", gain, "N m/m"), ("lead", lead, "s")):
            if not _real(value) or not math.isfinite(value) or value < 0.0:
                raise ControllerError(f"{name} must be finite and >= 0 [{unit}], got {value!r}")
        if max_moment is not None and (not _real(max_moment) or not math.isfinite(max_moment) or max_moment <= 0.0):
            raise ControllerError(f"max_moment must be None or finite and > 0 [N m], got {max_moment!r}")
        self.mass, self.com_height, self.period = float(mass), float(com_height), float(period)
        self.gain, self.lead, self.lag = float(gain), float(lead), float(lag)
        self.max_moment = None if max_moment is None else float(max_moment)
        self.gravity = float(gravity)
        self.omega = math.sqrt(self.gravity / self.com_height)
        self.inertia = self.mass * self.com_height  # m z_c [kg m]: moment per CoM acceleration
        # Tustin: C(z) = (b0 + b1 z^-1) / (1 + a1 z^-1)
        h = self.period
        denominator = 2.0 * self.lag / h + 1.0
        self._b0 = self.gain * (2.0 * self.lead / h + 1.0) / denominator
        self._b1 = self.gain * (1.0 - 2.0 * self.lead / h) / denominator
        self._a1 = (1.0 - 2.0 * self.lag / h) / denominator
        # exact transition of d'' = omega^2 d over one period
        self._cosh, self._sinh = math.cosh(self.omega * h), math.sinh(self.omega * h)
        self.reset()

    @property
    def closed_loop_stable(self) -> bool:
        """Whether the continuous closed loop of pendulum and PD is stable (Routh-Hurwitz on its cubic)."""
        m, mz = self.mass, self.inertia
        a3, a2 = mz * self.lag, mz
        a1 = self.gain * self.lead - m * self.gravity * self.lag
        a0 = self.gain - m * self.gravity
        return a3 > 0.0 and a2 > 0.0 and a1 > 0.0 and a0 > 0.0 and a2 * a1 > a3 * a0

    def reset(self) -> None:
        """No offset, the PD at rest."""
        self.offset = np.zeros(2)
        self.offset_rate = np.zeros(2)
        self._previous_offset = np.zeros(2)
        self._previous_output = np.zeros(2)

    def step(self, reference_moment: ArrayLike, full_moment: ArrayLike) -> ErrorCompensationOutput:
        """One control period: the offset at its start and the moment modification over it, for the reference
        contact moment ``T_ref`` and the full model's ``T_full`` [N m] (each ``(T_x, T_y)`` about the world's
        horizontal axes); then moves the pendulum to the period's end (:attr:`offset`, :attr:`offset_rate`)."""
        reference = _moment(reference_moment, "reference_moment")
        full = _moment(full_moment, "full_moment")
        # per axis x, y the ZMP moment u = (-T_y, T_x)
        error = np.array([-(full[1] - reference[1]), full[0] - reference[0]])
        d = self.offset
        output = self._b0 * d + self._b1 * self._previous_offset - self._a1 * self._previous_output
        self._previous_offset, self._previous_output = d.copy(), output
        control, saturated = output, False
        if self.max_moment is not None:
            control = np.clip(output, -self.max_moment, self.max_moment)
            saturated = bool(np.any(control != output))
        result = ErrorCompensationOutput(
            d.copy(), self.offset_rate.copy(), np.array([control[1], -control[0]]), saturated
        )
        # m z_c d'' = m g d + e - u_c, the input held: D = d + (e - u_c) / (m g) obeys D'' = omega^2 D
        shift = (error - control) / (self.mass * self.gravity)
        w, c, s = self.omega, self._cosh, self._sinh
        relative = d + shift
        self.offset = relative * c + self.offset_rate * (s / w) - shift
        self.offset_rate = relative * (w * s) + self.offset_rate * c
        return result


def _real(value: object) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))


def _moment(value: ArrayLike, name: str) -> NDArray[np.float64]:
    try:
        moment = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ControllerError(f"{name} must be a finite (T_x, T_y) [N m], got {value!r}") from None
    if moment.shape != (2,) or not np.all(np.isfinite(moment)):
        raise ControllerError(f"{name} must be a finite (T_x, T_y) [N m], got {value!r}")
    return moment

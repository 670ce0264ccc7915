"""Balance stabilization by CoM admittance on the measured ZMP and the divergent component of motion.

The fig. 4.3 scheme for a position-controlled robot: measured foot wrenches (the ZMP) and the measured state
(CoM and its velocity from the joint angles and the IMU-derived base pose) modify the task-space references
that the whole-body IK turns into joint position targets.

1. DCM feedback picks the ZMP that would bring the measured DCM back to the plan:
   ``r_d = r_ref + k_dcm (xi_m - xi_ref)`` (a DCM ahead of the plan asks for a ZMP further ahead).
2. The CoM reference is shifted by ``delta``, with the LIPM tracking law of Kajita et al. (2010):
   ``delta_dot = -k_zmp (r_d - r_m) + k_com (c_ref - c_m)``, ``c_ref`` the planned CoM; a measured ZMP behind the
   desired one slows the CoM down, which moves the ZMP forward.
The measured ZMP passes a first-order low-pass filter (``zmp_filter``): it jumps at every touchdown.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..exceptions import ControllerError

__all__ = ["Stabilizer", "StabilizerGains", "StabilizerOutput"]


@dataclass(frozen=True)
class StabilizerGains:
    """Gains of :class:`Stabilizer` (all >= 0; zeros switch the feedback off).

    Attributes:
        dcm: ``k_dcm`` [-], DCM error to ZMP shift.
        zmp: ``k_zmp`` [1/s], ZMP error to CoM velocity.
        com: ``k_com`` [1/s], CoM error (plan minus measurement) to CoM velocity.
        zmp_filter: time constant of the measured-ZMP low-pass [s].
        max_offset: largest horizontal CoM offset [m].
    """

    dcm: float = 1.0
    zmp: float = 1.0
    com: float = 1.0
    zmp_filter: float = 0.02
    max_offset: float = 0.1

    def __post_init__(self) -> None:
        for name in ("dcm", "zmp", "com", "zmp_filter", "max_offset"):
            value = getattr(self, name)
            if not np.isfinite(value) or value < 0.0:
                raise ControllerError(f"stabilizer gain {name} must be finite and >= 0, got {value!r}")

    @property
    def active(self) -> bool:
        """Whether any feedback is on."""
        return self.dcm > 0.0 or self.zmp > 0.0 or self.com > 0.0


class StabilizerOutput(NamedTuple):
    """What :meth:`Stabilizer.update` gives.

    Attributes:
        offset: horizontal CoM reference offset ``delta`` [m].
        rate: its rate [m/s] (added to the CoM velocity reference).
        desired_zmp: ``r_d`` [m].
        measured_zmp: filtered measured ZMP [m].
        dcm_error: ``xi_m - xi_ref`` [m].
    """

    offset: NDArray[np.float64]
    rate: NDArray[np.float64]
    desired_zmp: NDArray[np.float64]
    measured_zmp: NDArray[np.float64]
    dcm_error: NDArray[np.float64]


class Stabilizer:
    """CoM admittance on ZMP and DCM errors (see the module docstring).

    Args:
        gains: feedback gains.
        omega: LIPM ``omega = sqrt(g / z_c)`` [1/s].
    """

    def __init__(self, gains: StabilizerGains, omega: float) -> None:
        if not np.isfinite(omega) or omega <= 0.0:
            raise ControllerError(f"omega must be finite and > 0, got {omega!r}")
        self.gains = gains
        self.omega = float(omega)
        self.reset()

    def reset(self) -> None:
        """Zero offset and forget the filtered ZMP."""
        self._offset = np.zeros(2)
        self._zmp: NDArray[np.float64] | None = None

    def update(self, dt: float, com_ref: ArrayLike, dcm_ref: ArrayLike, zmp_ref: ArrayLike, com: ArrayLike,
               com_velocity: ArrayLike, zmp: ArrayLike | None) -> StabilizerOutput:
        """Advance one control period ``dt`` [s] from the plan (``*_ref``) and the measurement (x, y) [m, m/s].

        ``zmp`` None (no loaded foot) keeps the last filtered value.
        """
        g = self.gains
        if not np.isfinite(dt) or dt <= 0.0:
            raise ControllerError(f"dt must be finite and > 0, got {dt!r}")
        com_ref, dcm_ref, zmp_ref = (np.asarray(v, dtype=np.float64)[:2] for v in (com_ref, dcm_ref, zmp_ref))
        com, com_velocity = np.asarray(com, dtype=np.float64)[:2], np.asarray(com_velocity, dtype=np.float64)[:2]
        for name, value in (("com_ref", com_ref), ("dcm_ref", dcm_ref), ("zmp_ref", zmp_ref), ("com", com),
                            ("com_velocity", com_velocity)):
            if value.shape != (2,) or not np.all(np.isfinite(value)):
                raise ControllerError(f"{name} must be a finite (x, y), got {value!r}")
        dcm_error = com + com_velocity / self.omega - dcm_ref
        desired = zmp_ref + g.dcm * dcm_error
        if zmp is not None:
            zmp = np.asarray(zmp, dtype=np.float64)[:2]
            if zmp.shape != (2,) or not np.all(np.isfinite(zmp)):
                raise ControllerError(f"zmp must be None or a finite (x, y), got {zmp!r}")
            if self._zmp is None:
                self._zmp = zmp.copy()
            else:
                self._zmp += (dt / (g.zmp_filter + dt)) * (zmp - self._zmp)
        measured = desired if self._zmp is None else self._zmp
        rate = -g.zmp * (desired - measured) + g.com * (com_ref - com)
        offset = self._offset + rate * dt
        norm = float(np.linalg.norm(offset))
        if norm > g.max_offset:
            offset *= g.max_offset / norm
            rate = (offset - self._offset) / dt
        self._offset = offset
        return StabilizerOutput(offset.copy(), rate, desired, measured.copy(), dcm_error)

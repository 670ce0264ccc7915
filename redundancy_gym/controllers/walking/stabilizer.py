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

import math
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
        # the state as Python floats (x, y) [m]: the update runs once per control period in scalar math
        self._offset: tuple[float, float] = (0.0, 0.0)
        self._zmp: tuple[float, float] | None = None

    def update(
        self,
        dt: float,
        com_ref: ArrayLike,
        dcm_ref: ArrayLike,
        zmp_ref: ArrayLike,
        com: ArrayLike,
        com_velocity: ArrayLike,
        zmp: ArrayLike | None,
    ) -> StabilizerOutput:
        """Advance one control period ``dt`` [s] from the plan (``*_ref``) and the measurement (x, y) [m, m/s].

        Each point may have more entries (a 3-D CoM): its first two are used. ``zmp`` None (no loaded foot) keeps
        the last filtered value.
        """
        # Scalar math on x and y: on 2-vectors numpy's per-call overhead cost several times the arithmetic, in the
        # walking controller's per-period budget. The operations are those of the vector form in the same order.
        if not (isinstance(dt, float) and 0.0 < dt < math.inf):  # the usual float dt passes without numpy
            if not np.isfinite(dt) or dt <= 0.0:
                raise ControllerError(f"dt must be finite and > 0, got {dt!r}")
        # Python floats throughout: a NumPy scalar (float32 dt or gain) would otherwise set the precision
        dt = float(dt)
        g = self.gains
        k_dcm, k_zmp, k_com, max_offset = float(g.dcm), float(g.zmp), float(g.com), float(g.max_offset)
        points = (com_ref, dcm_ref, zmp_ref, com, com_velocity)
        if all(map(_is_float_vector, points)):  # the arrays of the controller: read without a conversion
            xy = [(p.item(0), p.item(1)) for p in points]  # type: ignore[union-attr]
        else:
            xy = _checked_points(points)
        (crx, cry), (xrx, xry), (zrx, zry), (cx, cy), (vx, vy) = xy
        # one finite check for all ten numbers (NaN and inf survive a sum); the message names the bad point
        if not math.isfinite(crx + cry + xrx + xry + zrx + zry + cx + cy + vx + vy):
            _checked_points(points)  # raises, unless the sum only overflowed
        w = self.omega
        ex, ey = cx + vx / w - xrx, cy + vy / w - xry  # dcm_error
        dx, dy = zrx + k_dcm * ex, zry + k_dcm * ey  # desired ZMP
        if zmp is not None:
            zx, zy = _zmp_point(zmp)
            if self._zmp is None:
                self._zmp = (zx, zy)
            else:
                fx, fy = self._zmp
                gain = dt / (float(g.zmp_filter) + dt)
                self._zmp = (fx + gain * (zx - fx), fy + gain * (zy - fy))
        mx, my = (dx, dy) if self._zmp is None else self._zmp  # measured ZMP
        rx, ry = -k_zmp * (dx - mx) + k_com * (crx - cx), -k_zmp * (dy - my) + k_com * (cry - cy)  # rate
        px, py = self._offset
        ox, oy = px + rx * dt, py + ry * dt
        norm = math.sqrt(ox * ox + oy * oy)  # as np.linalg.norm computes it (hypot rounds differently)
        if norm > max_offset:
            scale = max_offset / norm
            ox, oy = ox * scale, oy * scale
            rx, ry = (ox - px) / dt, (oy - py) / dt
        self._offset = (ox, oy)
        return StabilizerOutput(
            np.array((ox, oy)), np.array((rx, ry)), np.array((dx, dy)), np.array((mx, my)), np.array((ex, ey))
        )


_FLOAT64 = np.dtype(np.float64)
_POINT_NAMES = ("com_ref", "dcm_ref", "zmp_ref", "com", "com_velocity")


def _is_float_vector(value: object) -> bool:
    """Whether ``value`` is a 1-D float64 array of at least 2 entries: then ``np.asarray(value, np.float64)[:2]``
    are its first two entries, which :meth:`Stabilizer.update` reads without that conversion."""
    return type(value) is np.ndarray and value.dtype == _FLOAT64 and value.ndim == 1 and value.shape[0] >= 2


def _checked_points(values: tuple[ArrayLike, ...]) -> list[tuple[float, float]]:
    """The first two entries of each of :meth:`Stabilizer.update`'s points (``_POINT_NAMES``) as floats;
    ControllerError naming the first one that is not a finite (x, y)."""
    arrays = [np.asarray(v, dtype=np.float64)[:2] for v in values]
    for name, value in zip(_POINT_NAMES, arrays, strict=False):
        if value.shape != (2,) or not np.all(np.isfinite(value)):
            raise ControllerError(f"{name} must be a finite (x, y), got {value!r}")
    return [(a.item(0), a.item(1)) for a in arrays]


def _zmp_point(zmp: ArrayLike) -> tuple[float, float]:
    """The measured ZMP's first two entries as floats; ControllerError unless they are a finite (x, y)."""
    if _is_float_vector(zmp):
        x, y = zmp.item(0), zmp.item(1)  # type: ignore[union-attr]
        if math.isfinite(x + y):
            return x, y
    point = np.asarray(zmp, dtype=np.float64)[:2]
    if point.shape != (2,) or not np.all(np.isfinite(point)):
        raise ControllerError(f"zmp must be None or a finite (x, y), got {point!r}")
    return point.item(0), point.item(1)

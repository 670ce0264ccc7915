"""The ZMP and the per-foot centres of pressure from the two ankle force/torque sensors."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..exceptions import ControllerError

__all__ = ["ZmpEstimate", "estimate_zmp"]


class ZmpEstimate(NamedTuple):
    """Ground contact seen by the ankle sensors (world frame).

    Attributes:
        zmp: ZMP (x, y) [m] of both feet together; None when no foot carries ``min_force``.
        cop: centre of pressure (x, y) [m] per foot (rows right, left); NaN for an unloaded foot.
        normal_force: vertical ground reaction [N] per foot.
        moment: ground reaction moment about each ankle [N m] (rows right, left).
    """

    zmp: NDArray[np.float64] | None
    cop: NDArray[np.float64]
    normal_force: NDArray[np.float64]
    moment: NDArray[np.float64]


def estimate_zmp(rotations: ArrayLike, ankles: ArrayLike, forces: ArrayLike, torques: ArrayLike,
                 ground: float = 0.0, min_force: float = 20.0) -> ZmpEstimate:
    """ZMP from the wrenches that the shanks feel at the ankle sensors.

    The sensor measures what the foot exerts on the shank in the sensor frame; the ground reaction on the
    foot is its negative (the foot's own weight and inertia, about 2 % of the robot's, are neglected). With the
    reaction ``F``, ``T`` about the ankle ``a`` at height ``h`` above the ground, the centre of pressure is
    ``a + (-(T_y + h F_x), T_x - h F_y) / F_z`` and the ZMP the ``F_z``-weighted mean of the loaded feet.

    Args:
        rotations: sensor frame orientations in the world (2, 3, 3), right then left.
        ankles: sensor positions [m] (2, 3).
        forces, torques: sensor readings [N, N m] in the sensor frames (2, 3).
        ground: ground height [m].
        min_force: vertical force [N] below which a foot counts as unloaded.
    """
    rotations = np.asarray(rotations, dtype=np.float64)
    ankles = np.asarray(ankles, dtype=np.float64)
    forces = np.asarray(forces, dtype=np.float64)
    torques = np.asarray(torques, dtype=np.float64)
    if rotations.shape != (2, 3, 3) or ankles.shape != (2, 3) or forces.shape != (2, 3) or torques.shape != (2, 3):
        raise ControllerError("need rotations (2, 3, 3) and ankles, forces, torques (2, 3)")
    for name, value in (("rotations", rotations), ("ankles", ankles), ("forces", forces), ("torques", torques)):
        if not np.all(np.isfinite(value)):
            raise ControllerError(f"the ankle sensor {name} must be finite, got {value.tolist()}")
    reaction = -(rotations @ forces[:, :, None])[:, :, 0]
    moment = -(rotations @ torques[:, :, None])[:, :, 0]
    cop = np.full((2, 2), np.nan)
    fz = reaction[:, 2]
    total, weighted = 0.0, np.zeros(2)
    for i in range(2):
        if fz[i] < min_force:
            continue
        h = ankles[i, 2] - ground
        cop[i] = ankles[i, :2] + np.array([-(moment[i, 1] + h * reaction[i, 0]),
                                           moment[i, 0] - h * reaction[i, 1]]) / fz[i]
        total += fz[i]
        weighted += fz[i] * cop[i]
    return ZmpEstimate(weighted / total if total > 0.0 else None, cop, fz, moment)

"""The ZMP and the per-foot centres of pressure from the two ankle force/torque sensors."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, NamedTuple

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


def estimate_zmp(
    rotations: ArrayLike,
    ankles: ArrayLike,
    forces: ArrayLike,
    torques: ArrayLike,
    ground: float = 0.0,
    min_force: float = 20.0,
) -> ZmpEstimate:
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
    # Scalar math on Python lists: on (2, 3) arrays numpy's per-call overhead cost several times the arithmetic, in
    # the walking controller's per-period budget. The results agree with the matrix form to round-off (numpy's
    # matmul may sum in another order or fuse multiply and add).
    lists: Sequence[Any]  # the four inputs as nested lists
    if all(map(_is_float_array, (rotations, ankles, forces, torques), _SHAPES)):  # the controller's arrays
        lists = rotations.tolist(), ankles.tolist(), forces.tolist(), torques.tolist()  # type: ignore[union-attr]
    else:
        lists = _checked_lists(rotations, ankles, forces, torques)
    rotation_lists, ankle_list, force_list, torque_list = lists
    # the ground reaction on each foot, F and T, in the world frame: minus the sensor reading, rotated
    reaction, moment = _negated_in_world(rotation_lists, force_list), _negated_in_world(rotation_lists, torque_list)
    # one finite check: a non-finite sensor value makes a reaction or moment non-finite (NaN and inf survive
    # products and sums); the detailed check names the bad input, or passes when the sum only overflowed
    if not math.isfinite(
        sum(reaction[0]) + sum(reaction[1]) + sum(moment[0]) + sum(moment[1]) + sum(ankle_list[0]) + sum(ankle_list[1])
    ):
        _checked_lists(rotations, ankles, forces, torques)
    ground, min_force = float(ground), float(min_force)  # Python floats: a NumPy scalar would set the precision
    cop = [[math.nan, math.nan], [math.nan, math.nan]]
    total, weighted_x, weighted_y = 0.0, 0.0, 0.0
    for i in range(2):
        (fx, fy, fz), (mx, my, _), (ax, ay, az) = reaction[i], moment[i], ankle_list[i]
        if fz < min_force:
            continue
        h = az - ground
        x, y = ax + -(my + h * fx) / fz, ay + (mx - h * fy) / fz
        cop[i] = [x, y]
        total += fz
        weighted_x, weighted_y = weighted_x + fz * x, weighted_y + fz * y
    zmp = np.array((weighted_x / total, weighted_y / total)) if total > 0.0 else None
    return ZmpEstimate(zmp, np.array(cop), np.array((reaction[0][2], reaction[1][2])), np.array(moment))


_FLOAT64 = np.dtype(np.float64)
_SHAPES = ((2, 3, 3), (2, 3), (2, 3), (2, 3))
"""Shapes of :func:`estimate_zmp`'s rotations, ankles, forces and torques."""
_NAMES = ("rotations", "ankles", "forces", "torques")


def _is_float_array(value: object, shape: tuple[int, ...]) -> bool:
    """Whether ``value`` is a float64 array of ``shape``: then ``np.asarray(value, np.float64)`` is ``value``."""
    return type(value) is np.ndarray and value.dtype == _FLOAT64 and value.shape == shape


def _negated_in_world(rotations: list[list[list[float]]], vectors: list[list[float]]) -> list[list[float]]:
    """``-R_i v_i`` for each foot ``i`` (rows right, left): a sensor reading turned into the world frame, negated."""
    return [
        [-(r[0] * v[0] + r[1] * v[1] + r[2] * v[2]) for r in rotation]
        for rotation, v in zip(rotations, vectors, strict=False)
    ]


def _checked_lists(*values: ArrayLike) -> list[list[Any]]:
    """:func:`estimate_zmp`'s rotations, ankles, forces and torques as nested lists of floats; ControllerError for a
    wrong shape or, naming the input, a non-finite value."""
    arrays = [np.asarray(v, dtype=np.float64) for v in values]
    if any(a.shape != shape for a, shape in zip(arrays, _SHAPES, strict=False)):
        raise ControllerError("need rotations (2, 3, 3) and ankles, forces, torques (2, 3)")
    for name, value in zip(_NAMES, arrays, strict=False):
        if not np.all(np.isfinite(value)):
            raise ControllerError(f"the ankle sensor {name} must be finite, got {value.tolist()}")
    return [a.tolist() for a in arrays]

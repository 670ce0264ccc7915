"""Stance soles that take the tilt of rough ground: the IK's kinematic model stands on the sole as it really lies.

A rigid sole on rough ground rests on its two or three highest points and lies tilted by a few degrees (a 15 cm
wide sole over bumps 1-3 cm high: up to 8 deg). The whole-body IK plans with the sole flat on its foothold, so a
position-controlled leg holds the pelvis at the plan's attitude *relative to the sole*: the whole robot leans with
the sole, its CoM 0.9 m above the foot moves by up to 12 cm, and the next swing foot arrives tilted and centimetres
off in height. Measured on BipedTerrain's rough ground: pelvis rolls of 6-14 deg and touchdown forces of 2-4 kN,
falls within two metres (docs/terrain.md).

This component measures the tilt of each loaded stance sole against its planned orientation (the measured sole
rotation in the plan's frame, from the IMU's base pose and the joint angles) and turns the sole's reference
orientation towards it through a first-order low-pass: the kinematic model then stands on the tilted sole as the
robot does and the IK keeps the pelvis, the CoM and the swing foot where the plan wants them in the world. This is
the inverse of a stiff ankle: the ground sets the sole's attitude, the joints keep the body's (the "ground
adaptation" of the ankle in Kajita et al. 2010's foot torque control, here kinematic).

Following the sole must not become following a sole that tips over its edge: that takes away the ankle's
resistance, the one thing that stops the tipping (stepping stones fell in half the walks with the adaptation
everywhere; on rough ground a tilt that ran to 11 deg in single support ended a walk). Hence three guards:

- it acts only on footholds planned on rough ground (:attr:`~.terrain_map.Foothold.roughness` above
  ``min_roughness``): on a flat tread or stone, a sole that tilts is tipping;
- the tilt taken is bounded by what the ground's roughness allows: ``atan(roughness / width)``, the sole's width
  ``2 SOLE_HALF_WIDTH`` over the peak-to-peak height under it (and ``max_tilt``);
- it holds while the sole's centre of pressure lies within ``edge_margin`` of the sole's edge (the sole turning
  about that edge is tipping, not settling).

A foot in the air returns to the plan's orientation with ``release``.

Holding a tipping sole is not resisting it. In single support the stance sole on rough ground is also pressed
towards the stabilizer's desired ZMP: its tilt turns at ``cop_gain`` times the desired minus the measured centre of
pressure in the sole's frame, the sole's edge on the desired side pressed down (toes down for a desired CoP ahead,
the left edge down for one to the left), the damping control of the ankle in Kajita et al. 2010 on the kinematic
reference, within the same bound. A sole rolling onto an edge or its heel is so pressed down on the other side
instead of followed: on the development walks 19 of 32 against 14 of 32, falls 7 against 16, the roll doing the
work (docs/terrain.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ...validation import check_real
from ..exceptions import ControllerError
from .support_polygon import SOLE_HALF_WIDTH, SOLE_X
from .terrain_map import TerrainMapConfig

__all__ = ["SoleTilt", "SoleTiltConfig"]


@dataclass(frozen=True)
class SoleTiltConfig:
    """Parameters of :class:`SoleTilt`.

    Attributes:
        time_constant: of the low-pass from the measured to the reference tilt [s] (> 0).
        max_tilt: largest tilt [rad] about either axis taken into the reference (> 0).
        min_load: a sole's tilt is measured only while it carries more than this share of the measured total
            normal force [0, 1] (an unloaded sole's attitude is its own, not the ground's).
        min_roughness: the terrain's roughness under the foothold [m] above which its sole adapts (>= 0; by default
            the map's :attr:`~.terrain_map.TerrainMapConfig.rough_ground`, where it calls the ground rough).
        release: time constant [s] of a lifted sole's return to the plan's orientation (> 0).
        edge_margin: a sole whose centre of pressure lies within this [m] of its edge is tipping: its tilt holds.
        cop_gain: turn rate [rad/(m s)] of a single-support stance sole's tilt per metre of desired minus measured
            centre of pressure (>= 0; 0: no pressing).
    """

    time_constant: float = 0.05
    max_tilt: float = 0.2
    min_load: float = 0.3
    min_roughness: float = TerrainMapConfig.rough_ground
    release: float = 0.1
    edge_margin: float = 0.015
    cop_gain: float = 15.0

    def __post_init__(self) -> None:
        for name, low, low_open, high, unit in (
            ("time_constant", 0.0, True, None, "s"),
            ("max_tilt", 0.0, True, 0.5 * math.pi, "rad"),
            ("min_load", 0.0, False, 1.0, None),
            ("min_roughness", 0.0, False, None, "m"),
            ("release", 0.0, True, None, "s"),
            ("edge_margin", 0.0, False, SOLE_HALF_WIDTH, "m"),
            ("cop_gain", 0.0, False, None, "rad/(m s)"),
        ):
            check_real(
                f"SoleTiltConfig.{name}", getattr(self, name), low=low, low_open=low_open, high=high, unit=unit,
                error=ControllerError,
            )  # fmt: skip


def tilt_rotation(roll: float, pitch: float) -> NDArray[np.float64]:
    """``R_y(pitch) R_x(roll)``: the sole's tilt in its own frame (roll about its x, then pitch about y) [rad]."""
    cr, sr, cp, sp = math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch)
    return np.array([[cp, sp * sr, sp * cr], [0.0, cr, -sr], [-sp, cp * sr, cp * cr]])


def measured_tilt(planned: NDArray[np.float64], measured: NDArray[np.float64]) -> tuple[float, float]:
    """``(roll, pitch)`` [rad] of ``measured`` relative to ``planned`` (3x3 rotations): ``planned^T measured =
    R_z(yaw) R_y(pitch) R_x(roll)``; a yaw between them (a sole slipped about the vertical) is left out."""
    e = planned.T @ measured
    return math.atan2(e[2, 1], e[2, 2]), -math.asin(min(1.0, max(-1.0, e[2, 0])))


class SoleTilt:
    """The soles' reference tilts from their measured orientations on rough ground (module docstring).

    Args:
        config: the parameters.
    """

    def __init__(self, config: SoleTiltConfig | None = None) -> None:
        self.config = config or SoleTiltConfig()
        self.tilt = np.zeros((2, 2))  # (right, left) x (roll, pitch) [rad]

    def reset(self) -> None:
        """Both soles back to the plan's orientation."""
        self.tilt[:] = 0.0

    def limit(self, roughness: float) -> float:
        """The largest tilt [rad] a sole takes on a foothold of ``roughness`` [m] (0 at or below
        ``min_roughness``): ``min(max_tilt, atan(roughness / (2 SOLE_HALF_WIDTH)))``."""
        c = self.config
        if not roughness > c.min_roughness:
            return 0.0
        return min(c.max_tilt, math.atan(roughness / (2.0 * SOLE_HALF_WIDTH)))

    def tipping(self, cop: tuple[float, float]) -> bool:
        """Whether a centre of pressure at ``cop`` (along, across) [m] in the sole's frame, from the sole point,
        lies within ``edge_margin`` of the sole's edge (or outside it)."""
        m = self.config.edge_margin
        x, y = cop
        return not (SOLE_X[0] + m < x < SOLE_X[1] - m and abs(y) < SOLE_HALF_WIDTH - m)

    def update(
        self,
        dt: float,
        contact: tuple[bool, bool],
        limits: tuple[float, float],
        forces: tuple[float, float],
        planned: NDArray[np.float64],
        measured: NDArray[np.float64],
        tipping: tuple[bool, bool] = (False, False),
        cop_error: tuple[tuple[float, float] | None, tuple[float, float] | None] = (None, None),
    ) -> NDArray[np.float64]:
        """One control period ``dt`` [s]: the soles' (roll, pitch) [rad] to add to their planned orientations.

        Args:
            contact: the plan's contact per sole (right, left).
            limits: the largest tilt [rad] per sole (:meth:`limit` of its foothold's roughness; 0: it keeps its
                tilt).
            forces: the measured normal forces [N] (right, left).
            planned: the soles' planned orientations (2, 3, 3), in the plan's frame.
            measured: their measured orientations (2, 3, 3), in the plan's frame.
            tipping: whether each sole is tipping (:meth:`tipping` of its centre of pressure): it keeps its tilt.
            cop_error: per sole, the desired minus the measured centre of pressure (along, across) [m] in its frame
                where it is pressed towards it (the single support's stance sole), else None.
        """
        if not (isinstance(dt, float) and 0.0 < dt < math.inf) and (not np.isfinite(dt) or dt <= 0.0):
            raise ControllerError(f"dt must be finite and > 0, got {dt!r}")
        c = self.config
        total = max(forces[0] + forces[1], 1e-9)
        follow = dt / (c.time_constant + dt)
        back = 1.0 - dt / (c.release + dt)
        for i in range(2):
            bound = limits[i]
            error = cop_error[i]
            if error is not None and contact[i] and bound > 0.0:
                along, across = error
                self.tilt[i, 1] = min(bound, max(-bound, self.tilt[i, 1] + dt * c.cop_gain * along))
                self.tilt[i, 0] = min(bound, max(-bound, self.tilt[i, 0] - dt * c.cop_gain * across))
            if not contact[i]:
                self.tilt[i] *= back
            elif bound > 0.0 and not tipping[i] and forces[i] > c.min_load * total:
                roll, pitch = measured_tilt(planned[i], measured[i])
                target = (min(bound, max(-bound, roll)), min(bound, max(-bound, pitch)))
                self.tilt[i, 0] += follow * (target[0] - self.tilt[i, 0])
                self.tilt[i, 1] += follow * (target[1] - self.tilt[i, 1])
            # on flat ground, unloaded or tipping, a sole keeps its tilt: the ground's, taken while it settled
        return self.tilt

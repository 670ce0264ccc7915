"""Shared set-up of the walking tests: the standing biped and a walking controller on it."""

from __future__ import annotations

from typing import Any

import numpy as np

from redundancy_gym.assets import BIPED_JOINTS, BIPED_SOFT_LIMIT_MARGIN
from redundancy_gym.controllers.walking import WalkingController, WalkingIkConfig
from redundancy_gym.envs.biped_walk import NOMINAL_POSTURE
from redundancy_gym.model import RobotModel


def standing(model: RobotModel, **joints: float) -> np.ndarray:
    """The standing posture (with ``joints`` [rad] changed), soles on z = 0, identity base orientation."""
    posture = {**NOMINAL_POSTURE, **joints}
    q = np.zeros(model.nq)
    q[6] = 1.0  # identity quaternion (x, y, z, w)
    q[7:] = [posture.get(j, 0.0) for j in BIPED_JOINTS]
    model.update(q)
    q[2] = -min(model.frame_position(f)[2] for f in ("r_sole", "l_sole"))
    return q


def walking_controller(model: RobotModel, **ik: Any) -> WalkingController:
    """A 4 ms controller on the soft limits with one correction rollout and the IK options ``ik``."""
    lower, upper = model.lower_limits[7:], model.upper_limits[7:]
    return WalkingController(
        model,
        0.004,
        lower + BIPED_SOFT_LIMIT_MARGIN,
        upper - BIPED_SOFT_LIMIT_MARGIN,
        ik=WalkingIkConfig(**ik),
        correction_iterations=1,
    )

"""The walking controller measures relative to its stance foot: a robot turned and moved as a whole (a yaw slip
of the stance foot) gets the same feedback and the same joint targets."""

from __future__ import annotations

import numpy as np
import pytest

from redundancy_gym.assets import BIPED_XML
from redundancy_gym.model import RobotModel

from .biped_helpers import standing, walking_controller


@pytest.fixture(scope="module")
def model() -> RobotModel:
    return RobotModel.from_mjcf(BIPED_XML)


def moved(q: np.ndarray, yaw: float, shift: np.ndarray) -> np.ndarray:
    """``q`` with its floating base turned by ``yaw`` about the world z axis and shifted (pinocchio: x y z,
    quat x y z w)."""
    c, s = np.cos(yaw), np.sin(yaw)
    turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    out = q.copy()
    out[:3] = turn @ q[:3] + shift
    x, y, z, w = q[3:7]
    hc, hs = np.cos(yaw / 2), np.sin(yaw / 2)  # (0, 0, hs, hc) * (x, y, z, w)
    out[3:7] = [hc * x - hs * y, hc * y + hs * x, hc * z + hs * w, hc * w - hs * z]
    return out


@pytest.mark.parametrize("stance_frame", [True, False])
def test_a_rigidly_turned_robot_gets_the_same_feedback(model: RobotModel, stance_frame: bool) -> None:
    controllers = [walking_controller(model), walking_controller(model)]
    rng = np.random.default_rng(5)
    for c in controllers:
        c.stance_frame = stance_frame
        c.start(standing(model), 0.5)
    forces = np.array([[0.0, 0.0, -300.0], [0.0, 0.0, -290.0]])
    torques = np.array([[1.0, -2.0, 0.0], [0.5, 3.0, 0.0]])
    q = controllers[0].q_ref.copy()
    worst = {"targets": 0.0, "dcm_error": 0.0, "zmp": 0.0}
    while controllers[0].time < 1.2:  # the start's double support and into the first single support
        v = rng.normal(scale=0.05, size=model.nv)  # base twist in the base frame: the same for the moved robot
        a = controllers[0].step(q, v, forces, torques)
        b = controllers[1].step(moved(q, 0.3, np.array([0.2, -0.1, 0.0])), v, forces, torques)
        worst["targets"] = max(worst["targets"], float(np.max(np.abs(a.joint_targets - b.joint_targets))))
        worst["dcm_error"] = max(
            worst["dcm_error"], float(np.max(np.abs(a.stabilizer.dcm_error - b.stabilizer.dcm_error)))
        )
        assert a.contact.zmp is not None and b.contact.zmp is not None
        worst["zmp"] = max(worst["zmp"], float(np.max(np.abs(a.contact.zmp - b.contact.zmp))))
        q = a.ik.q
    if stance_frame:
        assert max(worst.values()) < 1e-9, worst
    else:  # in the world frame the turn is a DCM error of tens of centimetres
        assert worst["dcm_error"] > 0.1

"""BipedIkd's nullspace objectives: their gradient enters the preferred acceleration as ``-objective_gain dH/dq``,
in the nullspace of the task (the task rows and the contact moment stay exact)."""

from __future__ import annotations

import numpy as np
import pytest

from redundancy_gym.assets import BIPED_XML
from redundancy_gym.controllers import ControllerError, JointLimitObjective, PostureObjective
from redundancy_gym.controllers.ikd import BipedIkd
from redundancy_gym.controllers.objectives.actuated_objective import ActuatedObjective
from redundancy_gym.model import RobotModel
from tests.controllers.ikd.test_biped_ikd import _reference
from tests.controllers.walking.biped_helpers import standing


@pytest.fixture(scope="module")
def biped() -> RobotModel:
    return RobotModel.from_mjcf(BIPED_XML)


def test_a_posture_objective_equals_the_built_in_posture_stiffness(biped):
    # -k_H w (q - q0) from the objective is -K (q - q0) of the posture term when k_H w = K: the same qddot
    q0 = standing(biped)
    q = q0.copy()
    q[-3:] += 0.2  # an arm away from the posture (the base at the posture's)
    qdot = 0.1 * np.ones(biped.nv)
    biped.update(q)
    reference = _reference(biped, q, biped.com()[:2].copy())
    built_in = BipedIkd(biped, posture=q0, posture_stiffness=25.0).step(q, qdot, reference)
    objective = ActuatedObjective(PostureObjective(q0[7:], 0.5), biped)
    by_objective = BipedIkd(biped, posture=None, objectives=(objective,), objective_gain=50.0).step(q, qdot, reference)
    assert built_in.success and by_objective.success
    np.testing.assert_allclose(by_objective.qddot, built_in.qddot, rtol=0.0, atol=1e-9 * np.abs(built_in.qddot).max())


def test_a_joint_limit_objective_pushes_a_joint_off_its_limit_without_touching_the_task(biped):
    q = standing(biped)
    biped.update(q)
    reference = _reference(biped, q, biped.com()[:2].copy())
    joints = q[7:]
    lower, upper = joints - 1.0, joints + 1.0
    lower[-1] = joints[-1] - 0.05  # the last arm joint 0.05 rad above its soft lower limit
    limits = ActuatedObjective(JointLimitObjective(lower, upper, activation_distance=0.15, slope=2.0), biped)
    free = BipedIkd(biped, posture=q).step(q, np.zeros(biped.nv), reference)
    pushed = BipedIkd(biped, posture=q, objectives=(limits,)).step(q, np.zeros(biped.nv), reference)
    assert pushed.success and pushed.residual < 1e-9
    assert pushed.qddot[-1] > free.qddot[-1] + 1.0  # away from the lower limit [rad/s^2]
    np.testing.assert_allclose(pushed.moment, free.moment)  # the prescribed moment, still exact


def test_objectives_must_be_objectives(biped):
    with pytest.raises(ControllerError, match="objectives"):
        BipedIkd(biped, objectives=(object(),))
    with pytest.raises(ControllerError, match="objective_gain"):
        BipedIkd(biped, objective_gain=-1.0)

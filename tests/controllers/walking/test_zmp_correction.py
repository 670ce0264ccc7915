"""The walking controller's multi-body ZMP correction does not depend on the walks before it: estimated from each
start's own state, or once per speed from a given standing posture."""

from __future__ import annotations

import numpy as np
import pytest

from redundancy_gym.assets import BIPED_JOINTS, BIPED_SOFT_LIMIT_MARGIN, BIPED_XML
from redundancy_gym.controllers import ControllerError
from redundancy_gym.controllers.walking import WalkingController
from redundancy_gym.envs.biped_walk import NOMINAL_POSTURE
from redundancy_gym.model import RobotModel

from .biped_helpers import standing, walking_controller


@pytest.fixture(scope="module")
def model() -> RobotModel:
    return RobotModel.from_mjcf(BIPED_XML)


def _offsets(controller: WalkingController) -> np.ndarray:
    assert controller.pattern is not None and controller.pattern.correction is not None
    return controller.pattern.correction.offsets


def test_a_walk_gets_the_correction_of_its_own_start_whatever_came_before(model: RobotModel) -> None:
    # two standing states that differ by a bent knee; a controller that started from the other one first gives
    # the second walk the same correction as a fresh controller (a correction kept per speed did not)
    first, second = standing(model, r_knee=0.25, l_knee=0.25), standing(model, r_knee=0.35, l_knee=0.35)
    used, fresh = walking_controller(model), walking_controller(model)
    used.start(first, 0.5)
    before = _offsets(used).copy()
    used.start(second, 0.5)
    fresh.start(second, 0.5)
    np.testing.assert_array_equal(_offsets(used), _offsets(fresh))
    assert np.max(np.abs(_offsets(used) - before)) > 1e-4  # and the two starts' corrections do differ


def test_a_correction_from_the_nominal_posture_is_the_same_for_every_start(model: RobotModel) -> None:
    lower, upper = model.lower_limits[7:], model.upper_limits[7:]
    nominal = [NOMINAL_POSTURE.get(j, 0.0) for j in BIPED_JOINTS]

    def controller() -> WalkingController:
        return WalkingController(
            model,
            0.004,
            lower + BIPED_SOFT_LIMIT_MARGIN,
            upper - BIPED_SOFT_LIMIT_MARGIN,
            correction_iterations=1,
            correction_configuration=nominal,
        )

    a, b = controller(), controller()
    a.start(standing(model, r_knee=0.25, l_knee=0.25), 0.5)
    a.start(standing(model, r_knee=0.35, l_knee=0.35), 0.5)
    b.start(standing(model, r_knee=0.35, l_knee=0.35), 0.5)
    np.testing.assert_array_equal(_offsets(a), _offsets(b))
    with pytest.raises(ControllerError, match="correction_configuration"):
        WalkingController(model, 0.004, lower, upper, correction_configuration=[0.0] * 3)

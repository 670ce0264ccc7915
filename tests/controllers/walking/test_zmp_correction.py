"""The walking controller's multi-body ZMP correction does not depend on the walks before it: estimated from each
start's own state, or once per speed from a given standing posture."""

from __future__ import annotations

import numpy as np
import pytest

from redundancy_gym.assets import BIPED_JOINTS, BIPED_SOFT_LIMIT_MARGIN, BIPED_XML
from redundancy_gym.controllers import ControllerError
from redundancy_gym.controllers.walking import WalkingController, ZmpCorrection
from redundancy_gym.envs.biped_walk import NOMINAL_POSTURE
from redundancy_gym.model import RobotModel

from .biped_helpers import standing, walking_controller


@pytest.fixture(scope="module")
def model() -> RobotModel:
    return RobotModel.from_mjcf(BIPED_XML)


def _nominal_controller(model: RobotModel, **kwargs: object) -> WalkingController:
    """A 4 ms controller on the soft limits whose correction comes from the env's nominal standing posture."""
    lower, upper = model.lower_limits[7:], model.upper_limits[7:]
    nominal = [NOMINAL_POSTURE.get(j, 0.0) for j in BIPED_JOINTS]
    return WalkingController(
        model,
        0.004,
        lower + BIPED_SOFT_LIMIT_MARGIN,
        upper - BIPED_SOFT_LIMIT_MARGIN,
        correction_configuration=nominal,
        **kwargs,  # type: ignore[arg-type]
    )


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


def test_the_plans_whole_body_zmp_follows_the_reference_only_with_the_correction(model: RobotModel) -> None:
    # plan_zmp rolls the IK out on the pattern and takes the ZMP from the whole model's CoM and momentum rate: with
    # the multi-body correction (three rollouts) the steady steps' ZMP stays near the reference and 20 mm inside the
    # soles; the plain LIPM (no correction) leaves it where the swinging legs push it (97 mm rms, 25 cm at worst)
    lower, upper = model.lower_limits[7:], model.upper_limits[7:]
    nominal = [NOMINAL_POSTURE.get(j, 0.0) for j in BIPED_JOINTS]

    def plan(iterations: int):
        result = _nominal_controller(model, correction_iterations=iterations).plan_zmp(0.7, steps=4)
        steady = result.times >= result.step_starts[2]
        distance = np.linalg.norm(result.zmp - result.reference, axis=1)[steady]
        return float(np.sqrt(np.mean(distance**2))), float(distance.max()), float(result.margin[steady].min())

    corrected, plain = plan(3), plan(0)
    assert corrected[0] < 0.02 and corrected[1] < 0.05 and corrected[2] > 0.02
    assert plain[1] > 0.08 and plain[0] > 2.0 * corrected[0]
    with pytest.raises(ControllerError, match="steps"):
        WalkingController(model, 0.004, lower, upper, correction_configuration=nominal).plan_zmp(0.7, steps=0)


def test_the_first_steps_own_tables_keep_their_whole_body_zmp_20_mm_inside_the_soles(model: RobotModel) -> None:
    # the first step starts from standing with another momentum profile than the steady steps, whose tables put its
    # whole-body ZMP 21 mm outside the soles at 0.7 m/s; with tables of its own (the rollout's first two steps) every
    # step of the plan keeps 20 mm inside (issue 35's margin), and the steady steps' tables stay as they were

    def plan(first_steps: int):
        controller = _nominal_controller(model, correction_first_steps=first_steps)
        result = controller.plan_zmp(0.7, steps=4)
        margins = [
            float(result.margin[(result.times >= a) & (result.times < b)].min())
            for a, b in zip(result.step_starts[:-1], result.step_starts[1:], strict=True)
        ]
        correction = controller._corrections[next(iter(controller._corrections))]
        return margins, correction

    own, steady = plan(2), plan(0)
    assert min(own[0]) > 0.02, own[0]
    assert steady[0][0] < 0.0 < steady[0][1]  # the steady tables' first step leaves the soles
    assert own[1].first is not None and own[1].first.shape == (2, 20, 2) and steady[1].first is None
    np.testing.assert_allclose(own[1].offsets, steady[1].offsets, atol=0.01)  # steady steps near as before
    assert np.max(np.abs(own[1].first[0] - own[1].offsets[0])) > 0.01  # and the first step's table differs


def test_a_correction_takes_its_first_step_tables_then_the_steady_ones() -> None:
    phases = np.arange(4) / 4
    offsets = np.stack([np.full((4, 2), 1.0), np.full((4, 2), 2.0)])
    first = np.stack([np.full((4, 2), 10.0), np.full((4, 2), 20.0)])
    correction = ZmpCorrection(phases, offsets, first)
    assert [float(correction.table(k)[0, 0]) for k in range(5)] == [10.0, 20.0, 1.0, 2.0, 1.0]
    assert [float(ZmpCorrection(phases, offsets).table(k)[0, 0]) for k in range(3)] == [1.0, 2.0, 1.0]
    with pytest.raises(ControllerError, match=r"first \(m, 4, 2\)"):
        ZmpCorrection(phases, offsets, np.zeros((2, 3, 2)))
    with pytest.raises(ControllerError, match="finite"):
        ZmpCorrection(phases, offsets, np.full((1, 4, 2), np.nan))


@pytest.mark.parametrize("value", [-1, 3, 1.5, "2"])
def test_correction_first_steps_outside_0_to_2_raises_naming_it(model: RobotModel, value: object) -> None:
    lower, upper = model.lower_limits[7:], model.upper_limits[7:]
    with pytest.raises(ControllerError, match=r"correction_first_steps must be an int in \[0, 2\]"):
        WalkingController(model, 0.004, lower, upper, correction_first_steps=value)  # type: ignore[arg-type]

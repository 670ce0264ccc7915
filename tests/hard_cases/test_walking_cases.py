"""Hard cases of the walking layers: pattern at speed 0 and over long times, DCM plan invariants against finite
differences, bad inputs, the whole-body IK pulled towards an unreachable CoM, and the controller's call order.

The cases marked ``xfail(strict=True)`` are findings in the walking code that is being changed elsewhere; each
turns into a failure (XPASS) when fixed, so the mark is removed with the fix.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from redundancy_gym.assets import BIPED_XML
from redundancy_gym.controllers import ControllerError
from redundancy_gym.controllers.walking import (
    DcmPlanner,
    GaitConfig,
    Stabilizer,
    StabilizerGains,
    WalkingPattern,
    WholeBodyReference,
)
from redundancy_gym.model import ModelError, RobotModel

from ..controllers.walking.biped_helpers import standing, walking_controller

FEET = ([0.025, -0.09, 0.0], [0.025, 0.09, 0.0])
COM = [0.025, 0.0]


@pytest.fixture(scope="module")
def biped() -> RobotModel:
    return RobotModel.from_mjcf(BIPED_XML)


# ----------------------------------------------------------------------------------------------- the pattern
def test_speed_zero_pattern_steps_in_place() -> None:
    """Speed 0: zero step length, the feet come back to their footholds, the CoM stays between them."""
    pattern = WalkingPattern(GaitConfig(), FEET[0], FEET[1], COM, 0.0)
    assert pattern.step_length == 0.0 and pattern.speed == 0.0
    for t in np.arange(0.0, 20.0, 0.01):
        s = pattern.sample(t)
        assert np.all(np.isfinite(s.com)) and np.all(np.isfinite(s.feet)) and np.all(np.isfinite(s.zmp))
        np.testing.assert_allclose(s.feet[:, 1], np.array(FEET)[:, 1], atol=1e-12)  # no foot moves sideways
        # nor forward, but for the swing foot turning about its toe (toe_length (1 - cos(pitch)) < 1 cm)
        np.testing.assert_allclose(s.feet[:, 0], np.array(FEET)[:, 0], atol=1e-12 if all(s.contact) else 0.01)
        assert abs(s.com[0] - COM[0]) < 0.02 and abs(s.com[1]) < 0.09
        assert s.feet[:, 2].min() >= -1e-12
    assert s.step > 20  # it did step


def test_fast_command_is_capped_at_the_longest_quickest_step() -> None:
    pattern = WalkingPattern(GaitConfig(), FEET[0], FEET[1], COM, 1e6)
    config = GaitConfig()
    assert pattern.step_length == config.max_step_length and pattern.step_duration == config.min_step_duration
    s = pattern.sample(3.0)
    assert np.all(np.isfinite(s.com)) and np.all(np.isfinite(s.feet))


@pytest.mark.parametrize(
    "speed, t, match",
    [
        (float("nan"), None, "speed"),
        (float("inf"), None, "speed"),
        (-0.1, None, "speed"),
        (0.5, float("nan"), "time"),
        (0.5, -1e-9, "time"),
        (0.5, float("inf"), "time"),
    ],
)
def test_non_finite_or_negative_inputs_raise_naming_them(speed: float, t: float | None, match: str) -> None:
    with pytest.raises(ControllerError, match=match):
        WalkingPattern(GaitConfig(), FEET[0], FEET[1], COM, speed).sample(0.0 if t is None else t)


@pytest.mark.parametrize(
    "kwargs", [{"right_foot": [np.nan, -0.09, 0.0]}, {"com": [np.inf, 0.0]}, {"com": [0.0, 0.0, 0.0]}]
)
def test_bad_start_state_raises(kwargs: dict) -> None:
    args = {"right_foot": FEET[0], "left_foot": FEET[1], "com": COM, **kwargs}
    with pytest.raises(ControllerError):
        WalkingPattern(GaitConfig(), args["right_foot"], args["left_foot"], args["com"], 0.5)


def test_foot_of_two_entries_is_a_controller_error() -> None:
    with pytest.raises(ControllerError, match="right_foot and left_foot"):
        WalkingPattern(GaitConfig(), FEET[0], [0.0, 0.09], COM, 0.5)


@pytest.mark.parametrize(
    "field, value",
    [
        ("step_duration", float("nan")),
        ("com_height", 0.0),
        ("double_support_ratio", 1.0),
        ("preview_steps", 1),
        ("swing_pitch", 0.7),
        ("min_step_duration", 0.9),
    ],
)
def test_gait_config_rejects_bad_values_naming_the_field(field: str, value: float) -> None:
    with pytest.raises(ControllerError, match=field):
        kwargs: dict[str, Any] = {field: value}
        GaitConfig(**kwargs)


@pytest.mark.parametrize("value", ["0.8", None])
def test_gait_config_value_that_is_no_number_is_a_controller_error(value: object) -> None:
    with pytest.raises(ControllerError, match="step_duration"):
        GaitConfig(step_duration=value)  # type: ignore[arg-type]


def test_pattern_sampled_after_a_long_pause_stays_finite() -> None:
    pattern = WalkingPattern(GaitConfig(), FEET[0], FEET[1], COM, 0.0)
    pattern.sample(50.0)
    s = pattern.sample(1000.0)
    assert np.all(np.isfinite(s.com)) and np.all(np.isfinite(s.dcm))


def test_pattern_sampled_densely_for_a_long_time_stays_finite() -> None:
    """Replanned at every step (as the controller samples it), 600 s of walking stay finite and on course."""
    pattern = WalkingPattern(GaitConfig(), FEET[0], FEET[1], COM, 0.5)
    for t in np.arange(0.0, 600.0, 0.2):
        s = pattern.sample(float(t))
        assert np.all(np.isfinite(s.com)) and np.all(np.isfinite(s.dcm))
    assert s.com[0] == pytest.approx(COM[0] + 0.5 * (600.0 - 0.2), abs=1.0)
    assert abs(s.com[1]) < 0.1


# ------------------------------------------------------------------------------------------------ the DCM plan
def _plan():
    planner = DcmPlanner(0.9)
    times = np.array([0.0, 0.4, 1.0, 1.2, 1.8, 2.0, 2.6])
    zmp = np.array([[0.0, 0.0], [0.0, 0.08], [0.02, 0.08], [0.3, -0.08], [0.32, -0.08], [0.6, 0.08], [0.6, 0.0]])
    return planner, planner.plan(times, planner.start_zmp(times, zmp, [0.01, 0.0]), [0.01, 0.0]), times


def test_dcm_plan_obeys_its_differential_equations_by_finite_differences() -> None:
    """``xi' = omega (xi - r)`` and ``x' = omega (xi - x)`` at off-knot times, by central differences."""
    planner, plan, times = _plan()
    w, h = planner.omega, 1e-5
    for t in np.linspace(0.01, times[-1] - 0.01, 97):
        s = plan.sample(t)
        dcm_rate = (plan.sample(t + h).dcm - plan.sample(t - h).dcm) / (2 * h)
        com_rate = (plan.sample(t + h).position - plan.sample(t - h).position) / (2 * h)
        np.testing.assert_allclose(dcm_rate, w * (s.dcm - s.zmp), atol=2e-6)
        np.testing.assert_allclose(com_rate, w * (s.dcm - s.position), atol=2e-6)
        np.testing.assert_allclose(s.acceleration, w**2 * (s.position - s.zmp), atol=1e-12)


def test_dcm_plan_zmp_is_the_piecewise_linear_reference() -> None:
    _, plan, times = _plan()
    for t in np.linspace(0.0, times[-1], 131):
        expected = np.array([np.interp(t, plan.times, plan.zmp[:, 0]), np.interp(t, plan.times, plan.zmp[:, 1])])
        np.testing.assert_allclose(plan.sample(t).zmp, expected, atol=1e-12)
    np.testing.assert_allclose(plan.dcm[-1], plan.zmp[-1], atol=1e-15)  # the walk ends at rest over the ZMP
    np.testing.assert_allclose(plan.sample(0.0).velocity, 0.0, atol=1e-12)  # and starts from rest


@pytest.mark.parametrize(
    "times, zmp, match",
    [
        ([0.0], [[0.0, 0.0]], ">= 2 knot times"),
        ([0.0, 0.0], [[0.0, 0.0], [0.1, 0.0]], "increase strictly"),
        ([0.0, np.nan], [[0.0, 0.0], [0.1, 0.0]], "finite"),
        ([0.0, 1.0], [[0.0, 0.0], [np.inf, 0.0]], "finite"),
    ],
)
def test_dcm_planner_bad_knots_raise(times: list, zmp: list, match: str) -> None:
    with pytest.raises(ControllerError, match=match):
        DcmPlanner(0.9).plan(times, zmp, [0.0, 0.0])


@pytest.mark.parametrize("com", [[np.nan, 0.0], [0.0, 0.0, 0.0]], ids=["nan", "three-entries"])
def test_dcm_planner_bad_com_raises(com: list) -> None:
    with pytest.raises(ControllerError, match="com"):
        DcmPlanner(0.9).plan([0.0, 1.0], [[0.0, 0.0], [0.1, 0.0]], com)


@pytest.mark.parametrize(
    "height, gravity", [(1.0, 8.8e-271), (1e300, 9.81)], ids=["vanishing-gravity", "huge-com-height"]
)
def test_dcm_planner_with_an_extreme_omega_is_rejected_or_finite(height: float, gravity: float) -> None:
    try:
        planner = DcmPlanner(height, gravity)
    except ControllerError:
        return
    assert np.all(np.isfinite(planner.start_zmp([0.0, 1.0], [[0.0, 0.0], [0.0, 0.0]], [0.0, 0.0])))


def test_start_zmp_of_a_vanishing_segment_raises_or_is_finite() -> None:
    try:
        start = DcmPlanner(1.0).start_zmp([0.0, 1e-9], [[0.0, 0.0], [0.0, 0.0]], [0.0, 0.0])
    except ControllerError:
        return
    assert np.all(np.isfinite(start))


def test_pattern_with_a_tiny_com_height_is_rejected_or_finite() -> None:
    try:
        pattern = WalkingPattern(GaitConfig(com_height=3.6e-94, heel_toe_shift=0.0), FEET[0], FEET[1], [0.0, 0.0], 0.0)
    except ControllerError:
        return
    assert np.all(np.isfinite(pattern.sample(0.5).com))


@pytest.mark.parametrize("argument", ["dt", "com"])
def test_stabilizer_non_finite_measurement_raises(argument: str) -> None:
    stabilizer = Stabilizer(StabilizerGains(), DcmPlanner(0.9).omega)
    inputs: dict[str, Any] = (
        {"dt": 0.004, "com": [np.nan, 0.0]} if argument == "com" else {"dt": np.nan, "com": [0.01, 0.0]}
    )
    with pytest.raises(ControllerError, match=argument):
        stabilizer.update(inputs["dt"], [0.0, 0.0], [0.0, 0.0], [0.0, 0.0], inputs["com"], [0.0, 0.0], [0.0, 0.0])


def test_stabilizer_offset_stays_within_its_bound_under_a_huge_error() -> None:
    gains = StabilizerGains(max_offset=0.05)
    stabilizer = Stabilizer(gains, DcmPlanner(0.9).omega)
    for _ in range(2000):
        out = stabilizer.update(0.004, [0.0, 0.0], [0.0, 0.0], [0.0, 0.0], [3.0, -2.0], [10.0, 5.0], [5.0, 5.0])
        assert np.all(np.isfinite(out.offset)) and np.linalg.norm(out.offset) <= 0.05 + 1e-15


# ------------------------------------------------------------------------------ whole-body IK and the controller
def test_whole_body_ik_towards_an_unreachable_com_is_limited_and_finite(biped: RobotModel) -> None:
    """The CoM reference 2 m ahead and 0.5 m up (out of reach with the feet held): every step is scaled to
    ``max_velocity`` (``limited``), stays finite and successful, and the CoM moves towards the reference."""
    controller = walking_controller(biped)
    q = standing(biped)
    controller.start(q, 0.5)
    ik = controller.ik
    ref = controller._reference(controller.pattern.sample(0.0), np.zeros(2), np.zeros(2))
    far = WholeBodyReference(
        ref.com + [2.0, 0.0, 0.5],
        ref.com_velocity,
        ref.feet_position,
        ref.feet_rotation,
        ref.feet_velocity,
        ref.torso_rotation,
        ref.torso_angular_velocity,
    )
    biped.update(q)
    start_gap = np.linalg.norm(far.com - biped.com())
    for _ in range(150):
        result = ik.step(q, far, far, controller.dt)
        assert result.success and result.limited
        assert np.all(np.isfinite(result.q)) and np.all(np.isfinite(result.qdot))
        assert np.max(np.abs(result.qdot)) <= ik.max_velocity * (1 + 1e-12)
        q = result.q
    biped.update(q)
    assert np.linalg.norm(far.com - biped.com()) < start_gap


def test_whole_body_ik_non_finite_configuration_and_period_raise(biped: RobotModel) -> None:
    controller = walking_controller(biped)
    q = standing(biped)
    controller.start(q, 0.5)
    ref = controller._reference(controller.pattern.sample(0.0), np.zeros(2), np.zeros(2))
    with pytest.raises(ModelError, match="non-finite"):
        controller.ik.step(np.r_[np.nan, q[1:]], ref, ref, controller.dt)
    with pytest.raises(ControllerError, match="dt"):
        controller.ik.step(q, ref, ref, float("nan"))


def test_whole_body_ik_non_finite_reference_raises(biped: RobotModel) -> None:
    controller = walking_controller(biped)
    q = standing(biped)
    controller.start(q, 0.5)
    ref = controller._reference(controller.pattern.sample(0.0), np.zeros(2), np.zeros(2))
    bad = WholeBodyReference(
        ref.com + [np.nan, 0.0, 0.0],
        ref.com_velocity,
        ref.feet_position,
        ref.feet_rotation,
        ref.feet_velocity,
        ref.torso_rotation,
        ref.torso_angular_velocity,
    )
    with pytest.raises(ControllerError):
        controller.ik.step(q, bad, bad, controller.dt)


def test_walking_controller_step_before_start_raises(biped: RobotModel) -> None:
    controller = walking_controller(biped)
    q = standing(biped)
    with pytest.raises(ControllerError, match=r"start\(q, speed\) before step"):
        controller.step(q, np.zeros(biped.nv), np.zeros((2, 3)), np.zeros((2, 3)))


@pytest.mark.parametrize("speed", [float("nan"), -1.0, float("inf")])
def test_walking_controller_bad_speed_raises_naming_it(biped: RobotModel, speed: float) -> None:
    with pytest.raises(ControllerError, match="speed"):
        walking_controller(biped).start(standing(biped), speed)

"""Turning: a yaw-rate command turns the footholds, the ZMP knots, the swing feet, the IK references and the step
adjuster's box; straight walking is left as it was."""

from __future__ import annotations

import math

import numpy as np
import pytest

from redundancy_gym.controllers import ControllerError
from redundancy_gym.controllers.walking import (
    GaitConfig,
    StepAdjuster,
    StepAdjusterConfig,
    WalkingController,
    WalkingPattern,
)
from redundancy_gym.controllers.walking.walking_pattern import MAX_STEP_TURN, TURN_WIDENING

FEET = ([0.0, -0.09, 0.0], [0.0, 0.09, 0.0])


def turning(yaw_rate: float = 0.25, speed: float = 0.4, t: float = 0.0) -> WalkingPattern:
    pattern = WalkingPattern(GaitConfig(), FEET[0], FEET[1], [0.0, 0.0], speed)
    for s in np.arange(0.0, t, 0.004):
        pattern.sample(float(s))
    pattern.set_velocity(t, speed, 0.0, yaw_rate=yaw_rate)
    return pattern


def rz(yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s], [s, c]])


def test_straight_walking_has_no_yaw() -> None:
    pattern = WalkingPattern(GaitConfig(), FEET[0], FEET[1], [0.0, 0.0], 0.5)
    pattern.set_velocity(0.0, 0.3, 0.05)  # a velocity command without a yaw rate stays straight
    for t in np.arange(0.0, 5.0, 0.05):
        sample = pattern.sample(float(t))
        assert not np.any(sample.feet_yaw) and not np.any(sample.feet_yaw_rate)
    assert all(pattern.heading(j) == 0.0 for j in range(12)) and pattern.yaw_rate == 0.0


def test_footholds_turn_by_the_yaw_rate_times_the_step_duration_per_step() -> None:
    yaw_rate, speed = 0.25, 0.4
    pattern = turning(yaw_rate, speed)
    T, w = pattern.step_duration, pattern.config.step_width
    turn = yaw_rate * T
    assert [pattern.heading(j) for j in range(6)] == pytest.approx([0.0, 0.0, turn, 2 * turn, 3 * turn, 4 * turn])
    for j in range(2, 10):
        heading = pattern.heading(j)
        side = -1.0 if j % 2 == 0 else 1.0
        # the foothold lies (half the step width + the turn's widening) beside the walking line, perpendicular to
        # its heading; the line advances by the step displacement turned by the step's mean heading
        offset = side * (0.5 * w + TURN_WIDENING * pattern.config.toe_length * turn)
        line = pattern.foothold(j)[:2] - rz(heading) @ [0.0, offset]
        previous = np.zeros(2) if j == 2 else pattern.foothold(j - 1)[:2] - rz(pattern.heading(j - 1)) @ [0.0, -offset]
        np.testing.assert_allclose(line - previous, rz(heading - 0.5 * turn) @ [speed * T, 0.0], atol=1e-12)


def test_a_command_during_a_step_turns_only_the_footholds_after_its_landing() -> None:
    pattern = turning(0.0, 0.4, t=2.1)  # step 2 under way: it lands h_4
    before = [pattern.foothold(j) for j in range(6)]
    pattern.set_velocity(2.1, 0.4, 0.0, yaw_rate=-0.3)
    for j in range(5):
        np.testing.assert_array_equal(pattern.foothold(j), before[j])
    assert pattern.heading(4) == 0.0 and pattern.heading(5) == pytest.approx(-0.3 * pattern.step_duration)


def test_yaw_rate_bound() -> None:
    pattern = turning(0.0)
    sharpest = MAX_STEP_TURN / pattern.step_duration
    pattern.set_velocity(0.0, 0.4, 0.0, yaw_rate=-sharpest)
    for bad in (sharpest * 1.01, np.nan, np.inf):
        with pytest.raises(ControllerError, match="yaw_rate"):
            pattern.set_velocity(0.0, 0.4, 0.0, yaw_rate=bad)


def test_the_swing_foot_turns_smoothly_from_lift_off_to_landing() -> None:
    pattern = turning(0.3)
    dt = 0.001
    samples = [pattern.sample(float(t)) for t in np.arange(0.0, 4.0, dt)]
    yaw = np.array([s.feet_yaw for s in samples])
    rate = np.array([s.feet_yaw_rate for s in samples])
    np.testing.assert_allclose(np.diff(yaw, axis=0), 0.5 * dt * (rate[1:] + rate[:-1]), atol=1e-6)  # rate = d yaw/dt
    assert np.max(np.abs(np.diff(rate, axis=0))) < 0.02  # continuous rate (zero at lift-off and landing)
    feet = np.array([s.feet for s in samples])
    velocity = np.array([s.feet_velocity for s in samples])
    np.testing.assert_allclose(np.diff(feet, axis=0), 0.5 * dt * (velocity[1:] + velocity[:-1]), atol=1e-5)
    last = samples[-1]
    k = last.step
    for side, j in ((k % 2, k + 2), ((k + 1) % 2, k + 1)):
        if last.contact[side]:
            assert last.feet_yaw[side] == pytest.approx(pattern.heading(j))


def test_zmp_knots_lie_along_and_across_the_turned_feet() -> None:
    pattern = turning(0.3)
    config = pattern.config
    for j in range(2, 8):
        h, heading = pattern.foothold(j)[:2], pattern.heading(j)
        inward = 1.0 if j % 2 == 0 else -1.0
        np.testing.assert_allclose(
            pattern._zmp_point(j, config.heel_toe_shift),
            h + rz(heading) @ [config.heel_toe_shift, inward * config.zmp_inset],
            atol=1e-12,
        )


def test_the_ik_reference_turns_the_soles_and_the_torso() -> None:
    pattern = turning(0.3)
    sample = next(
        s
        for s in (pattern.sample(float(t)) for t in np.arange(2.0, 4.0, 0.004))
        if not all(s.contact) and abs(s.feet_yaw_rate).max() > 0.1 and abs(s.feet_pitch).max() > 0.05
    )
    a = WalkingController._reference_array(sample, np.zeros(2), np.zeros(2))
    for i in range(2):
        yaw, pitch = sample.feet_yaw[i], sample.feet_pitch[i]
        cz, sz, c, s = math.cos(yaw), math.sin(yaw), math.cos(pitch), math.sin(pitch)
        expected = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]]) @ np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
        np.testing.assert_allclose(a[12 + 9 * i : 21 + 9 * i].reshape(3, 3), expected, atol=1e-12)
        omega = np.array([-sz * sample.feet_pitch_rate[i], cz * sample.feet_pitch_rate[i], sample.feet_yaw_rate[i]])
        np.testing.assert_allclose(a[33 + 6 * i : 36 + 6 * i], omega, atol=1e-12)
    mean = sample.feet_yaw.mean()
    np.testing.assert_allclose(a[42:51].reshape(3, 3)[:2, :2], rz(mean), atol=1e-12)
    assert a[53] == pytest.approx(sample.feet_yaw_rate.mean())


@pytest.mark.parametrize("push", [(0.0, -0.5), (0.0, 0.5), (0.5, 0.0)])
def test_the_step_adjuster_box_lies_in_the_turned_stance_foot_frame(push: tuple[float, float]) -> None:
    """Half a turn later a push across the walking line cannot make the swing foot cross the stance foot."""
    pattern = turning(0.45, 0.4)
    k = 7
    t = pattern.step_start(k) + 0.1
    for s in np.arange(0.0, t, 0.004):
        pattern.sample(float(s))
    heading = pattern.heading(k + 1)
    assert heading > 1.0
    adjuster = StepAdjuster(StepAdjusterConfig(error_filter=0.0))
    stance = pattern.foothold(k + 1)[:2]
    dcm = pattern.dcm(t) + rz(heading) @ np.array(push)  # the push in the stance foot's frame
    adjustment = adjuster.update(pattern, t, dcm)
    assert adjustment is not None
    local = rz(heading).T @ (pattern.foothold(k + 2)[:2] - stance)
    c = adjuster.config
    side = 1.0 if (k + 2) % 2 == 1 else -1.0
    assert -c.max_backward - 1e-9 <= local[0] <= c.max_forward + 1e-9
    assert c.min_width - 1e-9 <= side * local[1] <= c.max_width + 1e-9

"""The grasp-approach reference path: its durations follow the timing, its samples pass through the given poses,
and the deprecated duration function gives the planned path's durations."""

from __future__ import annotations

import numpy as np
import pytest

from redundancy_gym.geometry import GraspPath, GraspPathTiming, grasp_path_durations

START = np.array([0.4, -0.1, 0.9])
START_AXIS = np.array([1.0, 0.0, 0.0])
PREGRASP = np.array([0.7, 0.2, 1.1])
GRASP = np.array([0.8, 0.2, 1.1])
APPROACH = np.array([0.0, 1.0, 0.0])
POSES = (START, START_AXIS, PREGRASP, GRASP, APPROACH)


def test_durations_are_the_slowest_of_distance_turn_and_minimum() -> None:
    timing = GraspPathTiming(max_speed=0.2, max_turn_rate=0.5, min_duration=0.1, approach_speed=0.05)
    assert timing.durations(0.4, np.pi / 2, 0.1) == pytest.approx((np.pi, 2.0), rel=1e-12)  # the turn is slowest
    assert timing.durations(1.0, 0.1, 0.1)[0] == pytest.approx(5.0, rel=1e-12)  # the distance is
    assert timing._replace(min_duration=10.0).durations(1.0, 0.1, 0.1)[0] == 10.0
    assert timing.durations(1.0, 0.1, 1e-3)[1] == 0.5  # the approach's floor


def test_the_planned_path_rests_on_its_poses_and_lasts_its_durations() -> None:
    timing = GraspPathTiming(max_speed=0.2, max_turn_rate=0.5, min_duration=0.1, approach_speed=0.05)
    path = GraspPath.plan(*POSES, timing)
    # the move: 0.469 m at 0.2 m/s (2.35 s) against a quarter turn of the tool axis at 0.5 rad/s (pi s)
    move, approach = np.pi, 0.1 / 0.05
    assert (path.move_duration, path.approach_duration) == pytest.approx((move, approach), rel=1e-12)
    assert path.duration == path.move_duration + path.approach_duration
    np.testing.assert_allclose(path.position(0.0), START, atol=1e-12)
    np.testing.assert_allclose(path.position(path.move_duration), PREGRASP, atol=1e-12)
    np.testing.assert_allclose(path.position(path.duration), GRASP, atol=1e-12)


def test_the_deprecated_duration_function_warns_and_agrees() -> None:
    timing = GraspPathTiming(max_speed=0.1)
    with pytest.warns(DeprecationWarning, match="GraspPath.plan"):
        old = grasp_path_durations(*POSES, timing)
    with pytest.warns(DeprecationWarning):
        keyword = grasp_path_durations(*POSES, timing=timing)
    with pytest.warns(DeprecationWarning):
        default = grasp_path_durations(*POSES)
    planned = GraspPath.plan(*POSES, timing)
    assert old == keyword == (planned.move_duration, planned.approach_duration)
    assert default == (GraspPath.plan(*POSES).move_duration, GraspPath.plan(*POSES).approach_duration)

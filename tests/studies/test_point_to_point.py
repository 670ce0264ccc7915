"""Fig. 5.10: the point-to-point move self-collides without nullspace collision avoidance and not with it."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from redundancy_gym.assets import AGRI_ARM_XML
from redundancy_gym.model import RobotModel
from redundancy_gym.studies.point_to_point import FIG_5_10, rollout_point_to_point


@pytest.fixture(scope="module")
def traces() -> dict[bool, object]:
    return {on: rollout_point_to_point(FIG_5_10, collision_avoidance=on) for on in (False, True)}


def test_without_avoidance_the_arm_hits_itself_and_with_it_stays_clear(traces: dict) -> None:
    off, on = traces[False], traces[True]
    assert off.self_clearance.min() < -0.02  # penetration by more than 2 cm: a real self-collision
    assert on.self_clearance.min() > 0.03
    # the avoidance acts in the nullspace: both runs track the same task and end at the goal
    for trace in (off, on):
        assert trace.task_error.max() < 0.01
        assert trace.final_position_error < 1e-3
    assert not np.allclose(off.q, on.q, atol=1e-2)  # ... with different joint motions


def test_the_start_and_goal_postures_are_collision_free_and_within_limits(traces: dict) -> None:
    model = RobotModel.from_mjcf(AGRI_ARM_XML)
    for posture in (FIG_5_10.q_start, FIG_5_10.q_goal):
        q = np.asarray(posture)
        assert np.all(q > model.lower_limits) and np.all(q < model.upper_limits)
    assert traces[False].self_clearance[0] > 0.0 and traces[True].self_clearance[-1] > 0.0


def test_rollout_rejects_wrong_sizes() -> None:
    from redundancy_gym.eval import EvalError

    with pytest.raises(EvalError, match="9 entries"):
        rollout_point_to_point(dataclasses.replace(FIG_5_10, q_start=(0.0, 0.0)))

"""Hard cases where the Python ``Clik`` and the compiled ``CompiledClik`` must agree (found by the nightly fuzz).

1. A joint exactly on its limit whose command is zero analytically (its Jacobian column is orthogonal to the
   task velocity: the links after it straight, the target on their line) gets ``+-1e-16`` with a round-off sign
   that differs between the backends (the kernel contracts to FMA). Clamping that noise to zero flipped
   ``limited`` in one backend only; now holding a joint counts as ``limited`` only when it changes the command
   by more than round-off.
2. ``q = [1e300, 1, 0, 0]`` (planar, pseudoinverse and DLS): the nullspace gradients grow with the distance to
   the limits (5e300 here), swamp the task's part of the command, and each backend returned its own noise
   (``[0, -0.007, 0, -3]`` against ``[0, 1.77, 3, -2.57]``). A coordinate beyond ``MAX_COORDINATE`` is now
   rejected like a non-finite one, with the same message in both backends.
"""

from __future__ import annotations

import numpy as np
import pytest

from redundancy_gym.assets import PLANAR_ARM_TCP, PLANAR_ARM_XML
from redundancy_gym.controllers import (
    AccelerationClik,
    Clik,
    CompiledClik,
    ControllerError,
    FramePositionTask,
    JointLimitObjective,
    Objective,
    PostureObjective,
    resolve,
)
from redundancy_gym.controllers.clik.redundancy_resolution import MAX_COORDINATE
from redundancy_gym.model import RobotModel

METHODS = ("pseudoinverse", "dls", "transpose")


@pytest.fixture(scope="module")
def planar() -> RobotModel:
    return RobotModel.from_mjcf(PLANAR_ARM_XML)


def _on_the_line_of_the_outer_links(model: RobotModel, clik: Clik, q: np.ndarray, s: float) -> np.ndarray:
    """A target on the line through joints 2..4 and the TCP (q[2] = q[3] = 0): the task velocity is orthogonal
    to the Jacobian columns of joints 2, 3 and 4, whose transposed-Jacobian commands are then zero."""
    jacobian = clik.build(q, np.zeros(2)).jacobian
    along = np.array([jacobian[1, 3], -jacobian[0, 3]])
    model.update(q)
    return model.frame_position(PLANAR_ARM_TCP)[[0, 2]] + s * along / np.linalg.norm(along)


@pytest.mark.parametrize("limit", ["lower", "upper"])
def test_transpose_joint_on_its_limit_with_round_off_command_is_not_limited_in_either_backend(
    planar: RobotModel, limit: str
) -> None:
    clik = Clik(planar, FramePositionTask(PLANAR_ARM_TCP, "xz"), method="transpose")
    compiled = CompiledClik(clik)
    bound = planar.lower_limits[1] if limit == "lower" else planar.upper_limits[1]
    outward = 0
    for q0 in np.linspace(-2.0, 2.0, 9):
        for s in (-0.5, -0.2, 0.3):  # slow enough that the speed limits do not act
            q = np.array([q0, bound, 0.0, 0.0])
            target = _on_the_line_of_the_outer_links(planar, clik, q, s)
            problem = clik.build(q, target)
            raw = resolve(problem.jacobian, problem.velocity, None, clik.weights, method="transpose").x
            assert abs(raw[1]) < 1e-14  # zero but for round-off: the case protected here
            outward += int(raw[1] < 0.0 if limit == "lower" else raw[1] > 0.0)
            reference, result = clik.step(q, target), compiled.step(q, target)
            assert not reference.limited and not result.limited, (q, target, raw)
            np.testing.assert_allclose(result.qdot, reference.qdot, atol=1e-12)
            assert reference.qdot[1] * (1.0 if limit == "lower" else -1.0) >= 0.0  # never further out
    assert outward > 0  # some of the round-off pointed out of the range (was clamped and flagged then)


def test_a_limit_acting_on_a_real_command_is_still_limited(planar: RobotModel) -> None:
    """The round-off tolerance does not hide a limit: joint 2 on its lower limit, a target that folds it further."""
    clik = Clik(planar, FramePositionTask(PLANAR_ARM_TCP, "xz"), method="transpose")
    q = np.array([0.0, planar.lower_limits[1], 0.0, 0.0])
    planar.update(q)
    jacobian = clik.build(q, np.zeros(2)).jacobian
    target = planar.frame_position(PLANAR_ARM_TCP)[[0, 2]] - 0.01 * jacobian[:, 1] / np.linalg.norm(jacobian[:, 1])
    for controller in (clik, CompiledClik(clik)):
        result = controller.step(q, target)
        assert result.limited and result.qdot[1] == 0.0


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("backend", ["python", "compiled"])
@pytest.mark.parametrize("value", [1e300, -1e300, 1.5 * MAX_COORDINATE, 1e150])
def test_huge_configuration_is_rejected_naming_q(planar: RobotModel, method: str, backend: str, value: float) -> None:
    objectives: list[Objective] = [
        JointLimitObjective.from_model(planar, activation_distance=0.3),
        PostureObjective(np.zeros(4), [1.0, 0.5, 0.2, 0.1]),
    ]
    clik = Clik(planar, FramePositionTask(PLANAR_ARM_TCP, "xz"), method=method, objectives=objectives)
    controller = CompiledClik(clik) if backend == "compiled" else clik
    with pytest.raises(ControllerError, match=r"^q must be finite, with every \|entry\| <= 1e\+06"):
        controller.step(np.array([value, 1.0, 0.0, 0.0]), np.zeros(2))
    # the largest accepted coordinate still gives a finite, bounded command
    result = controller.step(np.array([MAX_COORDINATE, 1.0, 0.0, 0.0]), np.zeros(2))
    assert np.all(np.isfinite(result.qdot)) and np.all(np.abs(result.qdot) <= clik.max_joint_velocity)


def test_huge_configuration_backends_agree_just_inside_the_accepted_range(planar: RobotModel) -> None:
    """At ``|q| = MAX_COORDINATE`` the gradients' round-off is still far below the command: both backends agree."""
    objectives: list[Objective] = [
        JointLimitObjective.from_model(planar, activation_distance=0.3),
        PostureObjective(np.zeros(4), [1.0, 0.5, 0.2, 0.1]),
    ]
    for method in METHODS:
        clik = Clik(planar, FramePositionTask(PLANAR_ARM_TCP, "xz"), method=method, objectives=objectives)
        compiled = CompiledClik(clik)
        for entries in (
            [MAX_COORDINATE, 1.0, 0.0, 0.0],
            [-MAX_COORDINATE, 0.0, 0.0, 0.0],
            [0.3, 0.0, MAX_COORDINATE, 0.0],
        ):
            q = np.array(entries)
            reference, result = clik.step(q, np.zeros(2)), compiled.step(q, np.zeros(2))
            np.testing.assert_allclose(result.qdot, reference.qdot, atol=1e-6)
            assert (result.status, result.limited) == (reference.status, reference.limited)


def test_acceleration_clik_rejects_a_huge_configuration(planar: RobotModel) -> None:
    clik = AccelerationClik(planar, FramePositionTask(PLANAR_ARM_TCP, "xz"))
    with pytest.raises(ControllerError, match=r"^q must be finite, with every \|entry\|"):
        clik.step(np.array([0.0, 1e300, 0.0, 0.0]), np.zeros(4), np.zeros(2), np.zeros(2), np.zeros(2))

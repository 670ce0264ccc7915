"""FrameAxisTask: error and Jacobian against finite differences on the 9-DoF agricultural arm."""

from __future__ import annotations

import numpy as np
import pytest

from redundancy_gym.assets import AGRI_ARM_XML
from redundancy_gym.controllers import Clik, ControllerError, FrameAxisTask
from redundancy_gym.model import RobotModel


@pytest.fixture(scope="module")
def model() -> RobotModel:
    return RobotModel.from_mjcf(AGRI_ARM_XML)


def test_error_derivative_is_minus_jacobian(model: RobotModel, rng: np.random.Generator) -> None:
    task = FrameAxisTask("tcp")
    for _ in range(5):
        q = rng.uniform(model.lower_limits, model.upper_limits) * 0.6
        model.update(q)
        target = task.value(model)  # zero error: u, v may move with q without changing de/dq there
        jac = task.jacobian(model)
        dq = rng.normal(size=model.nv)
        h = 1e-6
        model.update(q + h * dq)
        e_plus = task.error(model, target)
        model.update(q - h * dq)
        e_minus = task.error(model, target)
        np.testing.assert_allclose((e_plus - e_minus) / (2 * h), -jac @ dq, atol=1e-6)


def test_axis_error_is_sine_of_the_angle(model: RobotModel) -> None:
    task = FrameAxisTask("tcp")
    model.update(np.zeros(model.nq))
    a = task.value(model)[3:]
    angle = 0.3
    rotated = np.array([np.cos(angle), 0.0, np.sin(angle)]) if abs(a[0]) > 0.9 else None
    assert rotated is not None
    e = task.error(model, np.concatenate([task.value(model)[:3], rotated]))
    assert np.linalg.norm(e[:3]) == pytest.approx(0.0, abs=1e-12)
    assert np.linalg.norm(e[3:]) == pytest.approx(np.sin(angle), abs=1e-12)


def test_clik_converges_on_position_and_axis(model: RobotModel) -> None:
    task = FrameAxisTask("tcp")
    clik = Clik(model, task, method="dls", gain=10.0)
    q = np.array([0.4, 0.0, -1.42, 1.77, 0.0, 1.12, 0.0, -1.31, 0.0])
    model.update(q)
    start = task.value(model)
    axis = np.array([0.9, 0.3, 0.3]) / np.linalg.norm([0.9, 0.3, 0.3])
    target = np.concatenate([start[:3] + np.array([0.05, 0.1, 0.05]), axis])
    for _ in range(400):
        q = q + 0.01 * clik.step(q, target).qdot
    model.update(q)
    final = task.value(model)
    assert np.linalg.norm(final[:3] - target[:3]) < 1e-4
    assert np.arccos(np.clip(final[3:] @ axis, -1, 1)) < 1e-3


def test_bad_arguments_raise(model: RobotModel) -> None:
    with pytest.raises(ControllerError, match="axis"):
        FrameAxisTask("tcp", axis=3)
    task = FrameAxisTask("tcp")
    model.update(np.zeros(model.nq))
    with pytest.raises(ControllerError, match="shape"):
        task.error(model, np.zeros(5))
    with pytest.raises(ControllerError, match="zero"):
        task.error(model, np.zeros(6))

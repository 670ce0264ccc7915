"""Whole-body IK: (5.62) by Sherman-Morrison-Woodbury, exact tracking in a kinematic rollout, L_z reduction."""

from __future__ import annotations

import numpy as np
import pytest

from redundancy_gym.assets import BIPED_XML
from redundancy_gym.controllers import ControllerError
from redundancy_gym.controllers.walking import WholeBodyIk
from redundancy_gym.model import RobotModel

from .biped_helpers import standing, walking_controller


@pytest.fixture(scope="module")
def model() -> RobotModel:
    return RobotModel.from_mjcf(BIPED_XML)


def test_smw_solve_equals_the_dense_weighted_pseudoinverse(model: RobotModel) -> None:
    rng = np.random.default_rng(3)
    ik = WholeBodyIk(model, gamma=0.008)
    jac = rng.normal(size=(18, model.nv))
    j_lz = rng.normal(size=model.nv)
    rhs, gradient = rng.normal(size=18), rng.normal(size=model.nv)
    qdot, _, ok = ik.solve(jac, rhs, j_lz, gradient)
    w = 0.008 * np.eye(model.nv) + np.outer(j_lz, j_lz)
    w_inv = np.linalg.inv(w)
    pinv = w_inv @ jac.T @ np.linalg.inv(jac @ w_inv @ jac.T)
    z = (ik.nullspace_gain / ik.beta) * gradient
    expected = pinv @ rhs - (np.eye(model.nv) - pinv @ jac) @ w_inv @ z  # (5.14) with W of (5.62)
    assert ok and np.allclose(qdot, expected, rtol=1e-7, atol=1e-9)
    assert np.allclose(jac @ qdot, rhs, atol=1e-8)


def test_kinematic_rollout_tracks_the_pattern_to_1e6(model: RobotModel) -> None:
    controller = walking_controller(model)
    controller.start(standing(model), 0.7)
    ik, pattern = controller.ik, controller.pattern
    q = controller.q_ref
    assert q is not None
    worst = 0.0
    start = controller._reference(pattern.sample(0.0), np.zeros(2), np.zeros(2))
    for k in range(int(round(pattern.step_start(3) / controller.dt))):
        end = controller._reference(pattern.sample((k + 1) * controller.dt), np.zeros(2), np.zeros(2))
        result = ik.step(q, start, end, controller.dt)
        assert result.success
        q, start = result.q, end
        _, error, _ = ik.build(q, end)
        worst = max(worst, float(np.max(np.abs(error))))
    assert worst < 1e-6


def test_momentum_minimization_lowers_peak_lz(model: RobotModel) -> None:
    peaks = {}
    for on in (False, True):
        controller = walking_controller(model, momentum_minimization=on)
        controller.start(standing(model), 0.7)
        q, pattern = controller.q_ref, controller.pattern
        assert q is not None
        lz = []
        start = controller._reference(pattern.sample(0.0), np.zeros(2), np.zeros(2))
        for k in range(int(round(pattern.step_start(4) / controller.dt))):
            end = controller._reference(pattern.sample((k + 1) * controller.dt), np.zeros(2), np.zeros(2))
            result = controller.ik.step(q, start, end, controller.dt)
            q, start = result.q, end
            lz.append(result.lz)
        peaks[on] = float(np.max(np.abs(lz[int(round(pattern.step_start(1) / controller.dt)) :])))
    assert peaks[True] < 0.7 * peaks[False]


def test_ik_rejects_fixed_base_and_bad_parameters(model: RobotModel) -> None:
    from redundancy_gym.assets import PLANAR_ARM_XML

    with pytest.raises(ControllerError, match="floating-base"):
        WholeBodyIk(RobotModel.from_mjcf(PLANAR_ARM_XML))
    with pytest.raises(ControllerError, match="gamma"):
        WholeBodyIk(model, gamma=0.0)
    with pytest.raises(ControllerError, match="start"):
        walking_controller(model).step(np.zeros(model.nq), np.zeros(model.nv), np.zeros((2, 3)), np.zeros((2, 3)))

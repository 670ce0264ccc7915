"""General Inverse Kineto-Dynamics (5.92)-(5.96) on the 9-DoF agricultural arm, against pinocchio's forward
dynamics (ABA) as the independent reference."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from redundancy_gym.assets import AGRI_ARM_TCP, AGRI_ARM_XML
from redundancy_gym.controllers import ControllerError, FramePositionTask
from redundancy_gym.controllers.ikd import GeneralIkd
from redundancy_gym.model import RobotModel

LIFT = 0  # the prismatic lift joint


@pytest.fixture(scope="module")
def arm() -> RobotModel:
    return RobotModel.from_mjcf(AGRI_ARM_XML)


def _state(arm: RobotModel, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    middle = 0.5 * (arm.lower_limits + arm.upper_limits)
    return middle + rng.uniform(-0.3, 0.3, arm.nq), rng.normal(0.0, 0.5, arm.nv)


def _tcp_acceleration(arm: RobotModel, q: np.ndarray, qdot: np.ndarray, qddot: np.ndarray) -> np.ndarray:
    drift = arm.frame_jacobian_derivative_times_velocity(q, qdot, AGRI_ARM_TCP, "translational")
    return arm.frame_jacobian(AGRI_ARM_TCP, "translational") @ qddot + drift


def test_the_forward_dynamics_under_the_solved_forces_give_the_prescribed_tcp_acceleration(arm):
    # the lift's force prescribed, the TCP's acceleration prescribed, the other eight joint torques solved: the
    # motion they give in forward dynamics is the IKD's, with the TCP accelerating as prescribed
    ikd = GeneralIkd(arm, FramePositionTask(AGRI_ARM_TCP), known_forces=[LIFT])
    model, data = arm.pinocchio_model, arm.pinocchio_model.createData()
    rng = np.random.default_rng(7)
    for _ in range(20):
        q, qdot = _state(arm, rng)
        lift_force = np.array([rng.uniform(300.0, 900.0)])
        acceleration = rng.normal(0.0, 1.0, 3)
        result = ikd.step(q, qdot, lift_force, np.zeros(3), np.zeros(3), acceleration)
        assert result.success and result.status == "ok"
        assert result.forces[LIFT] == lift_force[0]
        forward = pin.aba(model, data, q, qdot, result.forces)
        np.testing.assert_allclose(forward, result.qddot, rtol=0.0, atol=1e-9 * np.abs(result.qddot).max())
        np.testing.assert_allclose(_tcp_acceleration(arm, q, qdot, forward), acceleration, rtol=0.0, atol=1e-9)
        assert result.residual < 1e-9


def test_the_inverse_dynamics_of_the_solved_motion_are_the_solved_forces(arm):
    ikd = GeneralIkd(arm, FramePositionTask(AGRI_ARM_TCP), known_forces=[LIFT])
    model, data = arm.pinocchio_model, arm.pinocchio_model.createData()
    rng = np.random.default_rng(8)
    q, qdot = _state(arm, rng)
    result = ikd.step(q, qdot, np.array([500.0]), np.zeros(3), np.zeros(3), np.array([0.2, -0.1, 0.3]))
    torques = pin.rnea(model, data, q, qdot, result.qddot)
    np.testing.assert_allclose(torques, result.forces, rtol=1e-9, atol=1e-9 * np.abs(result.forces).max())


def test_a_free_task_row_is_solved_for_and_is_the_motion_s_own_acceleration(arm):
    # seven torques known, two unknown, the TCP's z left free: three unknowns for three task rows
    known = [LIFT, 1, 2, 3, 4, 5, 6]
    ikd = GeneralIkd(arm, FramePositionTask(AGRI_ARM_TCP), known_forces=known, known_task=[0, 1])
    model, data = arm.pinocchio_model, arm.pinocchio_model.createData()
    rng = np.random.default_rng(9)
    q, qdot = _state(arm, rng)
    gravity = pin.computeGeneralizedGravity(model, data, q)
    result = ikd.step(q, qdot, gravity[known], np.zeros(2), np.zeros(2), np.array([0.1, -0.2]))
    assert result.success and result.unknown_forces.shape == (2,) and result.unknown_task_acceleration.shape == (1,)
    forward = pin.aba(model, data, q, qdot, result.forces)
    tcp = _tcp_acceleration(arm, q, qdot, forward)
    np.testing.assert_allclose(tcp[:2], [0.1, -0.2], atol=1e-9)
    np.testing.assert_allclose(tcp[2], result.unknown_task_acceleration[0], atol=1e-9)


def test_a_tcp_path_is_followed_with_the_lift_force_prescribed_and_the_lift_moves_by_itself(arm):
    # 1 s along a quintic line with the lift pushed by a constant force 2 N above its static load: the stabilized
    # IKD, integrated, follows the path; the lift joint, driven only by its prescribed force and the constraint,
    # moves as the dynamics say, and the damped self-motion stays bounded
    task = FramePositionTask(AGRI_ARM_TCP)
    ikd = GeneralIkd(arm, task, known_forces=[LIFT], stiffness=400.0, damping=40.0, self_motion_damping=5.0)
    rng = np.random.default_rng(10)
    q, _ = _state(arm, rng)
    qdot = np.zeros(arm.nv)
    model, data = arm.pinocchio_model, arm.pinocchio_model.createData()
    push = float(pin.computeGeneralizedGravity(model, data, q)[LIFT]) + 2.0
    arm.update(q)
    start = arm.frame_position(AGRI_ARM_TCP).copy()
    end = start + np.array([-0.08, 0.05, 0.06])
    dt, steps = 0.001, 1000
    worst = 0.0
    lift_start = q[LIFT]
    for k in range(steps):
        s = k * dt
        tau = s / (steps * dt)
        shape = 10 * tau**3 - 15 * tau**4 + 6 * tau**5
        rate = (30 * tau**2 - 60 * tau**3 + 30 * tau**4) / (steps * dt)
        accel = (60 * tau - 180 * tau**2 + 120 * tau**3) / (steps * dt) ** 2
        target = start + shape * (end - start)
        result = ikd.step(q, qdot, np.array([push]), target, rate * (end - start), accel * (end - start))
        assert result.success and result.forces[LIFT] == push
        qdot = qdot + dt * result.qddot
        q = arm.integrate(q, qdot, dt)
        arm.update(q)
        worst = max(worst, float(np.linalg.norm(arm.frame_position(AGRI_ARM_TCP) - target)))
    assert worst < 1e-3
    np.testing.assert_allclose(arm.frame_position(AGRI_ARM_TCP), end, atol=1e-3)
    assert abs(q[LIFT] - lift_start) > 0.01  # not the lift's static load: it moves
    assert np.all(np.abs(qdot) < 1.0)
    # with the torque norm alone and no damping of the self-motion, the light wrist joints take the motion and run off
    plain = GeneralIkd(arm, task, known_forces=[LIFT], stiffness=400.0, damping=40.0, weighting="forces")
    q, qdot = _state(arm, np.random.default_rng(10))[0], np.zeros(arm.nv)
    peak = 0.0
    for k in range(steps):
        tau = k / steps
        shape = 10 * tau**3 - 15 * tau**4 + 6 * tau**5
        result = plain.step(q, qdot, np.array([push]), start + shape * (end - start), np.zeros(3), np.zeros(3))
        if not result.success:
            break
        qdot = qdot + dt * result.qddot
        q = arm.integrate(q, qdot, dt)
        peak = max(peak, float(np.abs(qdot).max()))
        if peak > 10.0:
            break
    assert peak > 10.0


def test_more_prescribed_task_rows_than_unknowns_is_singular_and_returns_zeros(arm):
    ikd = GeneralIkd(arm, FramePositionTask(AGRI_ARM_TCP), known_forces=list(range(8)))
    rng = np.random.default_rng(11)
    q, qdot = _state(arm, rng)
    result = ikd.step(q, qdot, np.zeros(8), np.zeros(3), np.zeros(3), np.ones(3))
    assert not result.success and result.status == "singular"
    assert np.all(result.qddot == 0.0) and np.all(np.isfinite(result.forces))
    damped = GeneralIkd(
        arm,
        FramePositionTask(AGRI_ARM_TCP),
        known_forces=list(range(8)),
        method="dls",
        dls_threshold=1e3,
        dls_max_damping=1e-3,
    ).step(q, qdot, np.zeros(8), np.zeros(3), np.zeros(3), np.ones(3))
    assert damped.success and damped.status == "damped" and np.all(np.isfinite(damped.qddot))
    assert damped.residual > 0.0  # a least-squares compromise, not an exact solution


def test_bad_arguments_raise_naming_them(arm):
    task = FramePositionTask(AGRI_ARM_TCP)
    with pytest.raises(ControllerError, match="known_forces"):
        GeneralIkd(arm, task, known_forces=[9])
    with pytest.raises(ControllerError, match="known_forces"):
        GeneralIkd(arm, task, known_forces=[0, 0])
    with pytest.raises(ControllerError, match="known_task"):
        GeneralIkd(arm, task, known_forces=[0], known_task=[3])
    with pytest.raises(ControllerError, match="nothing to solve"):
        GeneralIkd(arm, task, known_forces=list(range(9)))
    with pytest.raises(ControllerError, match="force_map"):
        GeneralIkd(arm, task, known_forces=[0], force_map=np.eye(3))
    with pytest.raises(ControllerError, match="stiffness"):
        GeneralIkd(arm, task, known_forces=[0], stiffness=-1.0)
    with pytest.raises(ControllerError, match="method"):
        GeneralIkd(arm, task, known_forces=[0], method="transpose")
    with pytest.raises(ControllerError, match="weighting"):
        GeneralIkd(arm, task, known_forces=[0], weighting="torque")
    with pytest.raises(ControllerError, match="posture"):
        GeneralIkd(arm, task, known_forces=[0], posture_stiffness=1.0)
    ikd = GeneralIkd(arm, task, known_forces=[0])
    q = 0.5 * (arm.lower_limits + arm.upper_limits)
    with pytest.raises(ControllerError, match="known_forces"):
        ikd.step(q, np.zeros(9), np.array([1.0, 2.0]), np.zeros(3), np.zeros(3), np.zeros(3))
    with pytest.raises(ControllerError, match="target_acceleration"):
        ikd.step(q, np.zeros(9), np.array([1.0]), np.zeros(3), np.zeros(3), np.array([np.nan, 0.0, 0.0]))
    with pytest.raises(ControllerError, match="qdot"):
        ikd.step(q, np.zeros(8), np.array([1.0]), np.zeros(3), np.zeros(3), np.zeros(3))

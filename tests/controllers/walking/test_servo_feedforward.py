"""ServoFeedforward: the inverse dynamics with contact wrenches, and stiff servos that stop sagging with it."""

from __future__ import annotations

import numpy as np
import pytest

from redundancy_gym.constants import GRAVITY
from redundancy_gym.controllers import ControllerError
from redundancy_gym.controllers.walking import (
    CompiledServoFeedforward,
    ServoFeedforward,
    WalkingController,
    WalkingIkConfig,
    WalkingIkdConfig,
)
from redundancy_gym.envs.biped_walk import BipedWalkEnv
from redundancy_gym.model import RobotModel

from .biped_helpers import standing


@pytest.fixture(scope="module")
def model() -> RobotModel:
    return RobotModel.from_mjcf(BipedWalkEnv.ROBOT_XML)


@pytest.fixture(scope="module")
def stiffness() -> np.ndarray:
    env = BipedWalkEnv()
    try:
        return env.servo_stiffness
    finally:
        env.close()


def test_env_reports_the_servo_gains_of_its_model_file(stiffness: np.ndarray) -> None:
    # biped.xml: knees 5000, ankle pitch 3000, toes 300 N m/rad (right leg first, BIPED_JOINTS order)
    assert stiffness.shape == (22,)
    assert (stiffness[3], stiffness[4], stiffness[6]) == (5000.0, 3000.0, 300.0)


TWINS = [ServoFeedforward, CompiledServoFeedforward]


@pytest.mark.parametrize("twin", TWINS)
@pytest.mark.parametrize(("contact", "right_load"), [((True, True), 0.3), ((True, False), 1.0), ((False, True), 0.0)])
def test_contact_wrenches_balance_the_base(
    model: RobotModel, stiffness: np.ndarray, contact, right_load, twin: type[ServoFeedforward]
) -> None:
    rng = np.random.default_rng(4)
    q = standing(model)
    qdot, qddot = 0.3 * rng.normal(size=model.nv), rng.normal(size=model.nv)
    result = twin(model, stiffness).torques(q, qdot, qddot, contact, right_load)
    tau = model.inverse_dynamics(q, qdot, qddot) + model.joint_damping * qdot
    for i, wrench in enumerate(result.wrenches):
        if contact[i]:
            tau -= model.frame_jacobian(("r_sole", "l_sole")[i]).T @ wrench
        else:
            assert not wrench.any()  # a foot in the air carries nothing
    assert np.max(np.abs(tau[:6])) < 1e-8 * np.max(np.abs(result.torques))  # the base needs no actuator
    assert result.base_residual < 1e-8 * np.max(np.abs(result.torques))
    assert np.allclose(result.torques, tau[6:])
    assert np.allclose(result.offsets, result.torques / stiffness)


def test_the_compiled_twin_gives_the_references_torques_and_wrenches(model: RobotModel, stiffness: np.ndarray) -> None:
    rng = np.random.default_rng(11)
    reference, compiled = (
        ServoFeedforward(model, stiffness, gain=0.8),
        CompiledServoFeedforward(model, stiffness, gain=0.8),
    )
    # double and single support, a foot at its touchdown (load below MIN_LOAD) and flight
    cases = [
        ((True, True), 0.37),
        ((False, True), 0.0),
        ((True, True), 1e-4),
        ((True, False), 1.0),
        ((False, False), 0.5),
    ]
    for contact, right_load in cases:
        q = standing(model)
        q[7:] += 0.05 * rng.normal(size=model.nq - 7)
        qdot, qddot = 0.5 * rng.normal(size=model.nv), 2.0 * rng.normal(size=model.nv)
        a = reference.torques(q, qdot, qddot, contact, right_load)
        b = compiled.torques(q, qdot, qddot, contact, right_load)
        scale = np.max(np.abs(a.torques))
        assert np.max(np.abs(a.torques - b.torques)) < 1e-10 * scale, contact
        assert np.max(np.abs(a.offsets - b.offsets)) < 1e-10 * np.max(np.abs(a.offsets))
        assert np.max(np.abs(a.wrenches - b.wrenches)) < 1e-10 * max(1.0, np.max(np.abs(a.wrenches)))
        assert b.base_residual == pytest.approx(a.base_residual, rel=1e-9, abs=1e-9 * scale)


def test_the_walking_controller_picks_the_twin_by_its_backend(model: RobotModel, stiffness: np.ndarray) -> None:
    lower, upper = model.lower_limits[7:], model.upper_limits[7:]
    for backend, twin in (("compiled", CompiledServoFeedforward), ("python", ServoFeedforward)):
        controller = WalkingController(
            model,
            0.004,
            lower,
            upper,
            ik=WalkingIkConfig(backend=backend),
            ikd=WalkingIkdConfig(),
            servo_stiffness=stiffness,
        )
        assert type(controller.feedforward) is twin


def test_standing_weight_is_split_by_the_load_share(model: RobotModel, stiffness: np.ndarray) -> None:
    q, zero = standing(model), np.zeros(model.nv)
    for right_load in (0.2, 0.5, 0.8):
        wrenches = ServoFeedforward(model, stiffness).torques(q, zero, zero, (True, True), right_load).wrenches
        weight = model.total_mass * GRAVITY
        assert wrenches[0, 2] + wrenches[1, 2] == pytest.approx(weight)
        assert wrenches[0, 2] / weight == pytest.approx(right_load, abs=0.03)


def test_feedforward_removes_the_servos_sag_in_the_simulator(model: RobotModel, stiffness: np.ndarray) -> None:
    # The biped stands for 1 s holding its reset posture with and without the feedforward: the servos settle
    # tau / k_p short of their targets (about a milliradian at the knees) unless the targets lead by that much.
    def sag(feedforward: bool) -> float:
        env = BipedWalkEnv()
        try:
            obs, _ = env.reset(seed=0)
            qpos = env.unwrapped.data.qpos.copy()
            q, _ = model.from_mujoco_state(qpos, np.zeros(model.nv))
            targets = qpos[7:].copy()
            if feedforward:
                zero = np.zeros(model.nv)
                targets += ServoFeedforward(model, stiffness).torques(q, zero, zero, (True, True), 0.5).offsets
            action = (targets - env.nominal_configuration) / env.action_scale
            for _ in range(250):
                env.step(action.astype(np.float32))
            return float(np.sqrt(np.mean((env.unwrapped.data.qpos[7:] - qpos[7:]) ** 2)))
        finally:
            env.close()

    plain, compensated = sag(False), sag(True)
    assert plain > 5e-4
    assert compensated < 0.2 * plain


def test_invalid_arguments_are_named(model: RobotModel, stiffness: np.ndarray) -> None:
    with pytest.raises(ControllerError, match="stiffness"):
        ServoFeedforward(model, stiffness[:5])
    with pytest.raises(ControllerError, match="stiffness"):
        ServoFeedforward(model, np.zeros(22))
    for gain in (-1.0, float("nan"), "1"):
        with pytest.raises(ControllerError, match=r"gain must be a finite real number >= 0"):
            ServoFeedforward(model, stiffness, gain=gain)  # type: ignore[arg-type]
    zero = np.zeros(model.nv)
    for twin in TWINS:
        for load in (1.5, -0.1, float("nan"), None):
            with pytest.raises(ControllerError, match=r"right_load must be a finite real number in \[0, 1\]"):
                twin(model, stiffness).torques(standing(model), zero, zero, (True, True), load)  # type: ignore[arg-type]


def test_the_clik_walker_cannot_feed_forward(model: RobotModel, stiffness: np.ndarray) -> None:
    lower, upper = model.lower_limits[7:], model.upper_limits[7:]
    with pytest.raises(ControllerError, match="servo_stiffness needs the IKD"):
        WalkingController(model, 0.004, lower, upper, servo_stiffness=stiffness)
    controller = WalkingController(model, 0.004, lower, upper, ikd=WalkingIkdConfig(), servo_stiffness=stiffness)
    assert controller.feedforward is not None

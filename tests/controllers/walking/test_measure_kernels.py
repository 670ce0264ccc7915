"""The walking controller's compiled measurement (CompiledMeasurement) agrees with the pinocchio/NumPy path it
replaces, and the controller's step takes the checked path for inputs the kernel does not read."""

from __future__ import annotations

import numpy as np
import pytest

from redundancy_gym.assets import BIPED_XML
from redundancy_gym.controllers.walking import CompiledMeasurement
from redundancy_gym.controllers.walking.zmp_estimator import estimate_zmp
from redundancy_gym.model import ModelError, RobotModel

from .biped_helpers import standing, walking_controller

FRAMES = ("r_ankle_ft", "l_ankle_ft", "r_sole", "l_sole")


@pytest.fixture(scope="module")
def model() -> RobotModel:
    return RobotModel.from_mjcf(BIPED_XML)


def random_state(model: RobotModel, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A pinocchio ``(q, v)``: the standing posture moved and turned, joints perturbed, a random velocity."""
    q = standing(model)
    q[:3] += rng.normal(scale=0.2, size=3)
    quat = rng.normal(size=4)
    q[3:7] = quat / np.linalg.norm(quat)
    q[7:] += rng.normal(scale=0.2, size=model.nq - 7)
    return q, rng.normal(size=model.nv)


def reference(
    model: RobotModel,
    q: np.ndarray,
    v: np.ndarray,
    sensors: np.ndarray,
    stance: int,
    planned: tuple[float, float, float],
    stance_frame: bool,
    ground: float,
) -> dict[str, object]:
    """What WalkingController measured through pinocchio and NumPy before the kernel (its _in_stance_frame)."""
    com, com_velocity, rotations, positions = model.measure(q, v, FRAMES)
    turn, shift = np.eye(3), np.zeros(3)
    if stance_frame:
        rotation = rotations[2 + stance]
        yaw = np.arctan2(rotation[1, 0], rotation[0, 0]) - planned[2]
        c, s = np.cos(yaw), np.sin(yaw)
        turn = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
        real = positions[2 + stance]
        shift = np.array([planned[0], planned[1], 0.0]) - turn @ np.array([real[0], real[1], 0.0])
        com, com_velocity, rotations, positions = (
            turn @ com + shift,
            turn @ com_velocity,
            turn @ rotations,
            positions @ turn.T + shift,
        )
    wrench = sensors.reshape(2, 6)
    contact = estimate_zmp(rotations[:2], positions[:2], wrench[:, :3], wrench[:, 3:], ground=ground)
    return {
        "com": com,
        "com_velocity": com_velocity,
        "rotations": rotations,
        "positions": positions,
        "turn": turn,
        "shift": shift,
        "zmp": contact.zmp,
        "cop": contact.cop,
        "normal_force": contact.normal_force,
        "moment": contact.moment,
    }


def to_mujoco(q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """MuJoCo's qpos (w x y z) and qvel (world linear velocity) of a pinocchio state."""
    qpos = q.copy()
    qpos[3:7] = q[[6, 3, 4, 5]]
    x, y, z, w = q[3:7]
    rotation = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
    qvel = v.copy()
    qvel[:3] = rotation @ v[:3]
    return qpos, qvel


@pytest.mark.parametrize("stance_frame", [True, False])
@pytest.mark.parametrize("mujoco", [True, False])
def test_the_kernel_agrees_with_pinocchio_and_numpy(model: RobotModel, stance_frame: bool, mujoco: bool) -> None:
    measurement = CompiledMeasurement(model, FRAMES)
    rng = np.random.default_rng(3)
    for trial in range(20):
        q, v = random_state(model, rng)
        sensors = rng.normal(scale=50.0, size=12)
        sensors[[2, 8]] = -rng.uniform(0.0, 400.0, size=2)  # one foot unloaded now and then (below 20 N)
        if trial % 5 == 0:
            sensors[2] = -5.0
        stance = trial % 2
        planned = (float(rng.normal()), float(rng.normal()), float(rng.normal()) if trial % 3 else 0.0)
        inputs = to_mujoco(q, v) if mujoco else (q, v)
        m = measurement.measure(
            *inputs, sensors, mujoco=mujoco, stance_frame=stance_frame, stance=stance, planned=planned, ground=0.01
        )
        assert m is not None
        expected = reference(model, q, v, sensors, stance, planned, stance_frame, 0.01)
        np.testing.assert_allclose(m.q, q, rtol=0.0, atol=1e-12)
        np.testing.assert_allclose(m.v, v, rtol=0.0, atol=1e-12)
        for name, value in expected.items():
            got = getattr(m, name)
            if value is None:
                assert got is None, name
                continue
            np.testing.assert_allclose(got, value, rtol=0.0, atol=1e-10, err_msg=name)


def test_non_finite_inputs_and_a_zero_quaternion_give_none(model: RobotModel) -> None:
    measurement = CompiledMeasurement(model, FRAMES)
    q, v = random_state(model, np.random.default_rng(0))
    sensors = np.zeros(12)
    kwargs = {"stance_frame": True, "stance": 0, "planned": (0.0, 0.0, 0.0), "ground": 0.0}
    assert measurement.measure(q, v, sensors, mujoco=False, **kwargs) is not None
    for k in range(3):  # a NaN in q, in v, in the sensors
        args = [q.copy(), v.copy(), sensors.copy()]
        args[k][5] = np.nan
        assert measurement.measure(*args, mujoco=False, **kwargs) is None
    qpos, qvel = to_mujoco(q, v)
    qpos[3:7] = 0.0
    assert measurement.measure(qpos, qvel, sensors, mujoco=True, **kwargs) is None


def test_step_mujoco_is_step_on_the_converted_state(model: RobotModel) -> None:
    """step_mujoco (the policy's path) and step on from_mujoco_state give the same walk; lists take the checked
    path with the same result; a NaN configuration is named as before."""
    controllers = [walking_controller(model) for _ in range(3)]
    for c in controllers:
        c.start(standing(model), 0.5)
    rng = np.random.default_rng(1)
    forces = np.array([[0.0, 0.0, -300.0], [0.0, 0.0, -290.0]])
    torques = np.array([[1.0, -2.0, 0.0], [0.5, 3.0, 0.0]])
    wrenches = np.concatenate([forces, torques], axis=1).reshape(-1)
    q = controllers[0].q_ref.copy()
    while controllers[0].time < 1.0:
        v = rng.normal(scale=0.05, size=model.nv)
        qpos, qvel = to_mujoco(q, v)
        a = controllers[0].step_mujoco(qpos, qvel, wrenches)
        b = controllers[1].step(*model.from_mujoco_state(qpos, qvel), forces, torques)
        c = controllers[2].step(
            *(x.tolist() for x in model.from_mujoco_state(qpos, qvel)), forces.tolist(), torques.tolist()
        )
        np.testing.assert_allclose(a.joint_targets, b.joint_targets, rtol=0.0, atol=1e-12)
        np.testing.assert_allclose(c.joint_targets, b.joint_targets, rtol=0.0, atol=1e-12)
        np.testing.assert_allclose(a.contact.zmp, b.contact.zmp, rtol=0.0, atol=1e-12)
        q = a.ik.q
    bad = q.copy()
    bad[9] = np.nan
    with pytest.raises(ModelError, match="non-finite"):
        controllers[1].step(bad, np.zeros(model.nv), forces, torques)

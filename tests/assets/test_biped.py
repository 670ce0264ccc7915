"""The Lola-like biped MJCF: the published facts, the documented choices, and pinocchio agreeing with MuJoCo."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from redundancy_gym.assets import (
    BIPED_ANKLE_SITES,
    BIPED_HARDWARE_LIMITS_DEG,
    BIPED_JOINTS,
    BIPED_SERVOS,
    BIPED_SOFT_LIMIT_MARGIN,
    BIPED_SOLE_GEOMS,
    BIPED_XML,
)
from redundancy_gym.geometry import GeometryError  # noqa: F401 - the collision model is built below
from redundancy_gym.model import RobotModel, collision_model_from_mjcf

MIRRORED = ("hip_yaw", "hip_roll", "ankle_roll", "shoulder_roll")


@pytest.fixture(scope="module")
def plant() -> tuple[mujoco.MjModel, mujoco.MjData]:
    model = mujoco.MjModel.from_xml_path(str(BIPED_XML))
    return model, mujoco.MjData(model)


def _with_floor() -> mujoco.MjModel:
    xml = (
        f'<mujoco><include file="{BIPED_XML}"/><worldbody><geom name="floor" type="plane" size="5 5 0.1" '
        'contype="1" conaffinity="1"/></worldbody></mujoco>'
    )
    return mujoco.MjModel.from_xml_string(xml)


def test_published_facts(plant) -> None:
    """About 1.8 m and 60 kg; 7 joints per leg with a toe, 2 pelvis joints, 3 per arm, all actuated; free base."""
    model, data = plant
    mujoco.mj_forward(model, data)
    assert model.body_subtreemass[0] == pytest.approx(60.0)
    assert data.site("head_top").xpos[2] == pytest.approx(1.80, abs=1e-9)
    assert model.jnt_type[0] == mujoco.mjtJoint.mjJNT_FREE
    hinges = [model.joint(i).name for i in range(1, model.njnt)]
    assert tuple(hinges) == BIPED_JOINTS and len(hinges) == 22
    assert tuple(model.actuator(i).name for i in range(model.nu)) == BIPED_SERVOS
    assert [model.actuator(s).trnid[0] for s in BIPED_SERVOS] == [model.joint(j).id for j in BIPED_JOINTS]


def test_sole_is_26_by_15_cm_with_a_toe_segment(plant) -> None:
    model, data = plant
    mujoco.mj_forward(model, data)
    for side in ("r", "l"):
        boxes = [data.geom(f"{side}_sole_geom"), data.geom(f"{side}_toe_sole_geom")]
        sizes = [model.geom(g.id).size for g in boxes]
        front = boxes[1].xpos[0] + sizes[1][0]
        back = boxes[0].xpos[0] - sizes[0][0]
        assert front - back == pytest.approx(0.26)
        assert 2 * sizes[0][1] == pytest.approx(0.15) and 2 * sizes[1][1] == pytest.approx(0.15)
        # standing straight the soles touch z = 0
        assert min(b.xpos[2] - s[2] for b, s in zip(boxes, sizes, strict=False)) == pytest.approx(0.0, abs=1e-9)
    assert set(BIPED_SOLE_GEOMS) <= {model.geom(i).name for i in range(model.ngeom)}


def test_joint_ranges_are_the_measured_hardware_limits_mirrored_left(plant) -> None:
    model, _ = plant
    for name, (lo, hi) in BIPED_HARDWARE_LIMITS_DEG.items():
        sides = ("r_", "l_") if f"r_{name}" in BIPED_JOINTS else ("",)
        for side in sides:
            expected = (-hi, -lo) if side == "l_" and name in MIRRORED else (lo, hi)
            assert np.degrees(model.joint(side + name).range) == pytest.approx(expected, abs=1e-3)
    assert np.degrees(BIPED_SOFT_LIMIT_MARGIN) == pytest.approx(5.0)


def _pinocchio_q(qpos: np.ndarray) -> np.ndarray:
    """MuJoCo's free-joint quaternion is (w, x, y, z); pinocchio's is (x, y, z, w)."""
    q = qpos.copy()
    q[3:7] = qpos[[4, 5, 6, 3]]
    return q


def test_pinocchio_and_mujoco_agree_on_kinematics_and_com(plant, rng) -> None:
    model, data = plant
    robot = RobotModel.from_mjcf(BIPED_XML)
    assert robot.nq == model.nq and robot.nv == model.nv
    assert robot.total_mass == pytest.approx(60.0)
    sites = ("head_top", "imu", "r_sole", "l_sole", "r_hand", "l_hand", *BIPED_ANKLE_SITES)
    for _ in range(20):
        quat = rng.normal(size=4)
        qpos = np.concatenate(
            [
                rng.normal(0.0, 0.3, 3) + [0, 0, 1],
                quat / np.linalg.norm(quat),
                rng.uniform(model.jnt_range[1:, 0], model.jnt_range[1:, 1]),
            ]
        )
        data.qpos[:] = qpos
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        robot.update(_pinocchio_q(qpos))
        for site in sites:
            np.testing.assert_allclose(robot.frame_position(site), data.site(site).xpos, atol=1e-9)
            np.testing.assert_allclose(robot.frame_rotation(site), data.site(site).xmat.reshape(3, 3), atol=1e-9)
        np.testing.assert_allclose(robot.com(), data.subtree_com[0], atol=1e-9)


def test_stands_on_the_floor_and_the_ankle_sensors_carry_its_weight() -> None:
    """Slightly bent legs under the position servos: 2 s upright, and the ankle force sensors carry the weight
    above them (everything but the feet and toes)."""
    model = _with_floor()
    data = mujoco.MjData(model)
    bend = {"knee": 0.3, "hip_pitch": -0.15, "ankle_pitch": -0.15}
    for side in ("r", "l"):
        for joint, value in bend.items():
            data.ctrl[model.actuator(f"servo_{side}_{joint}").id] = value
    for _ in range(int(2.0 / model.opt.timestep)):
        mujoco.mj_step(model, data)
    assert data.qpos[2] == pytest.approx(0.08 + 2 * 0.42 * np.cos(0.15) + 0.1, abs=5e-3)
    assert np.linalg.norm(data.qpos[4:6]) < 0.01  # upright
    feet = sum(model.body(f"{s}_{b}").mass[0] for s in ("r", "l") for b in ("foot", "toe"))
    load = -sum(data.sensor(f"{s}_ankle_force").data[2] for s in ("r", "l"))
    assert load == pytest.approx((60.0 - feet) * 9.81, rel=1e-3)


def test_capsules_double_as_a_self_collision_model_that_is_clear_when_standing() -> None:
    robot = RobotModel.from_mjcf(BIPED_XML)
    collision = collision_model_from_mjcf(robot)
    names = {s.name for s in collision.robot}
    assert {"r_thigh", "l_thigh", "r_shank", "r_foot", "r_toe", "torso", "r_forearm"} <= names
    q = np.zeros(robot.nq)
    q[6] = 1.0  # identity quaternion (x, y, z, w)
    robot.update(q)
    state = collision.evaluate(robot)
    assert state.distance.min() > 0.0

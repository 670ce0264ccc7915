import mujoco
import numpy as np

from redundancy_gym.assets import (
    PLANAR_ARM_JOINTS,
    PLANAR_ARM_LINK_GEOMS,
    PLANAR_ARM_TCP,
    PLANAR_ARM_XML,
    PLANAR_OBSTACLE_GEOM,
)
from redundancy_gym.assets.planar_arm_scene import planar_arm_scene_xml


def test_documented_dimensions() -> None:
    model = mujoco.MjModel.from_xml_path(str(PLANAR_ARM_XML))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)  # q = 0: stretched along +x
    assert np.allclose(data.site(PLANAR_ARM_TCP).xpos, [1.4, 0.0, 0.0])
    masses = [model.body(f"link{i}").mass[0] for i in range(1, 5)]
    assert masses == [4.0, 3.0, 2.0, 1.0]
    ranges_deg = np.degrees([model.joint(j).range for j in PLANAR_ARM_JOINTS])
    assert np.allclose(ranges_deg[:, 1], [150, 140, 140, 120], atol=1e-4)
    assert all(model.joint(j).type == mujoco.mjtJoint.mjJNT_HINGE for j in PLANAR_ARM_JOINTS)
    assert all(np.allclose(model.joint(j).axis, [0, 1, 0]) for j in PLANAR_ARM_JOINTS)


def test_scene_includes_obstacle_only_when_asked() -> None:
    def scene(obstacle_center: tuple[float, float] | None) -> str:
        return planar_arm_scene_xml(
            obstacle_center=obstacle_center, obstacle_radius=0.1, line_start=(0.9, 0.4), line_end=(0.9, -0.4)
        )

    with_obstacle = mujoco.MjModel.from_xml_string(scene((0.5, 0.0)))
    without = mujoco.MjModel.from_xml_string(scene(None))
    assert with_obstacle.geom(PLANAR_OBSTACLE_GEOM).size[0] == 0.1
    names = {without.geom(i).name for i in range(without.ngeom)}
    assert PLANAR_OBSTACLE_GEOM not in names and set(PLANAR_ARM_LINK_GEOMS) <= names
    # links collide with the obstacle, not with each other
    link = with_obstacle.geom(PLANAR_ARM_LINK_GEOMS[0])
    obstacle = with_obstacle.geom(PLANAR_OBSTACLE_GEOM)
    assert link.contype[0] & obstacle.conaffinity[0] or obstacle.contype[0] & link.conaffinity[0]
    assert not (link.contype[0] & link.conaffinity[0])

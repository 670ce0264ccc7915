"""Scene composition for the biped on flat ground: the robot, a colliding floor, a tracking camera and light."""

from __future__ import annotations

from dm_control import mjcf

from . import BIPED_XML
from .backdrop import add_backdrop

__all__ = ["BIPED_FLOOR_GEOM", "biped_scene_xml"]

BIPED_FLOOR_GEOM = "ground"
"""The colliding floor plane (contype/conaffinity 1 against the robot's 2/1)."""


def biped_scene_xml(*, floor_friction: float = 1.0, floor_size: float = 60.0) -> str:
    """MJCF text of the flat-ground walking scene.

    Args:
        floor_friction: sliding friction of the floor [-] (MuJoCo takes the larger of the two geoms').
        floor_size: half size of the floor [m].
    """
    root = mjcf.from_path(str(BIPED_XML))
    add_backdrop(root, floor_size=floor_size, floor_colors=((0.82, 0.84, 0.86), (0.72, 0.74, 0.78)),
                 floor_repeat=int(floor_size))
    world = root.worldbody
    world.add("geom", name=BIPED_FLOOR_GEOM, type="plane", size=[floor_size, floor_size, 0.1], contype=1,
              conaffinity=1, friction=[floor_friction, 0.02, 0.001], rgba=[0, 0, 0, 0])
    # a camera that follows the pelvis from the side, as in Gymnasium's Humanoid
    pelvis = root.find("body", "pelvis")
    pelvis.add("camera", name="track", mode="trackcom", pos=[0.4, -3.2, 0.1], xyaxes=[1, 0, 0, 0, 0.1, 1])
    return root.to_xml_string()

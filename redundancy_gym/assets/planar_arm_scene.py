"""Scene composition for the planar arm: the robot, optionally a sphere obstacle, a camera and the target line."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from dm_control import mjcf

from . import PLANAR_ARM_XML, PLANAR_OBSTACLE_GEOM
from .backdrop import add_backdrop

__all__ = ["planar_arm_scene_xml"]


def planar_arm_scene_xml(
    *,
    obstacle_center: Sequence[float] | None,
    obstacle_radius: float,
    line_start: Sequence[float],
    line_end: Sequence[float],
) -> str:
    """MJCF text of the planar-arm scene.

    Args:
        obstacle_center: ``(x, z)`` of the sphere obstacle [m], or ``None`` to leave it out of the scene.
        obstacle_radius: obstacle radius [m].
        line_start: ``(x, z)`` where the TCP line starts [m] (drawn, not collidable).
        line_end: ``(x, z)`` where it ends [m].
    """
    root = mjcf.from_path(str(PLANAR_ARM_XML))
    add_backdrop(
        root,
        floor_size=2.0,
        floor_position=(0.5, 0.0, -0.7),
        floor_colors=((0.82, 0.84, 0.86), (0.74, 0.76, 0.79)),
        floor_repeat=6,
    )
    world = root.worldbody
    world.add("camera", name="side", pos=[0.55, -2.6, 0.15], xyaxes=[1, 0, 0, 0, 0.05, 1])
    start = [line_start[0], 0.0, line_start[1]]
    end = [line_end[0], 0.0, line_end[1]]
    if not np.allclose(start, end):
        world.add(
            "geom",
            name="target_line",
            type="capsule",
            fromto=start + end,
            size=[0.004],
            contype=0,
            conaffinity=0,
            rgba=[0.1, 0.7, 0.2, 0.6],
        )
    if obstacle_center is not None:
        # contype/conaffinity 1/2 against the links' 2/1: the obstacle touches the robot, links do not touch each other
        world.add(
            "geom",
            name=PLANAR_OBSTACLE_GEOM,
            type="sphere",
            size=[obstacle_radius],
            pos=[obstacle_center[0], 0.0, obstacle_center[1]],
            contype=1,
            conaffinity=2,
            rgba=[0.95, 0.55, 0.1, 1.0],
        )
    return root.to_xml_string()

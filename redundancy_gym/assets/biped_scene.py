"""Scene composition for the biped on flat ground: the robot, a colliding floor, a tracking camera and light; and
the same scene with obstacles on the path (BipedObstacles)."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Sequence

from dm_control import mjcf

from . import BIPED_XML
from .backdrop import add_backdrop, look_at_xyaxes
from .obstacle_course import MjcfParts, Obstacle
from .terrain import Terrain

__all__ = [
    "BIPED_CAMERA",
    "BIPED_FLOOR_GEOM",
    "TERRAIN_GEOM_PREFIX",
    "biped_scene_xml",
    "obstacle_geom_name",
    "obstacle_scene_xml",
    "terrain_scene_xml",
]

BIPED_FLOOR_GEOM = "ground"
"""The colliding floor plane (contype/conaffinity 1 against the robot's 2/1)."""
BIPED_CAMERA = "track"
"""The default render camera: follows the robot's centre of mass (``mode="trackcom"``), looking at the whole body
from ahead and to its right (-y), so the walk goes left to right across the image."""
TERRAIN_GEOM_PREFIX = "terrain"
"""Terrain geoms are named ``terrain_{k}`` (boxes, then ramps, then rough patches: :meth:`Terrain.mjcf`)."""
_CAMERA_OFFSET = (1.6, -2.9, 0.4)  # [m] camera position relative to the centre of mass (world axes)
_CAMERA_AIM = (0.15, 0.0, -0.05)  # [m] the point it looks at, relative to the centre of mass


def biped_scene_xml(*, floor_friction: float = 1.0, floor_size: float = 60.0) -> str:
    """MJCF text of the flat-ground walking scene.

    Rendering: a contrasting checker floor of 0.5 m squares with marked edges (the walk shows against it), a
    directional light that follows the robot in place of the robot file's fixed spot light (which left the floor
    dark a few metres on), a brighter headlight, and the tracking camera :data:`BIPED_CAMERA`.

    Args:
        floor_friction: sliding friction of the floor [-] (MuJoCo takes the larger of the two geoms').
        floor_size: half size of the floor [m].
    """
    root = mjcf.from_path(str(BIPED_XML))
    add_backdrop(
        root,
        floor_size=floor_size,
        floor_colors=((0.86, 0.87, 0.89), (0.55, 0.6, 0.66)),
        floor_repeat=int(2 * floor_size),
        floor_lines=(0.3, 0.33, 0.38),
    )
    world = root.worldbody
    world.add(
        "geom",
        name=BIPED_FLOOR_GEOM,
        type="plane",
        size=[floor_size, floor_size, 0.1],
        contype=1,
        conaffinity=1,
        friction=[floor_friction, 0.02, 0.001],
        rgba=[0, 0, 0, 0],
    )
    headlight = root.visual.headlight
    headlight.ambient, headlight.diffuse, headlight.specular = [0.35, 0.35, 0.35], [0.45, 0.45, 0.45], [0.1, 0.1, 0.1]
    # the robot file's spot light lights a fixed patch of floor the robot walks out of
    root.find("light", "key_light").remove()
    pelvis = root.find("body", "pelvis")
    pelvis.add(
        "light",
        name="key_light",
        mode="trackcom",
        directional="true",
        castshadow="true",
        pos=[-1.0, -1.5, 4.0],
        dir=[0.25, 0.35, -1.0],
        diffuse=[0.55, 0.55, 0.55],
        specular=[0.2, 0.2, 0.2],
    )
    pelvis.add(
        "camera",
        name=BIPED_CAMERA,
        mode="trackcom",
        pos=list(_CAMERA_OFFSET),
        xyaxes=look_at_xyaxes(_CAMERA_OFFSET, _CAMERA_AIM),
    )
    return root.to_xml_string()


def obstacle_geom_name(index: int) -> str:
    """MJCF name of the geom of the ``index``-th obstacle of a course (its prism mesh: ``{name}_prism``)."""
    return f"obstacle_{index}"


def obstacle_scene_xml(scene_xml: str, obstacles: Sequence[Obstacle]) -> str:
    """The MJCF text of a composed scene (:func:`biped_scene_xml`) with ``obstacles`` added to its world body, geoms
    named :func:`obstacle_geom_name` in course order (their prism meshes in ``<asset>``; see :meth:`Obstacle.mjcf`).

    A random course changes at every reset, so this edits the composed text (about 1 ms) instead of composing the
    robot file again with ``dm_control.mjcf`` (about 27 ms); the geoms come after the floor's, so their ids are
    consecutive.
    """
    return _with_parts(scene_xml, [obstacle.mjcf(obstacle_geom_name(k)) for k, obstacle in enumerate(obstacles)])


def terrain_scene_xml(scene_xml: str, terrain: Terrain) -> str:
    """The MJCF text of a composed scene (:func:`biped_scene_xml`) with ``terrain``'s geoms (:meth:`Terrain.mjcf`,
    named ``terrain_{k}``) added to its world body after the floor's, so that the floor and the terrain have
    consecutive geom ids (the envs count a sole's contact with any of them as ground contact)."""
    return _with_parts(scene_xml, [terrain.mjcf(TERRAIN_GEOM_PREFIX)])


def _with_parts(scene_xml: str, parts: Sequence[MjcfParts]) -> str:
    """``scene_xml`` with each part's assets added to ``<asset>`` and its geoms to ``<worldbody>``, in order."""
    root = ET.fromstring(scene_xml)
    asset = root.find("asset")
    if asset is None:
        asset = ET.SubElement(root, "asset")
    world = root.find("worldbody")
    if world is None:
        raise ValueError("scene_xml has no <worldbody>")
    for part in parts:
        for element in part.assets:
            ET.SubElement(asset, element.tag, element.attributes)
        for element in part.geoms:
            ET.SubElement(world, element.tag, element.attributes)
    return ET.tostring(root, encoding="unicode")

"""Scene composition for AgriReach: the 9-DoF arm plus pools of plant geoms, composed with ``dm_control.mjcf``.

The scene is compiled once per env with as many plant geoms of each category as the (pruned) crop row can
hold; every reset places the new row's parts into them and hides the spare ones, so a reset never recompiles.
Plant geoms are visual in MuJoCo (``contype = conaffinity = 0``): the env judges contacts on the swept-sphere
model of the same parts. Stems, shoots and petioles are capsules, peppers spheres, and a leaf blade (two TSS)
one flat ellipsoid (MuJoCo has no swept triangle: the TSS stays in the collision model and the plant draws any shape
that covers it, a mesh or a box; an ellipsoid draws the blade's outline with one geom). The pool ``leaf`` counts blades.
"""

from __future__ import annotations

from collections.abc import Mapping

from dm_control import mjcf

from . import AGRI_ARM_XML
from .backdrop import add_backdrop, look_at_xyaxes

__all__ = ["CAMERAS", "PLANT_COLORS", "POOL_CATEGORIES", "TARGET_COLOR", "agri_scene_xml", "pool_geom_name"]

POOL_CATEGORIES = ("stem", "shoot", "fruit", "petiole", "leaf")
PLANT_COLORS = {
    "stem": (0.35, 0.55, 0.2, 1.0),
    "shoot": (0.4, 0.6, 0.22, 1.0),
    "petiole": (0.3, 0.6, 0.25, 1.0),
    "leaf": (0.2, 0.55, 0.15, 0.9),
    "fruit": (0.8, 0.12, 0.08, 1.0),
}
TARGET_COLOR = (1.0, 0.75, 0.05, 1.0)
CAMERAS = {
    "side": ((-0.35, -1.6, 2.3), (0.55, 0.0, 1.05)),
    "front": ((-0.6, 1.35, 2.4), (0.6, 0.0, 1.05)),
}
"""World-fixed cameras of the scene: (position, point looked at) [m]. Both look down from the path onto the
region a target can lie in (the near row's harvest band within the arm's reach: x about 1 m, |y| < 0.5 m,
z 0.9-1.3 m) and frame the arm, the target and the plants around it; ``side`` from the arm's right (-y), the
default render camera, ``front`` from its left (+y)."""
_POOL_TYPE = {"stem": "capsule", "shoot": "capsule", "petiole": "capsule", "fruit": "sphere", "leaf": "ellipsoid"}


def pool_geom_name(category: str, index: int) -> str:
    """MJCF name of the ``index``-th pooled geom of a category."""
    return f"{category}_{index}"


def agri_scene_xml(capacity: Mapping[str, int]) -> str:
    """MJCF text of the arm with ``capacity[category]`` hidden plant geoms per category of :data:`POOL_CATEGORIES`.

    Also adds a floor, the cameras of :data:`CAMERAS`, and the (non-colliding) ``approach_line`` marker.
    """
    unknown = set(capacity) - set(POOL_CATEGORIES)
    if unknown:
        raise ValueError(f"unknown plant categories {sorted(unknown)}; valid: {', '.join(POOL_CATEGORIES)}")
    root = mjcf.from_path(str(AGRI_ARM_XML))
    add_backdrop(root, floor_size=5.0, floor_colors=((0.55, 0.5, 0.42), (0.5, 0.45, 0.38)), floor_repeat=8)
    world = root.worldbody
    headlight = root.visual.headlight
    headlight.ambient, headlight.diffuse, headlight.specular = [0.3, 0.3, 0.3], [0.4, 0.4, 0.4], [0.1, 0.1, 0.1]
    for name, (position, target) in CAMERAS.items():
        world.add("camera", name=name, pos=list(position), xyaxes=look_at_xyaxes(position, target))
    for category in POOL_CATEGORIES:
        for k in range(int(capacity.get(category, 0))):
            world.add(
                "geom",
                name=pool_geom_name(category, k),
                type=_POOL_TYPE[category],
                size=[0.01, 0.01, 0.01],
                pos=[0.0, 0.0, -10.0],
                rgba=[0, 0, 0, 0],
                contype=0,
                conaffinity=0,
                group=2,
            )
    world.add(
        "geom",
        name="approach_line",
        type="capsule",
        size=[0.003, 0.075],
        pos=[0.0, 0.0, -10.0],
        rgba=[1.0, 0.75, 0.05, 0.6],
        contype=0,
        conaffinity=0,
        group=3,
    )
    return root.to_xml_string()

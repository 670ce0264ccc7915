"""Robot and scene descriptions (MJCF) and the names used in them, resolved in one place.

This module only holds paths and name constants, so that any layer may import it; the scene builders that
compose MJCF with ``dm_control.mjcf`` live in their own modules and are used by :mod:`redundancy_gym.envs`.
"""

from __future__ import annotations

from pathlib import Path

__all__ = [
    "ASSETS_DIR",
    "PLANAR_ARM_JOINTS",
    "PLANAR_ARM_LINK_GEOMS",
    "PLANAR_ARM_SERVOS",
    "PLANAR_ARM_FEEDFORWARDS",
    "PLANAR_ARM_TCP",
    "PLANAR_ARM_XML",
    "PLANAR_OBSTACLE_GEOM",
]

ASSETS_DIR = Path(__file__).resolve().parent

PLANAR_ARM_XML = ASSETS_DIR / "planar_arm.xml"
"""The planar 4-DoF arm (robot only; scenes add the obstacle)."""
PLANAR_ARM_JOINTS = ("joint1", "joint2", "joint3", "joint4")
PLANAR_ARM_LINK_GEOMS = ("link1_geom", "link2_geom", "link3_geom", "link4_geom")
PLANAR_ARM_SERVOS = ("servo1", "servo2", "servo3", "servo4")
PLANAR_ARM_FEEDFORWARDS = ("feedforward1", "feedforward2", "feedforward3", "feedforward4")
PLANAR_ARM_TCP = "tcp"
PLANAR_OBSTACLE_GEOM = "obstacle"

"""Robot and scene descriptions (MJCF) and the names used in them, resolved in one place.

This module only holds paths and name constants, so that any layer may import it; the scene builders that
compose MJCF with ``dm_control.mjcf`` live in their own modules and are used by :mod:`redundancy_gym.envs`.
"""

from __future__ import annotations

from pathlib import Path

__all__ = [
    "AGRI_ARM_FEEDFORWARDS",
    "AGRI_ARM_GEOMS",
    "AGRI_ARM_JOINTS",
    "AGRI_ARM_SERVOS",
    "AGRI_ARM_TCP",
    "AGRI_ARM_XML",
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

AGRI_ARM_XML = ASSETS_DIR / "agri_arm.xml"
"""The CROPS-like 9-DoF arm (robot and lift column only; scenes add the crop row)."""
AGRI_ARM_JOINTS = ("lift", "shoulder_yaw", "shoulder_pitch", "elbow_pitch", "forearm_roll", "wrist_pitch", "wrist_yaw",
                   "wrist_pitch2", "tool_roll")
AGRI_ARM_SERVOS = tuple(f"servo_{j}" for j in AGRI_ARM_JOINTS)
AGRI_ARM_FEEDFORWARDS = tuple(f"feedforward_{j}" for j in AGRI_ARM_JOINTS)
AGRI_ARM_GEOMS = ("column", "carriage_geom", "shoulder_geom", "upper_arm_geom", "elbow_geom", "forearm_geom",
                  "wrist_geom", "gripper_geom", "camera_geom")
"""The arm's swept-sphere geoms (sphere -> PSS, capsule -> LSS), the world-fixed lift column first."""
AGRI_ARM_TCP = "tcp"

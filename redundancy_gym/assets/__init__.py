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
    "BIPED_ANKLE_SITES",
    "BIPED_HARDWARE_LIMITS_DEG",
    "BIPED_JOINTS",
    "BIPED_SERVOS",
    "BIPED_SOFT_LIMIT_MARGIN",
    "BIPED_SOLE_GEOMS",
    "BIPED_XML",
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
AGRI_ARM_JOINTS = (
    "lift",
    "shoulder_yaw",
    "shoulder_pitch",
    "elbow_pitch",
    "forearm_roll",
    "wrist_pitch",
    "wrist_yaw",
    "wrist_pitch2",
    "tool_roll",
)
AGRI_ARM_SERVOS = tuple(f"servo_{j}" for j in AGRI_ARM_JOINTS)
AGRI_ARM_FEEDFORWARDS = tuple(f"feedforward_{j}" for j in AGRI_ARM_JOINTS)
AGRI_ARM_GEOMS = (
    "column",
    "carriage_geom",
    "shoulder_geom",
    "upper_arm_geom",
    "elbow_geom",
    "forearm_geom",
    "wrist_geom",
    "gripper_geom",
    "camera_geom",
)
"""The arm's swept-sphere geoms (sphere -> PSS, capsule -> LSS), the world-fixed lift column first."""
AGRI_ARM_TCP = "tcp"

BIPED_XML = ASSETS_DIR / "biped.xml"
"""The Lola-like biped (robot only, free-floating base; scenes add the ground)."""
_LEG = ("hip_yaw", "hip_roll", "hip_pitch", "knee", "ankle_pitch", "ankle_roll", "toe")
_ARM = ("shoulder_pitch", "shoulder_roll", "elbow")
BIPED_JOINTS = (
    tuple(f"r_{j}" for j in _LEG)
    + tuple(f"l_{j}" for j in _LEG)
    + ("pelvis_roll", "pelvis_yaw")
    + tuple(f"r_{j}" for j in _ARM)
    + tuple(f"l_{j}" for j in _ARM)
)
"""The 22 actuated joints in model order: right leg, left leg (7 each), pelvis roll and yaw, right and left arm."""
BIPED_SERVOS = tuple(f"servo_{j}" for j in BIPED_JOINTS)
BIPED_HARDWARE_LIMITS_DEG: dict[str, tuple[float, float]] = {
    "pelvis_yaw": (-19.4, 19.4),
    "pelvis_roll": (-15.1, 14.7),
    "hip_yaw": (-26.1, 24.7),
    "hip_roll": (-34.5, 40.4),
    "hip_pitch": (-92.0, 44.9),
    "knee": (-4.5, 120.0),
    "ankle_roll": (-23.5, 23.9),
    "ankle_pitch": (-49.0, 43.8),
    "toe": (-49.5, 14.3),
    "shoulder_pitch": (-170.0, 60.0),
    "shoulder_roll": (-120.0, 1.5),
    "elbow": (-120.0, 5.0),
}
"""Lola's measured right-side hardware limits [deg]; the left side mirrors roll and yaw (ranges negated)."""
BIPED_SOFT_LIMIT_MARGIN = 5.0 * 3.141592653589793 / 180.0
"""Software margin [rad] that controllers keep inside every hardware limit."""
BIPED_SOLE_GEOMS = ("r_sole_geom", "r_toe_sole_geom", "l_sole_geom", "l_toe_sole_geom")
"""Contact boxes of the soles (foot plate and toe segment per foot)."""
BIPED_ANKLE_SITES = ("r_ankle_ft", "l_ankle_ft")
"""Sites of the 6-axis ankle force/torque sensors (``{site}`` -> sensors ``{side}_ankle_force/torque``)."""

"""Registration of every env id with gymnasium, in one place."""

from __future__ import annotations

import gymnasium as gym

__all__ = ["ENV_IDS", "register_envs"]

ENV_IDS: tuple[str, ...] = ("redundancy_gym/PlanarReach-v0", "redundancy_gym/AgriReach-v0", "redundancy_gym/BipedWalk-v0")


def register_envs() -> None:
    """Register the env ids (idempotent)."""
    if "redundancy_gym/PlanarReach-v0" not in gym.registry:
        gym.register(
            id="redundancy_gym/PlanarReach-v0",
            entry_point="redundancy_gym.envs.planar_reach:PlanarReachEnv",
            max_episode_steps=250,
        )
    if "redundancy_gym/AgriReach-v0" not in gym.registry:
        gym.register(
            id="redundancy_gym/AgriReach-v0",
            entry_point="redundancy_gym.envs.agri_reach:AgriReachEnv",
            max_episode_steps=500,
        )
    if "redundancy_gym/BipedWalk-v0" not in gym.registry:
        gym.register(
            id="redundancy_gym/BipedWalk-v0",
            entry_point="redundancy_gym.envs.biped_walk:BipedWalkEnv",
            max_episode_steps=2500,
        )

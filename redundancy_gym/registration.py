"""Registration of every env id with gymnasium, in one place."""

from __future__ import annotations

from typing import NamedTuple

import gymnasium as gym

__all__ = ["BASE_ENV_IDS", "ENV_CARDS", "ENV_IDS", "WRAPPED_ENV_IDS", "EnvCard", "register_envs", "wrapped_env_id"]

BASE_ENV_IDS: tuple[str, ...] = (
    "redundancy_gym/PlanarReach-v0",
    "redundancy_gym/AgriReach-v0",
    "redundancy_gym/BipedWalk-v0",
    "redundancy_gym/BipedObstacles-v0",
    "redundancy_gym/BipedTerrain-v0",
)

# (wrapped id, base id, wrapper name of the registry in redundancy_gym.policies)
_WRAPPED: tuple[tuple[str, str, str], ...] = tuple(
    (f"redundancy_gym/{env}-{suffix}-v0", f"redundancy_gym/{env}-v0", wrapper)
    for env, wrappers in (
        ("PlanarReach", ("TaskSpace", "Nullspace", "Residual")),
        ("AgriReach", ("TaskSpace", "Nullspace", "Residual")),
        ("BipedWalk", ("Residual", "WalkingCommand")),
        ("BipedObstacles", ("Residual", "WalkingCommand")),
        ("BipedTerrain", ("Residual", "WalkingCommand")),
    )
    for suffix in wrappers
    for wrapper in (
        {
            "TaskSpace": "task_space",
            "Nullspace": "nullspace",
            "Residual": "residual",
            "WalkingCommand": "walking_command",
        }[suffix],
    )
)
WRAPPED_ENV_IDS: tuple[str, ...] = tuple(w for w, _, _ in _WRAPPED)
"""The env ids of an env in an action wrapper (``redundancy_gym.wrappers``): ``<Env>-<Wrapper>-v0``."""

ENV_IDS: tuple[str, ...] = BASE_ENV_IDS + WRAPPED_ENV_IDS


class EnvCard(NamedTuple):
    """What an env id's default env offers, known without building it.

    Attributes:
        observation_shape, action_shape: its spaces' shapes with the default keyword arguments.
        control_period_s: its ``dt`` [s].
        capabilities: what the policy registry reads (``redundancy_gym.policies.env_capabilities`` of the built env:
            its declared ``CAPABILITIES`` and those of its action space).
    """

    observation_shape: tuple[int, ...]
    action_shape: tuple[int, ...]
    control_period_s: float
    capabilities: frozenset[str]


_BOX = frozenset({"box_action", "bounded_action"})
_BIPED = _BOX | {"biped"}
ENV_CARDS: dict[str, EnvCard] = {
    "redundancy_gym/PlanarReach-v0": EnvCard((20,), (4,), 0.01, _BOX | {"tcp_reference", "tcp_tracking"}),
    "redundancy_gym/AgriReach-v0": EnvCard((530,), (9,), 0.01, _BOX | {"grasp_task"}),
    "redundancy_gym/BipedWalk-v0": EnvCard((81,), (22,), 0.004, _BIPED),
    "redundancy_gym/BipedObstacles-v0": EnvCard((193,), (22,), 0.004, _BIPED),
    "redundancy_gym/BipedTerrain-v0": EnvCard((200,), (22,), 0.004, _BIPED),
    # an action wrapper keeps its env's observation and period; the action is its own, no capability but the box's
    "redundancy_gym/PlanarReach-TaskSpace-v0": EnvCard((20,), (2,), 0.01, _BOX),
    "redundancy_gym/PlanarReach-Nullspace-v0": EnvCard((20,), (4,), 0.01, _BOX),
    "redundancy_gym/PlanarReach-Residual-v0": EnvCard((20,), (4,), 0.01, _BOX),
    "redundancy_gym/AgriReach-TaskSpace-v0": EnvCard((530,), (5,), 0.01, _BOX),
    "redundancy_gym/AgriReach-Nullspace-v0": EnvCard((530,), (9,), 0.01, _BOX),
    "redundancy_gym/AgriReach-Residual-v0": EnvCard((530,), (9,), 0.01, _BOX),
    "redundancy_gym/BipedWalk-Residual-v0": EnvCard((81,), (22,), 0.004, _BOX),
    "redundancy_gym/BipedWalk-WalkingCommand-v0": EnvCard((81,), (3,), 0.004, _BOX),
    "redundancy_gym/BipedObstacles-Residual-v0": EnvCard((193,), (22,), 0.004, _BOX),
    "redundancy_gym/BipedObstacles-WalkingCommand-v0": EnvCard((193,), (3,), 0.004, _BOX),
    "redundancy_gym/BipedTerrain-Residual-v0": EnvCard((200,), (22,), 0.004, _BOX),
    "redundancy_gym/BipedTerrain-WalkingCommand-v0": EnvCard((200,), (3,), 0.004, _BOX),
}
"""Every env id's :class:`EnvCard`: what ``redundancy-gym list`` and the policy registry's tables of supported env ids
read instead of building the 17 envs (seconds, and kernels compiled for a table). ``tests/test_registration.py``
builds each env and holds it equal to its card."""


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
    if "redundancy_gym/BipedObstacles-v0" not in gym.registry:
        gym.register(
            id="redundancy_gym/BipedObstacles-v0",
            entry_point="redundancy_gym.envs.biped_obstacles:BipedObstaclesEnv",
            # 45 s of 4 ms steps: the longest default random course takes 44.65 s at 0.4 m/s
            # (redundancy_gym.envs.biped_obstacles.MAX_EPISODE_STEPS; not imported here: that would load MuJoCo)
            max_episode_steps=11250,
        )
    if "redundancy_gym/BipedTerrain-v0" not in gym.registry:
        gym.register(
            id="redundancy_gym/BipedTerrain-v0",
            entry_point="redundancy_gym.envs.biped_terrain:BipedTerrainEnv",
            # 52 s of 4 ms steps: the longest default random terrain takes 51.65 s at 0.4 m/s
            # (redundancy_gym.envs.biped_terrain.MAX_EPISODE_STEPS; not imported here: that would load MuJoCo)
            max_episode_steps=13000,
        )
    for wrapped, base, wrapper in _WRAPPED:
        if wrapped not in gym.registry:
            gym.register(
                id=wrapped,
                entry_point="redundancy_gym.wrappers.wrapped_env:make_wrapped_env",
                max_episode_steps=gym.spec(base).max_episode_steps,
                kwargs={"env_id": base, "wrapper": wrapper},
            )


def wrapped_env_id(env_id: str, wrapper: str) -> str | None:
    """The registered id of ``env_id`` in the wrapper ``wrapper`` (``redundancy_gym/AgriReach-v0`` and
    ``nullspace``: ``redundancy_gym/AgriReach-Nullspace-v0``), or None when there is none."""
    return next((w for w, base, name in _WRAPPED if base == env_id and name == wrapper), None)

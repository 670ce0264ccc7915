"""The constructor arguments of every registered env, one generic check for all of them.

Each env writes its keyword arguments and their defaults once, in its explicit ``__init__`` signature (explicit for
IDE help, as Gymnasium's v5 envs); ``default_config()`` and the arguments ``EzPickle`` records are read from it
(``redundancy_gym.envs.validation``). These tests hold the three together and the docstring to them:

- ``default_config()`` is every argument but the rendering ones, with the signature's defaults;
- a pickled env is made again with every argument it was given (an env made with a non-default value for every
  argument comes back with the same arguments and the same first steps): this fails when the pickling record
  drops an argument or puts its default in place of the value given;
- the docstring's ``## Arguments`` section names every argument.
"""

from __future__ import annotations

import inspect
import pickle
import re
import sys
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.envs.registration import load_env_creator
from gymnasium.utils import EzPickle

import redundancy_gym
from redundancy_gym.envs.validation import RENDER_ARGUMENTS
from redundancy_gym.registration import BASE_ENV_IDS

_WALK_ARGUMENTS: dict[str, Any] = {
    "target_speed": 0.3,
    "speed_weight": 2.0,
    "lateral_weight": 0.3,
    "healthy_reward": 0.1,
    "energy_weight": 0.002,
    "fall_penalty": 5.0,
    "min_base_height": 0.5,
    "max_torso_tilt": 0.7,
    "reset_noise_scale": 0.01,
    "velocity_feedforward": False,
    "floor_friction": 0.8,
    "frame_skip": 3,
    "render_mode": "rgb_array",
    "width": 64,
    "height": 48,
    "camera_name": None,
    "sensor_noise": {"q": 0.001},
    "push": [{"time": 0.0, "force": (0.0, 20.0, 0.0), "duration": 0.05}],
    "actuator_torque_scale": 0.9,
    "speed_scale": 0.3,
    "backend": "python",
    "dynamics": {"mass": (0.9, 1.1), "latency": 1},
}

NON_DEFAULT: dict[str, dict[str, Any]] = {
    "redundancy_gym/PlanarReach-v0": {
        "obstacle": False,
        "obstacle_center": (0.6, -0.2),
        "obstacle_radius": 0.08,
        "line_start": (0.85, 0.4),
        "line_end": (0.85, -0.4),
        "duration": 2.2,
        "initial_configuration": (-1.2, 1.0, 0.8, 0.5),
        "max_joint_speed": 2.5,
        "tracking_weight": 5.0,
        "energy_weight": 20.0,
        "collision_penalty": 50.0,
        "reset_noise_scale": 0.05,
        "success_tolerance": 2e-3,
        "frame_skip": 5,
        "render_mode": "rgb_array",
        "width": 64,
        "height": 48,
        "camera_name": None,
        "obs_noise": {"q": 0.001},
        "backend": "python",
        "dynamics": {"mass": (0.9, 1.1), "latency": 1},
    },
    "redundancy_gym/AgriReach-v0": {
        "difficulty": "easy",
        "leaves_per_stem": 3,
        "fruits_per_stem": (1, 3),
        "shoot_probability": 0.2,
        "cluster_spread": 0.06,
        "row_distance": 1.0,
        "row_gap": 0.5,
        "row_length": 6.0,
        "stem_spacing": (0.28, 0.36),
        "stem_diameter": (0.011, 0.014),
        "fruit_diameter": (0.075, 0.085),
        "harvest_band": (0.85, 1.3),
        "prune": False,
        "pregrasp_distance": 0.12,
        "approach_elevation": (5.0, 25.0),
        "observed_obstacles": 8,
        "max_joint_speed": 1.4,
        "max_lift_speed": 0.35,
        "position_weight": 2.0,
        "orientation_weight": 0.3,
        "energy_weight": 5.0,
        "leaf_penalty": 0.2,
        "collision_penalty": 150.0,
        "success_bonus": 5.0,
        "success_position_tolerance": 0.02,
        "success_angle_tolerance": 8.0,
        "clearance_horizon": 0.15,
        "reset_noise_scale": 0.03,
        "frame_skip": 2,
        "reference_speed": 0.3,
        "reference_turn_rate": 0.7,
        "reference_min_duration": 1.6,
        "reference_approach_speed": 0.1,
        "render_mode": "rgb_array",
        "width": 64,
        "height": 48,
        "camera_name": "front",
        "obs_noise": 0.001,
        "backend": "python",
        "dynamics": {"mass": (0.9, 1.1), "latency": 1},
    },
    "redundancy_gym/BipedWalk-v0": _WALK_ARGUMENTS,
    "redundancy_gym/BipedObstacles-v0": {
        **_WALK_ARGUMENTS,
        "course": "triangle",
        "obstacles": [{"shape": "box", "center": [1.2, 0.0, 0.05], "size": [0.2, 0.6, 0.1]}],
        "n_obstacles": (2, 4),
        "obstacle_spacing": (1.0, 2.0),
        "first_obstacle_distance": 1.0,
        "observed_obstacles": 4,
        "contact_weight": 2.0,
        "success_distance": 0.5,
    },
    "redundancy_gym/BipedTerrain-v0": {
        **_WALK_ARGUMENTS,
        "terrain": "stairs",
        "segments": [{"kind": "platform", "height": 0.1, "length": 1.0}],
        "terrain_ranges": {"stairs": {"rise": (0.1, 0.12)}},
        "n_segments": (1, 2),
        "segment_spacing": (0.8, 1.2),
        "first_segment_distance": 1.0,
        "scan_size": (1.2, 0.4),
        "scan_spacing": 0.05,
        "scan_offset": -0.1,
        "support_tolerance": 0.03,
        "min_support": 0.6,
        "unsupported_weight": 2.0,
        "success_distance": 0.5,
    },
}
"""A valid value other than the default for every argument of each env (rendering ones included)."""


def _env_class(env_id: str) -> type[gym.Env]:
    """The class a registered id makes (its entry point)."""
    entry_point = gym.spec(env_id).entry_point
    assert isinstance(entry_point, str), entry_point
    creator = load_env_creator(entry_point)
    assert inspect.isclass(creator) and issubclass(creator, gym.Env), entry_point
    return creator


def _parameters(cls: type) -> dict[str, inspect.Parameter]:
    """The constructor's parameters taken by name (``self`` and ``**kwargs`` left out)."""
    kinds = (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)
    return {name: p for name, p in inspect.signature(cls).parameters.items() if p.kind in kinds}


def _recorded_arguments(env: gym.Env) -> dict[str, Any]:
    """Every argument EzPickle recorded for ``env``, by name, defaults filled in for the ones it left out."""
    assert isinstance(env, EzPickle)
    bound = inspect.signature(type(env)).bind(*env._ezpickle_args, **env._ezpickle_kwargs)
    bound.apply_defaults()
    arguments = dict(bound.arguments)
    assert arguments.pop("kwargs", {}) == {}  # nothing recorded that the constructor does not take by name
    return arguments


def _arguments_section(cls: type) -> str:
    """The ``## Arguments`` section of a class docstring (empty when it has none)."""
    match = re.search(r"## Arguments\n(.*?)(?:\n\s*## |\Z)", inspect.getdoc(cls) or "", re.S)
    return match.group(1) if match else ""


def test_every_base_env_is_registered_and_listed() -> None:
    assert set(BASE_ENV_IDS) <= set(redundancy_gym.ENV_IDS)
    assert set(NON_DEFAULT) == set(BASE_ENV_IDS)


@pytest.mark.parametrize("env_id", BASE_ENV_IDS)
def test_default_config_is_every_argument_but_rendering_with_the_signature_defaults(env_id: str) -> None:
    cls = _env_class(env_id)
    params = _parameters(cls)
    config = sys.modules[cls.__module__].default_config()
    assert set(RENDER_ARGUMENTS) <= set(params)
    assert set(config) == set(params) - set(RENDER_ARGUMENTS)
    for name, p in params.items():
        assert p.default is not inspect.Parameter.empty, f"{name} has no default: gym.make({env_id!r}) would fail"
        if name in config:
            assert config[name] == p.default, name
    config["frame_skip"] = -1
    assert sys.modules[cls.__module__].default_config()["frame_skip"] == params["frame_skip"].default  # fresh dict


@pytest.mark.parametrize("env_id", BASE_ENV_IDS)
def test_pickle_round_trip_keeps_every_argument(env_id: str) -> None:
    cls = _env_class(env_id)
    params = _parameters(cls)
    given = NON_DEFAULT[env_id]
    assert set(given) == set(params), "NON_DEFAULT must give every argument a non-default value"
    for name, value in given.items():
        assert value != params[name].default, name
    env = cls(**given)
    restored = pickle.loads(pickle.dumps(env))
    try:
        assert type(restored) is cls
        assert _recorded_arguments(env) == given
        assert _recorded_arguments(restored) == given
        # and it is the same env: the same episode start and first step from the same seed
        first, _ = env.reset(seed=3)
        again, _ = restored.reset(seed=3)
        np.testing.assert_array_equal(again, first)
        assert isinstance(env.action_space, gym.spaces.Box)
        action = np.full(env.action_space.shape, 0.1)
        step, reward, *_ = env.step(action)
        step_again, reward_again, *_ = restored.step(action)
        np.testing.assert_array_equal(step_again, step)
        assert reward_again == reward
    finally:
        env.close()
        restored.close()


@pytest.mark.parametrize("env_id", BASE_ENV_IDS)
def test_docstring_arguments_section_names_every_argument(env_id: str) -> None:
    cls = _env_class(env_id)
    section = _arguments_section(cls)
    assert section, f"{cls.__name__} has no '## Arguments' section"
    # an env that extends another says so ("Every argument of BipedWalk") and inherits its section
    for base in cls.__mro__[1:]:
        if base.__module__.startswith("redundancy_gym.envs.") and base.__name__.removesuffix("Env") in section:
            section += _arguments_section(base)
    missing = [name for name in _parameters(cls) if f"``{name}``" not in section]
    assert not missing, f"{cls.__name__}'s '## Arguments' does not name {missing}"

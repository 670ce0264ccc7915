"""Hard cases of argument checking (issue 17, "What was seen" items 4 and 5).

Every constructor argument of the envs, the policy options and the geometry constructors is checked in one
place (:mod:`redundancy_gym.validation`): a bool is a bool, a number is a real number (not a string), finite and
inside its range, and the error names the argument, the value and what is valid. Each case below failed (was
accepted, or raised an unrelated error) before the checks were shared.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import fields
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import redundancy_gym  # noqa: F401 - registers the ids
from redundancy_gym.envs import EnvConfigError
from redundancy_gym.geometry import LSS, PSS, TSS, GeometryError, PackedVolumes, indexed_distances
from redundancy_gym.policies import PolicyError

PLANAR = "redundancy_gym/PlanarReach-v0"
AGRI = "redundancy_gym/AgriReach-v0"
BIPED = "redundancy_gym/BipedWalk-v0"


@pytest.fixture(scope="module")
def envs() -> Iterator[dict[str, gym.Env]]:
    made = {env_id: gym.make(env_id) for env_id in (PLANAR, AGRI, BIPED)}
    yield made
    for env in made.values():
        env.close()


# ---------------------------------------------------------------------------------------------- envs: item 4
def test_planar_reach_obstacle_no_is_not_true() -> None:
    with pytest.raises(EnvConfigError, match=r"obstacle must be a bool.*'no'"):
        gym.make(PLANAR, obstacle="no")


def test_agri_reach_prune_no_is_not_true() -> None:
    with pytest.raises(EnvConfigError, match=r"prune must be a bool.*'no'"):
        gym.make(AGRI, prune="no")


def test_biped_walk_velocity_feedforward_no_is_not_true() -> None:
    with pytest.raises(EnvConfigError, match=r"velocity_feedforward must be a bool.*'no'"):
        gym.make(BIPED, velocity_feedforward="no")


@pytest.mark.parametrize("env_id", [PLANAR, AGRI, BIPED])
def test_width_as_a_string_is_rejected(env_id: str) -> None:
    with pytest.raises(EnvConfigError, match=r"width must be an int.*'480'"):
        gym.make(env_id, width="480")


@pytest.mark.parametrize(
    "env_id, kwargs, match",
    [
        (PLANAR, {"duration": "2.0"}, r"duration must be a finite real number > 0.*'2.0'"),
        (
            PLANAR,
            {"obstacle_radius": True},
            r"obstacle_radius must be a finite real number in \[1e-06, 2\] \[m\], got True",
        ),
        (PLANAR, {"obstacle_center": ("0.7", "-0.12")}, r"obstacle_center must be .*real numbers"),
        (PLANAR, {"frame_skip": 2.0}, r"frame_skip must be an int in \[1, 1000\], got 2.0"),
        (PLANAR, {"height": 0}, r"height must be an int >= 1"),
        (AGRI, {"observed_obstacles": True}, r"observed_obstacles must be an int >= 0"),
        (AGRI, {"difficulty": "extreme"}, r"difficulty must be one of easy, medium, hard; got 'extreme'"),
        (AGRI, {"fruits_per_stem": (1.5, 2)}, r"fruits_per_stem must be a \(low, high\) pair of ints"),
        (AGRI, {"shoot_probability": 1.5}, r"shoot_probability must be a finite real number in \[0, 1\]"),
        (AGRI, {"approach_elevation": (0.0, 90.0)}, r"approach_elevation must be a \(low, high\) pair .*\[0, 60\]"),
        (BIPED, {"floor_friction": float("inf")}, r"floor_friction must be a finite real number > 0.*inf"),
        (BIPED, {"target_speed": float("nan")}, r"target_speed must be a finite real number in \[0, 1\].*nan"),
    ],
)
def test_env_arguments_are_checked_by_type_finiteness_and_range(
    env_id: str, kwargs: dict[str, Any], match: str
) -> None:
    with pytest.raises(EnvConfigError, match=match):
        gym.make(env_id, **kwargs)


def test_agri_reach_stem_spacing_from_zero_is_a_clear_error() -> None:
    """(0.0, 0.3) divided by zero deep in the scene generator (OverflowError / ZeroDivisionError)."""
    with pytest.raises(EnvConfigError, match=r"stem_spacing must be a \(low, high\) pair .*> 0.*0\.0, 0\.3"):
        gym.make(AGRI, stem_spacing=(0.0, 0.3))


def test_agri_reach_stems_closer_than_their_diameter_are_rejected() -> None:
    with pytest.raises(EnvConfigError, match=r"stem_spacing.*stem_diameter"):
        gym.make(AGRI, stem_spacing=(0.005, 0.3))


def test_biped_walk_target_speed_beyond_the_walker_is_rejected() -> None:
    """target_speed=10 was accepted; the walking reference's fastest gait is 0.6 m steps every 0.6 s."""
    with pytest.raises(EnvConfigError, match=r"target_speed must be a finite real number in \[0, 1\] \[m/s\].*got 10"):
        gym.make(BIPED, target_speed=10)
    gym.make(BIPED, target_speed=1.0).close()  # the bound itself is valid


def test_biped_walk_min_base_height_above_the_standing_pelvis_is_rejected(envs: dict[str, gym.Env]) -> None:
    """min_base_height=2.0 ended every episode at step 1 (the pelvis stands lower than that)."""
    with pytest.raises(
        EnvConfigError,
        match=r"min_base_height must be a finite real number in \(0, 0\.9\d*\).*"
        r"standing pelvis height.*got 2\.0",
    ):
        gym.make(BIPED, min_base_height=2.0)
    from redundancy_gym.envs.biped_walk import STANDING_PELVIS_HEIGHT

    _, info = envs[BIPED].reset(seed=0)
    # the bound is the pelvis height of the env's own starting posture
    assert envs[BIPED].unwrapped.data.qpos[2] == pytest.approx(STANDING_PELVIS_HEIGHT, abs=5e-3)


# ---------------------------------------------------------------------------------------------- envs: item 5
def test_biped_walk_standing_still_at_zero_speed_is_a_success() -> None:
    """target_speed=0 with the zero policy stands 10 s without falling: a success (the 10 % band was empty)."""
    env = gym.make(BIPED, target_speed=0.0)
    env.reset(seed=0)
    terminated = truncated = False
    while not (terminated or truncated):
        _, _, terminated, truncated, info = env.step(np.zeros(22))
    assert truncated and not terminated
    assert info["time"] == pytest.approx(10.0) and info["is_success"]
    env.close()


def test_biped_walk_standing_still_is_no_success_at_walking_speed() -> None:
    env = gym.make(BIPED, target_speed=0.5)
    env.reset(seed=0)
    for _ in range(250):
        _, _, terminated, _, info = env.step(np.zeros(22))
    assert not terminated and not info["is_success"]
    env.close()


# ---------------------------------------------------------------------------------------------- policy options
@pytest.mark.parametrize(
    "policy, env_id, option, value",
    [
        ("clik", PLANAR, "posture_weight", float("nan")),
        ("clik", PLANAR, "joint_limit_weight", float("nan")),
        ("clik", PLANAR, "gain", "20"),
        ("clik", AGRI, "max_speed", float("nan")),
        ("clik", AGRI, "approach_speed", -0.1),
        ("clik", AGRI, "max_turn_rate", float("nan")),
        ("clik", AGRI, "min_duration", -1.0),
        ("clik", AGRI, "max_speed", 0.0),  # ZeroDivisionError before
        ("walking", BIPED, "self_collision_weight", float("nan")),
    ],
)
def test_policy_option_out_of_range_raises_naming_it(
    envs: dict[str, gym.Env], policy: str, env_id: str, option: str, value: Any
) -> None:
    with pytest.raises(PolicyError, match=rf"^{option} must be .*got {value!r}"):
        redundancy_gym.make_policy(policy, envs[env_id], **{option: value})


def test_min_duration_nan_names_min_duration(envs: dict[str, gym.Env]) -> None:
    """Was "target must be finite" from deep inside the controller."""
    with pytest.raises(PolicyError, match=r"^min_duration must be None or a finite real number >= 0 \[s\], got nan$"):
        redundancy_gym.make_policy("clik", envs[AGRI], min_duration=float("nan"))


def test_joint_limit_activation_names_joint_limit_activation(envs: dict[str, gym.Env]) -> None:
    """Was "activation_distance must be ..." from the joint-limit objective."""
    with pytest.raises(PolicyError, match=r"^joint_limit_activation must be a finite real number > 0.*-0\.1"):
        redundancy_gym.make_policy("clik", envs[PLANAR], joint_limit_activation=-0.1)
    with pytest.raises(PolicyError, match=r"^joint_limit_activation must be a finite real number > 0"):
        redundancy_gym.make_policy("clik", envs[AGRI], joint_limit_activation=0.0)


@pytest.mark.parametrize(
    "policy, env_id, option, value, match",
    [
        ("clik", PLANAR, "self_collision", "no", r"self_collision must be a bool"),
        ("clik", PLANAR, "method", 3, r"method must be one of pseudoinverse, dls, transpose; got 3"),
        ("clik", PLANAR, "backend", "gpu", r"backend must be one of compiled, python; got 'gpu'"),
        ("predictive", PLANAR, "iterations", 2.5, r"iterations must be an int >= 0"),
        ("predictive", PLANAR, "augmented", 1, r"augmented must be a bool"),
        ("predictive", PLANAR, "sample_time", float("inf"), r"sample_time must be None or a finite real number > 0"),
        ("predictive", PLANAR, "descent", "newton", r"descent must be one of fletcher_reeves, .*; got 'newton'"),
        ("walking", BIPED, "gamma", 0.0, r"gamma must be a finite real number > 0"),
        ("walking", BIPED, "stabilizer", "yes", r"stabilizer must be a bool"),
        ("walking", BIPED, "correction_iterations", -1, r"correction_iterations must be an int >= 0"),
    ],
)
def test_policy_options_are_checked_from_their_types(
    envs: dict[str, gym.Env], policy: str, env_id: str, option: str, value: Any, match: str
) -> None:
    with pytest.raises(PolicyError, match=match):
        redundancy_gym.make_policy(policy, envs[env_id], **{option: value})


def test_every_numeric_policy_option_has_a_range() -> None:
    """A new float or int option of a config class gets a range in policy_options.py, or this test says so."""
    from redundancy_gym.policies import ClikPolicyConfig
    from redundancy_gym.policies.grasp_clik_policy import GraspClikConfig
    from redundancy_gym.policies.options import option_rule
    from redundancy_gym.policies.predictive_policy import PredictivePolicyConfig
    from redundancy_gym.policies.walking_policy import WalkingPolicyConfig

    for config in (ClikPolicyConfig, GraspClikConfig, PredictivePolicyConfig, WalkingPolicyConfig):
        for f in fields(config):
            rule = option_rule(config, f.name)
            assert rule is not None, f"{config.__name__}.{f.name} is not checked"
            assert (
                rule.has_range
                or rule.kind == "bool"
                or rule.kind == "str"
                and f.name in ("method", "backend", "descent", "collision_avoidance")
            ), f"{config.__name__}.{f.name} has no range (policy_options.py)"
            rule.check(f.name, getattr(config(), f.name), PolicyError)  # the defaults pass their own rule


# ---------------------------------------------------------------------------------------------- geometry
def test_pss_radius_as_a_string_is_rejected() -> None:
    radius: Any = "0.1"  # the wrong type on purpose: the runtime check is under test
    with pytest.raises(GeometryError, match=r"radius must be a finite real number >= 0.*'0\.1'"):
        PSS([0.0, 0.0, 0.0], radius=radius)


@pytest.mark.parametrize(
    "make",
    [
        lambda: LSS([0, 0, 0], [1, 0, 0], radius=np.nan),
        lambda: TSS([0, 0, 0], [1, 0, 0], [0, 1, 0], radius=True),
        lambda: PSS(["0", "0", "0"], 0.1),
        lambda: LSS([0, 0, 0], [np.inf, 0, 0], 0.1),
    ],
)
def test_ssv_constructors_reject_non_numbers(make: Any) -> None:
    with pytest.raises(GeometryError):
        make()


def _packed(vertex: float = 0.0) -> PackedVolumes:
    vertices = np.zeros((2, 3, 3))
    vertices[1] = [1.0, 0.0, 0.0]
    vertices[1, 0, 2] = vertex
    return PackedVolumes(vertices, np.array([0.1, 0.1]), np.array([0, 0], dtype=np.int64))


def test_packed_volumes_with_a_nan_vertex_raise() -> None:
    with pytest.raises(GeometryError, match=r"vertices must be finite.*volume 1"):
        _packed(np.nan)


def test_indexed_distances_with_a_nan_vertex_raise() -> None:
    volumes = _packed()
    assert indexed_distances(volumes, [0], [1]).distance[0] == pytest.approx(0.8)
    volumes.vertices[1, 0, 2] = np.nan  # written in place after packing
    with pytest.raises(GeometryError, match=r"vertices must be finite.*volume 1"):
        indexed_distances(volumes, [0], [1])


@pytest.mark.parametrize(
    "radii, kinds, match",
    [
        (np.array([0.1, -0.1]), np.array([0, 0]), r"radii must be finite and >= 0.*volume 1"),
        (np.array([0.1, np.nan]), np.array([0, 0]), r"radii must be finite and >= 0"),
        (np.array([0.1, 0.1]), np.array([0, 3]), r"kinds must be 0 \(PSS\), 1 \(LSS\) or 2 \(TSS\)"),
        (np.array([0.1]), np.array([0, 0]), r"radii must have shape \(2,\)"),
    ],
)
def test_packed_volumes_check_radii_and_kinds(radii: np.ndarray, kinds: np.ndarray, match: str) -> None:
    with pytest.raises(GeometryError, match=match):
        PackedVolumes(np.zeros((2, 3, 3)), radii, kinds.astype(np.int64))


# ---------------------------------------------------------------------------------------------- the shared checks
def test_shared_checks_raise_the_callers_exception_naming_argument_value_and_range() -> None:
    from redundancy_gym import validation as v

    class MyError(ValueError):
        pass

    bad: Any  # each loop below goes through values of other types, most of them wrong on purpose
    assert v.check_bool("flag", np.bool_(True), error=MyError) is True
    for bad in ("no", 1, 0.0, None):
        with pytest.raises(MyError, match=r"flag must be a bool \(True or False\), got"):
            v.check_bool("flag", bad, error=MyError)
    assert v.check_real("x", np.float32(0.5), low=0.0, high=1.0, error=MyError) == 0.5
    assert type(v.check_real("x", 2, error=MyError)) is float
    with pytest.raises(MyError, match=r"^x must be a finite real number in \(0, 1\] \[m\], got 0\.0$"):
        v.check_real("x", 0.0, low=0.0, high=1.0, low_open=True, unit="m", error=MyError)
    with pytest.raises(MyError, match=r"x must be a finite real number < 2, got 2"):
        v.check_real("x", 2, high=2, high_open=True, error=MyError)
    for bad in ("1", True, None, [1.0], np.nan, -np.inf, 1 + 0j):
        with pytest.raises(MyError, match="x must be a finite real number"):
            v.check_real("x", bad, error=MyError)
    assert v.check_real("x", None, optional=True, error=MyError) is None
    assert v.check_int("n", np.int32(3), low=1, error=MyError) == 3
    for bad in (3.0, True, "3"):
        with pytest.raises(MyError, match=r"n must be an int >= 1"):
            v.check_int("n", bad, low=1, error=MyError)
    assert v.check_choice("mode", "b", ("a", "b"), error=MyError) == "b"
    with pytest.raises(MyError, match=r"mode must be one of a, b; got 'c'"):
        v.check_choice("mode", "c", ("a", "b"), error=MyError)
    with pytest.raises(MyError, match=r"mode must be one of a, b; got \['a'\] \(list\)"):
        v.check_choice("mode", ["a"], ("a", "b"), error=MyError)  # unhashable: still the package's error
    assert v.check_range_pair("r", (1, 2), low=0.0, error=MyError) == (1.0, 2.0)
    assert v.check_range_pair("r", (1, 2), integer=True, error=MyError) == (1, 2)
    for bad in ((2.0, 1.0), (0.0,), ("1", "2"), (np.nan, 1.0), (-1.0, 1.0), 1.0):
        with pytest.raises(
            MyError,
            match=r"r must be a \(low, high\) pair of finite real numbers with "
            r"low <= high, both >= 0",
        ):
            v.check_range_pair("r", bad, low=0.0, error=MyError)
    p = v.check_real_array("p", [1, 2], shape=(2,), error=MyError)
    assert p.dtype == np.float64 and p.tolist() == [1.0, 2.0]
    for bad in (["1", "2"], [1.0, np.nan], [1.0], [True, False], "ab"):
        with pytest.raises(MyError, match=r"p must be .*2 finite real numbers"):
            v.check_real_array("p", bad, shape=(2,), error=MyError)

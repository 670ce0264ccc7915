"""BipedTerrain-v0: the height scan against MuJoCo's rays at known poses, both backends equal, terrain-relative
falls, the sole's support on a platform edge, terrain drawn per reset (and kept when it does not change), and bad
arguments named."""

from __future__ import annotations

import math

import gymnasium as gym
import mujoco
import numpy as np
import pytest

import redundancy_gym  # noqa: F401 - registers the ids
from redundancy_gym.envs import BipedTerrainEnv, EnvConfigError
from redundancy_gym.envs.biped_walk import BipedWalkEnv

ENV_ID = "redundancy_gym/BipedTerrain-v0"


def _pose(env: BipedTerrainEnv, x: float, y: float, z: float, yaw: float) -> None:
    """Put the standing robot's pelvis at (x, y, z) [m] turned by ``yaw`` [rad] (kinematics only)."""
    qpos = env.init_qpos.copy()
    qpos[:7] = (x, y, z, math.cos(0.5 * yaw), 0.0, 0.0, math.sin(0.5 * yaw))
    qpos[7:] = env.nominal_configuration
    env.set_state(qpos, np.zeros(env.model.nv))


def _ray_height(env: BipedTerrainEnv, x: float, y: float) -> float:
    """The height [m] of the highest world geom under (x, y) (the robot's bodies left out)."""
    geom = np.zeros(1, np.int32)
    group = np.array([1, 1, 1, 1, 1, 1], dtype=np.uint8)
    distance = mujoco.mj_ray(env.model, env.data, np.array([x, y, 3.0]), np.array([0.0, 0.0, -1.0]), group, 1, 1, geom)
    # bodyexclude = 1 leaves out the pelvis's subtree root only: a ray that met the robot would show here
    assert env.model.geom_bodyid[geom[0]] == 0, "the ray met the robot"
    return 3.0 - distance


@pytest.mark.parametrize("terrain", ["stairs", "stepping_stones", "slope", "rough"])
def test_height_scan_matches_mujoco_rays_at_known_poses(terrain: str) -> None:
    env = BipedTerrainEnv(terrain=terrain, first_segment_distance=0.6)
    env.reset(seed=5)
    layout = env.OBSERVATION_LAYOUT["height_scan"]
    offsets = env.scan_points
    assert layout.stop - layout.start == len(offsets) == 17 * 7
    segment = env.terrain.segments[0]
    for x, y, yaw in (
        # off the 0.1 m grid: a scan point exactly on a box side stands on the box here, and a ray may pass it
        (segment.start - 0.287, 0.0, 0.0),
        (segment.start + 0.4, 0.05, 0.3),
        (segment.end - 0.5, -0.1, -0.5),
    ):
        z = 0.9 + float(env.terrain_heights(np.array([x, y])))
        _pose(env, x, y, z + 10.0, yaw)  # the robot far above: the rays from 3 m down meet only terrain
        scan = env._get_obs()[layout]
        c, s = math.cos(yaw), math.sin(yaw)
        expected = [_ray_height(env, x + c * fx - s * fy, y + s * fx + c * fy) - (z + 10.0) for fx, fy in offsets]
        np.testing.assert_allclose(scan, expected, atol=2e-7)
        assert np.ptp(scan) > 0.005  # the scan sees the terrain's relief


def test_flat_ground_scan_is_minus_the_pelvis_height() -> None:
    env = BipedTerrainEnv(terrain="platform", first_segment_distance=3.0)
    obs, info = env.reset(seed=0)
    np.testing.assert_array_equal(obs[env.OBSERVATION_LAYOUT["height_scan"]], -obs[2])
    assert info["terrain_kind"] == "flat" and info["terrain_height"] == 0.0
    assert info["course_end"] == pytest.approx(env.terrain.end + 1.0)


def test_python_and_compiled_backends_give_the_same_bits() -> None:
    runs = []
    for backend in ("compiled", "python"):
        env = gym.make(ENV_ID, terrain="random", first_segment_distance=0.5, backend=backend)
        rng = np.random.default_rng(2)
        obs, info = env.reset(seed=11)
        seen = [obs]
        infos = [info]
        for _ in range(60):
            obs, reward, terminated, truncated, info = env.step(rng.uniform(-0.3, 0.3, 22))
            seen.append(obs)
            infos.append(info)
            if terminated or truncated:
                break
        runs.append((seen, infos))
    (a, ia), (b, ib) = runs
    assert len(a) == len(b)
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(x, y)
    for x, y in zip(ia, ib, strict=True):
        for key in ("support_fraction", "edge_distance", "terrain_height", "normal_force", "zmp"):
            np.testing.assert_array_equal(x[key], y[key])


def test_a_fall_is_measured_from_the_terrain_under_the_pelvis() -> None:
    env = BipedTerrainEnv(segments=[{"kind": "platform", "height": 0.16, "length": 1.5}], first_segment_distance=1.0)
    env.reset(seed=0)
    # 0.5 m above the platform: 0.66 m above the floor, below min_base_height (0.55 m) over the platform's top
    _pose(env, 1.7, 0.0, 0.16 + 0.5, 0.0)
    assert env._metrics(0.0)["fell"]
    _pose(env, 1.7, 0.0, 0.16 + 0.6, 0.0)
    metrics = env._metrics(0.0)
    assert not metrics["fell"] and metrics["terrain_height"] == pytest.approx(0.16)
    assert metrics["terrain_kind"] == "platform"


def test_support_fraction_of_a_sole_half_over_a_platform_edge() -> None:
    env = BipedTerrainEnv(segments=[{"kind": "platform", "height": 0.1, "length": 1.0}], first_segment_distance=1.0)
    env.reset(seed=0)
    _pose(env, 0.0, 0.0, 0.0, 0.0)
    sole = env.model.geom("r_sole_geom").id
    # the standing sole's lowest point, and the plate's centre relative to the pelvis
    bottom = env.data.geom_xpos[sole, 2] - env.model.geom_size[sole, 2] - env.data.qpos[2]
    plate_x = env.data.geom_xpos[sole, 0]
    platform_end = 2.0
    for overhang in (0.0, 0.5, 1.0):
        # put the plate's far part beyond the platform's end by `overhang` of the plate's length (0.19 m)
        x = platform_end - plate_x - 0.095 + overhang * 0.19
        _pose(env, x, 0.0, 0.1 - bottom + 1e-4, 0.0)
        fraction, edge, slip = env._touchdown(0, env.data.geom_xpos[sole, :2].copy())
        # the toe segment (0.07 m, hinged ahead of the plate) is beyond the edge in every case
        supported_area = (1.0 - overhang) * 0.19
        assert fraction == pytest.approx(supported_area / 0.26, abs=0.02), overhang
        assert slip == 0.0
        if overhang < 1.0:
            assert edge == pytest.approx(-0.07 - overhang * 0.19)  # the toe tip's overhang
        else:  # the plate off the platform: on the ground, its heel against the platform's side
            assert edge == pytest.approx(0.0, abs=1e-9)


def test_a_terrain_that_does_not_change_is_not_recompiled() -> None:
    fixed = [{"kind": "stairs", "steps": 3, "rise": 0.1, "tread": 0.3, "landing": 0.8}]
    env = BipedTerrainEnv(segments=fixed)
    env.reset(seed=0)
    model = env.model
    env.reset(seed=1)
    assert env.model is model
    drawn = BipedTerrainEnv(terrain="stairs")
    drawn.reset(seed=0)
    first = drawn.terrain
    drawn.reset(seed=1)
    assert drawn.terrain != first
    drawn.reset(seed=0)
    assert drawn.terrain == first  # the same seed draws the same terrain


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"terrain": "moon"}, "terrain must be one of stairs, platform, stepping_stones, slope, rough, random"),
        ({"terrain_ranges": {"lava": {}}}, "terrain_ranges class must be one of stairs"),
        ({"terrain_ranges": {"stairs": {"height": (0.1, 0.2)}}}, "parameter must be one of steps, rise, tread"),
        ({"terrain_ranges": {"stairs": {"rise": (0.2, 0.1)}}}, r"\(low, high\) pair"),
        ({"segments": []}, "segments must be None or a non-empty list"),
        ({"segments": [{"kind": "stairs", "rise": -0.1}]}, r"segments\[0\]\['rise'\] must be"),
        ({"segments": [{"kind": "slope", "rise": 0.1}]}, r"segments\[0\] parameter must be one of gap, angle"),
        ({"scan_size": (1.0, -0.5)}, "scan_size must be"),
        ({"scan_spacing": 0.0}, "scan_spacing must be"),
        ({"first_segment_distance": 0.2}, "first_segment_distance must be"),
        ({"min_support": 1.5}, "min_support must be"),
    ],
)
def test_bad_arguments_are_named(kwargs: dict, match: str) -> None:
    with pytest.raises(EnvConfigError, match=match):
        BipedTerrainEnv(**kwargs)


def test_it_is_a_biped_walk_env_with_the_scan_after_its_entries() -> None:
    env = gym.make(ENV_ID, scan_size=(1.0, 0.4), scan_spacing=0.2)
    assert isinstance(env.unwrapped, BipedWalkEnv)
    layout = env.unwrapped.OBSERVATION_LAYOUT
    assert layout["height_scan"] == slice(81, 81 + 6 * 3)
    assert env.observation_space.shape == (81 + 18,)


def test_a_landing_is_measured_when_the_foot_carries_weight_and_a_scuff_is_no_landing() -> None:
    env = BipedTerrainEnv(terrain="platform", first_segment_distance=3.0)
    env.reset(seed=0)
    half = 0.5 * env._weight
    # the right foot swings (no force for 0.1 s), catches an edge for two periods, lifts, then lands and loads
    for right in [0.0] * 25 + [30.0, 30.0] + [0.0] * 25 + [40.0, 0.5 * half, 1.2 * half]:
        env._track_touchdowns(np.array([right, 2.0 * half]))
    assert env._scuffs == 1 and env._touchdowns == 1
    assert env._last[0] == 1.0  # the standing sole on flat ground: fully supported
    # a contact after a flicker of less than 50 ms off the ground is the same stance, not a new landing
    env._track_touchdowns(np.array([0.0, 2.0 * half]))
    env._track_touchdowns(np.array([1.2 * half, 2.0 * half]))
    assert env._touchdowns == 1


@pytest.mark.parametrize("backend", ["python", "compiled"])
def test_feet_on_a_ramp_carry_the_weight_upwards(backend: str) -> None:
    # a ramp is a mesh, whose geom type sorts after the soles' boxes: MuJoCo's contact then has the sole as geom1
    # and reports the force on the ramp; the sole's is its opposite (it read as a negative normal force)
    env = BipedTerrainEnv(
        segments=[{"kind": "slope", "angle": 3.0, "length": 2.0, "top": 1.0}],
        first_segment_distance=1.0,
        backend=backend,
    )
    env.reset(seed=0)
    x = 2.0  # on the rising ramp
    _pose(env, x, 0.0, float(env.terrain_heights(np.array([[x, 0.0]]))[0]) + env.data.qpos[2] + 0.01, 0.0)
    normal = []
    stand = np.zeros(22, dtype=np.float32)  # the nominal posture
    for _ in range(150):
        _, _, terminated, _, info = env.step(stand)
        assert not terminated
        normal.append(info["normal_force"].copy())
    assert env._ground[1] - env._ground[0] > 1  # the floor and the ramp's geoms
    late = np.array(normal[-50:])
    assert np.all(late >= 0.0)
    assert late.sum(axis=1).mean() == pytest.approx(env._weight, rel=0.1)

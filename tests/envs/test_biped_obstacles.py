"""BipedObstacles-v0 and its obstacle courses: swept-sphere models that fit the shapes, bounding boxes, the
monograph's courses, seeded random courses within their ranges, contacts, clearances, the observation's obstacle
block, argument checks, rendering after a course change, and the evaluation's obstacle fields."""

from __future__ import annotations

import gc
import math
import weakref

import gymnasium as gym
import mujoco
import numpy as np
import pytest

import redundancy_gym  # noqa: F401 - registers the ids
from redundancy_gym.assets.biped_scene import biped_scene_xml, obstacle_scene_xml
from redundancy_gym.assets.obstacle_course import (
    BESIDE,
    FOOT_PATH_Y,
    STEP_OVER,
    SWING_AROUND,
    Obstacle,
    beam_course,
    random_course,
    triangle_course,
)
from redundancy_gym.envs import BipedObstaclesEnv, EnvConfigError
from redundancy_gym.envs.biped_obstacles import OBSTACLE_FEATURES, OBSTACLE_LOOKBEHIND
from redundancy_gym.eval.evaluate import EvalReport, format_report, run_episode
from redundancy_gym.geometry import LSS, PSS, SSV, PackedVolumes, distance, distances

ENV_ID = "redundancy_gym/BipedObstacles-v0"
# a course near the start, clear of the standing robot (toes at x = 0.19 m): every shape, one of them yawed
NEAR = [
    {"shape": "box", "center": [0.45, 0.1, 0.05], "size": [0.1, 0.2, 0.1]},
    {"shape": "cylinder", "center": [0.5, -0.3, 0.2], "size": [0.04, 0.4]},
    {"shape": "prism", "center": [1.0, 0.0, 0.15], "size": [0.09, 0.13, 0.3], "yaw": 0.3},
    {"shape": "box", "center": [1.6, -0.05, 0.08], "size": [0.3, 0.08, 0.16], "yaw": -0.4},
]
SHAPES = [
    Obstacle("box", (1.0, 0.2, 0.1), (0.08, 0.35, 0.2)),
    Obstacle("box", (2.0, -0.3, 0.3), (0.5, 0.3, 0.6), 0.7),  # smallest extent the width: a vertical rectangle
    Obstacle("box", (0.0, 0.0, 0.02), (0.4, 0.5, 0.04), -1.2),  # a flat plate: a horizontal rectangle
    Obstacle("prism", (1.28, 0.0, 0.15), (0.09, 0.13, 0.3)),
    Obstacle("prism", (3.0, 1.0, 0.2), (0.3, 0.2, 0.4), 2.0),
    Obstacle("cylinder", (0.5, 0.5, 0.25), (0.06, 0.5)),
    Obstacle("cylinder", (0.5, -0.5, 0.3), (0.2, 0.3), 0.9),
]


def _surface_points(obstacle: Obstacle, rng: np.random.Generator, n: int = 2000) -> np.ndarray:
    """Points [m] uniformly on the faces of the shape (corners, edges and faces all sampled), world frame."""
    if obstacle.shape == "box":
        u = rng.uniform(-1.0, 1.0, (n, 3))
        face = rng.integers(3, size=n)
        u[np.arange(n), face] = rng.choice((-1.0, 1.0), n)
        local = 0.5 * u * np.asarray(obstacle.size)
        corners = (
            np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * 0.5 * np.asarray(obstacle.size)
        )
        return obstacle.to_world(np.concatenate([local, corners]))
    if obstacle.shape == "cylinder":
        radius, height = obstacle.size
        phi = rng.uniform(0.0, 2.0 * np.pi, n)
        r = np.where(rng.uniform(size=n) < 0.5, radius, radius * np.sqrt(rng.uniform(size=n)))
        z = np.where(r < radius, rng.choice((-0.5, 0.5), n) * height, rng.uniform(-0.5, 0.5, n) * height)
        return obstacle.to_world(np.column_stack([r * np.cos(phi), r * np.sin(phi), z]))
    corners = obstacle.vertices() - np.asarray(obstacle.center)
    corners = corners @ obstacle.rotation  # local frame
    tri = corners[:3, 1:]  # (y, z) of the triangle
    depth = obstacle.size[0]
    a, b = rng.uniform(size=(2, n))
    flip = a + b > 1.0
    a[flip], b[flip] = 1.0 - a[flip], 1.0 - b[flip]
    inside = tri[0] + a[:, None] * (tri[1] - tri[0]) + b[:, None] * (tri[2] - tri[0])  # the two end faces
    edge = rng.integers(3, size=n)
    t = rng.uniform(size=n)
    on_edge = tri[edge] + t[:, None] * (tri[(edge + 1) % 3] - tri[edge])  # the three side faces
    end = rng.uniform(size=n) < 0.5
    yz = np.where(end[:, None], inside, on_edge)
    x = np.where(end, rng.choice((-0.5, 0.5), n) * depth, rng.uniform(-0.5, 0.5, n) * depth)
    return obstacle.to_world(np.column_stack([x, yz]))


def _distance_to_volumes(points: np.ndarray, volumes: tuple[SSV, ...]) -> np.ndarray:
    """Smallest SSV distance [m] of each point (a PSS of radius 0) to the volumes."""
    out = np.full(len(points), np.inf)
    packed_points = PackedVolumes(
        np.repeat(points[:, None], 3, axis=1), np.zeros(len(points)), np.zeros(len(points), dtype=np.int64)
    )
    for v in volumes:
        many = PackedVolumes.from_volumes([v] * len(points))
        out = np.minimum(out, distances(packed_points, many).distance)
    return out


# ---------------------------------------------------------------------- obstacles
@pytest.mark.parametrize("obstacle", SHAPES, ids=lambda o: f"{o.shape}-yaw{o.yaw:g}")
def test_swept_sphere_model_fits_the_shape(obstacle: Obstacle) -> None:
    points = _surface_points(obstacle, np.random.default_rng(0))
    volumes = obstacle.volumes()
    if obstacle.shape == "box":
        # the box with rounded edges: inside the box, touching every face at its centre, and no box point
        # farther from it than (sqrt 3 - 1) r (a corner; (sqrt 2 - 1) r along an edge)
        radius = 0.5 * min(obstacle.size)
        assert np.max(_distance_to_volumes(points, volumes)) <= (math.sqrt(3.0) - 1.0) * radius + 1e-12
        half = 0.5 * np.asarray(obstacle.size)
        faces = np.concatenate([np.diag(half), -np.diag(half)])
        np.testing.assert_allclose(_distance_to_volumes(obstacle.to_world(faces), volumes), 0.0, atol=1e-12)
        outside = obstacle.to_world(faces * 1.001 + np.sign(faces) * 1e-4)
        assert np.all(_distance_to_volumes(outside, volumes) > 0.0)
        corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * half
        assert np.all(_distance_to_volumes(obstacle.to_world(corners), volumes) > 0.0)
    else:
        assert np.max(_distance_to_volumes(points, volumes)) <= 1e-12
    # and it is the model the docstring says: tight along the smallest extent
    if obstacle.shape == "box":
        assert [v.kind_name for v in volumes] == ["TSS", "TSS"]
        assert volumes[0].radius == pytest.approx(0.5 * min(obstacle.size))
        # the rectangle lies in the mid-plane: the box's centre is on it
        assert (
            distance(PSS(obstacle.center, 0.0), volumes[0]).distance + volumes[0].radius <= 1e-12
            or distance(PSS(obstacle.center, 0.0), volumes[1]).distance + volumes[1].radius <= 1e-12
        )
    elif obstacle.shape == "prism":
        assert [v.kind_name for v in volumes] == ["TSS"] and volumes[0].radius == pytest.approx(0.5 * obstacle.size[0])
    else:
        assert volumes == (
            LSS(
                np.subtract(obstacle.center, (0, 0, 0.5 * obstacle.height)),
                np.add(obstacle.center, (0, 0, 0.5 * obstacle.height)),
                obstacle.size[0],
            ),
        )


@pytest.mark.parametrize("obstacle", SHAPES, ids=lambda o: f"{o.shape}-yaw{o.yaw:g}")
def test_bounding_box_is_tight_around_the_shape(obstacle: Obstacle) -> None:
    points = _surface_points(obstacle, np.random.default_rng(1), n=20000)
    lower, upper = obstacle.bounding_box()
    assert np.all(points >= lower - 1e-12) and np.all(points <= upper + 1e-12)
    assert np.allclose(points.min(axis=0), lower, atol=5e-3) and np.allclose(points.max(axis=0), upper, atol=5e-3)
    assert np.allclose(0.5 * (lower + upper), obstacle.center)  # center is the bounding box's centre


def test_bounding_boxes_of_axis_aligned_shapes() -> None:
    lower, upper = Obstacle("box", (1.0, 2.0, 0.1), (0.2, 0.4, 0.2)).bounding_box()
    assert np.allclose(lower, (0.9, 1.8, 0.0)) and np.allclose(upper, (1.1, 2.2, 0.2))
    lower, upper = Obstacle("box", (0.0, 0.0, 0.1), (0.2, 0.4, 0.2), math.pi / 2).bounding_box()
    assert np.allclose(lower, (-0.2, -0.1, 0.0)) and np.allclose(upper, (0.2, 0.1, 0.2))
    lower, upper = Obstacle("cylinder", (1.0, 0.0, 0.2), (0.05, 0.4), 1.0).bounding_box()
    assert np.allclose(lower, (0.95, -0.05, 0.0)) and np.allclose(upper, (1.05, 0.05, 0.4))


@pytest.mark.parametrize("obstacle", SHAPES, ids=lambda o: f"{o.shape}-yaw{o.yaw:g}")
def test_mjcf_geom_is_the_shape(obstacle: Obstacle) -> None:
    """The compiled MuJoCo geom has the obstacle's pose and size (a prism: its six corners)."""
    model = mujoco.MjModel.from_xml_string(obstacle_scene_xml(biped_scene_xml(), [obstacle]))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    g = model.geom("obstacle_0").id
    assert model.geom_bodyid[g] == 0 and model.geom_contype[g] == 1 and model.geom_conaffinity[g] == 1
    frame = data.geom_xmat[g].reshape(3, 3)
    if obstacle.shape == "prism":
        mesh = model.geom_dataid[g]
        local = model.mesh_vert[model.mesh_vertadr[mesh] : model.mesh_vertadr[mesh] + model.mesh_vertnum[mesh]]
        world = data.geom_xpos[g] + local @ frame.T
        expected = obstacle.vertices()
        assert len(world) == 6 and all(np.min(np.linalg.norm(world - p, axis=1)) < 1e-6 for p in expected)
        return
    assert np.allclose(data.geom_xpos[g], obstacle.center)
    assert np.allclose(frame, obstacle.rotation, atol=1e-12)
    if obstacle.shape == "box":
        assert model.geom_type[g] == mujoco.mjtGeom.mjGEOM_BOX
        assert np.allclose(model.geom_size[g], 0.5 * np.asarray(obstacle.size))
    else:
        assert model.geom_type[g] == mujoco.mjtGeom.mjGEOM_CYLINDER
        assert np.allclose(model.geom_size[g, :2], (obstacle.size[0], 0.5 * obstacle.size[1]))


def test_obstacle_arguments_are_checked() -> None:
    with pytest.raises(ValueError, match="shape must be one of box, prism, cylinder"):
        Obstacle("sphere", (0, 0, 0), (1, 1, 1))
    with pytest.raises(ValueError, match=r"size must be a cylinder's \(radius, height\)"):
        Obstacle("cylinder", (0, 0, 0), (1, 1, 1))
    with pytest.raises(ValueError, match="size"):
        Obstacle("box", (0, 0, 0), (1, 0, 1))
    with pytest.raises(ValueError, match="kind"):
        Obstacle("box", (0, 0, 0), (1, 1, 1), kind="wall")
    # lists on purpose (the annotation asks for tuples): the constructor must coerce them
    assert Obstacle("box", [0, 0, 0.5], [1, 1, 1]) == Obstacle(  # type: ignore[arg-type]
        "box", (0.0, 0.0, 0.5), (1.0, 1.0, 1.0)
    )


# ---------------------------------------------------------------------- courses
def test_the_monographs_courses() -> None:
    (beam,) = beam_course()
    assert beam.shape == "box" and beam.kind == "step_over"
    lower, upper = beam.bounding_box()
    assert np.allclose(upper - lower, (0.08, 0.35, 0.161))  # 8 cm deep, 35 cm wide, 16.1 cm high
    assert np.allclose(beam.center[:2], (1.28, 0.0)) and lower[2] == pytest.approx(0.0)
    assert 1.28 == pytest.approx((5 - 1) * 0.32)  # the nominal 5th foothold at 0.4 m/s
    (prism,) = triangle_course()
    assert prism.shape == "prism" and prism.kind == "swing_around"
    lower, upper = prism.bounding_box()
    assert np.allclose(upper - lower, (0.09, 0.13, 0.30)) and lower[2] == pytest.approx(0.0)
    assert np.allclose(prism.center[:2], (1.28, 0.0))
    apex = prism.vertices()[2]
    assert np.allclose(apex, (1.28 - 0.045, 0.0, 0.30))
    # it overlaps each foot's path (soles 0.15 m wide at y = +-0.09) by 5 cm
    assert min(upper[1], FOOT_PATH_Y[1]) - max(lower[1], FOOT_PATH_Y[0]) == pytest.approx(0.05)
    assert min(-FOOT_PATH_Y[0], upper[1]) - max(-FOOT_PATH_Y[1], lower[1]) == pytest.approx(0.05)


def _overlap(lower: float, upper: float, band: tuple[float, float]) -> float:
    return min(upper, band[1]) - max(lower, band[0])


def test_random_courses_are_seeded() -> None:
    a = random_course(np.random.default_rng(5))
    assert a == random_course(np.random.default_rng(5))
    assert a != random_course(np.random.default_rng(6))


@pytest.mark.parametrize("kwargs", [{}, {"n_obstacles": (1, 2), "spacing": (0.5, 0.6), "first_obstacle_distance": 3.0}])
def test_random_courses_respect_every_range(kwargs: dict) -> None:
    n_range = kwargs.get("n_obstacles", (3, 6))
    gap = kwargs.get("spacing", (1.2, 3.0))
    first = kwargs.get("first_obstacle_distance", 1.5)
    counts, kinds, shapes, overlaps = set(), [], set(), []
    for seed in range(400):
        course = random_course(np.random.default_rng(seed), **kwargs)
        counts.add(len(course))
        assert n_range[0] <= len(course) <= n_range[1]
        x = [o.center[0] for o in course]
        assert x[0] == pytest.approx(first)
        assert all(gap[0] <= b - a <= gap[1] for a, b in zip(x, x[1:], strict=False))
        for o in course:
            kinds.append(o.kind)
            shapes.add((o.kind, o.shape))
            lower, upper = o.bounding_box()
            assert lower[2] == pytest.approx(0.0) and o.yaw == 0.0  # standing on the ground
            height = upper[2]
            left, right = _overlap(lower[1], upper[1], FOOT_PATH_Y), _overlap(lower[1], upper[1], (-0.165, -0.015))
            if o.kind == "step_over":
                assert o.shape == "box"
                depth, width, _ = o.size
                assert STEP_OVER["height"][0] <= height <= STEP_OVER["height"][1]
                assert STEP_OVER["depth"][0] <= depth <= STEP_OVER["depth"][1]
                assert STEP_OVER["width"][0] <= width <= STEP_OVER["width"][1]
                assert abs(o.center[1]) <= 0.05
            elif o.kind == "swing_around":
                assert o.shape in ("prism", "cylinder")
                width = upper[1] - lower[1]
                assert 0.20 <= height <= 0.40 and 0.05 <= width <= 0.13 + 1e-12
                if o.shape == "prism":
                    assert SWING_AROUND["prism_depth"][0] <= o.size[0] <= SWING_AROUND["prism_depth"][1]
                # overlaps exactly one foot's path, by 0-10 cm, from outside it
                assert (left > 0.0) != (right > 0.0) or max(left, right) <= 1e-12
                overlap = max(left, right, 0.0)
                assert overlap <= 0.10 + 1e-12
                assert abs(o.center[1]) > 0.165 - overlap  # the obstacle reaches in from the outer side
                overlaps.append(overlap)
            else:
                assert o.kind == "beside" and o.shape == "box"
                assert BESIDE["height"][0] <= height <= BESIDE["height"][1]
                assert min(abs(lower[1]), abs(upper[1])) >= 0.165 + 0.05 - 1e-12  # clear of both soles' paths
                assert lower[1] > 0.0 or upper[1] < 0.0
    assert counts == set(range(n_range[0], n_range[1] + 1))
    assert {k: kinds.count(k) / len(kinds) for k in set(kinds)} == pytest.approx(
        {"step_over": 1 / 3, "swing_around": 1 / 3, "beside": 1 / 3}, abs=0.06
    )
    assert {("swing_around", "prism"), ("swing_around", "cylinder")} <= shapes
    # the overlap is uniform over 0-10 cm: its quartiles near 2.5, 5, 7.5 cm
    assert np.allclose(np.percentile(overlaps, [25, 50, 75]), [0.025, 0.05, 0.075], atol=0.012)


# ---------------------------------------------------------------------- the env
def test_observation_layout_padding_and_order() -> None:
    env = gym.make(ENV_ID, obstacles=NEAR, observed_obstacles=8)
    base = env.unwrapped
    obs, _ = env.reset(seed=0)
    layout = base.OBSERVATION_LAYOUT
    assert base.OBSTACLE_FEATURES == OBSTACLE_FEATURES == 14
    assert layout["obstacles"] == slice(81, 81 + 14 * 8) and obs.shape == env.observation_space.shape == (193,)
    assert BipedObstaclesEnv.OBSERVATION_LAYOUT["obstacles"] == slice(81, 193)  # the default K's
    volumes = base.obstacle_volumes
    assert len(volumes) == 6  # box: 2 TSS, cylinder: 1 LSS, prism: 1 TSS, box: 2 TSS
    block = obs[layout["obstacles"]].reshape(8, 14)
    assert np.all(block[6:] == 0.0) and np.all(block[:6, 0] == 1.0)  # padded with zero rows, mask 0

    def low_x(v: SSV) -> float:
        return float(v.points[:, 0].min() - v.radius)

    ordered = sorted(volumes, key=low_x)
    for row, v in zip(block, ordered, strict=False):
        assert row[1 + v.kind] == 1.0 and row[1:4].sum() == 1.0
        assert np.array_equal(row[4:13], v.vertices.reshape(-1)) and row[13] == v.radius
    assert np.all(np.diff([low_x(v) for v in ordered]) >= 0.0)
    lss = next(row for row in block if row[2] == 1.0)
    assert np.array_equal(lss[10:13], lss[7:10])  # the unused vertex repeats the last one
    # K smaller than the course: the first K by their smallest x
    small = gym.make(ENV_ID, obstacles=NEAR, observed_obstacles=3)
    obs3, _ = small.reset(seed=0)
    assert obs3.shape == (81 + 42,) and np.array_equal(obs3[81:], block[:3].reshape(-1))
    assert gym.make(ENV_ID, obstacles=NEAR, observed_obstacles=0).reset(seed=0)[0].shape == (81,)
    # volumes left more than 0.6 m behind the pelvis drop out, the next ones move up
    data = base.data
    qpos = data.qpos.copy()
    high_x = max(float(v.points[:, 0].max() + v.radius) for v in ordered[:2])
    qpos[0] = high_x + OBSTACLE_LOOKBEHIND + 1e-3
    base.set_state(qpos, data.qvel)
    moved = base._get_obs()[81:].reshape(8, 14)
    behind = sum(float(v.points[:, 0].max() + v.radius) < qpos[0] - OBSTACLE_LOOKBEHIND for v in ordered)
    assert behind >= 2 and np.array_equal(moved[: 6 - behind], block[behind:6]) and np.all(moved[6 - behind :] == 0)


def test_foot_inside_a_box_is_an_obstacle_contact() -> None:
    box = {"shape": "box", "center": [0.8, 0.09, 0.05], "size": [0.3, 0.2, 0.1]}  # on the left foot's path
    env = gym.make(ENV_ID, obstacles=[box], contact_weight=2.5)
    base = env.unwrapped
    _, info = env.reset(seed=0)
    assert not info["obstacle_contact"] and info["obstacle_contacts"] == 0 and info["min_obstacle_clearance"] > 0.3
    _, _, _, _, info = env.step(np.zeros(22))
    assert not info["obstacle_contact"] and info["reward_obstacle"] == 0.0 and not info["collision"]
    qpos = base.data.qpos.copy()
    qpos[0] += 0.8  # the left sole (x from -0.07 to 0.19 around the ankle) now stands inside the box
    base.set_state(qpos, base.data.qvel)
    _, reward, _, _, info = env.step(np.zeros(22))
    assert info["obstacle_contact"] and info["obstacle_contacts"] == 1 and info["collision"]
    assert not info["self_collision"] and info["min_obstacle_clearance"] < 0.0
    assert info["reward_obstacle"] == -2.5
    assert reward == pytest.approx(sum(v for k, v in info.items() if k.startswith("reward_")))
    # the robot geoms in contact with the box: the left foot's
    box_id = int(base.obstacle_geoms[0])
    touching = {
        base.model.geom(int(g)).name for pair in base.data.contact.geom if box_id in pair for g in pair if g != box_id
    }
    assert touching and all(name.startswith("l_") for name in touching), touching
    _, _, _, _, info = env.step(np.zeros(22))
    assert info["obstacle_contacts"] >= 1 and not info["is_success"]


def _robot_volumes(base: BipedObstaclesEnv) -> list[SSV]:
    """The robot's swept-sphere volumes from MuJoCo's sphere and capsule geoms (brute force, no batch)."""
    m, d = base.model, base.data
    out: list[SSV] = []
    for g in range(m.ngeom):
        if m.geom_bodyid[g] == 0:
            continue
        if m.geom_type[g] == mujoco.mjtGeom.mjGEOM_SPHERE:
            out.append(PSS(d.geom_xpos[g], m.geom_size[g, 0]))
        elif m.geom_type[g] == mujoco.mjtGeom.mjGEOM_CAPSULE:
            axis = d.geom_xmat[g].reshape(3, 3)[:, 2] * m.geom_size[g, 1]
            out.append(LSS(d.geom_xpos[g] - axis, d.geom_xpos[g] + axis, m.geom_size[g, 0]))
    return out


def test_min_obstacle_clearance_is_the_brute_force_minimum() -> None:
    env = gym.make(ENV_ID, obstacles=NEAR)
    base = env.unwrapped
    assert isinstance(base, BipedObstaclesEnv)
    rng = np.random.default_rng(0)
    _, info = env.reset(seed=2)
    checked = []

    def check(info: dict) -> None:
        robot = _robot_volumes(base)
        assert len(robot) == 22
        brute = min(distance(a, b).distance for a in robot for b in base.obstacle_volumes)
        assert info["min_obstacle_clearance"] == pytest.approx(brute, abs=1e-12)
        assert info["min_clearance"] == min(brute, info["min_self_clearance"])
        checked.append(brute)

    for _ in range(30):  # random motion in place
        check(info)
        _, _, terminated, _, info = env.step(rng.uniform(-0.3, 0.3, 22))
        assert not terminated
    for x in np.arange(-1.0, 2.6, 0.05):  # then carried along and beside the course: far, near, overlapping
        qpos = base.data.qpos.copy()
        qpos[:2] = x, 0.1 * math.sin(7.0 * x)
        base.set_state(qpos, base.data.qvel)
        _, _, _, _, info = env.step(np.zeros(22))
        check(info)
    assert min(checked) < 0.0 < 0.25 < max(checked)  # overlapping, near and far pairs were all exercised
    # the same far from every obstacle (the clearance search widens its margin)
    far = gym.make(ENV_ID, obstacles=[{"shape": "cylinder", "center": [9.0, 3.0, 0.5], "size": [0.1, 1.0]}])
    _, info = far.reset(seed=0)
    far_base = far.unwrapped
    assert isinstance(far_base, BipedObstaclesEnv)
    brute = min(distance(a, b).distance for a in _robot_volumes(far_base) for b in far_base.obstacle_volumes)
    assert info["min_obstacle_clearance"] == pytest.approx(brute, abs=1e-12) and brute > 8.0


def test_success_past_the_course_end_ends_the_episode() -> None:
    env = gym.make(ENV_ID, course="beam", success_distance=0.5)
    base = env.unwrapped
    _, info = env.reset(seed=0)
    assert info["course_end"] == pytest.approx(1.32 + 0.5) == base.course_end
    assert info["obstacles_passed"] == 0 and not info["is_success"]
    qpos = base.data.qpos.copy()
    qpos[0] = 1.5  # past the beam (its far face at 1.32 m), before the end
    base.set_state(qpos, base.data.qvel)
    _, _, terminated, _, info = env.step(np.zeros(22))
    assert info["obstacles_passed"] == 1 and not info["is_success"] and not terminated
    qpos = base.data.qpos.copy()
    qpos[0] = 1.9
    base.set_state(qpos, base.data.qvel)
    _, _, terminated, _, info = env.step(np.zeros(22))
    assert info["is_success"] and terminated and not info["fell"]


def test_fixed_course_matches_bipedwalk_physics_and_is_compiled_once() -> None:
    """Away from the obstacles the robot moves exactly as in BipedWalk: stepping physics step by step (to see every
    contact) changes nothing."""
    walk = gym.make("redundancy_gym/BipedWalk-v0")
    obstacles = gym.make(ENV_ID, course="triangle", target_speed=0.5)
    rng = np.random.default_rng(3)
    a, _ = walk.reset(seed=4)
    b, _ = obstacles.reset(seed=4)
    model = obstacles.unwrapped.model
    for _ in range(50):
        action = rng.uniform(-0.2, 0.2, 22)
        a, *_ = walk.step(action)
        b, *_ = obstacles.step(action)
    assert np.array_equal(a, b[:81])
    obstacles.reset(seed=5)
    assert obstacles.unwrapped.model is model  # a fixed course is not recompiled


def test_random_course_per_reset_is_seeded() -> None:
    env = gym.make(ENV_ID)
    base = env.unwrapped
    first, _ = env.reset(seed=11)
    course, model = base.obstacles, base.model
    assert 3 <= len(course) <= 6 and base.obstacle_geoms.size == len(course)
    again, _ = env.reset(seed=11)
    assert base.obstacles == course and base.model is model and np.array_equal(first, again)  # not recompiled
    env.reset(seed=12)
    assert base.obstacles != course and base.model is not model
    assert [base.model.geom(int(g)).name for g in base.obstacle_geoms] == [
        f"obstacle_{k}" for k in range(len(base.obstacles))
    ]


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"course": "forest"}, "course must be one of beam, triangle, random"),
        ({"obstacles": []}, "obstacles must be None or a non-empty list"),
        ({"obstacles": {"shape": "box"}}, "obstacles must be None or a non-empty list"),
        (
            {"obstacles": [{"shape": "sphere", "center": [1, 0, 0], "size": [1, 1, 1]}]},
            r"obstacles\[0\]\['shape'\] must be one of box, prism, cylinder",
        ),
        (
            {"obstacles": [{"shape": "cylinder", "center": [1, 0, 0], "size": [0.1, 0.2, 0.3]}]},
            r"obstacles\[0\]\['size'\] must be a cylinder's \(radius, height\)",
        ),
        ({"obstacles": [{"shape": "box", "center": [1, 0], "size": [0.1, 0.2, 0.3]}]}, r"obstacles\[0\]\['center'\]"),
        ({"obstacles": [{"shape": "box", "center": [1, 0, 0], "size": [0.1, -0.2, 0.3]}]}, r"obstacles\[0\]\['size'\]"),
        (
            {"obstacles": [{"shape": "box", "center": [1, 0, 0], "size": [0.1, 0.2, 0.3], "yaw": "left"}]},
            r"obstacles\[0\]\['yaw'\]",
        ),
        (
            {"obstacles": [{"shape": "box", "center": [1, 0, 0], "size": [0.1, 0.2, 0.3], "colour": "red"}]},
            r"obstacles\[0\] has unknown key\(s\) colour",
        ),
        ({"obstacles": [{"shape": "box", "center": [1, 0, 0]}]}, r"obstacles\[0\] has missing key\(s\) size"),
        (
            {"obstacles": [{"shape": "box", "center": [0.1, 0.0, 0.1], "size": [0.2, 0.2, 0.2]}]},
            r"obstacles\[0\] overlaps the standing robot",
        ),
        ({"n_obstacles": (0, 3)}, "n_obstacles"),
        ({"n_obstacles": (4, 3)}, "n_obstacles"),
        ({"n_obstacles": (1.0, 3)}, "n_obstacles"),
        ({"obstacle_spacing": (0.1, 1.0)}, "obstacle_spacing must be .* both >= 0.4"),
        ({"first_obstacle_distance": 0.2}, "first_obstacle_distance must be .* >= 0.5"),
        ({"observed_obstacles": -1}, "observed_obstacles"),
        ({"observed_obstacles": 2.0}, "observed_obstacles"),
        ({"contact_weight": -1.0}, "contact_weight"),
        ({"success_distance": float("nan")}, "success_distance"),
        ({"target_speed": 2.0}, "target_speed"),
        ({"obstacle": None}, "unknown keyword argument.*valid: .*obstacles"),
    ],
)
def test_invalid_arguments_raise_naming_the_argument(kwargs: dict, match: str) -> None:
    with pytest.raises(EnvConfigError, match=match):
        gym.make(ENV_ID, **kwargs)


def test_default_config_makes_the_default_env() -> None:
    from redundancy_gym.envs.biped_obstacles import MAX_EPISODE_STEPS, default_config

    config = default_config()
    assert config["target_speed"] == 0.4 and config["course"] == "random" and config["observed_obstacles"] == 8
    env = gym.make(ENV_ID, **config)
    assert env.observation_space.shape == (193,)
    assert gym.spec(ENV_ID).max_episode_steps == MAX_EPISODE_STEPS == 11250
    assert MAX_EPISODE_STEPS * env.unwrapped.dt >= 0.4 + (1.5 + 5 * 3.0 + 0.2 + 1.0) / 0.4


def test_renders_after_a_reset_that_changed_the_course() -> None:
    env = gym.make(ENV_ID, render_mode="rgb_array", width=96, height=72)
    env.reset(seed=0)
    first = env.render()
    model = env.unwrapped.model
    old = weakref.ref(env.unwrapped.mujoco_renderer.viewer.con)
    gc.disable()  # the old renderer must go by reference counting, not by a later collection
    try:
        env.reset(seed=1)
        assert old() is None  # its MjrContext is freed before the new context exists
    finally:
        gc.enable()
    assert env.unwrapped.model is not model
    frame = env.render()
    assert isinstance(first, np.ndarray) and isinstance(frame, np.ndarray)
    assert frame.shape == (72, 96, 3) and frame.dtype == np.uint8 and frame.std() > 0
    assert first.shape == frame.shape and not np.array_equal(first, frame)  # another episode
    for _ in range(3):
        env.step(np.zeros(22))
        assert env.render().std() > 0
    env.close()


def test_eval_reports_obstacle_contacts_and_clearance() -> None:
    box = {"shape": "box", "center": [0.8, 0.09, 0.05], "size": [0.3, 0.2, 0.1]}
    env = gym.make(ENV_ID, obstacles=[box], max_episode_steps=20)
    zero = redundancy_gym.make_policy("zero", env)
    clean, _ = run_episode(env, zero, seed=0)
    base = env.unwrapped

    class PlaceInTheBox:
        """The zero action, after moving the robot into the box at its first step."""

        def predict(self, observation, state=None, episode_start=None, deterministic=True):  # noqa: ANN001, ANN201
            if episode_start is not None and episode_start[0]:
                qpos = base.data.qpos.copy()
                qpos[0] += 0.8
                base.set_state(qpos, base.data.qvel)
            return np.zeros(22), state

    touched, _ = run_episode(env, PlaceInTheBox(), seed=1)
    assert clean.obstacle_contact is False and touched.obstacle_contact is True
    report = EvalReport(ENV_ID, "zero", 2, 0, {}, [clean, touched], np.ones(40)).to_json()
    assert report["obstacle_contact_rate"] == 0.5
    assert touched.min_obstacle_clearance is not None and touched.min_obstacle_clearance < 0.0
    assert report["min_obstacle_clearance"] == touched.min_obstacle_clearance
    assert report["per_episode"][1]["obstacle_contact"] is True
    text = format_report(report)
    assert "obstacle contact rate" in text and "to obstacles" in text


@pytest.mark.parametrize("backend", ["compiled", "python"])
def test_clearance_search_ends_on_a_non_finite_state(backend: str) -> None:
    """A robot state of NaN (a simulation gone unstable) must not make the widening margin search loop forever."""
    env = gym.make(ENV_ID, course="beam", backend=backend)
    env.reset(seed=0)
    base = env.unwrapped
    if backend == "python":  # the robot's volumes as _self_clearance would place them from NaN frames
        base._batch.vertices[:] = np.nan
        assert not math.isfinite(base._obstacle_clearance())
    else:  # the compiled metrics place them from the geoms' frames and search both batches in the same call
        base.data.geom_xpos[:] = np.nan
        metrics = base._metrics(0.0)
        assert not math.isfinite(metrics["min_obstacle_clearance"])
        assert not math.isfinite(metrics["min_self_clearance"])

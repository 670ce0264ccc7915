"""Collision model: pairs, bounding capsules, and dd/dq (5.61) against finite differences."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.typing import ArrayLike, NDArray

from redundancy_gym.geometry import LSS, PSS, TSS, CollisionModel, GeometryError, Segment, bounding_lss, distance
from redundancy_gym.model import RobotModel, collision_geometry_from_mjcf, collision_model_from_mjcf

OBSTACLE = Segment("obstacle", (PSS([0.6, 0.0, 0.0], 0.1),))


def test_segments_and_pairs_from_the_planar_arm(planar_model: RobotModel) -> None:
    geometry = collision_geometry_from_mjcf(planar_model)
    assert [s.name for s in geometry.robot] == ["link1", "link2", "link3", "link4"]
    assert all(isinstance(s.volumes[0], LSS) for s in geometry.robot)
    assert set(geometry.adjacent) == {("link1", "link2"), ("link2", "link3"), ("link3", "link4")}
    model = collision_model_from_mjcf(planar_model, [OBSTACLE])
    # non-adjacent robot pairs, then every link against the obstacle
    assert model.pairs == (
        ("link1", "link3"),
        ("link1", "link4"),
        ("link2", "link4"),
        ("link1", "obstacle"),
        ("link2", "obstacle"),
        ("link3", "obstacle"),
        ("link4", "obstacle"),
    )
    without_self = collision_model_from_mjcf(planar_model, [OBSTACLE], self_collision=False)
    assert without_self.num_pairs == 4


def test_distances_match_direct_queries(planar_model: RobotModel, rng: np.random.Generator) -> None:
    model = collision_model_from_mjcf(planar_model, [OBSTACLE])
    segments = {s.name: s for s in model.segments}
    for _ in range(5):
        q = rng.uniform(planar_model.lower_limits, planar_model.upper_limits)
        planar_model.update(q)
        state = model.evaluate(planar_model)
        for p, (a, b) in enumerate(state.pairs):
            va, vb = segments[a].volumes[0], segments[b].volumes[0]
            frame_a, frame_b = segments[a].frame, segments[b].frame
            if frame_a:
                va = va.transformed(*planar_model.frame_placement(frame_a))
            if frame_b:
                vb = vb.transformed(*planar_model.frame_placement(frame_b))
            assert state.distance[p] == pytest.approx(distance(va, vb).distance, abs=1e-12)


def test_distance_gradient_matches_finite_differences(planar_model: RobotModel, rng: np.random.Generator) -> None:
    model = collision_model_from_mjcf(planar_model, [OBSTACLE])
    h = 1e-7
    checked = 0
    while checked < 8:
        q = rng.uniform(0.8 * planar_model.lower_limits, 0.8 * planar_model.upper_limits)
        planar_model.update(q)
        state = model.evaluate(planar_model)
        if np.any(state.distance < 0.01):  # touching primitives: the gradient is not defined there
            continue
        grad = model.distance_gradient(planar_model, state)
        fd = np.zeros_like(grad)
        for k in range(planar_model.nv):
            dq = np.zeros(planar_model.nv)
            dq[k] = h
            planar_model.update(q + dq)
            plus = model.evaluate(planar_model).distance
            planar_model.update(q - dq)
            minus = model.evaluate(planar_model).distance
            fd[:, k] = (plus - minus) / (2 * h)
        np.testing.assert_allclose(grad, fd, atol=1e-6)
        checked += 1


def test_bounding_capsule_contains_its_volumes_and_skips_far_pairs() -> None:
    rng = np.random.default_rng(2)
    volumes = (
        LSS([0, 0, 0], [0.3, 0, 0], 0.05),
        PSS([0.1, 0.1, 0], 0.02),
        TSS([0, 0, 0.1], [0.2, 0, 0.1], [0, 0.1, 0.1], 0.01),
    )
    bound = bounding_lss(volumes)
    axis = LSS(bound.points[0], bound.points[1], 0.0)
    for v in volumes:  # every vertex ball of every volume lies inside the capsule
        for p in v.points:
            assert distance(PSS(p, 0.0), axis).distance + v.radius <= bound.radius + 1e-12
    for _ in range(50):
        probe = PSS(rng.uniform(-1, 1, 3), 0.01)
        assert distance(probe, bound).distance <= min(distance(probe, v).distance for v in volumes) + 1e-12

    class World:
        nv = 0

        def frame_placement(self, frame: str) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
            return np.eye(3), np.zeros(3)

        def point_jacobian(self, frame: str, point: ArrayLike) -> NDArray[np.float64]:
            return np.zeros((3, 0))

    near = Segment("near", (PSS([0.5, 0, 0], 0.05),))
    far = Segment("far", (PSS([5.0, 0, 0], 0.05),))
    model = CollisionModel([Segment("body", volumes, frame="base")], [near, far], bounding_margin=0.5)
    state = model.evaluate(World())
    assert state.exact.tolist() == [True, False]
    exact_model = CollisionModel([Segment("body", volumes, frame="base")], [near, far], bounding=False)
    exact = exact_model.evaluate(World())
    assert state.distance[0] == exact.distance[0]
    assert state.distance[1] <= exact.distance[1]  # the skipped pair reports a lower bound


def test_invalid_models_raise() -> None:
    seg = Segment("a", (PSS([0, 0, 0], 0.1),), frame="f")
    with pytest.raises(GeometryError, match="unique"):
        CollisionModel([seg, seg])
    with pytest.raises(GeometryError, match="needs a frame"):
        CollisionModel([Segment("b", (PSS([0, 0, 0], 0.1),))])
    with pytest.raises(GeometryError, match="unknown segments"):
        CollisionModel([seg], exclude=[("a", "nope")])
    with pytest.raises(GeometryError, match="no volumes"):
        Segment("empty", ())


def test_layout_and_environment_volumes_describe_the_model(planar_model: RobotModel) -> None:
    """The flat layout (for compiled consumers) reproduces every pair distance; environment moves bump the version."""
    from redundancy_gym.geometry import PackedVolumes
    from redundancy_gym.geometry.ssv_kernels import volume_pair_distance

    model = collision_model_from_mjcf(planar_model, [OBSTACLE])
    layout = model.layout()
    assert len(layout.frames) == len(model.segments) and layout.segment_pairs.shape == (model.num_pairs, 2)
    version = model.version
    model.set_environment_placement("obstacle", np.eye(3), [0.1, 0.0, 0.3])
    model.set_environment_radius("obstacle", 0.05)
    assert model.version == version + 2
    q = np.array([0.3, -0.4, 0.5, 0.2])
    planar_model.update(q)
    state = model.evaluate(planar_model)
    env = model.environment_volumes()
    vertices = layout.local.copy()
    first = len(vertices) - len(env)
    vertices[first:] = env.vertices
    radii = layout.radii.copy()
    radii[first:] = env.radii
    for s, frame in enumerate(layout.frames):
        if frame is not None:
            rotation, position = planar_model.frame_placement(frame)
            sl = slice(layout.segment_starts[s], layout.segment_starts[s + 1])
            vertices[sl] = layout.local[sl] @ rotation.T + position
    packed = PackedVolumes(vertices, radii, layout.kinds)
    for p in range(model.num_pairs):
        ks = range(layout.pair_starts[p], layout.pair_starts[p + 1])
        best = min(
            volume_pair_distance(packed.vertices, packed.radii, packed.kinds, layout.volume_a[k], layout.volume_b[k])[0]
            for k in ks
        )
        if state.exact[p]:
            assert best == pytest.approx(state.distance[p], abs=1e-12)
        else:  # skipped by its bounding capsule: the reported distance is a lower bound
            assert best >= state.distance[p] - 1e-12

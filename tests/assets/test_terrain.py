"""Terrain segments and their heights: the analytic heights against MuJoCo's rays on the compiled scene (boxes,
ramp meshes, heightfields with MuJoCo's triangulation), the compiled kernel against the reference bit for bit, the
generator's ranges, explicit parameters, edge distances on hand-made terrain, and bad values named."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from redundancy_gym.assets.biped_scene import biped_scene_xml, terrain_scene_xml
from redundancy_gym.assets.obstacle_course import FOOT_Y
from redundancy_gym.assets.terrain import (
    TERRAIN_KINDS,
    TERRAIN_RANGES,
    Terrain,
    TerrainSegment,
    draw_segment,
    explicit_terrain,
    random_terrain,
    segment_length_bound,
)
from redundancy_gym.envs.terrain_kernels import pack_terrain, terrain_heights_kernel

_SCENE = biped_scene_xml()


def _ray_heights(terrain: Terrain, points: np.ndarray) -> np.ndarray:
    """Terrain heights [m] from MuJoCo's rays straight down onto the compiled scene (the robot stands at x < 0.3)."""
    model = mujoco.MjModel.from_xml_string(terrain_scene_xml(_SCENE, terrain))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    geom = np.zeros(1, np.int32)
    down = np.array([0.0, 0.0, -1.0])
    heights = []
    for x, y in points:
        distance = mujoco.mj_ray(model, data, np.array([x, y, 2.0]), down, None, 1, -1, geom)
        heights.append(2.0 - distance)
    return np.array(heights)


@pytest.mark.parametrize("kind", TERRAIN_KINDS)
def test_heights_match_mujoco_rays(kind: str) -> None:
    rng = np.random.default_rng(1)
    terrain = random_terrain(rng, kinds=(kind,), n_segments=(2, 2), first_distance=0.8)
    points = np.column_stack([rng.uniform(0.4, terrain.end + 0.3, 3000), rng.uniform(-1.1, 1.1, 3000)])
    # and points a micrometre inside the box edges (a ray exactly on an edge may pass it) and on rough vertices,
    # where a max over parts and the triangulation's sides decide
    e = 1e-6
    for x0, x1, y0, y1, _ in terrain.boxes[:5]:
        points = np.vstack([points, [[x0 + e, 0.5 * (y0 + y1)], [x1 - e, y1 - e], [0.5 * (x0 + x1), y0 + e]]])
    for patch in terrain.patches:
        rows, cols = patch.heights.shape
        points = np.vstack(
            [points, [[patch.x0 + c * patch.spacing, patch.y0 + 7 * patch.spacing] for c in range(cols)]]
        )
    expected = _ray_heights(terrain, points)
    heights = terrain.heights(points)
    # float32 mesh vertices and heightfield values: MuJoCo's geometry is exact to ~1e-7 m
    np.testing.assert_allclose(heights, expected, atol=2e-7)
    assert heights.max() > 0.005  # the segments are there (and the rays saw them)


def test_compiled_heights_equal_the_reference_bit_for_bit() -> None:
    for seed in range(4):
        terrain = random_terrain(np.random.default_rng(seed), n_segments=(5, 5))
        rng = np.random.default_rng(100 + seed)
        points = np.column_stack([rng.uniform(0.0, terrain.end, 4000), rng.uniform(-1.2, 1.2, 4000)])
        points[:500] = np.round(points[:500], 1)  # on grid lines and box sides
        out = np.empty(len(points))
        compiled = terrain_heights_kernel(points[:, 0].copy(), points[:, 1].copy(), *pack_terrain(terrain), out)
        assert np.array_equal(compiled, terrain.heights(points))


def test_drawn_segments_stay_in_their_ranges() -> None:
    rng = np.random.default_rng(7)
    for _ in range(30):
        stairs = draw_segment("stairs", 2.0, rng)
        values = dict(stairs.parameters)
        tops = np.array([b[4] for b in stairs.boxes])
        n = int(values["steps"])
        assert TERRAIN_RANGES["stairs"]["steps"][0] <= n <= TERRAIN_RANGES["stairs"]["steps"][1]
        np.testing.assert_allclose(np.diff(tops[:n]), values["rise"])  # each step one rise up to the landing
        np.testing.assert_allclose(tops.max(), n * values["rise"])
        assert len(stairs.boxes) == 2 * n - 1 and stairs.start == 2.0
        assert stairs.end == pytest.approx(2.0 + 2 * (n - 1) * values["tread"] + values["landing"])
        stones = draw_segment("stepping_stones", 1.0, rng)
        r = TERRAIN_RANGES["stepping_stones"]
        for x0, x1, y0, y1, top in stones.boxes:
            assert r["length"][0] - 1e-12 <= x1 - x0 <= r["length"][1] + 1e-12
            assert r["width"][0] - 1e-12 <= y1 - y0 <= r["width"][1] + 1e-12
            assert abs(top - r["height"][0]) <= r["height_spread"][0] + 1e-12
            assert min(abs(y0), abs(y1)) >= 0.005 - 1e-12 and y0 * y1 > 0  # never across the centre line
            lane = FOOT_Y if y0 > 0.0 else -FOOT_Y
            assert y0 <= lane <= y1  # the foot's lane runs over every stone of its side
        slope = draw_segment("slope", 1.0, rng)
        angle = dict(slope.parameters)["angle"]
        x0, a, _, _, height, _, _ = slope.ramps[0]
        assert np.degrees(np.arctan2(height, a - x0)) == pytest.approx(angle)
        rough = draw_segment("rough", 1.0, rng)
        patch = rough.patches[0]
        amplitude = dict(rough.parameters)["amplitude"]
        assert patch.heights.min() == 0.0 and patch.heights.max() <= 2.0 * amplitude + 1e-9
        assert not patch.heights[0].any() and not patch.heights[:, -1].any()  # flush with the ground at its border
    assert segment_length_bound() >= max(s.end - s.start for s in (stairs, stones, slope, rough))


def test_same_generator_state_same_terrain() -> None:
    first = random_terrain(np.random.default_rng(3), n_segments=(3, 3))
    again = random_terrain(np.random.default_rng(3), n_segments=(3, 3))
    other = random_terrain(np.random.default_rng(4), n_segments=(3, 3))
    assert first == again and first != other


def test_explicit_segments_keep_their_values_and_gaps() -> None:
    terrain = explicit_terrain(
        [{"kind": "stairs", "steps": 4, "rise": 0.15, "tread": 0.3, "landing": 0.8}, {"kind": "platform", "gap": 2.0}],
        np.random.default_rng(0),
        first_distance=1.5,
        default_gap=1.0,
    )
    stairs, platform = terrain.segments
    assert stairs.start == 1.5 and dict(stairs.parameters)["rise"] == 0.15
    assert stairs.end == pytest.approx(1.5 + 2 * 3 * 0.3 + 0.8)
    assert platform.start == pytest.approx(stairs.end + 2.0)
    assert terrain.kind_at(stairs.start + 0.1) == "stairs" and terrain.kind_at(stairs.end + 1.0) == "flat"
    assert terrain.heights(np.array([[1.5 + 3 * 0.3 + 0.1, 0.0]]))[0] == pytest.approx(0.6)  # the landing


def test_edge_distance_on_a_hand_made_platform() -> None:
    box = (1.0, 1.3, -1.0, 1.0, 0.12)
    terrain = Terrain((TerrainSegment("platform", 1.0, 1.3, boxes=(box,)),))
    sole = np.array([[-0.095, -0.075], [0.165, -0.075], [-0.095, 0.075], [0.165, 0.075]])
    on = sole + [1.12, 0.09]  # heel 2.5 cm in from the near edge, toe 1.5 cm from the far one
    assert terrain.edge_distance(on, on.mean(axis=0)) == pytest.approx(0.015)
    over = sole + [1.2, 0.09]  # the toe 6.5 cm beyond the far edge
    assert terrain.edge_distance(over, over.mean(axis=0)) == pytest.approx(-0.065)
    ground = sole + [0.7, 0.09]  # on the ground, toes 13.5 cm short of the riser
    assert terrain.edge_distance(ground, ground.mean(axis=0)) == pytest.approx(0.135)
    against = sole + [0.9, 0.09]  # on the ground, toes 6.5 cm into the riser's footprint
    assert terrain.edge_distance(against, np.array([0.85, 0.09])) == pytest.approx(-0.065)
    far = sole + [5.0, 0.0]
    assert terrain.edge_distance(far, far.mean(axis=0), cap=1.0) == 1.0


@pytest.mark.parametrize(
    "kind, ranges, match",
    [
        ("stairs", {"treads": (0.2, 0.3)}, "stairs has no parameter 'treads'; valid: steps, rise, tread, landing"),
        ("stairs", {"rise": (0.2, 0.1)}, r"stairs rise must be a \(low, high\) pair"),
        ("stairs", {"steps": (2.5, 4)}, "stairs steps must be a .* of ints"),
        ("stepping_stones", {"height": (0.05, 0.05)}, "height_spread .* must be below height"),
        ("slope", {"angle": (50.0, 50.0)}, r"slope angle must be in \(0, 45\) deg"),
        ("moon", None, "kind must be one of stairs, platform, stepping_stones, slope, rough"),
    ],
)
def test_bad_segment_values_are_named(kind: str, ranges: dict | None, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        draw_segment(kind, 1.0, np.random.default_rng(0), ranges)

"""The walker's terrain map: profiles filled from height scans, footholds placed on hand-made terrain against
edges, risers and margins, pitched along ramps, swing envelopes over steps, and the pattern's CoM height plan over
steps up and down (continuous in height and velocity)."""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import pytest

from redundancy_gym.assets.terrain import RoughPatch, Terrain, TerrainSegment
from redundancy_gym.controllers import ControllerError
from redundancy_gym.controllers.walking import GaitConfig, WalkingPattern
from redundancy_gym.controllers.walking.terrain_map import TerrainMap, TerrainMapConfig
from redundancy_gym.controllers.walking.walking_pattern import MAX_STEP_WIDTH, MIN_STEP_WIDTH

LANES = (-0.09, 0.09)
SCAN = np.array([[-0.2 + 0.1 * i, -0.3 + 0.1 * j] for i in range(17) for j in range(7)])  # BipedTerrain's default


def _mapped(terrain: Terrain, until: float = 6.0) -> TerrainMap:
    """A map filled by scans taken every 2 mm of a straight walk from x = 0 to ``until`` [m] (pelvis at 0.9 m)."""
    terrain_map = TerrainMap(LANES)
    for x in np.arange(0.0, until, 0.002):
        points = np.column_stack((x + SCAN[:, 0], SCAN[:, 1]))
        scan = terrain.heights(points) - 0.9
        terrain_map.observe((float(x), 0.0, 0.9, 0.0), scan, SCAN)
    return terrain_map


def _boxes(*boxes: tuple[float, float, float]) -> Terrain:
    """Full-width boxes (x0, x1, top) [m]."""
    return Terrain(
        (TerrainSegment("platform", boxes[0][0], boxes[-1][1], boxes=tuple((a, b, -1.0, 1.0, h) for a, b, h in boxes)),)
    )


def test_the_profile_locates_an_edge_to_a_cell_from_scans_0_1_m_apart() -> None:
    terrain = _boxes((1.503, 2.0, 0.12))
    heights = _mapped(terrain).profile(0)
    x = -2.0 + 0.01 * np.arange(heights.size)
    high = x[heights > 0.06]
    # the edge at 1.503 m: the first cell whose centre lies within half a cell of it or past it
    assert high[0] == pytest.approx(1.5, abs=0.011) and high[-1] == pytest.approx(2.0, abs=0.011)
    assert np.allclose(heights[(x > 1.52) & (x < 1.98)], 0.12)


def test_a_foothold_near_a_platform_edge_moves_onto_it_or_before_it_with_its_margin() -> None:
    terrain_map = _mapped(_boxes((1.5, 2.5, 0.1)))
    c = terrain_map.config
    # nominal: the heel 5 cm before the edge (the sole straddles it): moves back before it or onto it
    hold = terrain_map.place(0, 1.5 + c.heel - 0.05, 0.8, 2.5)
    on = hold.x - c.heel >= 1.5 + c.margin - 0.01 and hold.z == pytest.approx(0.1)
    before = hold.x + c.toe + c.riser_margin <= 1.5 + 0.01 and hold.z == pytest.approx(0.0)
    assert on or before, hold
    assert hold.support == 1.0 and hold.pitch == 0.0
    # the far end: the toe may not overhang with its margin
    end = terrain_map.place(0, 2.5 - c.toe + 0.03, 1.8, 2.6)
    assert end.x + c.toe + c.margin <= 2.5 + 0.01 or end.x - c.heel - c.margin >= 2.5 - 0.01, end


def test_a_tread_shorter_than_the_sole_keeps_the_toe_off_the_riser() -> None:
    tread = 0.25  # a 0.26 m sole
    terrain_map = _mapped(
        _boxes((1.5, 1.5 + tread, 0.1), (1.5 + tread, 1.5 + 2 * tread, 0.2), (1.75 + tread, 3.0, 0.3))
    )
    c = terrain_map.config
    hold = terrain_map.place(0, 1.5 + 0.5 * tread, 1.0, 2.2)
    assert hold.z == pytest.approx(0.1) and hold.pitch == 0.0
    riser = 1.5 + tread
    assert hold.x + c.toe + c.riser_margin <= riser + 0.011  # the toe clear of the next riser
    assert hold.x - c.heel < 1.5  # so the heel overhangs the lower side: the support that is left
    assert 0.7 < hold.support < 1.0


def test_a_ramp_pitches_the_foot_along_it() -> None:
    angle = math.radians(8.0)
    ramp = Terrain(
        (TerrainSegment("slope", 1.0, 5.0, ramps=((1.0, 3.0, 3.0, 5.0, 2.0 * math.tan(angle), -1.0, 1.0),)),)
    )
    terrain_map = _mapped(ramp)
    hold = terrain_map.place(1, 2.0, 1.5, 2.5)
    assert hold.pitch == pytest.approx(-angle, abs=0.01)  # toes up, uphill
    assert hold.z == pytest.approx((hold.x - 1.0) * math.tan(angle), abs=0.004)
    down = terrain_map.place(1, 4.0, 3.5, 4.5)
    assert down.pitch == pytest.approx(angle, abs=0.01)


def test_the_swing_envelope_clears_a_step_with_its_clearance() -> None:
    terrain_map = _mapped(_boxes((1.5, 1.8, 0.12), (1.8, 3.0, 0.24)))
    c = terrain_map.config
    envelope = terrain_map.envelope(0, 1.2, 1.9)  # from the ground onto the second level
    assert envelope.top == pytest.approx(0.24 + c.clearance)
    # the band begins where the toe reaches the first riser and lasts to the landing
    assert envelope.band[0] == pytest.approx(1.5 - c.toe, abs=0.011) and envelope.band[1] == pytest.approx(1.9)
    flat = terrain_map.envelope(0, 0.2, 0.8)
    assert flat.band[1] <= flat.band[0]  # nothing to pass


def test_bad_config_values_are_named() -> None:
    with pytest.raises(ControllerError, match="TerrainMapConfig.cell must be a finite number > 0"):
        TerrainMapConfig(cell=0.0)
    with pytest.raises(ControllerError, match="TerrainMapConfig.margin must be a finite number >= 0"):
        TerrainMapConfig(margin=-0.01)


def test_the_com_height_plan_is_continuous_over_steps_up_and_down() -> None:
    terrain = _boxes((0.9, 1.5, 0.1), (1.5, 2.4, 0.2), (2.4, 3.0, 0.1))
    terrain_map = _mapped(terrain, until=4.0)
    gait = GaitConfig()
    pattern = WalkingPattern(gait, (0.0, -0.09, 0.0), (0.0, 0.09, 0.0), (0.0, 0.0), 0.4)
    pattern.set_terrain(0.0, terrain_map, 0.0)
    times = np.arange(0.0, 12.0, 0.002)
    samples = [pattern.sample(t) for t in times]
    z = np.array([s.com[2] for s in samples])
    vz = np.array([s.com_velocity[2] for s in samples])
    feet = np.array([s.feet[:, 2] for s in samples])
    assert feet.max() >= 0.2 + terrain_map.config.clearance  # it climbs the upper level (the toe tip on the path)
    assert z.max() == pytest.approx(0.2 + gait.com_height)
    # C1: no jump in height or vertical velocity, and the velocity is the height's derivative
    assert np.max(np.abs(np.diff(z))) < 0.002 and np.max(np.abs(np.diff(vz))) < 0.02
    np.testing.assert_allclose(np.gradient(z, times)[1:-1], vz[1:-1], atol=2e-3)
    # every stance foot stands on the terrain's surface under it
    for s in samples[::50]:
        for side in (0, 1):
            if s.contact[side]:
                assert s.feet[side, 2] == pytest.approx(float(terrain.heights(s.feet[side, :2])), abs=1e-9)


def test_a_push_recovery_shift_moves_a_landing_placed_on_the_map() -> None:
    terrain_map = _mapped(_boxes((3.0, 3.5, 0.1)), until=2.0)
    pattern = WalkingPattern(GaitConfig(), (0.0, -0.09, 0.0), (0.0, 0.09, 0.0), (0.0, 0.0), 0.4)
    pattern.set_terrain(0.0, terrain_map, 0.0)
    t = pattern.step_start(2) + 0.1  # step 2 swings foothold 2 to foothold 4
    pattern.set_terrain(t, terrain_map, 0.0)
    landing = pattern.foothold(4).copy()
    assert pattern.level_step(t)  # flat ground: push recovery may move it
    pattern.adjust_step(t, (0.05, -0.02), pattern.single_support)
    np.testing.assert_allclose(pattern.foothold(4), landing + (0.05, -0.02, 0.0), atol=1e-12)
    # a step onto the block is not level: no push recovery there
    k = next(k for k in range(2, 12) if pattern.foothold(k + 2)[2] > 0.05)
    assert not pattern.level_step(pattern.step_start(k) + 0.1)


def _stone_lanes() -> Terrain:
    """A stone 6 cm high under the right lane only (y in [-0.178, -0.005]), x in [2.0, 2.6]; ground elsewhere."""
    return Terrain((TerrainSegment("stepping_stones", 2.0, 2.6, boxes=((2.0, 2.6, -0.178, -0.005, 0.06),)),))


def test_a_yawed_scan_writes_each_lane_from_the_points_nearest_to_it() -> None:
    terrain = _stone_lanes()
    yaw = math.radians(6.0)  # the far rows of a scan column drift 0.15 m across at 1.4 m ahead
    c, s = math.cos(yaw), math.sin(yaw)
    terrain_map = TerrainMap(LANES)
    for x in np.arange(0.8, 1.2, 0.01):
        points = np.column_stack((x + c * SCAN[:, 0] - s * SCAN[:, 1], s * SCAN[:, 0] + c * SCAN[:, 1]))
        terrain_map.observe((float(x), 0.0, 0.9, yaw), terrain.heights(points) - 0.9, SCAN)
    xs = np.arange(2.05, 2.56, 0.01)
    # the right lane sees its stone, the left lane the ground beside it: a whole column picked by the pelvis's
    # offset would have read the far rows from the other lane
    assert np.allclose(terrain_map.heights_at(0, xs), 0.06)
    assert np.allclose(terrain_map.heights_at(1, xs), 0.0)


def test_a_swing_clears_a_higher_stone_in_the_other_lane() -> None:
    terrain_map = _mapped(_stone_lanes())
    # the left foot swings over ground in its own lane beside the right lane's stone: held above the stone
    envelope = terrain_map.envelope(1, 1.9, 2.7)
    assert envelope.top == pytest.approx(0.06 + terrain_map.config.clearance)


def test_footholds_not_begun_land_on_the_worlds_lanes_when_the_plan_has_drifted() -> None:
    terrain_map = _mapped(_boxes((5.0, 6.0, 0.0)))  # flat ground: only the lanes matter
    pattern = WalkingPattern(GaitConfig(), (0.0, -0.09, 0.0), (0.0, 0.09, 0.0), (0.0, 0.0), 0.4)
    pattern.set_terrain(0.0, terrain_map, 0.0)
    before = [pattern.foothold(j)[1] for j in range(4, 8)]
    # the plan is the world turned by 0.02 rad and moved 3 cm to the left: y_plan = sin(a) x + cos(a) y + 0.03
    a = 0.02
    pattern.set_terrain(1.0, terrain_map, 0.0, (math.sin(a), math.cos(a), 0.03))
    for j, y in zip(range(4, 8), before, strict=True):
        h = pattern.foothold(j)
        assert h[1] == pytest.approx(math.sin(a) * h[0] + math.cos(a) * y + 0.03)


def _rough(amplitude: float, seed: int = 0) -> Terrain:
    """A rough patch x in [1.5, 4.5] of vertex heights in [0, 2 amplitude] every 0.1 m (BipedTerrain's)."""
    rng = np.random.default_rng(seed)
    heights = np.zeros((9, 31))
    heights[1:-1, 1:-1] = rng.uniform(0.0, 2.0 * amplitude, (7, 29))
    patch = RoughPatch(1.5, -0.4, 0.1, heights.astype(np.float32).astype(np.float64))
    return Terrain((TerrainSegment("rough", 1.5, 4.5, patches=(patch,)),))


def test_roughness_is_zero_on_treads_and_edges_and_centimetres_on_rough_ground() -> None:
    flat = _mapped(_boxes((1.5, 2.0, 0.1), (2.0, 3.0, 0.2)))
    c = flat.config
    assert flat.place(0, 1.75, 1.4, 2.1).roughness == 0.0  # on a tread
    # a sole straddling the riser: the other level is an edge, not roughness
    x = 2.0 + c.heel - 0.05
    hold = flat.place(0, x, x, x)  # the reach allows this one position
    assert hold.x - c.heel < 2.0 < hold.x + c.toe and hold.roughness == 0.0
    ramp = _mapped(
        Terrain((TerrainSegment("slope", 1.0, 5.0, ramps=((1.0, 3.0, 3.0, 5.0, 2.0 * math.tan(0.14), -1.0, 1.0),)),))
    )
    assert ramp.place(1, 2.0, 1.5, 2.5).roughness < 0.003  # the profile's cells along a ramp
    for amplitude in (0.01, 0.03):
        rough = _mapped(_rough(amplitude))
        values = [rough.place(0, x, x - 0.1, x + 0.1).roughness for x in np.arange(2.0, 4.0, 0.3)]
        # bumps of up to 2 amplitude under the lane's centre line, never more than the terrain's own range
        assert min(values) > 0.3 * amplitude and max(values) <= 2.0 * amplitude + 1e-6


def test_footholds_moved_onto_the_worlds_lanes_keep_the_step_width_within_its_bounds() -> None:
    terrain_map = _mapped(_boxes((5.0, 6.0, 0.0)))
    for drift in (-0.18, 0.18, 0.05):
        pattern = WalkingPattern(GaitConfig(), (0.0, -0.09, 0.0), (0.0, 0.09, 0.0), (0.0, 0.0), 0.4)
        pattern.set_terrain(0.0, terrain_map, 0.0)
        # a plan drifted across from the world: its lanes at y_plan = y + drift
        pattern.set_terrain(1.0, terrain_map, 0.0, (0.0, 1.0, drift))
        ys = [float(pattern.foothold(j)[1]) for j in range(3, 12)]
        widths = [abs(b - a) for a, b in itertools.pairwise(ys)]
        assert min(widths) >= MIN_STEP_WIDTH - 1e-12 and max(widths) <= MAX_STEP_WIDTH + 1e-12, (drift, widths)
        # back on the lanes within a few steps
        assert ys[-1] == pytest.approx(0.09 + drift) and ys[-2] == pytest.approx(-0.09 + drift), (drift, ys)


def test_push_recovery_may_act_on_a_step_over_rough_ground_but_not_on_one_over_an_edge() -> None:
    gait = GaitConfig()
    rough = _rough(0.03)  # bumps up to 6 cm: the swings hold the envelope over them
    pattern = WalkingPattern(gait, (0.0, -0.09, 0.0), (0.0, 0.09, 0.0), (0.0, 0.0), 0.4)
    terrain_map = _mapped(rough)
    pattern.set_terrain(0.0, terrain_map, 0.0)
    rough_steps = [
        k
        for k in range(2, 14)
        if max(pattern.foothold_roughness(j) for j in (k, k + 1, k + 2)) > terrain_map.config.rough_ground
    ]
    assert rough_steps
    level = {k: pattern.level_step(pattern.step_start(k) + 0.01) for k in rough_steps}
    # over rough ground: level when the footholds lie within height_step, the envelope's band over bumps aside
    for k, is_level in level.items():
        heights = [float(pattern.foothold(j)[2]) for j in (k, k + 1, k + 2)]
        assert is_level == (max(heights) - min(heights) <= terrain_map.config.height_step), (k, heights)
    assert any(level.values())
    # stairs: the step onto a tread passes its riser, no step adjustment there
    stairs = _mapped(_boxes((1.5, 1.8, 0.12), (1.8, 3.0, 0.24)))
    pattern = WalkingPattern(gait, (0.0, -0.09, 0.0), (0.0, 0.09, 0.0), (0.0, 0.0), 0.4)
    pattern.set_terrain(0.0, stairs, 0.0)
    over = [k for k in range(0, 12) if not pattern.level_step(pattern.step_start(k) + 0.01)]
    assert over and all(pattern.foothold_roughness(j) == 0.0 for k in over for j in (k, k + 1, k + 2))


def test_the_compiled_scan_write_is_the_numpy_one_bit_for_bit() -> None:
    rng = np.random.default_rng(3)
    # the default grid, and a layout whose rows differ in length (padded with the row's last point)
    layouts = (SCAN, SCAN[SCAN[:, 1] < 0.15 + 0.05 * (SCAN[:, 0] > 0.5)])
    for layout in layouts:
        compiled, reference = TerrainMap(LANES), TerrainMap(LANES, backend="python")
        for _ in range(200):
            # poses along and off the map's ends, yawed up to 0.3 rad, drifted across
            base = (rng.uniform(-3.0, 59.5), rng.uniform(-0.15, 0.15), 0.9, rng.uniform(-0.3, 0.3))
            scan = np.asarray(rng.normal(0.0, 0.03, layout.shape[0]) - 0.9)
            compiled.observe(base, scan, layout)
            reference.observe(base, scan, layout)
        assert np.isfinite(reference._heights).sum() > 1000
        np.testing.assert_array_equal(compiled._heights, reference._heights)
        for lane in (0, 1):
            np.testing.assert_array_equal(compiled.profile(lane), reference.profile(lane))


def test_a_bad_backend_is_named() -> None:
    with pytest.raises(ControllerError, match="backend must be one of compiled, python"):
        TerrainMap(LANES, backend="gpu")


@pytest.mark.parametrize("terrain", ["rough", "stairs"])
def test_what_the_pattern_keeps_between_periods_is_what_it_computes_afresh(terrain: str) -> None:
    # the footholds, CoM height ramps, level steps and pitch blends kept between calls, against a twin that keeps
    # nothing, through terrain replanning once a step and push recovery's previews and adjustments
    ground = _rough(0.02) if terrain == "rough" else _boxes((1.0, 1.6, 0.1), (1.6, 2.2, 0.2), (2.2, 4.0, 0.05))
    terrain_map = _mapped(ground, until=5.0)
    kept, fresh = (WalkingPattern(GaitConfig(), (0.0, -0.09, 0.0), (0.0, 0.09, 0.0), (0.0, 0.0), 0.4) for _ in "ab")
    fresh._keep(False)
    fresh._keep = lambda on: WalkingPattern._keep(fresh, False)  # type: ignore[method-assign]
    adjusted, planned = 0, -2
    for t in np.arange(0.0, 9.0, 0.002).tolist():
        k = kept.step_at(t)
        if k != planned:  # once a step, as the walking controller does, the plan drifted by a millimetre a step
            planned = k
            for pattern in (kept, fresh):
                pattern.set_terrain(t, terrain_map, 0.001 * k)
        a, b = kept.sample(t), fresh.sample(t)
        for field in dataclasses.fields(a):
            name = field.name
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=f"{name} at t={t}")
        assert kept.level_step(t) == fresh.level_step(t)
        assert [kept.foothold_roughness(j) for j in range(k, k + 4)] == [
            fresh.foothold_roughness(j) for j in range(k, k + 4)
        ]
        _, s, remaining = kept.swing_state(t)
        if k >= 2 and 0.1 < s and remaining > 0.2 and kept.level_step(t):
            single = s + 0.5 * remaining
            period = round(t / 0.002) % 40
            if period == 0:  # a preview, and an adjustment a period later, after a sample kept what it read
                preview = kept.preview_dcm(t, (0.02, -0.01), single)
                np.testing.assert_array_equal(preview, fresh.preview_dcm(t, (0.02, -0.01), single))
            elif period == 1:
                for pattern in (kept, fresh):
                    pattern.adjust_step(t, (0.01, 0.005), single)
                adjusted += 1
    assert adjusted >= 3


@pytest.mark.parametrize("angle_deg", [6.0, 10.0])
def test_a_foothold_does_not_straddle_a_ramps_kink(angle_deg: float) -> None:
    # a sole across the top of a ramp (the ramp's slope under its heel, the level top under its toes) rocks on the
    # ridge; a line through both deviates by under a centimetre, within a level's surface tolerance: only the
    # line's own, tighter, tolerance tells the kink
    angle = math.radians(angle_deg)
    ramp = Terrain(
        (TerrainSegment("slope", 1.0, 5.0, ramps=((1.0, 2.5, 3.5, 5.0, 1.5 * math.tan(angle), -1.0, 1.0),)),)
    )
    terrain_map = _mapped(ramp)
    c = terrain_map.config
    for kink in (2.5, 3.5):
        for nominal in np.arange(kink - 0.15, kink + 0.15, 0.02):
            hold = terrain_map.place(0, float(nominal), kink - 0.4, kink + 0.4)
            heel, toe = hold.x - c.heel, hold.x + c.toe
            # the sole lies along one of the two surfaces, most of it over that surface (not pitched in between, on the
            # ridge)
            sloping = abs(hold.pitch) > 0.5 * angle
            over_ramp = (kink - heel if kink == 2.5 else toe - kink) / (toe - heel)
            share = over_ramp if sloping else 1.0 - over_ramp
            assert share >= 0.6, (kink, nominal, hold, share)
            assert abs(hold.pitch) == pytest.approx(angle if sloping else 0.0, abs=0.02), (kink, nominal, hold)

"""SSTA (monograph 5.4.2): classification, footholds and swing control points on hand-made obstacle boxes."""

from __future__ import annotations

import numpy as np
import pytest

from redundancy_gym.controllers import ControllerError
from redundancy_gym.controllers.walking import (
    GaitConfig,
    ObstacleBox,
    Quintic,
    Ssta,
    SstaConfig,
    SwingModification,
    WalkingPattern,
    bounding_boxes,
)
from redundancy_gym.controllers.walking.ssta import BLOCKED_COST
from redundancy_gym.geometry import LSS, TSS

LANES = (-0.09, 0.09)
FEET = ([0.0, -0.09, 0.0], [0.0, 0.09, 0.0])


def rectangle(x: float, width: float, height: float, depth: float, y: float = 0.0) -> list[TSS]:
    """A block as the env models it: a vertical rectangle across the path swept by half its depth."""
    r = 0.5 * depth
    p = np.array(
        [[x, y - width / 2, 0.0], [x, y + width / 2, 0.0], [x, y + width / 2, height], [x, y - width / 2, height]]
    )
    return [TSS(p[0], p[1], p[2], r), TSS(p[0], p[2], p[3], r)]


def beam() -> list[TSS]:
    return rectangle(1.28, 0.35, 0.161, 0.08)


def triangle() -> list[TSS]:
    return [TSS([1.28, -0.065, 0.0], [1.28, 0.065, 0.0], [1.28, 0.0, 0.3], 0.045)]


def pattern_with(volumes: list, config: SstaConfig | None = None) -> tuple[WalkingPattern, Ssta]:
    pattern = WalkingPattern(GaitConfig(), *FEET, [0.0, 0.0], 0.4)
    ssta = Ssta(config or SstaConfig(), LANES)
    pattern.set_obstacles(0.0, bounding_boxes(volumes), ssta)
    return pattern, ssta


def test_the_two_triangles_of_a_block_merge_into_its_swept_sphere_bounding_box():
    boxes = bounding_boxes(beam())
    assert len(boxes) == 1
    np.testing.assert_allclose(boxes[0].lower, [1.24, -0.215, -0.04])
    np.testing.assert_allclose(boxes[0].upper, [1.32, 0.215, 0.201])


def test_separate_obstacles_stay_separate_and_sorted_along_the_path():
    boxes = bounding_boxes(rectangle(3.0, 0.4, 0.1, 0.1) + [LSS([1.0, 0.3, 0.0], [1.0, 0.3, 0.3], 0.05)])
    assert [round(float(b.lower[0]), 3) for b in boxes] == [0.95, 2.95]


def test_the_monograph_beam_is_stepped_over_with_both_feet():
    decision = Ssta(lanes=LANES).classify(bounding_boxes(beam())[0])
    assert decision.classification == "step_over"
    assert decision.feet == ("over", "over")


def test_the_monograph_triangle_is_passed_by_swinging_both_feet_around_it_outwards():
    decision = Ssta(lanes=LANES).classify(bounding_boxes(triangle())[0])
    assert decision.classification == "swing_around"
    assert decision.feet == ("around", "around")
    right, left = decision.lateral
    # the sole's edge plus the margin clear the box's side: 0.11 m half-width of the box, 0.075 m of the sole
    half = SstaConfig().foot_half_width + SstaConfig().lateral_margin
    assert right == pytest.approx(-(0.11 - (0.09 - half)))
    assert left == pytest.approx(0.11 - (0.09 - half))


def test_the_smaller_feasible_modification_wins():
    # 2.5 cm into the left lane from outside (4.5 cm with the lateral margin), 20 cm high: stepping over (18 cm
    # more raise) unless the foot may move 4.5 cm inwards, towards the stance leg
    box = ObstacleBox(np.array([1.0, 0.16, 0.0]), np.array([1.1, 0.6, 0.2]))
    assert Ssta(lanes=LANES).classify(box).feet == ("beside", "over")
    decision = Ssta(SstaConfig(max_inward_shift=0.05), lanes=LANES).classify(box)
    assert decision.feet == ("beside", "around")
    half = SstaConfig().foot_half_width + SstaConfig().lateral_margin
    assert decision.lateral[1] == pytest.approx(0.16 - (0.09 + half))


def test_a_box_beside_the_path_changes_nothing():
    volumes = rectangle(1.28, 0.2, 0.3, 0.1, y=0.5)
    decision = Ssta(lanes=LANES).classify(bounding_boxes(volumes)[0])
    assert decision.classification == "beside"
    plain = WalkingPattern(GaitConfig(), *FEET, [0.0, 0.0], 0.4)
    pattern, _ = pattern_with(volumes)
    for j in range(2, 12):
        np.testing.assert_array_equal(pattern.foothold(j), plain.foothold(j))
    assert all(pattern.swing_modification(k) is None for k in range(10))


def test_a_wall_is_too_large_and_the_walk_stops_in_front_of_it():
    volumes = rectangle(1.5, 2.0, 1.0, 0.2)
    ssta = Ssta(lanes=LANES)
    box = bounding_boxes(volumes)[0]
    assert ssta.classify(box).classification == "too_large"
    pattern, _ = pattern_with(volumes)
    assert pattern.stop_index is not None
    front = ssta.foothold_band(box)[0]
    for j in range(2, 20):
        assert pattern.foothold(j)[0] <= front + 1e-12


def test_a_stop_in_front_of_a_wall_names_the_wall_as_impassable_and_its_limits():
    volumes = rectangle(1.5, 2.0, 1.0, 0.2)
    pattern, _ = pattern_with(volumes)
    reason = pattern.stop_reason
    assert reason is not None
    assert reason.foothold == pattern.stop_index
    assert reason.cause == "too_large" and reason.classification == "too_large" and reason.impassable
    np.testing.assert_array_equal(reason.box.lower, bounding_boxes(volumes)[0].lower)
    # 1.1 m (1 m and the 0.1 m swept radius) + 0.05 m clearance above the 0.3 m the leg reaches; 2 m wide, beyond
    # the line's 0.3 m shift
    assert "1.150 m > max_step_over_height 0.300" in reason.limits
    assert "sidestep: beyond max_line_shift 0.300 m" in reason.limits
    assert "too_large before foothold" in reason.describe()


def test_no_stop_has_no_reason_and_a_passable_box_reads_within_its_limits():
    pattern, ssta = pattern_with(beam())
    assert pattern.stop_index is None and pattern.stop_reason is None
    limits = ssta.limits(bounding_boxes(beam())[0])
    assert "0.251 m <= max_step_over_height 0.300" in limits  # 0.201 m + 0.05 m clearance
    assert "sidestep: beyond max_line_shift" in limits  # 0.43 m wide: over it, not beside it


def test_a_foothold_that_fits_nowhere_stops_the_walk_with_no_foothold():
    # a beam too deep for a foothold in front of it within the step limits and the stance foot right before it
    volumes = rectangle(0.5, 2.0, 0.05, 0.2)
    config = SstaConfig(max_step_length=0.3)
    pattern, ssta = pattern_with(volumes, config)
    reason = pattern.stop_reason
    assert reason is not None and pattern.stop_index is not None
    assert reason.cause == "no_foothold"
    # the beam is low enough to step over: the stop is not one the classification allows
    assert reason.classification == "step_over" and not reason.impassable


def test_a_walk_stopped_in_front_of_a_wall_stays_stopped():
    pattern, ssta = pattern_with(rectangle(1.5, 2.0, 1.0, 0.2))
    stop = pattern.stop_index
    assert stop is not None
    t = pattern.step_start(stop) + 0.1  # stepping in place
    assert not pattern.resumable(t)
    before = [pattern.foothold(j) for j in range(stop - 2, stop + 6)]
    pattern.set_obstacles(t, pattern.obstacle_boxes, ssta)
    assert pattern.stop_index == stop
    for j, h in zip(range(stop - 2, stop + 6), before, strict=True):
        np.testing.assert_array_equal(pattern.foothold(j), h)


def test_a_walk_stopped_in_front_of_a_passable_box_plans_on_from_where_its_feet_stand():
    pattern, ssta = pattern_with(rectangle(0.5, 2.0, 0.05, 0.2), SstaConfig(max_step_length=0.3))
    stop = pattern.stop_index
    assert stop is not None and pattern.stop_reason is not None and not pattern.stop_reason.impassable
    t = pattern.step_start(stop) + 0.1
    assert pattern.resumable(t)
    first = pattern.step_at(t) + 3
    begun = [pattern.foothold(j) for j in range(stop - 2, first)]  # swings begun or planned stay where they are
    # the box still blocks: the walk stops again, its feet where they stood and no step ahead of them
    pattern.set_obstacles(t, pattern.obstacle_boxes, ssta)
    assert pattern.stop_index == first and pattern.stop_reason is not None
    for j, h in zip(range(stop - 2, first), begun, strict=True):
        np.testing.assert_array_equal(pattern.foothold(j), h)
    assert all(pattern.foothold(j)[0] <= max(h[0] for h in begun) for j in range(first, first + 4))
    # mapped again beside the path (the robot's drift moves the boxes it maps): the walk goes on from its feet
    assert pattern.set_obstacles(t, bounding_boxes(rectangle(0.5, 0.4, 0.05, 0.2, y=1.0)), ssta)
    assert pattern.stop_index is None and pattern.stop_reason is None
    for j, h in zip(range(stop - 2, first), begun, strict=True):
        np.testing.assert_array_equal(pattern.foothold(j), h)
    steps = np.diff([pattern.foothold(j)[0] for j in range(first - 1, first + 6)])
    np.testing.assert_allclose(steps, pattern.step_length)  # a step ahead of the feet, then the nominal steps


def test_footholds_keep_the_margin_and_take_the_smaller_step_change():
    box = bounding_boxes(beam())[0]
    ssta = Ssta(lanes=LANES)
    low, high = ssta.foothold_band(box)
    margin = SstaConfig().foothold_margin
    assert low == pytest.approx(1.24 - margin - 0.165)
    assert high == pytest.approx(1.32 + margin + 0.095)
    # a foothold at the beam's centre: 0.205 m forward beats 0.275 m back
    assert ssta.foothold_shift([1.28, 0.09, 0.0], [0.96, -0.09, 0.0], [box]) == pytest.approx(high - 1.28)
    # forward would make a 0.705 m step (> 0.6): back it goes
    assert ssta.foothold_shift([1.28, 0.09, 0.0], [0.78, -0.09, 0.0], [box]) == pytest.approx(low - 1.28)
    # clear of the band: no move
    assert ssta.foothold_shift([0.9, 0.09, 0.0], [0.6, -0.09, 0.0], [box]) == 0.0
    # neither fits: behind the previous foothold (back) or a step longer than the limit (forward, 0.435 m)
    short = Ssta(SstaConfig(max_step_length=0.3), lanes=LANES)
    assert short.foothold_shift([1.28, 0.09, 0.0], [1.05, -0.09, 0.0], [box]) is None


@pytest.mark.parametrize("course", [beam, triangle])
def test_no_planned_sole_overlaps_the_box_and_every_step_stays_feasible(course):
    pattern, ssta = pattern_with(course())
    box = pattern.obstacle_boxes[0]
    low, high = ssta.foothold_band(box)
    config = ssta.config
    for j in range(2, 14):
        h = pattern.foothold(j)
        if ssta.in_lane(box, float(h[1])):
            assert not low + 1e-9 < h[0] < high - 1e-9, (j, h)
        step = h[0] - pattern.foothold(j - 1)[0]
        assert config.min_step_length - 1e-9 <= step <= config.max_step_length + 1e-9
    # some foothold moved next to the box: the plan hugs it
    assert any(
        abs(pattern.foothold(j)[0] - high) < 1e-9 or abs(pattern.foothold(j)[0] - low) < 1e-9 for j in range(2, 14)
    )


def _swing_samples(pattern: WalkingPattern, k: int, n: int = 400) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Swing path (x, y, z), its velocity and acceleration over step ``k``'s single support (no toe pitch)."""
    single = pattern.step_single(k)
    s = np.linspace(0.0, single, n)
    out = [pattern._swing_kinematics(k, x) for x in s]  # noqa: SLF001 (the path itself, before the toe offset)
    position = np.array([[*h[0], v[0]] for h, v in out])
    velocity = np.array([[*h[1], v[1]] for h, v in out])
    acceleration = np.array([[*h[2], v[2]] for h, v in out])
    return position, velocity, acceleration


def test_a_swing_over_the_beam_is_above_it_wherever_the_sole_is_over_it():
    pattern, ssta = pattern_with(beam())
    box = pattern.obstacle_boxes[0]
    overs = [k for k in range(8) if (m := pattern.swing_modification(k)) is not None and m.kind == "over"]
    assert len(overs) == 2  # both feet step over it
    config = ssta.config
    for k in overs:
        position, _, _ = _swing_samples(pattern, k)
        front, back = position[:, 0] + config.toe_length, position[:, 0] - config.heel_length
        above = (front > box.lower[0]) & (back < box.upper[0])
        assert above.any()
        assert np.all(position[above, 2] >= box.height + config.clearance - 1e-9)
        np.testing.assert_allclose(position[-1], pattern.foothold(k + 2), atol=1e-12)
        np.testing.assert_allclose(position[0], pattern.foothold(k), atol=1e-12)
        assert np.all(np.diff(position[:, 0]) >= -1e-12)  # forward only: no backing into the box


def test_a_swing_around_the_triangle_is_beside_it_wherever_the_sole_passes_it():
    pattern, ssta = pattern_with(triangle())
    box = pattern.obstacle_boxes[0]
    config = ssta.config
    arounds = [k for k in range(8) if (m := pattern.swing_modification(k)) is not None and m.kind == "around"]
    assert len(arounds) == 2
    for k in arounds:
        position, _, _ = _swing_samples(pattern, k)
        front, back = position[:, 0] + config.toe_length, position[:, 0] - config.heel_length
        alongside = (front > box.lower[0]) & (back < box.upper[0])
        assert alongside.any()
        inner = np.where(
            position[:, 1] > 0, position[:, 1] - config.foot_half_width, -(position[:, 1] + config.foot_half_width)
        )
        assert np.all(inner[alongside] >= box.upper[1] - 1e-9)
        np.testing.assert_allclose(position[-1], pattern.foothold(k + 2), atol=1e-12)


@pytest.mark.parametrize("course", [beam, triangle])
def test_modified_swings_are_c2(course):
    pattern, _ = pattern_with(course())
    k = next(k for k in range(8) if pattern.swing_modification(k) is not None)
    position, velocity, acceleration = _swing_samples(pattern, k, n=4000)
    single = pattern.step_single(k)
    h = single / 3999
    # finite differences agree with the analytic derivatives (no jump anywhere, the piece joints included)
    np.testing.assert_allclose(
        np.gradient(position, h, axis=0)[1:-1], velocity[1:-1], atol=5e-3 * np.abs(velocity).max()
    )
    np.testing.assert_allclose(
        np.gradient(velocity, h, axis=0)[1:-1], acceleration[1:-1], atol=2e-2 * np.abs(acceleration).max()
    )
    np.testing.assert_allclose(velocity[[0, -1]], 0.0, atol=1e-12)
    np.testing.assert_allclose(acceleration[[0, -1]], 0.0, atol=1e-9)


def test_a_slower_step_over_reschedules_the_later_steps():
    pattern, _ = pattern_with(beam(), SstaConfig(step_over_single=0.9))
    overs = [k for k in range(8) if (m := pattern.swing_modification(k)) is not None and m.kind == "over"]
    plain = WalkingPattern(GaitConfig(), *FEET, [0.0, 0.0], 0.4)
    assert [pattern.step_single(k) for k in overs] == [0.9, 0.9]
    assert pattern.step_start(overs[-1] + 1) == pytest.approx(
        plain.step_start(overs[-1] + 1) + 2 * (0.9 - plain.single_support)
    )


def test_bad_configs_and_boxes_raise_naming_the_value():
    with pytest.raises(ControllerError, match="clearance"):
        SstaConfig(clearance=-0.1)
    with pytest.raises(ControllerError, match="step_over_single"):
        SstaConfig(step_over_single=0.0)
    with pytest.raises(ControllerError, match="upper corner"):
        ObstacleBox(np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 1.0]))
    with pytest.raises(ControllerError, match="lanes"):
        Ssta(lanes=(0.1, -0.1))


def test_a_tall_post_overlapping_a_lane_from_outside_is_passed_by_moving_the_walking_line_beside_it():
    # 4 cm into the left lane from outside, 35 cm tall: no step over, no inward swing: the line moves right
    post = [LSS([2.0, 0.2, 0.0], [2.0, 0.2, 0.35], 0.04)]
    box = bounding_boxes(post)[0]
    pattern, ssta = pattern_with(post)
    decision = ssta.classify(box)
    assert decision.classification == "sidestep" and decision.line_shift < 0.0
    low, high = ssta.foothold_band(box)
    half = ssta.config.foot_half_width + ssta.config.lateral_margin
    footholds = np.array([pattern.foothold(j) for j in range(0, 24)])
    for j in range(2, 24):
        start, end = footholds[j - 2], footholds[j]
        if end[0] > low and start[0] < high:  # this swing passes the post: both of its footholds beside it
            for h in (start, end):
                assert h[1] + half <= box.lower[1] + 1e-9 or h[1] - half >= box.upper[1] - 1e-9, (j, h)
        # the stance never narrows below the nominal width: the foot on the side of the move goes first
        left, right = (footholds[j], footholds[j - 1]) if j % 2 else (footholds[j - 1], footholds[j])
        assert left[1] - right[1] >= 0.18 - 1e-9, j
    # and the line comes back after the post
    np.testing.assert_allclose(footholds[-2:, 1], [-0.09, 0.09])
    assert pattern.stop_index is None


def _posts(*posts: tuple[float, float]) -> list[LSS]:
    """Tall (0.35 m) posts of 4 cm radius at (x, y): too tall to step over."""
    return [LSS([x, y, 0.0], [x, y, 0.35], 0.04) for x, y in posts]


def _passes_beside(pattern: WalkingPattern, ssta: Ssta, n: int) -> None:
    """Every swing whose sole passes a box's band passes it beside, both footholds clear of it sideways (by the
    margin less the tolerance); the stance never narrows nor widens past ``max_widening``; the line comes back."""
    c = ssta.config
    half = c.foot_half_width + c.lateral_margin - c.line_tolerance
    footholds = np.array([pattern.foothold(j) for j in range(n)])
    for j in range(2, n):
        start, end = footholds[j - 2], footholds[j]
        for box in pattern.obstacle_boxes:
            low, high = ssta.foothold_band(box)
            if end[0] > low and start[0] < high:
                for h in (start, end):
                    assert h[1] + half <= box.lower[1] + 1e-9 or h[1] - half >= box.upper[1] - 1e-9, (j, h, box)
        left, right = (footholds[j], footholds[j - 1]) if j % 2 else (footholds[j - 1], footholds[j])
        assert 0.18 - 1e-9 <= left[1] - right[1] <= 0.18 + c.max_widening + 1e-9, j
    np.testing.assert_allclose(footholds[-2:, 1], [-0.09, 0.09])
    assert pattern.stop_index is None


def test_the_walking_line_passes_two_posts_on_opposite_sides_one_after_the_other():
    # a post in the right lane, then one in the left lane 2.2 m on: the line moves left, then right (the case that
    # the earlier per-box sidesteps planned too late, through the second post)
    pattern, ssta = pattern_with(_posts((3.0, -0.12), (5.2, 0.12)))
    _passes_beside(pattern, ssta, 34)
    offsets = [pattern.foothold(j)[1] - (-0.09 if j % 2 == 0 else 0.09) for j in range(34)]
    assert max(offsets) > 0.05 and min(offsets) < -0.05  # left past one post, right past the other


def test_a_sidestep_never_moves_a_foot_into_a_box_beside_the_path():
    # a tall block beside the right lane just before a post in the left lane: the line moves right, but only after
    # the right foot has passed the block
    block = rectangle(1.5, 0.11, 0.33, 0.22, y=-0.355)
    pattern, ssta = pattern_with([*block, *_posts((2.85, 0.15))])
    _passes_beside(pattern, ssta, 30)


def test_posts_across_the_path_block_the_line_and_say_where():
    # no offset within max_line_shift passes a row of posts 12 cm apart: the plan says which swing is blocked
    ssta = Ssta(SstaConfig(), LANES)
    boxes = bounding_boxes(_posts(*[(2.0, y) for y in np.arange(-0.6, 0.61, 0.2)]))
    h = np.array([[0.32 * max(j - 1, 0), -0.09 if j % 2 == 0 else 0.09] for j in range(24)])
    plan = ssta.plan_line(h, 0, (0.0, 0.0), boxes)
    assert plan.blocked is not None and plan.cost >= BLOCKED_COST
    j = plan.blocked + 2  # the first swing that passes the posts
    assert h[j - 2, 0] < 2.04 + 0.3 and h[j, 0] > 2.0 - 0.04 - 0.3


def test_a_line_planned_before_the_robot_drifted_is_kept_with_less_margin_rather_than_blocked():
    # the right foot stands 1.5 cm closer to a post ahead than the margin less the tolerance allows (the post was
    # mapped further off when that foothold was planned): the plan relaxes the margin instead of stopping the walk
    ssta = Ssta(SstaConfig(), LANES)
    c = ssta.config
    edge = -0.03 - (c.foot_half_width + c.lateral_margin - c.line_tolerance) + 0.015
    post = ObstacleBox([1.5, -0.3, 0.0], [1.58, edge, 0.35])
    h = np.array([[1.2 + 0.32 * (j - 1) if j else 1.2, -0.09 if j % 2 == 0 else 0.09] for j in range(20)])
    fixed = (0.06, 0.06)  # the line moved left before: the right foot at -0.03, the left at 0.15
    strict = ssta._plan_line(h, 0, fixed, [post], False, c.line_tolerance)
    assert strict.blocked == 0  # with the first tolerance alone the next right swing could not pass
    plan = ssta.plan_line(h, 0, fixed, [post])
    assert plan.blocked is None


def test_a_modified_swing_back_along_x_still_starts_and_ends_on_its_footholds():
    # a foothold moved behind the same foot's previous one (rare: moves along x for two boxes): finite durations
    pattern = WalkingPattern(GaitConfig(), *FEET, [0.0, 0.0], 0.4)
    start, end = np.array([1.0, -0.09, 0.0]), np.array([0.9, -0.09, 0.0])
    vertical, horizontal = pattern._modified_swing(
        start, end, 0.48, SwingModification("around", 0.07, -0.05, (0.8, 1.1))
    )
    xy0, v0, _ = horizontal.evaluate(0.0)
    xy1, v1, _ = horizontal.evaluate(0.48)
    np.testing.assert_allclose(xy0, start[:2], atol=1e-12)
    np.testing.assert_allclose(xy1, end[:2], atol=1e-12)
    np.testing.assert_allclose([v0, v1], 0.0, atol=1e-12)
    path = np.array([horizontal.evaluate(t)[0] for t in np.linspace(0.0, 0.48, 49)])
    assert np.all(np.isfinite(path)) and path[:, 1].min() == pytest.approx(-0.14, abs=0.01)


def test_a_line_that_cannot_keep_the_stance_limits_from_its_fixed_footholds_says_it_is_blocked():
    # the fixed right foot 0.3 m left of its lane and the left foot 0.3 m right of its own (crossed): every next
    # foothold narrows or over-widens the stance, so no plan keeps the limits
    ssta = Ssta(SstaConfig(), LANES)
    h = np.array([[0.32 * j, -0.09 if j % 2 == 0 else 0.09] for j in range(10)])
    plan = ssta.plan_line(h, 0, (0.3, -0.3), _posts_boxes())
    assert plan.blocked == 0 and not np.isfinite(plan.cost)


def _posts_boxes() -> list[ObstacleBox]:
    return list(bounding_boxes(_posts((2.0, 0.3))))


@pytest.mark.parametrize("course", [lambda: [], beam, triangle])
def test_every_swing_comes_straight_down_onto_its_foothold(course):
    # the horizontal motion ends before the landing (GaitConfig.swing_settle): a foot that touches down a little
    # early lands on its foothold instead of short of it while still moving forward (it kicked the stance foot
    # back onto a box); a modified swing keeps at least half its last piece for that
    pattern, _ = pattern_with(course())
    settle = pattern.config.swing_settle
    assert settle > 0.0
    for k in range(8):
        single = pattern.step_single(k)
        nominal = pattern.swing_modification(k) is None
        still = (1.0 if nominal else 0.5) * settle * single
        for s in np.linspace(single - still, single, 25):
            (xy, vxy, _), (z, _, _) = pattern._swing_kinematics(k, s)  # noqa: SLF001
            np.testing.assert_allclose(xy, pattern.foothold(k + 2)[:2], atol=1e-12)
            np.testing.assert_allclose(vxy, 0.0, atol=1e-12)
            assert s == single or z > pattern.ground
        # before it the sole still moves along x
        (xy, _, _), _ = pattern._swing_kinematics(k, 0.5 * single)  # noqa: SLF001
        assert xy[0] < pattern.foothold(k + 2)[0] - 1e-3


def test_a_long_swing_is_slowed_to_the_mean_speed_of_the_longest_nominal_one():
    # around the triangle a foothold moves back in front of it: the next swing of that foot covers 0.85 m
    pattern, ssta = pattern_with(triangle())
    plain = WalkingPattern(GaitConfig(), *FEET, [0.0, 0.0], 0.4)
    longest, single = ssta.config.long_swing, plain.single_support
    slowed = 0
    for k in range(12):
        travel = float(np.hypot(*(pattern.foothold(k + 2) - pattern.foothold(k))[:2]))
        if travel > longest:
            assert pattern.step_single(k) == pytest.approx(single * travel / longest)
            slowed += 1
        else:
            assert pattern.step_single(k) == single
        # the later steps start later by the longer single supports before them
        assert pattern.step_start(k + 1) - pattern.step_start(k) == pytest.approx(
            plain.step_duration - single + pattern.step_single(k)
        )
    assert slowed == 2
    never = pattern_with(triangle(), SstaConfig(long_swing=None))[0]
    assert all(never.step_single(k) == single for k in range(12))


def test_a_swing_over_a_box_pitches_its_toes_down_with_its_height_and_its_toe_tip_keeps_to_the_path():
    pattern, ssta = pattern_with(beam())
    gain = ssta.config.raise_pitch
    k = next(k for k in range(8) if (m := pattern.swing_modification(k)) is not None and m.kind == "over")
    side = k % 2
    plain = WalkingPattern(GaitConfig(), *FEET, [0.0, 0.0], 0.4)
    toe = pattern.config.toe_length
    start, single = pattern.step_start(k), pattern.step_single(k)
    times = start + np.linspace(0.01, 0.99, 99) * single
    angles, rates = [], []
    for t in times:
        sample = pattern.sample(float(t))
        (_, _, _), (z, _, _) = pattern._swing_kinematics(k, t - start)  # noqa: SLF001
        angle = float(sample.feet_pitch[side])
        nominal = float(plain._swing_pitch.evaluate((t - start) * plain.single_support / single)[0])  # noqa: SLF001
        assert angle == pytest.approx(nominal + gain * (float(z) - pattern.ground), abs=1e-9)
        # the toe tip (the sole point turned back about it) is on the swing path
        assert float(sample.feet[side][2]) - toe * np.sin(angle) == pytest.approx(float(z), abs=1e-9)
        angles.append(angle)
        rates.append(float(sample.feet_pitch_rate[side]))
    top = pattern.swing_modification(k).height
    assert max(angles) >= gain * top
    # the rate is the angle's derivative (the height term included)
    np.testing.assert_allclose(np.gradient(angles, times)[1:-1], np.array(rates)[1:-1], atol=0.02 * max(np.abs(rates)))


def _staggered_posts() -> tuple[np.ndarray, list[ObstacleBox]]:
    """The footholds and boxes (plan frame) of a random course where the line, moved right past a post on the
    left, must move left before a post on the right 1.4 m on: the right foot's last chance to move lands 0.25 m
    in front of the second post."""
    h = np.array(
        [
            [8.645, 0.09],
            [8.965, -0.09],
            [9.285, 0.09],
            [9.437, -0.09],
            [9.757, 0.09],
            [10.077, -0.09],
            [10.397, 0.09],
            [10.717, -0.09],
            [11.037, 0.09],
            [11.357, -0.09],
        ]
    )
    boxes = [
        ObstacleBox(np.array([8.268, 0.107, -0.044]), np.array([8.356, 0.196, 0.354])),
        ObstacleBox(np.array([9.687, -0.296, -0.043]), np.array([9.774, -0.136, 0.42])),
    ]
    return h, boxes


def test_a_line_move_close_in_front_of_a_post_is_taken_rather_than_stopping_the_walk():
    ssta = Ssta(SstaConfig(), LANES)
    c = ssta.config
    h, boxes = _staggered_posts()
    fixed = (-0.09, -0.09)
    # with the full distance along x kept by moving swings, even the whole margin relaxed blocks it
    assert ssta._plan_line(h, 1, fixed, boxes, False, c.lateral_margin).blocked is not None  # noqa: SLF001
    plan = ssta.plan_line(h, 1, fixed, boxes)
    assert plan.blocked is None
    offsets = np.concatenate([fixed, plan.offsets])
    y = h[:, 1] + offsets
    half = c.foot_half_width
    for j in range(2, len(h)):
        for box in boxes:
            low = float(box.lower[0]) - c.toe_length
            high = float(box.upper[0]) + c.heel_length
            if h[j, 0] > low and h[j - 2, 0] < high:  # this swing passes the box: beside it, not moving
                assert y[j] == y[j - 2]
                assert y[j] + half <= box.lower[1] or y[j] - half >= box.upper[1], (j, y[j], box)


def test_the_line_moves_a_centimetre_rather_than_leave_a_foothold_where_no_move_along_x_fits():
    # a tall block beside the right lane, 9 mm into its margin; the right foothold in front of it can move
    # neither back (behind the left foot) nor forward (a 0.62 m step)
    block = ObstacleBox(np.array([2.716, -0.453, 0.0]), np.array([3.114, -0.191, 0.363]))
    h = np.array(
        [
            [2.022, 0.09],
            [2.342, -0.09],
            [2.662, 0.09],
            [2.982, -0.09],
            [3.302, 0.09],
            [3.622, -0.09],
            [3.942, 0.09],
            [4.262, -0.09],
            [4.582, 0.09],
            [4.902, -0.09],
        ]
    )
    ssta = Ssta(SstaConfig(), LANES)
    assert ssta.foothold_shift(h[3], h[2], [block], behind=float(h[1, 0])) is None
    plan = ssta.plan_line(h, 1, (0.0, 0.0), [block])
    assert plan.blocked is None
    y = h[3, 1] + plan.offsets[1]
    assert not ssta.in_lane(block, float(y)) and 0.0 < y - h[3, 1] <= 0.015
    stuck = ssta._plan_line(h, 1, (0.0, 0.0), [block], False, ssta.config.line_tolerance)  # noqa: SLF001
    assert stuck.offsets[1] == plan.offsets[1]
    free = Ssta(SstaConfig(stuck_cost=0.0), LANES).plan_line(h, 1, (0.0, 0.0), [block])
    assert free.offsets[1] == 0.0  # without the cost the line stays and the walk would stop


def test_a_swing_the_line_passes_with_less_margin_still_goes_around_its_box():
    # the line was planned with the margin relaxed (the robot's drift): with the full margin no shift clears the
    # post, so the swing takes the smallest one that does instead of going straight through it
    ssta = Ssta(SstaConfig(), LANES)
    post = ObstacleBox(np.array([6.52, -0.23, -0.04]), np.array([6.60, -0.07, 0.3]))
    modification = ssta.swing([6.3, -0.185, 0.0], [7.1, -0.185, 0.0], 0, [post])
    assert modification is not None and modification.kind == "around"
    c = ssta.config
    assert -0.185 + modification.lateral + c.foot_half_width <= float(post.lower[1]) + 1e-9
    assert abs(modification.lateral) <= c.max_outward_shift


def test_a_swing_just_begun_is_replanned_around_boxes_mapped_again():
    # the controller samples a new step before it maps the obstacles again: that swing's path must follow
    pattern = WalkingPattern(GaitConfig(), *FEET, [0.0, 0.0], 0.4)
    ssta = Ssta(SstaConfig(), LANES)
    pattern.set_obstacles(0.0, (), ssta)
    k = 4
    t = pattern.step_start(k)
    pattern.sample(t)  # the swing's path is planned (and cached) without obstacles
    assert pattern.swing_modification(k) is None
    x = 0.5 * float(pattern.foothold(k)[0] + pattern.foothold(k + 2)[0])
    beam_here = bounding_boxes(rectangle(x, 0.35, 0.05, 0.04))
    pattern.set_obstacles(t, beam_here, ssta)
    pattern.sample(t)
    assert pattern.swing_modification(k) is not None and pattern.swing_modification(k).kind == "over"
    # a swing well under way keeps its path
    later = pattern.step_start(k + 1) + 0.2
    pattern.sample(later)
    before = pattern.swing_modification(k + 1)
    pattern.set_obstacles(later, beam_here + bounding_boxes(rectangle(x + 0.32, 0.35, 0.05, 0.04)), ssta)
    assert pattern.swing_modification(k + 1) == before


def test_a_swing_around_a_box_keeps_the_nominal_progress_along_x():
    # the shift is added to the nominal path: the sole never stalls along x and then rushes to its landing
    pattern, _ = pattern_with(triangle())
    arounds = [k for k in range(8) if (m := pattern.swing_modification(k)) is not None and m.kind == "around"]
    assert arounds
    settle = pattern.config.swing_settle
    for k in arounds:
        single = pattern.step_single(k)
        nominal = Quintic.from_boundary(single * (1.0 - settle), pattern.foothold(k)[:2], pattern.foothold(k + 2)[:2])
        for s in np.linspace(0.0, single, 60):
            (xy, vxy, _), _ = pattern._swing_kinematics(k, s)  # noqa: SLF001
            x, vx, _ = nominal.evaluate(s)
            assert xy[0] == pytest.approx(float(x[0]), abs=1e-9) and vxy[0] == pytest.approx(float(vx[0]), abs=1e-9)


def test_a_swing_never_keeps_a_post_higher_than_the_straddle_height_between_the_legs():
    # a post overlapping the right lane from the inside: the right foot could only pass it shifted outwards, the
    # post between the legs, where the shank or knee passes over its top
    ssta = Ssta(SstaConfig(), LANES)
    c = ssta.config
    tall = bounding_boxes([LSS([2.0, -0.02, 0.0], [2.0, -0.02, 0.36], 0.03)])[0]
    low = bounding_boxes([LSS([2.0, -0.02, 0.0], [2.0, -0.02, 0.28], 0.03)])[0]
    assert tall.height > c.straddle_height >= low.height
    decision, shift, _ = ssta._swing_decision(tall, -0.09, 0)  # noqa: SLF001
    assert decision == "around" and shift < 0.0  # outwards
    assert ssta.swing_cost(tall, -0.09, 0) >= BLOCKED_COST
    assert ssta.swing_cost(low, -0.09, 0) < BLOCKED_COST
    # the monograph's triangle (0.345 m with its radius) is still passed with both feet around it
    pattern, _ = pattern_with(triangle())
    assert [m.kind for k in range(8) if (m := pattern.swing_modification(k)) is not None] == ["around", "around"]
    # the walking line moves so that neither foot keeps the tall post between the legs
    pattern, ssta = pattern_with([LSS([2.0, -0.02, 0.0], [2.0, -0.02, 0.36], 0.03)])
    assert pattern.stop_index is None
    footholds = [pattern.foothold(j) for j in range(24)]
    for j in range(2, 24):
        start, end = footholds[j - 2], footholds[j]
        low_x, high_x = ssta.foothold_band(tall)
        if end[0] > low_x and start[0] < high_x:
            m = ssta.swing(start, end, j % 2, [tall])
            assert m is None or m.kind != "around" or (m.lateral > 0.0) != (j % 2 == 1)


def test_the_line_never_keeps_a_tall_post_between_the_feet_either():
    # a 0.4 m post between the lanes: passing with one foot on each side (the stance widened around it) is as
    # blocked as a swing shifted outwards around it; both feet pass on one side
    # (the stance starts widened by 0.16 m: without the rule both feet would walk on past it, one on each side)
    ssta = Ssta(SstaConfig(), LANES)
    post = bounding_boxes([LSS([3.0, 0.0, 0.0], [3.0, 0.0, 0.36], 0.04)])[0]
    h = np.array([[0.32 * max(j - 1, 0), -0.09 if j % 2 == 0 else 0.09] for j in range(20)])
    fixed = (-0.08, 0.08)
    plan = ssta.plan_line(h, 0, fixed, [post])
    assert plan.blocked is None
    y = h[:, 1] + np.concatenate([fixed, plan.offsets])
    low, high = ssta.foothold_band(post)
    passing = [j for j in range(2, 20) if h[j, 0] > low and h[j - 2, 0] < high]
    assert passing
    half = ssta.config.foot_half_width
    for j in passing:
        right, left = (y[j], y[j - 1]) if j % 2 == 0 else (y[j - 1], y[j])
        assert not (right + half <= post.lower[1] and left - half >= post.upper[1]), (j, right, left)
    # a lower post may stay between the feet (the monograph's triangle is passed so)
    short = bounding_boxes([LSS([2.0, 0.0, 0.0], [2.0, 0.0, 0.25], 0.04)])[0]
    kept = ssta.plan_line(h, 0, fixed, [short])
    assert kept.blocked is None and np.allclose(kept.offsets[:8], np.tile(fixed, 4))


def test_a_past_swing_reports_the_modification_it_was_walked_with():
    # after the steps past the triangle, the boxes are mapped again 0.3 m further on (the robot's drift): the
    # swings already walked keep their record instead of being planned again around the moved box
    pattern, ssta = pattern_with(triangle())
    walked = {k: pattern.swing_modification(k) for k in range(6)}
    assert walked[2] is None and walked[3] is not None
    t = pattern.step_start(6) + 0.1
    pattern.sample(t)
    moved = bounding_boxes([TSS([0.98, -0.065, 0.0], [0.98, 0.065, 0.0], [0.98, 0.0, 0.3], 0.045)])
    pattern.set_obstacles(t, moved, ssta)
    pattern.sample(t)
    assert {k: pattern.swing_modification(k) for k in range(6)} == walked


def test_in_band_is_a_sole_point_in_the_band_of_a_box_in_its_lane():
    ssta = Ssta(SstaConfig(), LANES)
    box = bounding_boxes(beam())[0]
    low, high = ssta.foothold_band(box)
    assert ssta.in_band(0.5 * (low + high), 0.09, [box])
    assert not ssta.in_band(low - 1e-3, 0.09, [box]) and not ssta.in_band(high + 1e-3, 0.09, [box])
    assert not ssta.in_band(0.5 * (low + high), 0.5, [box])  # beside the beam
    assert not ssta.in_band(0.5 * (low + high), 0.09, [])

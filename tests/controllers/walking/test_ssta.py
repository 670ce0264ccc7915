"""SSTA (monograph 5.4.2): classification, footholds and swing control points on hand-made obstacle boxes."""

from __future__ import annotations

import numpy as np
import pytest

from redundancy_gym.controllers import ControllerError
from redundancy_gym.controllers.walking.ssta import BLOCKED_COST
from redundancy_gym.controllers.walking import (
    GaitConfig,
    ObstacleBox,
    Ssta,
    SstaConfig,
    SwingModification,
    WalkingPattern,
    bounding_boxes,
)
from redundancy_gym.geometry import LSS, TSS

LANES = (-0.09, 0.09)
FEET = ([0.0, -0.09, 0.0], [0.0, 0.09, 0.0])


def rectangle(x: float, width: float, height: float, depth: float, y: float = 0.0) -> list[TSS]:
    """A block as the env models it: a vertical rectangle across the path swept by half its depth."""
    r = 0.5 * depth
    p = np.array([[x, y - width / 2, 0.0], [x, y + width / 2, 0.0], [x, y + width / 2, height], [x, y - width / 2, height]])
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
    assert any(abs(pattern.foothold(j)[0] - high) < 1e-9 or abs(pattern.foothold(j)[0] - low) < 1e-9
               for j in range(2, 14))


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
        inner = np.where(position[:, 1] > 0, position[:, 1] - config.foot_half_width,
                         -(position[:, 1] + config.foot_half_width))
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
    np.testing.assert_allclose(np.gradient(position, h, axis=0)[1:-1], velocity[1:-1], atol=5e-3 * np.abs(velocity).max())
    np.testing.assert_allclose(np.gradient(velocity, h, axis=0)[1:-1], acceleration[1:-1],
                               atol=2e-2 * np.abs(acceleration).max())
    np.testing.assert_allclose(velocity[[0, -1]], 0.0, atol=1e-12)
    np.testing.assert_allclose(acceleration[[0, -1]], 0.0, atol=1e-9)


def test_a_slower_step_over_reschedules_the_later_steps():
    pattern, _ = pattern_with(beam(), SstaConfig(step_over_single=0.9))
    overs = [k for k in range(8) if (m := pattern.swing_modification(k)) is not None and m.kind == "over"]
    plain = WalkingPattern(GaitConfig(), *FEET, [0.0, 0.0], 0.4)
    assert [pattern.step_single(k) for k in overs] == [0.9, 0.9]
    assert pattern.step_start(overs[-1] + 1) == pytest.approx(plain.step_start(overs[-1] + 1) + 2 * (0.9 - plain.single_support))


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
    vertical, horizontal = pattern._modified_swing(start, end, 0.48, SwingModification("around", 0.07, -0.05, (0.8, 1.1)))
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

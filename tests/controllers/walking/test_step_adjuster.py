"""Push recovery by stepping: ``WalkingPattern.adjust_step`` / ``preview_dcm`` and ``StepAdjuster``."""

from __future__ import annotations

import dataclasses

import gymnasium as gym
import numpy as np
import pytest

import redundancy_gym  # noqa: F401  (registers the envs)
from redundancy_gym import make_policy
from redundancy_gym.controllers import ControllerError
from redundancy_gym.controllers.walking import DcmPlanner, GaitConfig, StepAdjuster, StepAdjusterConfig, WalkingPattern

FEET = ([0.025, -0.09, 0.0], [0.025, 0.09, 0.0])


def pattern_in_swing(speed: float = 0.5, t: float = 2.1) -> tuple[WalkingPattern, float]:
    """A pattern sampled up to ``t`` (step 2, the right foot 0.1 s into its swing at 0.5 m/s)."""
    pattern = WalkingPattern(GaitConfig(), FEET[0], FEET[1], [0.025, 0.0], speed)
    for s in np.arange(0.0, t, 0.004):
        pattern.sample(float(s))
    return pattern, t


def test_first_dcm_equals_the_backward_recursion() -> None:
    planner = DcmPlanner(0.91)
    rng = np.random.default_rng(3)
    times = np.cumsum(rng.uniform(0.02, 0.6, 60))
    zmp = rng.normal(size=(60, 2))
    np.testing.assert_allclose(planner.first_dcm(times, zmp), planner.dcm_at_knots(times, zmp)[0], atol=1e-12)


def test_preview_dcm_is_affine_in_the_shift_with_one_gain_for_x_and_y() -> None:
    pattern, t = pattern_in_swing()
    single = pattern.step_single(2)
    base = pattern.preview_dcm(t, [0.0, 0.0], single)
    a, b = np.array([0.1, -0.05]), np.array([-0.03, 0.2])
    da = pattern.preview_dcm(t, a, single) - base
    db = pattern.preview_dcm(t, b, single) - base
    np.testing.assert_allclose(pattern.preview_dcm(t, a + b, single) - base, da + db, atol=1e-12)
    gain = pattern.preview_dcm(t, [1.0, 1.0], single) - base
    assert gain[0] == pytest.approx(gain[1], rel=1e-9) and 0.0 < gain[0] < 1.0
    np.testing.assert_allclose(pattern.preview_dcm(t, [0.0, 0.0], single), pattern.dcm(t), atol=1e-12)  # no change


def test_adjust_step_replans_to_the_previewed_dcm_keeping_the_references_continuous() -> None:
    pattern, t = pattern_in_swing()
    before = pattern.sample(t)
    shift, single = np.array([0.12, -0.08]), pattern.step_single(2) - 0.1
    expected = pattern.preview_dcm(t, shift, single)
    landing = pattern.foothold(4) + [shift[0], shift[1], 0.0]
    pattern.adjust_step(t, shift, single)
    after = pattern.sample(t)
    np.testing.assert_allclose(after.dcm, expected, atol=1e-12)
    np.testing.assert_allclose(after.com, before.com, atol=1e-12)  # the CoM reference does not jump
    np.testing.assert_allclose(after.feet, before.feet, atol=1e-12)  # nor does the swing foot
    # the swing path's velocity is continuous; only the re-timed toes-down pitch rate changes, and the sole point
    # (turning about the toe tip) with it: its velocity jumps by exactly toe_length x the pitch rate's jump
    jump = np.linalg.norm(after.feet_velocity[0] - before.feet_velocity[0])
    rate_jump = abs(after.feet_pitch_rate[0] - before.feet_pitch_rate[0])
    assert jump == pytest.approx(GaitConfig().toe_length * rate_jump, abs=1e-12)
    np.testing.assert_allclose(pattern.foothold(4), landing, atol=1e-15)
    np.testing.assert_allclose(pattern.foothold(6)[:2] - pattern.foothold(4)[:2], [0.8, 0.0], atol=1e-12)
    touchdown = pattern.step_start(2) + single
    assert pattern.step_start(3) == pytest.approx(touchdown + 0.2 * 0.8)  # the double support keeps its length
    down = pattern.sample(touchdown + 1e-9)
    np.testing.assert_allclose(down.feet[0], landing, atol=1e-6)
    assert down.contact == (True, True)
    # the swing stays above the ground and reaches its landing from above
    for s in np.linspace(t, touchdown, 40):
        sample = pattern.sample(float(s))
        assert sample.feet[0, 2] >= -1e-12


def test_adjust_step_rejects_what_it_cannot_do() -> None:
    pattern, t = pattern_in_swing()
    single = pattern.step_single(2)
    with pytest.raises(ControllerError, match="single"):
        pattern.adjust_step(t, [0.0, 0.0], t - pattern.step_start(2))  # touchdown now
    with pytest.raises(ControllerError, match="shift"):
        pattern.adjust_step(t, [np.nan, 0.0], single)
    with pytest.raises(ControllerError, match="shift"):
        pattern.adjust_step(t, [3.0, 0.0], single)
    with pytest.raises(ControllerError, match="single support"):
        pattern.adjust_step(pattern.step_start(2) + single + 0.05, [0.0, 0.0], single)  # double support


def test_undisturbed_walking_is_not_adjusted() -> None:
    pattern, t = pattern_in_swing()
    adjuster = StepAdjuster()
    for s in np.arange(t, 6.0, 0.004):
        assert adjuster.update(pattern, float(s), pattern.sample(float(s)).dcm + [0.03, -0.02]) is None


def test_an_error_beyond_the_ankle_margin_is_stepped_out_inside_the_box() -> None:
    config = StepAdjusterConfig(error_filter=0.0)
    for error, axis in (([0.0, -0.1], 1), ([0.15, 0.0], 0)):
        pattern, t = pattern_in_swing()
        adjuster = StepAdjuster(config)
        planned = pattern.sample(t).dcm
        nominal = pattern.foothold(4)
        adjustment = adjuster.update(pattern, t, planned + error)
        assert adjustment is not None and adjustment.step == 2
        landing, stance = pattern.foothold(4), pattern.foothold(3)
        assert np.sign(landing[axis] - nominal[axis]) == np.sign(error[axis])  # steps where it is pushed
        assert config.min_width <= stance[1] - landing[1] <= config.max_width
        assert -config.max_backward <= landing[0] - stance[0] <= config.max_forward
        if not adjustment.clipped:  # the plan then leaves exactly ankle_share of the margin on the pushed axis
            left = planned + error - pattern.sample(t).dcm
            assert abs(left[axis]) == pytest.approx(config.ankle_share * config.ankle_margin[axis], abs=1e-9)


def test_a_push_towards_the_stance_foot_is_clipped_at_the_narrowest_step() -> None:
    """The right foot swings; a DCM far to the left (over the left stance foot) cannot be caught by crossing: the
    landing moves towards the stance foot but stays beside it."""
    config = StepAdjusterConfig(error_filter=0.0)
    pattern, t = pattern_in_swing()
    nominal_width = pattern.foothold(3)[1] - pattern.foothold(4)[1]
    adjustment = StepAdjuster(config).update(pattern, t, pattern.sample(t).dcm + [0.0, 0.3])
    assert adjustment is not None and adjustment.clipped
    assert config.min_width - 1e-12 <= pattern.foothold(3)[1] - pattern.foothold(4)[1] < nominal_width


def test_disabled_adjuster_never_adjusts() -> None:
    pattern, t = pattern_in_swing()
    assert StepAdjuster(StepAdjusterConfig(enabled=False)).update(pattern, t, pattern.dcm(t) + [0.5, 0.5]) is None


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"ankle_margin": (0.06, -0.1)}, "ankle_margin"),
        ({"ankle_share": 1.5}, "ankle_share"),
        ({"min_width": 0.5}, "min_width"),
        ({"max_forward": float("nan")}, "max_forward"),
        ({"timing_candidates": 0}, "timing_candidates"),
        ({"enabled": "yes"}, "enabled"),
    ],
)
def test_config_rejects_bad_values(kwargs: dict, match: str) -> None:
    with pytest.raises(ControllerError, match=match):
        StepAdjusterConfig(**kwargs)


def test_non_finite_dcm_raises() -> None:
    pattern, t = pattern_in_swing()
    with pytest.raises(ControllerError, match="DCM"):
        StepAdjuster().update(pattern, t, [np.nan, 0.0])


@pytest.mark.parametrize(
    "force, start",
    [((0.0, -150.0, 0.0), 2.36), ((0.0, 150.0, 0.0), 3.0)],
    ids=["right-foot-swinging-pushed-right", "left-foot-swinging-pushed-left"],
)
def test_a_15_Ns_lateral_push_towards_the_swing_side_is_recovered_by_stepping(force, start) -> None:
    """BipedWalk at 0.5 m/s, a 0.1 s push on the torso towards the swinging foot's side: the walker steps out and
    stands, where without step adjustment (ankle and hip strategy only) it falls."""
    outcomes = {}
    for push_recovery in (True, False):
        env = gym.make(
            "redundancy_gym/BipedWalk-v0",
            target_speed=0.5,
            push=[{"time": start, "force": list(force), "duration": 0.1}],
        )
        policy = make_policy("walking", env, push_recovery=push_recovery)
        obs, _ = env.reset(seed=0)
        adjusted, fell = 0, False
        for _ in range(int((start + 2.5) / env.unwrapped.dt)):
            action, _ = policy.predict(obs, deterministic=True)
            obs, _, terminated, _, _ = env.step(action)
            adjusted += policy.last_command.adjustment is not None
            if terminated:
                fell = True
                break
        outcomes[push_recovery] = (fell, adjusted)
        env.close()
    assert outcomes[True] == (False, outcomes[True][1]) and outcomes[True][1] > 0
    assert outcomes[False] == (True, 0)


def test_config_is_a_frozen_dataclass() -> None:
    config = StepAdjusterConfig()
    with pytest.raises(dataclasses.FrozenInstanceError):
        config.enabled = False  # type: ignore[misc]

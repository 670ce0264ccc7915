"""Fuzz the walking pattern's pieces: ``GaitConfig``, ``DcmPlanner`` (constructor, ``plan``, ``sample``) and
``WalkingPattern`` (constructor, ``sample`` over time and step adjustments) with numbers, sane, extreme and
hostile, and with values that are no numbers: a valid, finite result or ControllerError."""

from __future__ import annotations

from dataclasses import fields

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from redundancy_gym.controllers import ControllerError
from redundancy_gym.controllers.walking import DcmPlanner, GaitConfig, StepAdjuster, WalkingPattern

from .strategies import ANY_FLOATS, vectors

DEFAULTS = {f.name: f.default for f in fields(GaitConfig)}
FEET = ([0.025, -0.09, 0.0], [0.025, 0.09, 0.0])


# any float at all: positive magnitudes far from the physical ones (com_height 1e300 or 1e-94, gravity 1e-270)
# must be rejected or give finite plans
EXTREME = st.one_of(ANY_FLOATS, st.floats(allow_nan=False, allow_infinity=False))
NO_NUMBERS = st.sampled_from(["0.8", None, True, [0.8], {"value": 0.8}])
HOSTILE = st.one_of(st.floats(max_value=0.0), st.sampled_from([float("nan"), float("inf"), -float("inf")]))


def numbers_like(value) -> st.SearchStrategy:
    """Numbers around the default (scaled, negated, zero) and hostile ones (NaN, inf, <= 0)."""
    if isinstance(value, int):  # (a preview of 10^6 steps is valid but plans 10^6 steps at every step: slow)
        return st.one_of(st.integers(-2, 12), st.just(0))
    # positive values from a tenth of the default up (a 1 ms step is valid but takes 10^4 replans per 10 s)
    return st.one_of(
        st.floats(0.1 * abs(value), 3.0 * abs(value) + 0.1), st.floats(-abs(value) - 1.0, 0.0), HOSTILE, NO_NUMBERS
    )


CONFIGS = st.lists(st.sampled_from(sorted(DEFAULTS)), max_size=4, unique=True).flatmap(
    lambda keys: st.fixed_dictionaries({k: numbers_like(DEFAULTS[k]) for k in keys})
)


@given(kwargs=CONFIGS, speed=st.one_of(st.floats(0.0, 2.0), ANY_FLOATS))
def test_gait_config_is_valid_or_raises(kwargs, speed) -> None:
    try:
        config = GaitConfig(**kwargs)
    except ControllerError:
        return
    assert 0.0 < config.double_support_ratio < 1.0 and config.min_step_duration <= config.step_duration
    try:
        length, duration = config.timing(speed)
    except ControllerError:
        return
    assert 0.0 <= length <= config.max_step_length
    assert config.min_step_duration <= duration <= config.step_duration


def knots() -> st.SearchStrategy:
    """Strictly increasing knot times (sane gaps, or tiny / long ones) with a ZMP of one point each."""
    gaps = st.lists(st.one_of(st.floats(0.05, 1.0), st.sampled_from([1e-9, 1e-3, 5.0, 30.0])), min_size=1, max_size=8)
    return gaps.flatmap(
        lambda g: st.tuples(
            st.just(np.concatenate([[0.0], np.cumsum(g)])),
            st.lists(vectors(2, st.floats(-1.0, 1.0)), min_size=len(g) + 1, max_size=len(g) + 1).map(np.array),
        )
    )


GRAVITY = st.one_of(st.just(9.81), st.floats(0.1, 100.0), EXTREME, NO_NUMBERS)


@given(
    height=st.one_of(st.floats(0.1, 2.0), HOSTILE, EXTREME, NO_NUMBERS),
    gravity=GRAVITY,
    plan=knots(),
    com=vectors(2, st.floats(-1.0, 1.0)),
    probes=st.lists(st.floats(0.0, 1e6), max_size=5),
)
def test_dcm_plan_is_finite_and_ends_at_rest_or_raises(height, gravity, plan, com, probes) -> None:
    try:
        planner = DcmPlanner(height, gravity)
    except ControllerError:
        return
    times, zmp = plan
    result = planner.plan(times, zmp, com)
    assert np.all(np.isfinite(result.dcm)) and np.all(np.isfinite(result.com))
    np.testing.assert_allclose(result.dcm[-1], zmp[-1], atol=1e-12)
    np.testing.assert_array_equal(result.com[0], com)
    for t in probes:
        state = result.sample(t)
        for v in (state.position, state.velocity, state.acceleration, state.dcm, state.zmp):
            assert np.all(np.isfinite(v)), (t, v)
    try:
        start = planner.start_zmp(times, zmp, com)
    except ControllerError:
        return
    assert np.all(np.isfinite(start))
    np.testing.assert_allclose(planner.dcm_at_knots(times, start)[0], com, atol=1e-6 * (1.0 + np.abs(start).max()))


@given(
    kwargs=CONFIGS,
    speed=st.one_of(st.floats(0.0, 1.5), ANY_FLOATS),
    com=st.one_of(vectors(2, st.floats(-0.05, 0.1)), vectors(2, ANY_FLOATS)),
    steps=st.lists(st.floats(0.0, 0.5), min_size=1, max_size=12),
)
def test_walking_pattern_is_finite_over_time_or_raises(kwargs, speed, com, steps) -> None:
    try:
        pattern = WalkingPattern(GaitConfig(**kwargs), FEET[0], FEET[1], com, speed)
    except ControllerError:
        return
    t = 0.0
    for dt in steps:  # non-decreasing times, as the controller samples
        t += dt
        s = pattern.sample(t)
        for v in (s.com, s.com_velocity, s.zmp, s.dcm, s.feet, s.feet_velocity, s.feet_pitch):
            assert np.all(np.isfinite(v)), (t, v)
        assert 0.0 <= s.right_load <= 1.0 and s.step >= -1
        assert s.feet[:, 2].min() >= pattern.ground - 1e-9


@given(
    speed=st.floats(0.0, 1.0),
    start=st.floats(0.4, 3.0),
    adjustments=st.lists(
        st.tuples(
            st.floats(0.0, 0.3),
            st.one_of(vectors(2, st.floats(-0.5, 0.5)), vectors(2, ANY_FLOATS)),
            st.one_of(st.floats(-0.2, 1.5), ANY_FLOATS),
        ),
        max_size=4,
    ),
)
def test_step_adjustments_keep_the_pattern_finite_or_raise(speed, start, adjustments) -> None:
    """``adjust_step`` with any shift and timing, at any time: ControllerError, or a pattern that stays finite, keeps
    the swing foot's reference continuous and lands it on the adjusted foothold."""
    pattern = WalkingPattern(GaitConfig(), FEET[0], FEET[1], [0.0, 0.0], speed)
    t = start
    pattern.sample(t)
    for wait, shift, single_offset in adjustments:
        t += wait
        before = pattern.sample(t)
        k, s, _ = pattern.swing_state(t)
        try:
            pattern.adjust_step(t, shift, s + single_offset)
        except ControllerError:
            continue
        after = pattern.sample(t)
        np.testing.assert_allclose(after.feet, before.feet, atol=1e-9)
        np.testing.assert_allclose(after.com, before.com, atol=1e-9)
        landing = pattern.foothold(k + 2)
        touchdown = pattern.step_start(k) + pattern.step_single(k)
        sample = pattern.sample(touchdown + 1e-6)
        np.testing.assert_allclose(sample.feet[(k + 2) % 2], landing, atol=1e-6)
        t = touchdown + 1e-6
        for v in (sample.com, sample.com_velocity, sample.dcm, sample.feet):
            assert np.all(np.isfinite(v))


@given(
    speed=st.floats(0.0, 1.0),
    start=st.floats(0.4, 3.0),
    errors=st.lists(
        st.tuples(st.floats(0.0, 0.2), st.one_of(vectors(2, st.floats(-1.0, 1.0)), vectors(2, ANY_FLOATS))),
        min_size=1,
        max_size=6,
    ),
)
def test_step_adjuster_keeps_the_pattern_finite_or_raises(speed, start, errors) -> None:
    """The step adjuster fed any measured DCM: ControllerError for a non-finite one, else a pattern that stays finite
    with every landing inside the reachable box around its stance foot."""
    pattern = WalkingPattern(GaitConfig(), FEET[0], FEET[1], [0.0, 0.0], speed)
    adjuster = StepAdjuster()
    box = adjuster.config
    t = start
    for wait, offset in errors:
        t += wait
        planned = pattern.sample(t).dcm
        try:
            adjustment = adjuster.update(pattern, t, planned + offset)
        except ControllerError:
            assert not np.all(np.isfinite(planned + offset))
            continue
        sample = pattern.sample(t)
        for v in (sample.com, sample.com_velocity, sample.dcm, sample.feet, sample.feet_velocity):
            assert np.all(np.isfinite(v))
        if adjustment is not None:
            k = adjustment.step
            stance, landing = pattern.foothold(k + 1), pattern.foothold(k + 2)
            assert -box.max_backward - 1e-9 <= landing[0] - stance[0] <= box.max_forward + 1e-9
            assert box.min_width - 1e-9 <= abs(landing[1] - stance[1]) <= box.max_width + 1e-9

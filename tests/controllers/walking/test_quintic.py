"""Quintic pieces: the six boundary conditions, and C2 joins of the swing-height profile."""

from __future__ import annotations

import numpy as np
import pytest

from redundancy_gym.controllers import ControllerError
from redundancy_gym.controllers.walking import GaitConfig, PiecewiseQuintic, Quintic, WalkingPattern


def test_boundary_conditions_hold_to_c2() -> None:
    q = Quintic.from_boundary(0.7, [0.1, -0.2], [0.5, 0.3], [0.2, 0.0], [-0.1, 0.4], [1.0, -2.0], [0.5, 0.5])
    p0, v0, a0 = q.evaluate(0.0)
    p1, v1, a1 = q.evaluate(0.7)
    for got, want in (
        (p0, [0.1, -0.2]),
        (v0, [0.2, 0.0]),
        (a0, [1.0, -2.0]),
        (p1, [0.5, 0.3]),
        (v1, [-0.1, 0.4]),
        (a1, [0.5, 0.5]),
    ):
        assert np.allclose(got, want, atol=1e-12)
    # velocity and acceleration are the derivatives of position (central differences)
    h = 1e-5
    for s in (0.1, 0.35, 0.6):
        assert np.allclose((q.evaluate(s + h)[0] - q.evaluate(s - h)[0]) / (2 * h), q.evaluate(s)[1], atol=1e-8)
        assert np.allclose((q.evaluate(s + h)[1] - q.evaluate(s - h)[1]) / (2 * h), q.evaluate(s)[2], atol=1e-6)


def test_swing_height_is_c2_at_the_apex_and_rests_at_both_ends() -> None:
    pattern = WalkingPattern(GaitConfig(), [0.0, -0.09, 0.0], [0.0, 0.09, 0.0], [0.0, 0.0], 0.5)
    pattern.sample(pattern.step_start(0) + 0.01)  # builds step 0's swing
    vertical, horizontal = pattern._swing_cache[0]
    apex = vertical.breaks[1]
    left, right = vertical.pieces[0].evaluate(apex), vertical.pieces[1].evaluate(0.0)
    for a, b in zip(left, right, strict=False):
        assert float(a) == pytest.approx(float(b), abs=1e-12)
    assert float(left[0]) == pytest.approx(GaitConfig().step_height)
    for s in (0.0, vertical.duration):
        _, v, acc = vertical.evaluate(s)
        assert abs(float(v)) < 1e-12 and abs(float(acc)) < 1e-12
        _, v, acc = horizontal.evaluate(s)
        assert np.allclose(v, 0.0, atol=1e-12) and np.allclose(acc, 0.0, atol=1e-12)


def test_bad_pieces_raise() -> None:
    with pytest.raises(ControllerError, match="duration"):
        Quintic.from_boundary(0.0, 0.0, 1.0)
    with pytest.raises(ControllerError, match="at least one"):
        PiecewiseQuintic([])


@pytest.mark.parametrize("shape", [(), (2,), (3,), (2, 2)])
def test_scalar_evaluation_is_the_array_form_bit_for_bit(shape: tuple[int, ...]) -> None:
    """evaluate() on Python floats per component (scalars, vectors up to 3) gives the array form's floats and types;
    values() the same floats as lists, None for matrix values."""
    rng = np.random.default_rng(4)
    for _ in range(100):
        q = Quintic.from_boundary(rng.uniform(0.1, 1.0), *(rng.normal(size=shape) for _ in range(6)))
        s = rng.uniform(-0.1, 1.1)
        fast, array = q.evaluate(s), q._evaluate_array(min(max(s, 0.0), q.duration))
        for a, b in zip(fast, array, strict=False):
            assert type(a) is type(b) and np.shape(a) == np.shape(b)
            np.testing.assert_array_equal(a, b)
        values = q.values(s)
        if len(shape) == 2:
            assert values is None
        else:
            assert values is not None
            for listed, b in zip(values, array, strict=False):
                np.testing.assert_array_equal(listed, np.reshape(b, -1))

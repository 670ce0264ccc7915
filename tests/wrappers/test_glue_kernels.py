"""The wrappers' glue kernels give the bits of the NumPy expressions they replace, and flag non-finite actions."""

from __future__ import annotations

import numpy as np
import pytest

from redundancy_gym.wrappers.glue_kernels import clipped_finite, joint_command, residual_applied


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_clipped_finite_is_numpys_clip(dtype: type) -> None:
    action: np.ndarray = (3.0 * np.random.default_rng(0).standard_normal(10_000)).astype(dtype)
    clipped, finite = clipped_finite(action)
    assert finite and clipped.dtype == np.float64
    np.testing.assert_array_equal(clipped, action.astype(np.float64).clip(-1.0, 1.0))


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_clipped_finite_flags_a_non_finite_entry(bad: float) -> None:
    action = np.zeros(5)
    action[3] = bad
    assert not clipped_finite(action)[1]


def test_joint_command_is_numpys_expression() -> None:
    rng = np.random.default_rng(1)
    qdot, speeds = 5.0 * rng.standard_normal(10_000), rng.uniform(0.1, 3.0, 10_000)
    command = joint_command(qdot, speeds)
    assert command.dtype == np.float32
    np.testing.assert_array_equal(command, (qdot / speeds).clip(-1.0, 1.0).astype(np.float32))


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_residual_applied_is_numpys_expression(dtype: type) -> None:
    rng = np.random.default_rng(2)
    reference: np.ndarray = rng.uniform(-1.0, 1.0, 10_000).astype(dtype)
    low: np.ndarray = np.full(10_000, -1.0, dtype=dtype)
    high: np.ndarray = np.full(10_000, 1.0, dtype=dtype)
    scaled_range, action = 0.3 * rng.uniform(0.5, 2.0, 10_000), rng.uniform(-1.0, 1.0, 10_000)
    applied, residual = residual_applied(reference, scaled_range, action, low, high)
    expected = np.clip(reference + (scaled_range * action).astype(dtype), low, high)
    assert applied.dtype == residual.dtype == np.dtype(dtype)
    np.testing.assert_array_equal(applied, expected)
    np.testing.assert_array_equal(residual, expected - reference)
    # a zero residual gives the reference bit for bit
    np.testing.assert_array_equal(residual_applied(reference, scaled_range, 0.0 * action, low, high)[0], reference)

"""Stabilizer.update against the module docstring's laws computed by hand, its filter, bound and validation."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from redundancy_gym.controllers import ControllerError
from redundancy_gym.controllers.walking import Stabilizer, StabilizerGains

OMEGA = 3.3
DT = 0.004


def test_one_update_is_the_dcm_feedback_and_the_tracking_law() -> None:
    gains = StabilizerGains(dcm=1.5, zmp=0.8, com=2.0, zmp_filter=0.02, max_offset=1.0)
    stabilizer = Stabilizer(gains, OMEGA)
    com_ref, dcm_ref, zmp_ref = np.array([0.10, 0.02, 0.9]), np.array([0.12, 0.01]), np.array([0.08, -0.05])
    com, com_velocity, zmp = np.array([0.11, 0.00, 0.9]), np.array([0.3, -0.1, 0.0]), np.array([0.05, -0.04])
    out = stabilizer.update(DT, com_ref, dcm_ref, zmp_ref, com, com_velocity, zmp)
    dcm_error = com[:2] + com_velocity[:2] / OMEGA - dcm_ref
    desired = zmp_ref + 1.5 * dcm_error
    rate = -0.8 * (desired - zmp) + 2.0 * (com_ref[:2] - com[:2])  # the first ZMP initializes the filter
    np.testing.assert_allclose(out.dcm_error, dcm_error, rtol=1e-14)
    np.testing.assert_allclose(out.desired_zmp, desired, rtol=1e-14)
    np.testing.assert_allclose(out.measured_zmp, zmp, rtol=1e-14)
    np.testing.assert_allclose(out.rate, rate, rtol=1e-14)
    np.testing.assert_allclose(out.offset, rate * DT, rtol=1e-14)
    # the second: the low-pass moves the filtered ZMP by dt / (T + dt) of the gap, the offset integrates the rate
    zmp2 = np.array([0.07, -0.03])
    out2 = stabilizer.update(DT, com_ref, dcm_ref, zmp_ref, com, com_velocity, zmp2)
    filtered = zmp + DT / (0.02 + DT) * (zmp2 - zmp)
    rate2 = -0.8 * (desired - filtered) + 2.0 * (com_ref[:2] - com[:2])
    np.testing.assert_allclose(out2.measured_zmp, filtered, rtol=1e-14)
    np.testing.assert_allclose(out2.offset, out.offset + rate2 * DT, rtol=1e-13)
    # no loaded foot: the filtered ZMP stays
    out3 = stabilizer.update(DT, com_ref, dcm_ref, zmp_ref, com, com_velocity, None)
    np.testing.assert_allclose(out3.measured_zmp, filtered, rtol=1e-14)


def test_without_a_measured_zmp_the_desired_one_stands_in() -> None:
    stabilizer = Stabilizer(StabilizerGains(max_offset=1.0), OMEGA)
    out = stabilizer.update(DT, [0.1, 0.0], [0.1, 0.0], [0.0, 0.0], [0.0, 0.0], [0.0, 0.0], None)
    np.testing.assert_array_equal(out.measured_zmp, out.desired_zmp)
    np.testing.assert_allclose(out.rate, [1.0 * 0.1, 0.0], rtol=1e-14)  # only the CoM error acts


def test_the_offset_is_bounded_and_the_rate_is_what_reaches_the_bound() -> None:
    stabilizer = Stabilizer(StabilizerGains(max_offset=0.01), OMEGA)
    previous = np.zeros(2)
    for _ in range(50):
        out = stabilizer.update(DT, [0.0, 0.0], [0.0, 0.0], [0.0, 0.0], [-0.5, 0.2], [0.0, 0.0], [0.0, 0.0])
        assert np.linalg.norm(out.offset) <= 0.01 * (1 + 1e-15)
        np.testing.assert_allclose(out.rate, (out.offset - previous) / DT, atol=1e-12)
        previous = out.offset
    np.testing.assert_allclose(np.linalg.norm(previous), 0.01, rtol=1e-14)
    np.testing.assert_allclose(
        previous / np.linalg.norm(previous), np.array([0.5, -0.2]) / np.hypot(0.5, 0.2), rtol=1e-12
    )


def test_outputs_are_not_the_stabilizer_state() -> None:
    """A caller may keep and write what it got: the next update does not see it."""
    a, b = Stabilizer(StabilizerGains(), OMEGA), Stabilizer(StabilizerGains(), OMEGA)
    args = ([0.0, 0.0], [0.01, 0.0], [0.0, 0.0], [0.02, 0.01], [0.1, 0.0], [0.01, 0.0])
    out = a.update(DT, *args)
    b.update(DT, *args)
    for value in out:
        value[:] = 123.0
    np.testing.assert_array_equal(a.update(DT, *args).offset, b.update(DT, *args).offset)


@pytest.mark.parametrize("name", ["com_ref", "dcm_ref", "zmp_ref", "com", "com_velocity", "zmp"])
@pytest.mark.parametrize("bad", [[np.nan, 0.0], [0.0, np.inf], np.array([-np.inf, 0.0, 0.0]), [1.0]])
def test_a_bad_point_raises_naming_it(name: str, bad: object) -> None:
    names = ("com_ref", "dcm_ref", "zmp_ref", "com", "com_velocity", "zmp")
    args = {n: np.zeros(2) for n in names}
    args[name] = np.asarray(bad, dtype=np.float64)
    stabilizer = Stabilizer(StabilizerGains(), OMEGA)
    with pytest.raises(ControllerError, match=rf"^{name} must be (None or )?a finite \(x, y\), got array"):
        stabilizer.update(DT, *(args[n] for n in names))


@pytest.mark.parametrize("dt", [0.0, -DT, np.nan, np.inf, np.float64(-1.0)])
def test_a_bad_period_raises(dt: float) -> None:
    with pytest.raises(ControllerError, match="dt must be finite and > 0"):
        Stabilizer(StabilizerGains(), OMEGA).update(dt, [0, 0], [0, 0], [0, 0], [0, 0], [0, 0], None)


def test_lists_float32_and_numpy_scalars_give_the_float64_result() -> None:
    dcm: Any = np.float32(1.5)  # numpy scalars where floats are declared, on purpose
    dt: Any = np.float32(DT)
    gains = StabilizerGains(dcm=dcm, zmp=0.8, com=2, max_offset=1.0)
    args = ([0.1, 0.0], [0.12, 0.01], [0.08, -0.05], [0.11, 0.0], [0.3, -0.1], [0.05, -0.04])
    reference = Stabilizer(StabilizerGains(dcm=1.5, zmp=0.8, com=2.0, max_offset=1.0), OMEGA).update(DT, *args)
    out = Stabilizer(gains, OMEGA).update(dt, *(np.asarray(a, dtype=np.float32) for a in args))
    for got, expected in zip(out, reference, strict=False):
        assert got.dtype == np.float64
        # float32 inputs are rounded once; the arithmetic is float64 throughout
        np.testing.assert_allclose(got, expected, rtol=1e-6, atol=1e-8)

"""Stance soles on rough ground (SoleTilt): the measured tilt against the plan, the low-pass to it, its bounds (the
ground's roughness, max_tilt), the guards (flat footholds, unloaded or tipping soles keep their tilt) and the
release of a lifted sole; in the walker, the option on flat footholds leaves the walk bit for bit as without it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from redundancy_gym.controllers import ControllerError
from redundancy_gym.controllers.walking import SoleTilt, SoleTiltConfig
from redundancy_gym.controllers.walking.sole_tilt import measured_tilt, tilt_rotation
from redundancy_gym.controllers.walking.support_polygon import SOLE_HALF_WIDTH, SOLE_X

DT = 0.004
LOADED = (300.0, 300.0)


def _yaw(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


@pytest.mark.parametrize("heading", [0.0, 0.4, -2.0])
def test_the_measured_tilt_is_the_roll_and_pitch_between_plan_and_sole_whatever_the_heading(heading: float) -> None:
    planned = _yaw(heading) @ tilt_rotation(0.0, 0.1)  # a sole planned pitched on a ramp
    for roll, pitch in ((0.05, -0.03), (-0.12, 0.08), (0.0, 0.0)):
        measured = planned @ tilt_rotation(roll, pitch)
        assert measured_tilt(planned, measured) == pytest.approx((roll, pitch), abs=1e-12)
        # a slip about the sole's vertical between them is not a tilt
        slipped = planned @ _yaw(0.2) @ tilt_rotation(roll, pitch)
        assert measured_tilt(planned, slipped) == pytest.approx((roll, pitch), abs=1e-12)


def test_a_loaded_sole_on_rough_ground_takes_the_grounds_tilt_at_the_time_constant() -> None:
    tilt = SoleTilt(SoleTiltConfig(time_constant=0.05))
    planned = np.stack([np.eye(3), np.eye(3)])
    ground = (0.04, -0.03)  # [rad] within the bound of 3 cm roughness (0.197 rad)
    measured = np.stack([tilt_rotation(*ground), np.eye(3)])
    limits = (tilt.limit(0.03), tilt.limit(0.03))
    steps = int(round(0.05 / DT))
    for _ in range(steps):  # about one time constant: 1 - 1/e of the way (the discrete first-order low-pass's)
        tilt.update(DT, (True, True), limits, LOADED, planned, measured)
    share = 1.0 - (0.05 / (0.05 + DT)) ** steps
    assert share == pytest.approx(1.0 - math.exp(-1.0), abs=0.04)
    assert tilt.tilt[0] == pytest.approx(share * np.array(ground), rel=1e-9)
    for _ in range(200):
        tilt.update(DT, (True, True), limits, LOADED, planned, measured)
    np.testing.assert_allclose(tilt.tilt, [ground, (0.0, 0.0)], atol=1e-9)


def test_the_tilt_taken_is_bounded_by_the_grounds_roughness_and_max_tilt() -> None:
    tilt = SoleTilt(SoleTiltConfig(max_tilt=0.15))
    assert tilt.limit(0.01) == 0.0  # at min_roughness: flat enough, the plan's orientation
    assert tilt.limit(0.02) == pytest.approx(math.atan(0.02 / (2.0 * SOLE_HALF_WIDTH)))
    assert tilt.limit(0.2) == 0.15
    measured = np.stack([tilt_rotation(0.3, -0.3)] * 2)  # a sole lying on its edge, 17 deg
    for _ in range(500):
        tilt.update(DT, (True, True), (tilt.limit(0.02), tilt.limit(0.2)), LOADED, np.stack([np.eye(3)] * 2), measured)
    bound = math.atan(0.02 / (2.0 * SOLE_HALF_WIDTH))
    np.testing.assert_allclose(tilt.tilt, [(bound, -bound), (0.15, -0.15)], rtol=1e-9)


def test_flat_footholds_unloaded_and_tipping_soles_keep_their_tilt_and_a_lifted_sole_lets_go() -> None:
    tilt = SoleTilt()
    planned = np.stack([np.eye(3)] * 2)
    measured = np.stack([tilt_rotation(0.05, 0.05)] * 2)
    limits = (tilt.limit(0.03), tilt.limit(0.03))
    for _ in range(100):
        tilt.update(DT, (True, True), limits, LOADED, planned, measured)
    held = tilt.tilt.copy()
    flat = np.stack([np.eye(3)] * 2)  # the soles now measured flat: each guard keeps the tilt
    tilt.update(DT, (True, True), (0.0, 0.0), LOADED, planned, flat)  # footholds not rough
    tilt.update(DT, (True, True), limits, (0.0, 100.0), planned, flat)  # the right unloaded (the left: 1/1)
    tilt.update(DT, (True, True), limits, LOADED, planned, flat, tipping=(True, True))
    np.testing.assert_array_equal(tilt.tilt[0], held[0])
    left = tilt.tilt[1].copy()
    tilt.update(DT, (True, True), limits, (600.0, 100.0), planned, np.stack([measured[0], flat[1]]))  # left: 1/7
    np.testing.assert_array_equal(tilt.tilt[1], left)
    held = tilt.tilt.copy()
    for _ in range(int(round(0.5 / DT))):  # in the air for 0.5 s, release 0.1 s
        tilt.update(DT, (False, True), limits, (0.0, 600.0), planned, np.stack([flat[0], measured[1]]))
    assert np.abs(tilt.tilt[0]).max() < 0.01 * np.abs(held[0]).max()


def test_a_single_support_sole_is_pressed_towards_the_desired_centre_of_pressure_within_the_bound() -> None:
    tilt = SoleTilt(SoleTiltConfig(cop_gain=15.0))
    planned = np.stack([np.eye(3)] * 2)
    limits = (tilt.limit(0.03), tilt.limit(0.03))
    # the desired CoP 4 cm ahead of and 1 cm to the left of the measured one; the sole measured as planned and
    # tipping (its tilt otherwise held): toes pressed down, the left edge down, at the gain's rate
    tilt.update(DT, (True, False), limits, (600.0, 0.0), planned, planned, (True, False), ((0.04, 0.01), None))
    np.testing.assert_allclose(tilt.tilt, [(-DT * 15.0 * 0.01, DT * 15.0 * 0.04), (0.0, 0.0)], rtol=1e-12)
    for _ in range(2000):  # pressed on, never past the ground's bound
        tilt.update(DT, (True, False), limits, (600.0, 0.0), planned, planned, (True, False), ((0.04, 0.01), None))
    np.testing.assert_allclose(tilt.tilt[0], (-limits[0], limits[0]), rtol=1e-12)
    # not on flat footholds, not in the air
    other = SoleTilt()
    other.update(DT, (True, False), (0.0, 0.0), (600.0, 0.0), planned, planned, cop_error=((0.04, 0.01), None))
    other.update(DT, (False, True), limits, (0.0, 600.0), planned, planned, cop_error=((0.04, 0.01), None))
    assert not other.tilt.any()
    # no gain, no pressing
    off = SoleTilt(SoleTiltConfig(cop_gain=0.0))
    off.update(DT, (True, False), limits, (600.0, 0.0), planned, planned, (True, False), ((0.04, 0.01), None))
    assert not off.tilt.any()


def test_a_centre_of_pressure_near_the_soles_edge_is_tipping() -> None:
    tilt = SoleTilt(SoleTiltConfig(edge_margin=0.015))
    assert not tilt.tipping((0.03, 0.0))
    for cop in ((SOLE_X[0] + 0.01, 0.0), (SOLE_X[1] - 0.01, 0.0), (0.0, SOLE_HALF_WIDTH - 0.01), (0.0, -0.2)):
        assert tilt.tipping(cop), cop


@pytest.mark.parametrize(
    ("name", "value", "bound"),
    [
        ("time_constant", 0.0, r"> 0 \[s\]"),
        ("max_tilt", 2.0, r"in \(0, 1.5708\] \[rad\]"),
        ("min_load", 1.5, r"in \[0, 1\]"),
        ("min_roughness", math.nan, r">= 0 \[m\]"),
        ("edge_margin", -0.01, r"in \[0, 0.075\] \[m\]"),
        ("cop_gain", -1.0, r">= 0 \[rad/\(m s\)\]"),
    ],
)
def test_bad_config_values_are_named_with_their_range(name: str, value: float, bound: str) -> None:
    with pytest.raises(ControllerError, match=f"SoleTiltConfig.{name} must be a finite real number {bound}"):
        SoleTiltConfig(**{name: value})


def test_a_bad_period_is_named() -> None:
    with pytest.raises(ControllerError, match="dt must be finite and > 0"):
        SoleTilt().update(0.0, (True, True), (0.1, 0.1), LOADED, np.stack([np.eye(3)] * 2), np.stack([np.eye(3)] * 2))

"""estimate_zmp against centres of pressure computed by hand from the ankle wrenches."""

from __future__ import annotations

import numpy as np
import pytest

from redundancy_gym.controllers import ControllerError
from redundancy_gym.controllers.walking import estimate_zmp

IDENTITY = np.tile(np.eye(3), (2, 1, 1))


def _yaw(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def test_the_centre_of_pressure_of_one_foot_by_hand() -> None:
    """Sensor 0.08 m above the ground at (0.1, 0.2): the shank feels the foot push down with 400 N and a
    torque (-8, 12, 0) N m, so the ground pushes up with F = (0, 0, 400) and T = (8, -12, 0); the CoP is
    a + (-(T_y + h F_x), T_x - h F_y) / F_z = (0.1 + 12 / 400, 0.2 + 8 / 400)."""
    ankles = np.array([[0.1, 0.2, 0.08], [0.1, -0.2, 0.08]])
    forces = np.array([[0.0, 0.0, -400.0], [0.0, 0.0, 0.0]])
    torques = np.array([[-8.0, 12.0, 0.0], [0.0, 0.0, 0.0]])
    estimate = estimate_zmp(IDENTITY, ankles, forces, torques)
    np.testing.assert_allclose(estimate.cop[0], [0.13, 0.22], rtol=1e-15)
    assert np.all(np.isnan(estimate.cop[1]))  # the other foot is unloaded
    assert estimate.zmp is not None
    np.testing.assert_allclose(estimate.zmp, [0.13, 0.22], rtol=1e-15)
    np.testing.assert_allclose(estimate.normal_force, [400.0, 0.0], rtol=1e-15)
    np.testing.assert_allclose(estimate.moment, [[8.0, -12.0, 0.0], [0.0, 0.0, 0.0]], rtol=1e-15)


def test_a_horizontal_force_acts_through_the_sensor_height_and_the_sensor_frame_is_rotated() -> None:
    """A sensor turned by 90 degrees about z: its x reading is the world's y. A shear F_x = 40 N at
    h = 0.1 m above a ground at z = 0.02 shifts the CoP by -h F_x / F_z = -0.01 m."""
    rotations = np.array([_yaw(np.pi / 2), np.eye(3)])
    ankles = np.array([[0.0, 0.1, 0.12], [0.0, -0.1, 0.12]])
    # sensor 0: the shank feels -F; in its frame the world's -x is its +y
    forces = np.array([[0.0, 40.0, -400.0], [0.0, 0.0, -200.0]])
    torques = np.zeros((2, 3))
    estimate = estimate_zmp(rotations, ankles, forces, torques, ground=0.02)
    np.testing.assert_allclose(estimate.cop[0], [-0.1 * 40.0 / 400.0, 0.1], atol=1e-15)
    np.testing.assert_allclose(estimate.cop[1], [0.0, -0.1], atol=1e-15)
    # the ZMP is the F_z-weighted mean of the two feet
    assert estimate.zmp is not None
    np.testing.assert_allclose(estimate.zmp, (400.0 * estimate.cop[0] + 200.0 * estimate.cop[1]) / 600.0, atol=1e-15)


def test_feet_below_min_force_are_unloaded_and_none_loaded_gives_no_zmp() -> None:
    ankles = np.array([[0.0, 0.1, 0.08], [0.0, -0.1, 0.08]])
    forces = np.array([[0.0, 0.0, -19.0], [0.0, 0.0, -25.0]])
    estimate = estimate_zmp(IDENTITY, ankles, forces, np.zeros((2, 3)))
    assert np.all(np.isnan(estimate.cop[0])) and np.allclose(estimate.cop[1], [0.0, -0.1])
    assert estimate_zmp(IDENTITY, ankles, forces, np.zeros((2, 3)), min_force=30.0).zmp is None
    lists = estimate_zmp(IDENTITY.tolist(), ankles.tolist(), forces.tolist(), [[0, 0, 0]] * 2)
    np.testing.assert_array_equal(lists.cop, estimate.cop)  # sequences and int readings are read as float64


@pytest.mark.parametrize("index", range(4))
def test_a_non_finite_reading_raises_naming_the_input(index: int) -> None:
    names = ("rotations", "ankles", "forces", "torques")
    args = [IDENTITY.copy(), np.zeros((2, 3)), np.array([[0.0, 0.0, -300.0]] * 2), np.zeros((2, 3))]
    args[index][(1, 0)] = np.nan
    with pytest.raises(ControllerError, match=f"the ankle sensor {names[index]} must be finite"):
        estimate_zmp(args[0], args[1], args[2], args[3])
    args[index] = np.zeros((3, 3))
    with pytest.raises(ControllerError, match=r"need rotations \(2, 3, 3\)"):
        estimate_zmp(args[0], args[1], args[2], args[3])

"""Stabilization via planning (monograph 5.5.3): the restarted plan's ZMP modification, in double support only,
removes the DCM deviation by the double support's end, and keeps a deviating LIPM on the plan step after step."""

from __future__ import annotations

import math

import numpy as np
import pytest

from redundancy_gym.controllers import ControllerError
from redundancy_gym.controllers.ikd import PlanStabilizer

OMEGA = math.sqrt(9.81 / 0.91)


def _lipm(deviation: np.ndarray, rate: np.ndarray, shift: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """One period of ``e'' = omega^2 (e - shift)`` by fine explicit steps (independent of the stabilizer's own
    closed form)."""
    n = 200
    h = dt / n
    for _ in range(n):
        rate = rate + h * OMEGA**2 * (deviation - shift)
        deviation = deviation + h * rate
    return deviation, rate


@pytest.mark.parametrize(
    "deviation, rate", [((0.01, -0.005), (0.0, 0.0)), ((-0.002, 0.003), (0.02, -0.01)), ((0.0, 0.0), (-0.015, 0.0))]
)
def test_the_modification_in_double_support_brings_the_dcm_deviation_to_zero_at_its_end(deviation, rate):
    stabilizer = PlanStabilizer(OMEGA, max_shift=1.0)
    window = (0.64, 0.8)
    stabilizer.replan(0.6, deviation, rate, window)
    e, edot = np.array(deviation, dtype=float), np.array(rate, dtype=float)
    t, dt = 0.6, 0.001
    while t < window[1] - 1e-9:
        out = stabilizer.advance(t, dt)
        np.testing.assert_allclose(out.com_offset, e, atol=1e-6)  # its plan is the LIPM's own motion
        if t + dt <= window[0] + 1e-12:
            assert not out.zmp_shift.any()  # nothing before the double support
        e, edot = _lipm(e, edot, out.zmp_shift, dt)
        t += dt
    assert np.abs(e + edot / OMEGA).max() < 2e-5  # the DCM deviation is gone at t_1
    assert np.abs(np.array(deviation) + np.array(rate) / OMEGA).max() > 1e-3


def test_the_shape_is_a_trapezoid_over_the_double_support_only():
    stabilizer = PlanStabilizer(OMEGA, ramp=0.25)
    stabilizer.replan(0.0, (0.01, 0.0), (0.0, 0.0), (0.4, 0.6))
    assert stabilizer.shape(0.39) == 0.0 and stabilizer.shape(0.61) == 0.0
    assert stabilizer.shape(0.5) == pytest.approx(1.0)
    assert stabilizer.shape(0.425) == pytest.approx(0.5)
    assert stabilizer.shape(0.575) == pytest.approx(0.5)
    values = [stabilizer.shape(t) for t in np.linspace(0.4, 0.6, 101)]
    assert max(abs(a - b) for a, b in zip(values, values[1:], strict=False)) <= 0.04 + 1e-12  # continuous ramps


def test_a_saturated_modification_leaves_a_plan_that_converges_instead_of_diverging():
    stabilizer = PlanStabilizer(OMEGA, max_shift=0.01)
    amplitude = stabilizer.replan(0.0, (0.05, 0.0), (0.1, 0.0), (0.0, 0.16))
    assert amplitude[0] == pytest.approx(0.01)  # clipped
    t, dt = 0.0, 0.004
    offsets = []
    while t < 2.0:
        offsets.append(stabilizer.advance(t, dt).com_offset[0])
        t += dt
    # past the window the plan keeps its convergent part: it decays as e^{-omega t}
    assert abs(offsets[-1]) < 5e-3 * abs(offsets[40])  # e^{-omega 1.84 s} = 2.4e-3
    assert abs(stabilizer.offset_rate[0] + OMEGA * stabilizer.offset[0]) < 1e-12


def test_restarted_at_every_double_support_a_deviating_lipm_stays_on_the_plan():
    # the IKD's CoM is pushed off the plan a little in every step (the model error the plan leaves out); restarted
    # at every double support the deviation stays bounded, without the restart it runs off
    step, single, dt = 0.8, 0.64, 0.004

    def walk(planning: bool) -> float:
        stabilizer = PlanStabilizer(OMEGA)
        e, edot = np.zeros(2), np.zeros(2)
        largest, t, k = 0.0, 0.0, -1
        for n in range(int(6 * step / dt)):
            t = n * dt
            if planning and int(t // step) != k and t % step >= single:
                k = int(t // step)
                stabilizer.replan(t, e, edot, (k * step + single, (k + 1) * step))
            shift = stabilizer.advance(t, dt).zmp_shift
            disturbance = np.array([0.002, -0.001]) * math.sin(2 * math.pi * t / step)  # ZMP error [m]
            e, edot = _lipm(e, edot, shift + disturbance, dt)
            largest = max(largest, float(np.abs(e).max()))
        return largest

    assert walk(True) < 0.01
    assert walk(False) > 0.1


def test_bad_arguments_are_refused_by_name():
    with pytest.raises(ControllerError, match="omega"):
        PlanStabilizer(0.0)
    with pytest.raises(ControllerError, match="ramp"):
        PlanStabilizer(OMEGA, ramp=0.6)
    with pytest.raises(ControllerError, match="max_shift"):
        PlanStabilizer(OMEGA, max_shift=-1.0)
    stabilizer = PlanStabilizer(OMEGA)
    with pytest.raises(ControllerError, match="double_support"):
        stabilizer.replan(1.0, (0.0, 0.0), (0.0, 0.0), (0.4, 0.6))
    with pytest.raises(ControllerError, match="com_deviation"):
        stabilizer.replan(0.0, (np.nan, 0.0), (0.0, 0.0), (0.4, 0.6))

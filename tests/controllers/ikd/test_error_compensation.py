"""Dynamics error compensation (fig. 5.26, (5.98)): the discrete PD against its continuous transfer function, the
inverted-pendulum model against its analytic solution, the closed loop against the continuous one."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.linalg import expm

from redundancy_gym.controllers import ControllerError
from redundancy_gym.controllers.ikd.error_compensation import GRAVITY, ErrorCompensation

MASS, HEIGHT = 60.0, 0.91


def _pd_step_response(compensation: ErrorCompensation, samples: int) -> np.ndarray:
    """The PD's output for a unit offset held from sample 0 on (the filter driven directly, the pendulum aside)."""
    outputs = []
    for _ in range(samples):
        compensation.offset = np.array([1.0, 0.0])
        compensation.offset_rate = np.zeros(2)
        out = compensation.step(np.zeros(2), np.zeros(2))
        outputs.append(-out.moment_modification[1])  # u_x = -Delta T_y
    return np.array(outputs)


@pytest.mark.parametrize("period", [0.001, 0.004])
def test_the_tustin_pd_follows_the_continuous_step_response(period):
    # K_R (T_R s + 1) / (T_d s + 1) to a unit step: K_R (1 + (T_R / T_d - 1) e^(-t / T_d)); Tustin's rule
    # integrates the input by trapezoids, so the step acts as if it came half a period early (sample 0 is
    # K_R (2 T_R + h) / (2 T_d + h)), and the discrete pole (1 - h / 2T_d) / (1 + h / 2T_d) is e^(-h / T_d) to
    # third order in h / T_d: the samples are the continuous response at t + h / 2 to (h / T_d)^2 of the peak
    compensation = ErrorCompensation(MASS, HEIGHT, period)
    k, lead, lag = 3200.0, 0.2, 0.02
    response = _pd_step_response(compensation, int(0.2 / period))
    t = np.arange(response.size) * period + 0.5 * period
    continuous = k * (1.0 + (lead / lag - 1.0) * np.exp(-t / lag))
    assert response[0] == pytest.approx(k * (2.0 * lead + period) / (2.0 * lag + period), rel=1e-12)
    peak = k * lead / lag
    np.testing.assert_allclose(response, continuous, rtol=0.0, atol=0.2 * (period / lag) ** 2 * peak)
    assert response[-1] == pytest.approx(k, rel=1e-3)  # the DC gain K_R once the lag has decayed (10 T_d)


def test_the_tustin_pd_is_exact_at_the_prewarped_frequency():
    # a sinusoidal offset in steady state: the discrete output's amplitude and phase are C(j w') of the
    # continuous PD at w' = (2 / h) tan(w h / 2)
    period, omega = 0.004, 2.0 * math.pi * 5.0
    compensation = ErrorCompensation(MASS, HEIGHT, period)
    n = 3000
    outputs = []
    for i in range(n):
        compensation.offset = np.array([math.sin(omega * i * period), 0.0])
        compensation.offset_rate = np.zeros(2)
        outputs.append(-compensation.step(np.zeros(2), np.zeros(2)).moment_modification[1])
    tail = np.arange(n // 2, n)
    basis = np.column_stack([np.sin(omega * tail * period), np.cos(omega * tail * period)])
    sine, cosine = np.linalg.lstsq(basis, np.array(outputs)[tail], rcond=None)[0]
    warped = 2.0 / period * math.tan(omega * period / 2.0)
    expected = 3200.0 * (1j * warped * 0.2 + 1.0) / (1j * warped * 0.02 + 1.0)
    assert complex(sine, cosine) == pytest.approx(expected, rel=1e-9)


def test_without_the_pd_a_moment_error_tips_the_pendulum_as_its_analytic_solution():
    # K_R = 0: m z_c d'' = m g d + e from rest, d(t) = e / (m g) (cosh(omega t) - 1), exact at the samples (the input
    # is constant, the discretization exact for a held input); a T_y error moves x, a T_x error y, with the signs
    # of the ZMP moment u = (-T_y, T_x)
    period = 0.001
    compensation = ErrorCompensation(MASS, HEIGHT, period, gain=0.0)
    error = np.array([3.0, -5.0])  # T_full - T_ref [N m]
    offsets = [compensation.step(np.zeros(2), error).com_offset for _ in range(501)]
    t = 0.5
    omega = math.sqrt(GRAVITY / HEIGHT)
    u = np.array([-error[1], error[0]])
    expected = u / (MASS * GRAVITY) * (math.cosh(omega * t) - 1.0)
    np.testing.assert_allclose(offsets[-1], expected, rtol=1e-9)
    rate = u / (MASS * GRAVITY) * omega * math.sinh(omega * t)
    np.testing.assert_allclose(
        compensation.offset_rate, u / (MASS * GRAVITY) * omega * math.sinh(omega * (t + period)), rtol=1e-9
    )
    assert np.all(rate != 0.0)
    # the pendulum's own ZMP moment m g d - m z_c d'' cancels the error: it is -u at every instant
    d, dd = offsets[-1], u / (MASS * HEIGHT) * math.cosh(omega * t)
    np.testing.assert_allclose(MASS * GRAVITY * d - MASS * HEIGHT * dd, -u, rtol=1e-9)


def _continuous_closed_loop(error: float, times: np.ndarray) -> np.ndarray:
    """The continuous closed loop's offset for a constant ZMP-moment error from rest (matrix exponential).

    States: d, d', and the PD's lag state x with T_d x' = d - x; C d = K_R (T_R / T_d d + (1 - T_R / T_d) x).
    """
    k, lead, lag = 3200.0, 0.2, 0.02
    mz, mg = MASS * HEIGHT, MASS * GRAVITY
    a = np.array(
        [
            [0.0, 1.0, 0.0, 0.0],
            [(mg - k * lead / lag) / mz, 0.0, -k * (1.0 - lead / lag) / mz, error / mz],
            [1.0 / lag, 0.0, -1.0 / lag, 0.0],
            [0.0, 0.0, 0.0, 0.0],
        ]
    )
    start = np.array([0.0, 0.0, 0.0, 1.0])
    return np.array([(expm(a * t) @ start)[0] for t in times])


def test_the_closed_loop_keeps_the_pendulum_up_and_settles_where_the_analysis_says():
    # a constant error: the offset stays bounded, converges to e / (K_R - m g), follows the continuous closed loop,
    # and the moment modification settles at K_R e / (K_R - m g)
    period = 0.001
    compensation = ErrorCompensation(MASS, HEIGHT, period)
    assert compensation.closed_loop_stable
    error_ty = -40.0  # T_y error [N m]: u_x = 40
    outputs = [compensation.step(np.zeros(2), np.array([0.0, error_ty])) for _ in range(3000)]
    offsets = np.array([o.com_offset[0] for o in outputs])
    u = -error_ty
    settled = u / (3200.0 - MASS * GRAVITY)
    assert offsets[-1] == pytest.approx(settled, rel=1e-6)
    assert np.max(np.abs(offsets)) < 1.5 * abs(settled)
    np.testing.assert_allclose(np.array([o.com_offset[1] for o in outputs]), 0.0, atol=0.0)
    assert -outputs[-1].moment_modification[1] == pytest.approx(3200.0 * settled, rel=1e-6)
    times = np.arange(0, 3000, 50) * period
    continuous = _continuous_closed_loop(u, times)
    np.testing.assert_allclose(offsets[::50], continuous, rtol=0.0, atol=0.01 * abs(settled))


def test_the_stability_condition_and_the_saturation():
    assert not ErrorCompensation(MASS, HEIGHT, 0.001, gain=0.5 * MASS * GRAVITY).closed_loop_stable
    assert not ErrorCompensation(MASS, HEIGHT, 0.001, gain=0.0).closed_loop_stable
    # saturated, the modification never exceeds the limit; a small limit lets the pendulum fall
    limited = ErrorCompensation(MASS, HEIGHT, 0.001, max_moment=10.0)
    outputs = [limited.step(np.zeros(2), np.array([0.0, -40.0])) for _ in range(2000)]
    assert max(np.max(np.abs(o.moment_modification)) for o in outputs) <= 10.0
    assert outputs[-1].saturated and not outputs[0].saturated
    assert abs(outputs[-1].com_offset[0]) > 1.0
    limited.reset()
    assert np.all(limited.offset == 0.0) and np.all(limited.offset_rate == 0.0)
    assert not limited.step(np.zeros(2), np.zeros(2)).saturated


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"mass": 0.0}, "mass"),
        ({"com_height": -1.0}, "com_height"),
        ({"period": float("nan")}, "period"),
        ({"gain": -1.0}, "gain"),
        ({"lead": float("inf")}, "lead"),
        ({"lag": 0.0}, "lag"),
        ({"max_moment": 0.0}, "max_moment"),
        ({"gravity": True}, "gravity"),
    ],
)
def test_bad_parameters_are_refused_by_name(kwargs, name):
    args = {"mass": MASS, "com_height": HEIGHT, "period": 0.001}
    args.update({k: v for k, v in kwargs.items() if k in args})
    options = {k: v for k, v in kwargs.items() if k not in args}
    with pytest.raises(ControllerError, match=name):
        ErrorCompensation(args["mass"], args["com_height"], args["period"], **options)


def test_bad_moments_are_refused_by_name():
    compensation = ErrorCompensation(MASS, HEIGHT, 0.001)
    with pytest.raises(ControllerError, match="reference_moment"):
        compensation.step([np.nan, 0.0], np.zeros(2))
    with pytest.raises(ControllerError, match="full_moment"):
        compensation.step(np.zeros(2), np.zeros(3))
    with pytest.raises(ControllerError, match="full_moment"):
        compensation.step(np.zeros(2), "x")

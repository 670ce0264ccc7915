"""DcmPlan.sample against the closed form of the module docstring, evaluated here independently on 2-vectors."""

from __future__ import annotations

import numpy as np
import pytest

from redundancy_gym.controllers.walking import DcmPlan, DcmPlanner
from redundancy_gym.controllers.walking.dcm_planner import ComState


def _plan(rng: np.random.Generator, n: int = 7) -> DcmPlan:
    times = np.cumsum(rng.uniform(0.05, 0.6, n))
    zmp = rng.normal(size=(n, 2)) * 0.1
    return DcmPlanner(0.9).plan(times, zmp, rng.normal(size=2) * 0.05)


def _expected(plan: DcmPlan, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(x, xd, r)`` at ``t`` from the knots' DCM and CoM: the segment's closed form on numpy 2-vectors."""
    w, times = plan.omega, plan.times
    if t >= times[-1]:
        k, slope, s = times.size - 1, np.zeros(2), t - times[-1]
    else:
        k = max(int(np.searchsorted(times, t, side="right")) - 1, 0)
        slope = (plan.zmp[k + 1] - plan.zmp[k]) / (times[k + 1] - times[k])
        s = max(t - times[k], 0.0)
    c = plan.dcm[k] - plan.zmp[k] - slope / w
    d = plan.com[k] - plan.zmp[k] - 0.5 * c
    r = plan.zmp[k] + slope * s
    x = r + 0.5 * c * np.exp(w * s) + d * np.exp(-w * s)
    xd = slope + w * (0.5 * c * np.exp(w * s) - d * np.exp(-w * s))
    return x, xd, r


def test_sample_is_the_closed_form_before_on_and_after_the_knots() -> None:
    rng = np.random.default_rng(3)
    for _ in range(5):
        plan = _plan(rng)
        times = plan.times
        for t in [times[0] - 0.3, *times, *rng.uniform(times[0], times[-1], 40), times[-1] + 0.2, times[-1] + 1.0]:
            state = plan.sample(float(t))
            x, xd, r = _expected(plan, float(t))
            np.testing.assert_allclose(state.position, x, rtol=0, atol=1e-12)
            np.testing.assert_allclose(state.velocity, xd, rtol=0, atol=1e-12)
            np.testing.assert_allclose(state.zmp, r, rtol=0, atol=1e-15)
            np.testing.assert_allclose(state.dcm, x + xd / plan.omega, rtol=0, atol=1e-12)
            np.testing.assert_allclose(state.acceleration, plan.omega**2 * (x - r), rtol=0, atol=1e-10)


def test_sample_is_continuous_at_the_knots_and_hits_the_knot_states() -> None:
    """Left and right of each inner knot agree (CoM, velocity, DCM and ZMP are continuous), and at a knot the
    sample is the plan's knot CoM, DCM and ZMP."""
    rng = np.random.default_rng(4)
    plan = _plan(rng, 9)
    eps = 1e-9
    for k, t in enumerate(plan.times):
        at = plan.sample(float(t))
        np.testing.assert_allclose(at.position, plan.com[k], atol=1e-12)
        np.testing.assert_allclose(at.dcm, plan.dcm[k], atol=1e-12)
        np.testing.assert_allclose(at.zmp, plan.zmp[k], atol=1e-15)
        before, after = plan.sample(float(t) - eps), plan.sample(float(t) + eps)
        for field in ("position", "velocity", "dcm", "zmp"):
            np.testing.assert_allclose(getattr(before, field), getattr(after, field), atol=1e-6, err_msg=field)


def test_sample_results_are_fresh_arrays_and_do_not_depend_on_the_order_of_calls() -> None:
    rng = np.random.default_rng(5)
    plan = _plan(rng)
    ts = rng.uniform(plan.times[0] - 0.1, plan.times[-1] + 0.5, 30)
    forward = [plan.sample(float(t)) for t in ts]
    twin = DcmPlan(plan.omega, plan.times, plan.zmp, plan.dcm, plan.com)  # nothing cached yet
    for t, state in zip(ts[::-1], forward[::-1], strict=False):
        again = twin.sample(float(t))
        for field in ("position", "velocity", "acceleration", "dcm", "zmp"):
            np.testing.assert_array_equal(getattr(again, field), getattr(state, field))
    state = plan.sample(float(plan.times[-1]) + 1.0)
    assert isinstance(state, ComState)
    for field in ("position", "velocity", "acceleration", "dcm", "zmp"):
        value = getattr(state, field)
        assert value.shape == (2,) and value.dtype == np.float64
        assert not np.shares_memory(value, plan.zmp) and not np.shares_memory(value, plan.com)
    state.zmp[:] = 99.0  # a caller may keep and write what it got
    np.testing.assert_array_equal(plan.sample(float(plan.times[-1]) + 1.0).zmp, plan.zmp[-1])


def test_a_resting_end_stays_at_rest_for_any_pause() -> None:
    """At rest (DCM on the last ZMP) the divergent term is exactly zero, however long the pause."""
    plan = _plan(np.random.default_rng(6))
    for pause in (0.0, 10.0, 1e3, 1e6, np.inf):
        state = plan.sample(float(plan.times[-1] + pause))
        assert np.all(np.isfinite(state.position)), pause
        np.testing.assert_allclose(state.dcm, plan.zmp[-1], atol=1e-12)


@pytest.mark.parametrize("shift", [0.0, 1e-3])
def test_a_diverging_end_grows_with_the_capped_exponential(shift: float) -> None:
    """A DCM off the last ZMP diverges as ``c e^{omega s}``, the exponent capped (finite long after)."""
    plan = _plan(np.random.default_rng(7))
    dcm = plan.dcm.copy()
    dcm[-1, 0] += shift
    diverging = DcmPlan(plan.omega, plan.times, plan.zmp, dcm, plan.com)
    s = 0.5
    x, _, _ = _expected(diverging, float(plan.times[-1] + s))
    np.testing.assert_allclose(diverging.sample(float(plan.times[-1] + s)).position, x, atol=1e-12)
    assert np.all(np.isfinite(diverging.sample(float(plan.times[-1] + 1e6)).position))

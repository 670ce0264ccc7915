"""Walking pattern: the LIPM/DCM solution, the DCM conditions, and the ZMP inside the support polygon."""

from __future__ import annotations

import numpy as np
import pytest

from redundancy_gym.controllers import ControllerError
from redundancy_gym.controllers.walking import DcmPlanner, GaitConfig, WalkingPattern

SOLE_BACK, SOLE_FRONT, SOLE_HALF_WIDTH = -0.095, 0.165, 0.075  # the biped's sole around its sole point [m]
FEET = ([0.025, -0.09, 0.0], [0.025, 0.09, 0.0])


def test_planned_com_obeys_the_lipm_and_the_dcm_ends_at_the_last_zmp() -> None:
    planner = DcmPlanner(0.9)
    times = np.array([0.0, 0.5, 1.3, 1.5, 2.3])
    zmp = np.array([[0.0, 0.0], [0.0, -0.08], [0.05, -0.08], [0.3, 0.08], [0.35, 0.08]])
    plan = planner.plan(times, zmp, [0.0, 0.0])
    assert np.allclose(plan.dcm[-1], zmp[-1])
    w = planner.omega
    h = 1e-4
    for t in np.linspace(0.05, 2.25, 23):
        s = plan.sample(t)
        acc = (plan.sample(t + h).position - 2 * s.position + plan.sample(t - h).position) / h**2
        assert np.allclose(acc, w**2 * (s.position - s.zmp), atol=1e-4)  # xdd = omega^2 (x - r)
        vel = (plan.sample(t + h).position - plan.sample(t - h).position) / (2 * h)
        assert np.allclose(vel, s.velocity, atol=1e-7)
        dcm_rate = (plan.sample(t + h).dcm - plan.sample(t - h).dcm) / (2 * h)
        assert np.allclose(dcm_rate, w * (s.dcm - s.zmp), atol=1e-6)  # xid = omega (xi - r)


def test_start_zmp_starts_the_dcm_at_the_resting_com() -> None:
    planner = DcmPlanner(0.9)
    times = np.array([0.0, 0.4, 1.0, 1.2, 2.0])
    zmp = np.array([[9.0, 9.0], [0.0, 0.08], [0.02, 0.08], [0.3, -0.08], [0.32, -0.08]])
    zmp = planner.start_zmp(times, zmp, [0.01, 0.0])
    plan = planner.plan(times, zmp, [0.01, 0.0])
    assert np.allclose(plan.dcm[0], [0.01, 0.0], atol=1e-12)
    assert np.allclose(plan.sample(0.0).velocity, 0.0, atol=1e-12)


def _inside_support(zmp: np.ndarray, feet: np.ndarray, contact: tuple[bool, bool]) -> float:
    """Signed margin of the ZMP to the support polygon (convex hull of the soles on the ground) [m]."""
    corners = []
    for foot, on in zip(feet, contact, strict=False):
        if on:
            corners += [
                foot[:2] + [dx, dy] for dx in (SOLE_BACK, SOLE_FRONT) for dy in (-SOLE_HALF_WIDTH, SOLE_HALF_WIDTH)
            ]
    pts = np.array(corners)
    hull = _convex_hull(pts)
    margin = np.inf
    for a, b in zip(hull, np.roll(hull, -1, axis=0), strict=False):
        edge = b - a
        normal = np.array([edge[1], -edge[0]]) / np.linalg.norm(edge)  # outward for a counter-clockwise hull
        margin = min(margin, -float(normal @ (zmp - a)))
    return margin


def _cross(a: np.ndarray, b: np.ndarray) -> float:
    return float(a[0] * b[1] - a[1] * b[0])


def _convex_hull(points: np.ndarray) -> np.ndarray:
    pts = sorted(map(tuple, points))

    def half(seq):  # noqa: ANN001, ANN202
        out = []
        for p in seq:
            while len(out) >= 2 and _cross(np.subtract(out[-1], out[-2]), np.subtract(p, out[-2])) <= 0:
                out.pop()
            out.append(p)
        return out

    lower, upper = half(pts), half(reversed(pts))
    return np.array(lower[:-1] + upper[:-1])


@pytest.mark.parametrize("speed", [0.5, 0.7, 0.9])
def test_zmp_stays_inside_the_support_polygon(speed: float) -> None:
    pattern = WalkingPattern(GaitConfig(), FEET[0], FEET[1], [0.025, 0.0], speed)
    worst = np.inf
    for t in np.arange(0.0, 6.0, 0.004):
        s = pattern.sample(t)
        worst = min(worst, _inside_support(s.zmp, s.feet, s.contact))
        assert s.feet[:, 2].min() >= -1e-12
    assert worst > 0.005


def test_dcm_at_each_step_end_is_continuous_across_replanning() -> None:
    """The end-of-step DCM of one plan is where the next plan starts it (the preview converges)."""
    pattern = WalkingPattern(GaitConfig(), FEET[0], FEET[1], [0.025, 0.0], 0.7)
    dt = 0.002
    for k in range(1, 5):
        boundary = pattern.step_start(k)
        before = pattern.sample(boundary - dt)
        after = pattern.sample(boundary)
        # the DCM moves by omega (xi - r) dt at most, plus the preview error ~ e^(-omega T preview)
        assert np.linalg.norm(after.dcm - before.dcm) < 2 * dt * pattern.planner.omega * 0.3 + 1e-4
        assert np.linalg.norm(after.com - before.com) < 0.7 * dt * 1.5


def test_steady_speed_is_the_command_and_bad_input_raises() -> None:
    pattern = WalkingPattern(GaitConfig(), FEET[0], FEET[1], [0.025, 0.0], 0.7)
    a, b = pattern.step_start(4), pattern.step_start(8)
    for t in np.arange(0.0, b + 1e-9, 0.01):
        s = pattern.sample(t)
        if abs(t - a) < 1e-9:
            xa = s.com[0]
    assert (s.com[0] - xa) / (b - a) == pytest.approx(0.7, rel=1e-3)
    with pytest.raises(ControllerError, match="speed"):
        GaitConfig().timing(-1.0)
    with pytest.raises(ControllerError, match="double_support_ratio"):
        GaitConfig(double_support_ratio=1.0)
    # faster than the longest step at the nominal duration: the step gets shorter in time
    length, duration = GaitConfig().timing(0.9)
    assert length == pytest.approx(0.6) and duration == pytest.approx(0.6 / 0.9)


def test_a_new_velocity_moves_only_the_footholds_after_the_current_landing() -> None:
    pattern = WalkingPattern(GaitConfig(), FEET[0], FEET[1], [0.025, 0.0], 0.5)
    t = pattern.step_start(2) + 0.1  # in the swing of step 2, which lands on foothold 4
    before = [pattern.foothold(j) for j in range(8)]
    com = pattern.sample(t).com
    assert pattern.set_velocity(t, 0.3, 0.05)
    after = [pattern.foothold(j) for j in range(8)]
    for j in range(5):
        assert np.array_equal(after[j], before[j])
    duration = pattern.step_duration
    for j in range(5, 8):  # each later step covers the new velocity times the step duration
        assert after[j][0] - after[j - 1][0] == pytest.approx(0.3 * duration, abs=1e-12)
        if j >= 6:  # the same foot, two steps on
            assert after[j][1] - after[j - 2][1] == pytest.approx(2 * 0.05 * duration, abs=1e-12)
    np.testing.assert_allclose(pattern.sample(t).com, com, atol=1e-12)  # the CoM plan continues from here
    np.testing.assert_array_equal(pattern.velocity, [0.3, 0.05])
    assert not pattern.set_velocity(t + 0.01, 0.3, 0.05)  # the same command again changes nothing


def test_a_steady_new_velocity_is_walked() -> None:
    pattern = WalkingPattern(GaitConfig(), FEET[0], FEET[1], [0.025, 0.0], 0.5)
    pattern.set_velocity(1.0, 0.3, -0.05)
    a, b = pattern.step_start(6), pattern.step_start(10)
    for t in np.arange(1.0, b + 1e-9, 0.01):
        s = pattern.sample(t)
        if abs(t - a) < 1e-9:
            start = s.com[:2]
    np.testing.assert_allclose((s.com[:2] - start) / (b - a), [0.3, -0.05], rtol=1e-3, atol=1e-4)


def test_velocities_that_the_gait_cannot_walk_raise() -> None:
    pattern = WalkingPattern(GaitConfig(), FEET[0], FEET[1], [0.025, 0.0], 0.5)
    for forward, lateral in ((-0.1, 0.0), (0.8, 0.0), (0.5, 0.2), (np.nan, 0.0)):
        with pytest.raises(ControllerError, match="forward|lateral"):
            pattern.set_velocity(1.0, forward, lateral)

"""The arm CLIKs on a plant that differs from their model (issue 36): the placement calibration and the latency's
Smith predictor (``policies/plant_compensation.py``) bring the task error back to the nominal plant's."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import redundancy_gym  # noqa: F401  (registers the envs)
from redundancy_gym.policies import PolicyError, make_policy
from redundancy_gym.policies.plant_compensation import DelayCompensation

PLANAR = "redundancy_gym/PlanarReach-v0"
AGRI = "redundancy_gym/AgriReach-v0"


def _episode(env_id: str, seed: int, dynamics: Any, **options: Any) -> tuple[float, dict[str, Any]]:
    """The largest tracking error [m] of one ``clik`` episode and its last info."""
    env = gym.make(env_id, dynamics=dynamics)
    policy = make_policy("clik", env, **options)
    obs, info = env.reset(seed=seed)
    worst, start = 0.0, True
    while True:
        action, _ = policy.predict(obs, episode_start=np.array([start]))
        start = False
        obs, _, terminated, truncated, info = env.step(action)
        worst = max(worst, float(info["tracking_error"]))
        if terminated or truncated:
            env.close()
            return worst, info


def test_delay_compensation_predicts_the_joints_and_the_reference() -> None:
    delay = DelayCompensation(2, 0.01, 3)
    q = np.array([0.1, 0.2, 0.3])
    np.testing.assert_array_equal(delay.predict(q), q)
    delay.sent(np.array([1.0, 0.0, 0.0]))
    delay.sent(np.array([0.0, 2.0, 0.0]))
    np.testing.assert_allclose(delay.predict(q), q + [0.01, 0.02, 0.0])
    delay.sent(np.array([0.0, 0.0, 3.0]))  # the first command has reached the joints: only the last two remain
    np.testing.assert_allclose(delay.predict(q), q + [0.0, 0.02, 0.03])
    # a reference with constant acceleration a: extrapolated exactly over the horizon of 2 periods
    a, v0, p0 = np.array([2.0, -1.0]), np.array([0.5, 0.1]), np.array([1.0, 2.0])
    delay.reset()
    for k in range(3):
        t = 0.01 * k
        target, velocity = delay.reference(p0 + v0 * t + 0.5 * a * t**2, v0 + a * t)
    t = 0.02 + 0.02
    np.testing.assert_allclose(target, p0 + v0 * t + 0.5 * a * t**2, atol=1e-12)
    np.testing.assert_allclose(velocity, v0 + a * t, atol=1e-12)
    none = DelayCompensation(0, 0.01, 3)
    none.sent(np.ones(3))
    np.testing.assert_array_equal(none.predict(q), q)
    assert none.reference(p0, v0) == (p0, v0)


@pytest.mark.parametrize("plant", [0, 1, 3])
def test_the_latency_is_measured_from_rest(plant: int) -> None:
    """A plant at rest whose joints move ``plant`` periods after the first command that moves them: the measured
    latency is a lower bound while waiting, then exactly ``plant``."""
    delay = DelayCompensation(None, 0.01, 2)
    commands = [np.zeros(2), np.array([1e-12, 0.0]), np.array([0.0, 0.2]), np.array([0.1, 0.3])] + [np.ones(2)] * 6
    first = 2  # the first command above round-off
    for i, command in enumerate(commands):
        responded = i >= first + 1 + plant  # the observation before command i shows command i - 1 - plant
        delay.observe(np.array([0.0, 0.15]) if responded else np.array([1e-15, 0.0]))
        if responded:
            assert delay.latency == plant and delay.idle == (plant == 0)
        elif i > first:
            assert delay.latency == i - first  # the periods waited so far
        delay.sent(command)
    assert delay.latency == plant
    delay.reset()
    assert delay.latency == 0 and not delay.idle
    # a second predict on the same observation (its time did not advance) measures nothing and replaces the command
    again = DelayCompensation(None, 0.01, 2)
    for time in (0.0, 0.0, 0.01, 0.01, 0.02):
        again.observe(np.zeros(2), time)
        again.sent(np.array([0.0, 0.2]))
    assert again.latency == 2  # a lower bound of two periods since the first command (not four calls)
    np.testing.assert_allclose(again.predict(np.zeros(2)), [0.0, 0.004])
    moving = DelayCompensation(None, 0.01, 2)  # moving before any command: nothing to measure, no compensation
    moving.observe(np.array([0.5, 0.0]))
    assert moving.idle


def test_planar_calibration_tracks_a_displaced_robot() -> None:
    """A base displaced by up to 2 cm: the calibrated CLIK tracks the line within the env's 1 mm, the uncalibrated
    one is off by about the displacement."""
    calibrated, info = _episode(PLANAR, 3, {"placement": 0.02})
    shift = float(
        np.linalg.norm(
            np.asarray(gym.make(PLANAR, dynamics={"placement": 0.02}).reset(seed=3)[1]["dynamics"]["placement"])[[0, 2]]
        )
    )
    uncalibrated, _ = _episode(PLANAR, 3, {"placement": 0.02}, base_calibration=False)
    assert calibrated < 1e-3 and info["is_success"]
    assert uncalibrated > 0.5 * shift > 2e-3


def test_planar_latency_compensation_recovers_the_nominal_tracking() -> None:
    nominal, _ = _episode(PLANAR, 0, None)
    late, _ = _episode(PLANAR, 0, {"latency": 2}, latency=0)
    measured, info = _episode(PLANAR, 0, {"latency": 2})
    told, _ = _episode(PLANAR, 0, {"latency": 2}, latency=2)
    assert late > 1.5e-3 > 1e-3 > measured  # the env's success tolerance is 1 mm
    assert measured < 1.5 * nominal and info["is_success"]
    assert told == pytest.approx(measured, rel=0.05)  # measured from rest, the latency is known after 3 periods
    assert _episode(PLANAR, 0, None, latency=0)[0] == nominal  # nothing to measure on the nominal plant


def test_agri_calibration_and_latency_reach_the_grasp() -> None:
    """AgriReach with the base 2 cm off and two periods of latency: the CLIK, calibrated and measuring the latency,
    reaches the grasp pose (TCP within the env's tolerance, tool axis aligned); uncalibrated it ends as far off as
    the base."""
    dynamics = {"placement": 0.02, "latency": 2}
    _, info = _episode(AGRI, 1, dynamics)
    assert info["is_success"] and not info["collision"]
    _, off = _episode(AGRI, 1, dynamics, base_calibration=False)
    assert not off["is_success"] and off["goal_error"] > 5e-3


@pytest.mark.parametrize("env_id", [PLANAR, AGRI])
def test_calibration_is_round_off_on_the_nominal_plant(env_id: str) -> None:
    env = gym.make(env_id)
    policy = make_policy("clik", env)
    obs, _ = env.reset(seed=0)
    policy.predict(obs, episode_start=np.array([True]))
    plain = make_policy("clik", env, base_calibration=False)
    a, _ = policy.predict(obs, episode_start=np.array([True]))
    b, _ = plain.predict(obs, episode_start=np.array([True]))
    np.testing.assert_allclose(a, b, atol=1e-9)
    offset = getattr(policy, "_offset", None)
    if offset is not None:
        assert np.abs(offset).max() < 1e-12


@pytest.mark.parametrize(
    ("options", "match"),
    [
        ({"latency": 11}, r"latency must be None or an int in \[0, 10\]"),
        ({"latency": 0.5}, "latency must be None or an int"),
        ({"base_calibration": "yes"}, "base_calibration must be a bool"),
    ],
)
@pytest.mark.parametrize("env_id", [PLANAR, AGRI])
def test_bad_compensation_options_raise(env_id: str, options: dict[str, Any], match: str) -> None:
    with pytest.raises(PolicyError, match=match):
        make_policy("clik", gym.make(env_id), **options)

"""Hard cases of predictive IK (monograph 5.6) and its policies: a target at the start, horizons of one sample and
of 20 s, unreachable references, non-finite inputs; every result finite, with its status and diagnostics."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import redundancy_gym
from redundancy_gym.assets import PLANAR_ARM_TCP, PLANAR_ARM_XML
from redundancy_gym.controllers import (
    ControllerError,
    FramePositionTask,
    JointLimitObjective,
    PredictiveIk,
)
from redundancy_gym.controllers.predictive.receding_horizon import RecedingHorizon
from redundancy_gym.model import RobotModel
from redundancy_gym.policies import PolicyError

from ..controllers.predictive.test_predictive_ik import _planar

DT = 0.01


@pytest.fixture(scope="module")
def planar():
    return _planar()


def _tcp(pik: PredictiveIk, q: np.ndarray) -> np.ndarray:
    pik.model.update(q)
    return pik.model.frame_position(PLANAR_ARM_TCP)[[0, 2]]


def test_target_at_the_start_gives_no_motion(planar) -> None:
    """Zero task velocity from a posture away from the limits and the obstacle: the optimum is to stay, the cost 0,
    and the CLIK command at the TCP's own position is zero to round-off."""
    pik, q0, _ = planar
    result = pik.optimize(q0, np.zeros((50, 6)), DT, np.zeros((50, 4)), max_iterations=10)
    assert result.success and result.status == "converged" and result.iterations == 0
    assert result.rollout.cost == 0.0 and set(result.rollout.terms) >= {"velocity", "joint_limits", "collision"}
    np.testing.assert_array_equal(result.rollout.q, np.tile(q0, (51, 1)))
    qdot, error = pik.command(q0, np.zeros(4), _tcp(pik, q0), np.zeros(2), 10.0)
    assert np.max(np.abs(qdot)) < 1e-14 and np.max(np.abs(error)) < 1e-15


def test_horizon_of_one_sample(planar) -> None:
    pik, q0, wdot = planar
    result = pik.optimize(q0, wdot[100:101], DT, np.zeros((1, 4)), max_iterations=5)
    assert result.success and result.params.shape == (1, 4) and result.rollout.q.shape == (2, 4)
    assert np.all(np.isfinite(result.rollout.q)) and len(result.costs) == result.iterations + 1
    # the line search never raises the cost
    assert all(b <= a for a, b in zip(result.costs, result.costs[1:], strict=False))
    horizon = RecedingHorizon(pik, 1, DT)
    update = horizon.update(q0, wdot[100:101])
    assert update.u.shape == (4,) and np.all(np.isfinite(update.u)) and update.seconds >= 0.0
    assert np.all(np.isfinite(horizon.input_at(0.5 * DT)))


def test_long_horizon_of_2000_samples_stays_finite(planar) -> None:
    """20 s of a constant 0.2 m/s downwards: the TCP is driven past its reach and through singular postures; the
    prediction (damped pseudoinverse) and its cost stay finite and each iteration's cost does not rise."""
    pik, q0, _ = planar
    wdot = np.tile([0.0, -0.2, 0.0, 0.0, 0.0, 0.0], (2000, 1))
    with np.errstate(over="ignore"):  # the Hamiltonian's squared norm may overflow: it only sets beta
        result = pik.optimize(q0, wdot, DT, np.zeros((2000, 4)), max_iterations=3)
    assert result.success and np.all(np.isfinite(result.rollout.q)) and np.isfinite(result.rollout.cost)
    assert all(b <= a for a, b in zip(result.costs, result.costs[1:], strict=False))
    assert result.status in ("converged", "max_iterations", "no_decrease")


def test_unreachable_target_command_is_finite_and_within_the_damped_bound(planar) -> None:
    """A target 7 m away: ``|J# v| <= |v| / (2 sqrt(rho))`` for the damped pseudoinverse, whatever the posture."""
    pik, q0, _ = planar
    q = q0.copy()
    for _ in range(300):  # a kinematic closed loop towards it
        qdot, error = pik.command(q, np.zeros(4), [5.0, 5.0], np.zeros(2), 10.0)
        assert np.all(np.isfinite(qdot)) and np.all(np.isfinite(error))
        assert np.linalg.norm(qdot) <= 10.0 * np.linalg.norm(error) / (2.0 * np.sqrt(pik.damping)) * (1 + 1e-9)
        q = q + DT * np.clip(qdot, -3.0, 3.0)
    assert np.linalg.norm(error) < np.linalg.norm(np.array([5.0, 5.0]) - _tcp(pik, q0))


@pytest.mark.parametrize("argument", ["q0", "wdot", "initial", "u_b"])
def test_non_finite_optimize_input_raises(planar, argument: str) -> None:
    pik, q0, _ = planar
    augmented = PredictiveIk(pik.model, pik.task, joint_limits=pik.joint_limits, augmented=True)
    args = {"q0": q0, "wdot": np.zeros((5, 6)), "initial": np.zeros((5, 4)), "u_b": np.zeros(4)}
    args[argument] = np.full_like(args[argument], np.nan)
    with pytest.raises(ControllerError, match="finite"):
        augmented.optimize(args["q0"], args["wdot"], DT, args["initial"], u_b=args["u_b"])


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"dt": np.nan}, "dt"),
        ({"dt": 0.0}, "dt"),
        ({"max_iterations": -1}, "max_iterations"),
        ({"max_iterations": 2.5}, "max_iterations"),
        ({"method": "newton"}, "newton"),
        ({"step": 0.0}, "step"),
        ({"tolerance": np.nan}, "tolerance"),
    ],
)
def test_bad_optimize_options_raise_naming_them(planar, kwargs: dict, match: str) -> None:
    pik, q0, _ = planar
    args = {"dt": DT, **kwargs}
    dt = args.pop("dt")
    with pytest.raises(ControllerError, match=match):
        pik.optimize(q0, np.zeros((5, 6)), dt, np.zeros((5, 4)), **args)


@pytest.mark.parametrize("target, velocity", [([np.nan, 0.0], [0.0, 0.0]), ([0.5, 0.0], [np.inf, 0.0])])
def test_non_finite_command_target_raises(planar, target: list, velocity: list) -> None:
    pik, q0, _ = planar
    with pytest.raises(ControllerError, match="must be finite"):
        pik.command(q0, np.zeros(4), target, velocity, 10.0)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"velocity_weight": -1.0}, "velocity_weight"),
        ({"damping": np.nan}, "damping"),
        ({"input_weight": np.inf}, "input_weight"),
        ({"damping": "1e-6"}, "damping"),
    ],
)
def test_bad_constructor_arguments_raise_naming_them(kwargs: dict, match: str) -> None:
    model = RobotModel.from_mjcf(PLANAR_ARM_XML)
    with pytest.raises(ControllerError, match=match):
        PredictiveIk(model, FramePositionTask(PLANAR_ARM_TCP, "xz"), **kwargs)


def test_joint_limit_objective_of_another_robot_is_rejected() -> None:
    model = RobotModel.from_mjcf(PLANAR_ARM_XML)
    limits = JointLimitObjective(np.zeros(3), np.ones(3))
    with pytest.raises(ControllerError, match="joint-limit objective has 3 joints"):
        PredictiveIk(model, FramePositionTask(PLANAR_ARM_TCP, "xz"), joint_limits=limits)


def test_unreachable_line_is_rejected_by_the_env_naming_the_reach() -> None:
    from redundancy_gym.envs import EnvConfigError

    with pytest.raises(EnvConfigError, match="line_start .* outside the arm's reach of 1.4 m"):
        gym.make("redundancy_gym/PlanarReach-v0", line_start=(2.5, 0.45), line_end=(2.5, -0.45))


def test_predictive_policy_on_a_line_at_the_edge_of_the_reach_keeps_its_actions_finite_and_bounded() -> None:
    """PlanarReach with the line 1.3 m out, its ends 1.376 m from the shoulder (the arm reaches 1.4 m: nearly
    stretched, near the singularity): a whole episode of the ``predictive`` policy gives finite actions inside the
    action box and finite observations."""
    env = gym.make("redundancy_gym/PlanarReach-v0", line_start=(1.3, 0.45), line_end=(1.3, -0.45), obstacle=False)
    try:
        obs, _ = env.reset(seed=0)
        policy = redundancy_gym.make_policy("predictive", env, horizon=0.2)
        assert env.spec is not None and env.spec.max_episode_steps is not None  # registered with a time limit
        for _ in range(env.spec.max_episode_steps):
            action, _ = policy.predict(obs)
            assert np.all(np.isfinite(action)) and np.all(np.abs(action) <= 1.0)
            obs, reward, terminated, truncated, _ = env.step(action)
            assert np.all(np.isfinite(obs)) and np.isfinite(float(reward))
            if terminated or truncated:
                break
        assert policy.last_update is not None and policy.last_update.result.success
    finally:
        env.close()


@pytest.mark.parametrize(
    "kwargs, match",
    [({"horizon": np.inf}, "horizon"), ({"iterations": -1}, "iterations"), ({"sample_time": 0.0}, "sample_time")],
)
def test_predictive_policy_bad_options_raise_naming_them(kwargs: dict, match: str) -> None:
    env = gym.make("redundancy_gym/PlanarReach-v0")
    try:
        with pytest.raises(PolicyError, match=match):
            redundancy_gym.make_policy("predictive", env, **kwargs)
    finally:
        env.close()

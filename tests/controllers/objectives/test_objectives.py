import numpy as np
import pytest

from redundancy_gym.controllers import ControllerError, JointLimitObjective, Objective, PostureObjective


def _fd_gradient(objective, q: np.ndarray, h: float = 1e-7) -> np.ndarray:
    grad = np.zeros_like(q)
    for i in range(q.size):
        dq = np.zeros_like(q)
        dq[i] = h
        grad[i] = (objective.evaluate(None, q + dq).value - objective.evaluate(None, q - dq).value) / (2 * h)
    return grad


def test_joint_limit_gradient_matches_finite_differences(rng) -> None:
    lower, upper = -np.ones(4), np.ones(4)
    jl = JointLimitObjective(lower, upper, activation_distance=0.4, slope=2.0, weight=1.5)
    assert isinstance(jl, Objective)
    for _ in range(30):
        q = rng.uniform(-1.1, 1.1, 4)
        assert np.allclose(jl.evaluate(None, q).gradient, _fd_gradient(jl, q), atol=1e-5)


def test_joint_limit_zero_far_from_limits_and_pushes_inward() -> None:
    jl = JointLimitObjective(-np.ones(2), np.ones(2), activation_distance=0.3)
    value, grad = jl.evaluate(None, np.array([0.5, -0.6]))
    assert value == 0.0 and np.all(grad == 0.0)
    value, grad = jl.evaluate(None, np.array([0.95, -0.95]))
    assert value > 0 and grad[0] > 0 and grad[1] < 0  # descent -grad moves away from the limits
    assert np.allclose(jl.margins(np.array([0.95, -0.9])), [0.05, 0.1])


def test_posture_gradient(rng) -> None:
    po = PostureObjective(rng.normal(size=4), rng.uniform(0.1, 2.0, 4))
    q = rng.normal(size=4)
    assert np.allclose(po.evaluate(None, q).gradient, _fd_gradient(po, q), atol=1e-6)
    assert po.evaluate(None, po.reference).value == 0.0


def test_invalid_objective_arguments() -> None:
    with pytest.raises(ControllerError):
        JointLimitObjective(np.ones(2), np.zeros(2))
    with pytest.raises(ControllerError):
        JointLimitObjective(np.zeros(2), np.ones(2), weight=-1.0)
    with pytest.raises(ControllerError):
        PostureObjective(np.zeros(3), -1.0)

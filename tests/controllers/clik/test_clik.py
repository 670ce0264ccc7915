import numpy as np
import pytest

from redundancy_gym.assets import PLANAR_ARM_TCP
from redundancy_gym.controllers import (
    AccelerationClik,
    Clik,
    ControllerError,
    FramePositionTask,
    JointLimitObjective,
    WeightMatrix,
    resolve,
)
from redundancy_gym.model import RobotModel

REACH = 1.4


def _task() -> FramePositionTask:
    return FramePositionTask(PLANAR_ARM_TCP, "xz")


def _jacobian(model: RobotModel, q: np.ndarray) -> np.ndarray:
    model.update(q)
    return _task().jacobian(model)


def _run(clik: Clik, model: RobotModel, q: np.ndarray, target: np.ndarray, steps: int, dt: float = 0.01):
    results = []
    for _ in range(steps):
        res = clik.step(q, target, np.zeros(2))
        results.append(res)
        q = model.integrate(q, res.qdot, dt)
    return q, results


@pytest.mark.parametrize("weights", ["identity", "diagonal", "full"])
def test_nullspace_projection_is_in_the_jacobian_nullspace(planar_model: RobotModel, rng, weights: str) -> None:
    """J N_W x = 0 (5.17): with zero task velocity the solve returns -N_W W^-1 z."""
    W = {"identity": 1.0, "diagonal": rng.uniform(0.5, 2.0, 4), "full": None}[weights]
    if W is None:
        a = rng.normal(size=(4, 4))
        W = a @ a.T + 4 * np.eye(4)
    for _ in range(20):
        J = _jacobian(planar_model, rng.uniform(-2, 2, 4))
        x = rng.normal(size=4)
        res = resolve(J, np.zeros(2), x, WeightMatrix(W, 4))
        assert res.success
        assert np.linalg.norm(J @ res.x) < 1e-12 * max(1.0, float(np.linalg.norm(x)))
        assert np.linalg.norm(res.x) > 1e-6  # the projection is not trivially zero


def test_algorithm_10_equals_closed_form(planar_model: RobotModel, rng) -> None:
    """Algorithm 10 (no pseudoinverse) equals (5.14)-(5.16) with an explicit weighted pseudoinverse."""
    Wd = rng.uniform(0.5, 2.0, 4)
    W = np.diag(Wd)
    Winv = np.linalg.inv(W)
    for _ in range(20):
        J = _jacobian(planar_model, rng.uniform(-2, 2, 4))
        wdot = rng.normal(size=2)
        grad = rng.normal(size=4)
        alpha = 0.7
        pinv = Winv @ J.T @ np.linalg.inv(J @ Winv @ J.T)  # (5.15)
        N = np.eye(4) - pinv @ J  # (5.16)
        expected = pinv @ wdot - alpha * N @ Winv @ grad  # (5.14)
        res = resolve(J, wdot, alpha * grad, WeightMatrix(Wd, 4))
        assert np.allclose(res.x, expected, atol=1e-12)
        assert np.allclose(J @ res.x, wdot, atol=1e-12)


def test_clik_converges_to_reachable_static_target(planar_model: RobotModel) -> None:
    q0 = np.array([-1.2, 0.9, 0.8, 0.5])
    target = np.array([0.7, -0.3])
    jl = JointLimitObjective.from_model(planar_model)
    for method in ("pseudoinverse", "dls"):
        clik = Clik(planar_model, _task(), method=method, gain=20.0, objectives=[jl])
        q, results = _run(clik, planar_model, q0, target, 300)
        planar_model.update(q)
        assert np.linalg.norm(_task().error(planar_model, target)) < 1e-6
        assert all(r.success for r in results)


def test_transposed_jacobian_converges_static(planar_model: RobotModel) -> None:
    """(5.24) is Lyapunov stable for a static target: the error decreases to zero."""
    clik = Clik(planar_model, _task(), method="transpose", gain=5.0)
    q, results = _run(clik, planar_model, np.array([-1.2, 0.9, 0.8, 0.5]), np.array([0.8, 0.1]), 3000)
    errors = np.array([r.error_norm for r in results])
    assert errors[-1] < 1e-4
    assert np.all(np.diff(errors) <= 1e-12)


def test_nullspace_objective_keeps_task_and_lowers_potential(planar_model: RobotModel) -> None:
    """Joint-limit descent in the nullspace: same TCP, lower potential than without the objective."""
    q0 = np.array([-2.4, 2.2, 0.5, 0.3])  # joints 1 and 2 close to their limits
    planar_model.update(q0)
    target = _task().value(planar_model)
    jl = JointLimitObjective.from_model(planar_model, activation_distance=0.5)
    with_obj = Clik(planar_model, _task(), objectives=[jl], nullspace_gain=2.0)
    q, _ = _run(with_obj, planar_model, q0, target, 200)
    planar_model.update(q)
    assert np.linalg.norm(_task().error(planar_model, target)) < 1e-6
    assert jl.evaluate(None, q).value < 0.2 * jl.evaluate(None, q0).value


def test_stretched_arm_pseudoinverse_reports_singularity(planar_model: RobotModel) -> None:
    """q = 0 stretches the arm along x: J loses rank; the exact solve says so instead of returning NaN."""
    clik = Clik(planar_model, _task(), method="pseudoinverse")
    res = clik.step(np.zeros(4), np.array([1.3, 0.0]), np.zeros(2))
    assert not res.success and res.status == "singular"
    assert res.sigma_min < 1e-9
    assert np.all(np.isfinite(res.qdot)) and np.all(res.qdot == 0.0)


def test_stretched_arm_dls_finite_and_bounded(planar_model: RobotModel) -> None:
    clik = Clik(planar_model, _task(), method="dls", gain=10.0, dls_threshold=0.05, dls_max_damping=0.01)
    target = np.array([1.3, 0.05])  # pulls in along the singular direction and sideways
    res = clik.step(np.zeros(4), target, np.zeros(2))
    assert res.success and res.status == "damped" and res.damping == pytest.approx(0.01)
    # |qdot| <= |v| / (2 sqrt(k)) for the damped inverse J^T (J J^T + k I)^-1
    v = 10.0 * np.linalg.norm(target - np.array([1.4, 0.0]))
    assert np.all(np.isfinite(res.qdot)) and np.linalg.norm(res.qdot) <= v / (2 * np.sqrt(0.01)) + 1e-12


def test_unreachable_target_dls_stays_finite_and_approaches_boundary(planar_model: RobotModel) -> None:
    """|target| = 2.06 m > reach: the arm stretches towards it; DLS keeps |qdot| <= K |e| / eps at every step."""
    target = np.array([2.0, 0.5])
    gain, eps = 2.0, 0.05
    clik = Clik(planar_model, _task(), method="dls", gain=gain, dls_threshold=eps, dls_max_damping=0.01)
    q, results = _run(clik, planar_model, np.array([-0.8, 0.6, 0.5, 0.3]), target, 1500)
    for r in results:
        assert np.all(np.isfinite(r.qdot))
        assert np.linalg.norm(r.qdot) <= gain * r.error_norm / eps * (1 + 1e-9)
    planar_model.update(q)
    gap = np.linalg.norm(target) - REACH
    assert np.linalg.norm(_task().error(planar_model, target)) < gap + 1e-3  # as close as the reach allows
    assert results[-1].status == "damped" and results[-1].sigma_min < eps


def test_unreachable_target_pseudoinverse_reports_instead_of_nan(planar_model: RobotModel) -> None:
    """Without speed limits the exact solve stretches the arm into the singularity and says so (with the
    model's speed limits it slows down before it gets there: tests/hard_cases/test_clik_bounds.py)."""
    target = np.array([2.0, 0.5])
    clik = Clik(
        planar_model,
        _task(),
        method="pseudoinverse",
        gain=2.0,
        singular_threshold=1e-3,
        max_joint_velocity=np.inf,
        period=0.01,
    )
    q, results = _run(clik, planar_model, np.array([-0.8, 0.6, 0.5, 0.3]), target, 1500)
    assert all(np.all(np.isfinite(r.qdot)) for r in results)
    singular = [r for r in results if not r.success]
    assert singular and all(r.status == "singular" and r.sigma_min < 1e-3 for r in singular)


def test_target_on_workspace_boundary(planar_model: RobotModel) -> None:
    """A target at exactly full reach: DLS gets there within the damping's bias, finite throughout."""
    target = REACH * np.array([np.cos(0.3), -np.sin(0.3)])
    clik = Clik(planar_model, _task(), method="dls", gain=10.0)
    q, results = _run(clik, planar_model, np.array([0.1, 0.4, 0.3, 0.2]), target, 1500)
    assert all(np.all(np.isfinite(r.qdot)) for r in results)
    assert max(np.linalg.norm(r.qdot) for r in results) < 20.0
    planar_model.update(q)
    assert np.linalg.norm(_task().error(planar_model, target)) < 2e-3


def test_acceleration_level_solves_5_18_and_converges(planar_model: RobotModel, rng) -> None:
    task = _task()
    clik = AccelerationClik(planar_model, task, stiffness=100.0, damping=20.0)
    q = np.array([-1.2, 0.9, 0.8, 0.5])
    qdot = rng.normal(scale=0.3, size=4)
    target = np.array([0.75, -0.2])
    res = clik.step(q, qdot, target, np.zeros(2), np.zeros(2))
    drift = planar_model.frame_jacobian_derivative_times_velocity(q, qdot, PLANAR_ARM_TCP, "translational")[[0, 2]]
    planar_model.update(q)
    J = task.jacobian(planar_model)
    commanded = 20.0 * (0.0 - J @ qdot) + 100.0 * (target - task.value(planar_model))  # (5.19)
    assert np.allclose(J @ res.qddot + drift, commanded, atol=1e-10)  # (5.18)
    dt = 0.002
    for _ in range(2000):
        res = clik.step(q, qdot, target, np.zeros(2), np.zeros(2))
        qdot = qdot + dt * res.qddot
        q = q + dt * qdot
    planar_model.update(q)
    assert np.linalg.norm(task.error(planar_model, target)) < 1e-6
    assert np.linalg.norm(qdot) < 1e-4  # self-motion damped too


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(method="svd"), "pseudoinverse, dls, transpose"),
        (dict(gain=-1.0), "gain"),
        (dict(weights=np.zeros(4)), "weights"),
        (dict(nullspace_gain=np.nan), "nullspace_gain"),
        (dict(objectives=[object()]), "evaluate"),
    ],
)
def test_invalid_arguments(planar_model: RobotModel, kwargs: dict, match: str) -> None:
    with pytest.raises(ControllerError, match=match):
        Clik(planar_model, _task(), **kwargs)


def test_invalid_task_axes() -> None:
    with pytest.raises(ControllerError, match="xyz"):
        FramePositionTask("tcp", "xw")

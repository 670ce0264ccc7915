"""CompiledWholeBodyIk against WholeBodyIk (round-off), self-collision avoidance in the nullspace, hard cases."""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin
import pytest

from redundancy_gym.assets import BIPED_XML
from redundancy_gym.controllers import CollisionObjective, ControllerError, PostureObjective
from redundancy_gym.controllers.kernels.linalg import rotation_error
from redundancy_gym.controllers.walking import CompiledWholeBodyIk, WalkingIkConfig, WholeBodyIk, WholeBodyReference
from redundancy_gym.model import ModelError, RobotModel, collision_model_from_mjcf

from .biped_helpers import standing, walking_controller


@pytest.fixture(scope="module")
def model() -> RobotModel:
    return RobotModel.from_mjcf(BIPED_XML)


def _hold(model: RobotModel, q: np.ndarray, com_lift: float = 0.0) -> WholeBodyReference:
    """Keep the soles and the torso where they are at ``q`` and the CoM ``com_lift`` [m] higher."""
    model.update(q)
    feet = np.array([model.frame_position(f) for f in ("r_sole", "l_sole")])
    rotations = np.array([model.frame_rotation(f) for f in ("r_sole", "l_sole")])
    return WholeBodyReference(
        model.com() + [0.0, 0.0, com_lift],
        np.zeros(3),
        feet,
        rotations,
        np.zeros((2, 6)),
        model.frame_rotation("imu"),
        np.zeros(3),
    )


@pytest.mark.parametrize("momentum", [True, False], ids=("W_5_62", "W_identity"))
def test_compiled_step_equals_python_step_while_walking(model: RobotModel, momentum: bool) -> None:
    controller = walking_controller(model, momentum_minimization=momentum, backend="python")
    controller.start(standing(model), 0.7)
    ik, pattern = controller.ik, controller.pattern
    assert ik is not None
    assert any(isinstance(o, CollisionObjective) for o in ik.objectives)
    compiled = CompiledWholeBodyIk(ik)
    q = controller.q_ref
    assert q is not None
    start = controller._reference(pattern.sample(0.0), np.zeros(2), np.zeros(2))
    near = False
    for k in range(int(round(pattern.step_start(2) / controller.dt))):
        end = controller._reference(pattern.sample((k + 1) * controller.dt), np.zeros(2), np.zeros(2))
        expected, result = ik.step(q, start, end, controller.dt), compiled.step(q, start, end, controller.dt)
        np.testing.assert_allclose(result.q, expected.q, rtol=0.0, atol=1e-12)
        np.testing.assert_allclose(result.qdot, expected.qdot, rtol=1e-9, atol=1e-10)
        assert result.task_error == pytest.approx(expected.task_error, rel=1e-6, abs=1e-12)
        assert result.lz == pytest.approx(expected.lz, rel=1e-9, abs=1e-12)
        assert result.sigma_min == pytest.approx(expected.sigma_min, rel=1e-9)
        assert result.success == expected.success and result.limited == expected.limited
        near = near or compiled.last_min_distance < controller.ik_config.self_collision_activation
        q, start = expected.q, end
    assert near  # the self-collision term was active, so its gradient was compared too


def test_self_collision_gradient_matches_finite_differences_on_the_floating_base(model: RobotModel) -> None:
    objective = CollisionObjective(collision_model_from_mjcf(model), activation_distance=0.05, slope=10.0)
    rng = np.random.default_rng(5)
    q = standing(model, r_shoulder_roll=-0.06, l_shoulder_roll=0.06)
    q[3:7] = rng.normal(size=4)
    q[3:7] /= np.linalg.norm(q[3:7])
    model.update(q)
    value, gradient = objective.evaluate(model, q)
    assert value > 0.0
    assert np.allclose(gradient[:6], 0.0, atol=1e-12)  # a rigid motion of the whole robot changes no distance
    eps = 1e-6
    for k in range(model.nv):
        dv = np.zeros(model.nv)
        dv[k] = eps
        ends = []
        for sign in (1.0, -1.0):
            qk = model.integrate(q, sign * dv, 1.0)
            model.update(qk)
            ends.append(objective.evaluate(model, qk).value)
        assert (ends[0] - ends[1]) / (2 * eps) == pytest.approx(gradient[k], abs=1e-6)


def test_self_collision_avoidance_opens_the_closest_pair_in_the_nullspace(model: RobotModel) -> None:
    """Arms pressed against the torso (13 mm): with only the self-collision objective in the nullspace the
    clearance grows towards ``d_a`` while every task holds; without it the arms stay where they are."""
    q0 = standing(model, r_shoulder_roll=-0.06, l_shoulder_roll=0.06)
    reference = _hold(model, q0)
    collision_model = collision_model_from_mjcf(model)
    clearance = {}
    for weight in (0.0, 1.0):
        objectives = (CollisionObjective(collision_model, activation_distance=0.04, slope=10.0, weight=weight),)
        ik = WholeBodyIk(model, objectives=objectives, beta=10.0)
        compiled = CompiledWholeBodyIk(ik)
        q = q0.copy()
        for _ in range(500):
            result = compiled.step(q, reference, reference, 0.004)
            assert result.success
            q = result.q
            _, error, _ = ik.build(q, reference)  # after the Newton correction
            assert np.max(np.abs(error)) < 1e-8
        clearance[weight] = float(np.min(collision_model.evaluate(model).distance))
    model.update(q0)
    before = float(np.min(collision_model.evaluate(model).distance))
    assert before < 0.015
    assert clearance[0.0] == pytest.approx(before, abs=1e-6)
    assert clearance[1.0] > before + 0.01


def test_unreachable_com_on_stretched_legs_stays_bounded(model: RobotModel) -> None:
    """Hard case: knees straight and the CoM 5 cm above reach. The weighted pseudoinverse would ask for about
    14000 rad/s; both backends bound the step to ``max_velocity`` and agree."""
    q = standing(model, r_hip_pitch=0.0, r_knee=0.0, r_ankle_pitch=0.0, l_hip_pitch=0.0, l_knee=0.0, l_ankle_pitch=0.0)
    reference = _hold(model, q, com_lift=0.05)
    ik = WholeBodyIk(model)
    for solver in (ik, CompiledWholeBodyIk(ik)):
        result = solver.step(q, reference, reference, 0.004)
        assert result.success and result.limited
        assert np.all(np.isfinite(result.q))
        assert np.max(np.abs(result.qdot)) == pytest.approx(ik.max_velocity)
        assert np.max(np.abs(model.difference(q, result.q))) <= 2.0 * ik.max_velocity * 0.004 + 1e-12
    np.testing.assert_allclose(
        CompiledWholeBodyIk(ik).step(q, reference, reference, 0.004).q,
        ik.step(q, reference, reference, 0.004).q,
        atol=1e-10,
    )


def test_compiled_ik_rejects_what_it_cannot_compile_and_bad_inputs(model: RobotModel) -> None:
    with pytest.raises(ControllerError, match="ActuatedObjective"):
        CompiledWholeBodyIk(WholeBodyIk(model, objectives=(PostureObjective(np.zeros(model.nq)),)))
    with pytest.raises(ControllerError, match="WholeBodyIk"):
        CompiledWholeBodyIk(object())  # type: ignore[arg-type]
    with pytest.raises(ControllerError, match="backend"):
        WalkingIkConfig(backend="fortran")
    compiled = CompiledWholeBodyIk(WholeBodyIk(model))
    q = standing(model)
    reference = _hold(model, q)
    with pytest.raises(ModelError, match="non-finite"):
        compiled.step(np.full(model.nq, np.nan), reference, reference, 0.004)
    with pytest.raises(ModelError, match="shape"):
        compiled.step(q[:-1], reference, reference, 0.004)
    bad = dataclasses.replace(reference, com=np.array([np.nan, 0.0, 0.0]))
    with pytest.raises(ControllerError, match="finite"):
        compiled.step(q, reference, bad, 0.004)
    with pytest.raises(ControllerError, match="dt"):
        compiled.step(q, reference, reference, 0.0)


def test_rotation_error_is_log3(model: RobotModel) -> None:
    rng = np.random.default_rng(2)
    for angle in (0.0, 1e-8, 0.3, 2.0, np.pi - 1e-8, np.pi):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        desired = pin.exp3(rng.normal(size=3))
        actual = pin.exp3(-angle * axis) @ desired  # R_d R^T = exp(angle axis)
        error = rotation_error(desired, actual)
        expected = angle * axis
        if angle > np.pi - 1e-6:  # +-axis are the same half turn
            assert min(np.linalg.norm(error - expected), np.linalg.norm(error + expected)) < 1e-6
        else:
            np.testing.assert_allclose(error, expected, atol=1e-9)


def test_packed_reference_round_trip_and_controller_packing(model: RobotModel) -> None:
    controller = walking_controller(model)
    controller.start(standing(model), 0.7)
    sample = controller.pattern.sample(1.234)  # mid-swing: a pitched foot with a pitch rate
    offset, rate = np.array([0.01, -0.02]), np.array([0.1, 0.2])
    packed = controller._reference_array(sample, offset, rate)
    reference = WholeBodyReference.from_array(packed)
    np.testing.assert_array_equal(reference.to_array(), packed)
    np.testing.assert_allclose(reference.com[:2], sample.com[:2] + offset)
    np.testing.assert_allclose(reference.com_velocity[:2], sample.com_velocity[:2] + rate)
    np.testing.assert_array_equal(reference.feet_position, sample.feet)
    for i in range(2):
        np.testing.assert_allclose(
            reference.feet_rotation[i], pin.utils.rpyToMatrix(0.0, sample.feet_pitch[i], 0.0), atol=1e-15
        )
        np.testing.assert_array_equal(
            reference.feet_velocity[i], [*sample.feet_velocity[i], 0.0, sample.feet_pitch_rate[i], 0.0]
        )
    assert np.any(sample.feet_pitch != 0.0)
    with pytest.raises(ControllerError, match="shape"):
        WholeBodyReference.from_array(np.zeros(5))


def test_packed_references_give_the_same_step_and_results_are_the_callers(model: RobotModel) -> None:
    """References packed by :meth:`WholeBodyReference.to_array` go to the same kernel inputs (start, then end);
    the next step does not write into a result already returned."""
    compiled = CompiledWholeBodyIk(WholeBodyIk(model))
    q = standing(model)
    start, end = _hold(model, q), _hold(model, q, com_lift=-0.01)
    first = compiled.step(q, start, end, 0.004)
    packed = compiled.step(q, start.to_array(), end.to_array(), 0.004)
    np.testing.assert_array_equal(packed.q, first.q)
    np.testing.assert_array_equal(packed.qdot, first.qdot)
    assert packed[2:] == first[2:]
    swapped = compiled.step(q, end.to_array(), start.to_array(), 0.004)
    assert not np.array_equal(swapped.q, first.q)  # start and end are not interchangeable inputs
    kept = first.q.copy(), first.qdot.copy()
    compiled.step(first.q, end, _hold(model, q, com_lift=-0.02), 0.004)
    np.testing.assert_array_equal(first.q, kept[0])
    np.testing.assert_array_equal(first.qdot, kept[1])
    with pytest.raises(ControllerError, match=r"packed reference has shape \(54,\), got \(53,\)"):
        compiled.step(q, start, end.to_array()[:-1], 0.004)
    with pytest.raises(ControllerError, match="dt must be finite and > 0, got nan"):
        compiled.step(q, start, end, float("nan"))

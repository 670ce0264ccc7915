"""CompiledClik: the fused kernel gives Clik's step to round-off, on the cases that matter and the hard ones."""

from __future__ import annotations

import numpy as np
import pytest

from redundancy_gym.assets import AGRI_ARM_TCP, AGRI_ARM_XML, PLANAR_ARM_TCP, PLANAR_ARM_XML
from redundancy_gym.controllers import (
    Clik,
    ClikResult,
    CollisionObjective,
    CompiledClik,
    ControllerError,
    FrameAxisTask,
    FramePositionTask,
    JointLimitObjective,
    Objective,
    ObjectiveValue,
    PostureObjective,
)
from redundancy_gym.geometry import LSS, PSS, TSS, Segment
from redundancy_gym.model import ModelError, RobotModel, collision_model_from_mjcf

# a stem, a fruit and a leaf triangle in front of the agricultural arm, inside its reach
PLANT = (
    Segment("stem", (LSS([0.55, 0.05, 0.2], [0.55, 0.05, 1.7], 0.007),)),
    Segment("fruit", (PSS([0.5, -0.08, 1.0], 0.045),)),
    Segment("leaf", (TSS([0.45, 0.1, 1.2], [0.6, 0.2, 1.25], [0.5, 0.25, 1.1], 0.002),)),
)


def assert_same(a: ClikResult, b: ClikResult) -> None:
    scale = max(1.0, float(np.abs(a.qdot).max()))
    np.testing.assert_allclose(b.qdot, a.qdot, atol=1e-9 * scale)
    np.testing.assert_allclose(b.error, a.error, atol=1e-12)
    assert b.error_norm == pytest.approx(a.error_norm, abs=1e-12)
    assert b.sigma_min == pytest.approx(a.sigma_min, abs=1e-9)
    assert b.damping == pytest.approx(a.damping, abs=1e-12)
    assert b.objective == pytest.approx(a.objective, rel=1e-9, abs=1e-12)
    assert (b.status, b.success, b.limited) == (a.status, a.success, a.limited)


def agri_clik(method: str, model: RobotModel | None = None) -> tuple[Clik, CollisionObjective]:
    model = model or RobotModel.from_mjcf(AGRI_ARM_XML)
    collision = CollisionObjective(
        collision_model_from_mjcf(model, PLANT), activation_distance=0.1, slope=4.0, weight=10.0
    )
    limits = JointLimitObjective.from_model(model, activation_distance=0.2, weight=0.5)
    return Clik(model, FrameAxisTask(AGRI_ARM_TCP), method=method, objectives=[limits, collision]), collision


@pytest.mark.parametrize("method", ["dls", "pseudoinverse", "transpose"])
def test_agri_arm_step_matches_clik(method: str, rng: np.random.Generator) -> None:
    """9-DoF arm, 5-D task, joint limits and self + plant collisions: same qdot, error, sigma, H, status."""
    clik, collision = agri_clik(method)
    compiled = CompiledClik(clik)
    near = 0
    for k in range(150):
        q = rng.uniform(clik.model.lower_limits, clik.model.upper_limits)
        target = np.concatenate([rng.normal(0.0, 0.3, 3) + [0.5, 0.0, 1.0], rng.normal(size=3)])
        velocity = rng.normal(size=6) if k % 2 else None
        reference = clik.step(q, target, velocity)
        assert_same(reference, compiled.step(q, target, velocity))
        distances = collision.last_state.distance
        near += int(np.any(distances < 0.1))
        if np.any(distances < 0.1):  # the kernel saw the same closest pair
            assert compiled.last_min_distance == pytest.approx(distances.min(), abs=1e-9)
    assert near > 50  # the collision gradient was exercised, not only the task


def test_planar_arm_with_posture_and_a_moving_obstacle_matches_clik(planar_model: RobotModel, rng) -> None:
    """FramePositionTask rows, posture and limit objectives, and an environment sphere moved between steps."""
    obstacle = Segment("ball", (PSS(np.zeros(3), 1.0),))
    collision = CollisionObjective(
        collision_model_from_mjcf(planar_model, [obstacle]), activation_distance=0.15, slope=2.0, weight=3.0
    )
    objectives: list[Objective] = [
        JointLimitObjective.from_model(planar_model, activation_distance=0.3),
        PostureObjective(np.zeros(4), [1.0, 0.5, 0.2, 0.1]),
        collision,
    ]
    clik = Clik(
        planar_model,
        FramePositionTask(PLANAR_ARM_TCP, "xz"),
        method="dls",
        gain=[5.0, 8.0],
        weights=[1.0, 2.0, 3.0, 4.0],
        nullspace_gain=0.7,
        objectives=objectives,
    )
    compiled = CompiledClik(clik)
    model = collision.collision_model
    for _ in range(60):
        model.set_environment_placement("ball", np.eye(3), [rng.uniform(0.2, 1.0), 0.0, rng.uniform(-0.5, 0.5)])
        model.set_environment_radius("ball", rng.uniform(0.05, 0.2))
        q = rng.uniform(planar_model.lower_limits, planar_model.upper_limits)
        target, velocity = rng.uniform(-1.0, 1.0, 2), rng.normal(size=2)
        assert_same(clik.step(q, target, velocity), compiled.step(q, target, velocity))


@pytest.mark.parametrize(("method", "status"), [("pseudoinverse", "singular"), ("dls", "damped")])
def test_stretched_planar_arm_singularity(planar_model: RobotModel, method: str, status: str) -> None:
    """Fully stretched arm (q = 0): the pseudoinverse reports the singularity with zero qdot, DLS damps it."""
    clik = Clik(planar_model, FramePositionTask(PLANAR_ARM_TCP, "xz"), method=method)
    compiled = CompiledClik(clik)
    result = compiled.step(np.zeros(4), [1.0, 0.2], [0.0, 0.1])
    assert result.status == status and result.success == (status != "singular")
    assert np.all(np.isfinite(result.qdot))
    if status == "singular":
        assert not np.any(result.qdot)
    assert_same(clik.step(np.zeros(4), [1.0, 0.2], [0.0, 0.1]), result)


def test_bad_inputs_raise_like_clik() -> None:
    clik, _ = agri_clik("dls")
    compiled = CompiledClik(clik)
    q = np.zeros(9)
    good = np.array([0.5, 0.0, 1.0, 1.0, 0.0, 0.0])
    with pytest.raises(ControllerError, match="q must be finite"):
        compiled.step(np.full(9, np.nan), good)
    with pytest.raises(ModelError, match="shape"):
        compiled.step(np.zeros(8), good)
    with pytest.raises(ControllerError, match="finite"):
        compiled.step(q, np.array([np.nan, 0, 1, 1, 0, 0]))
    with pytest.raises(ControllerError, match="axis"):
        compiled.step(q, np.array([0.5, 0.0, 1.0, 0.0, 0.0, 0.0]))
    with pytest.raises(ControllerError, match="target_velocity"):
        compiled.step(q, good, np.array([0, 0, np.inf, 0, 0, 0]))
    with pytest.raises(ControllerError, match="shape"):
        compiled.step(q, good[:5])
    # the buffers are not left in a state that changes the next result
    assert_same(clik.step(q, good), compiled.step(q, good))


class _Custom:
    def evaluate(self, model: RobotModel, q: np.ndarray) -> ObjectiveValue:
        return ObjectiveValue(0.0, np.zeros(model.nv))


def test_rejects_what_it_cannot_compile(planar_model: RobotModel) -> None:
    task = FramePositionTask(PLANAR_ARM_TCP, "xz")
    with pytest.raises(ControllerError, match="diagonal"):
        CompiledClik(Clik(planar_model, task, weights=np.eye(4)))
    with pytest.raises(ControllerError, match="JointLimitObjective, PostureObjective, CollisionObjective"):
        CompiledClik(Clik(planar_model, task, objectives=[_Custom()]))
    collision = CollisionObjective(collision_model_from_mjcf(planar_model))
    with pytest.raises(ControllerError, match="at most one"):
        CompiledClik(Clik(planar_model, task, objectives=[collision, collision]))
    with pytest.raises(ControllerError, match="compiles a Clik"):
        CompiledClik(task)  # type: ignore[arg-type]


def test_tracking_rollout_matches_clik() -> None:
    """A closed-loop rollout: the two backends stay together over 200 steps (no drift from round-off)."""
    model = RobotModel.from_mjcf(AGRI_ARM_XML)
    clik, _ = agri_clik("dls", model)
    compiled = CompiledClik(clik)
    q0 = np.array([0.5, 0.0, -0.6, 1.2, 0.0, 0.8, 0.0, 0.0, 0.0])
    model.update(q0)
    target = np.concatenate([model.frame_position(AGRI_ARM_TCP) + [0.1, 0.05, -0.1], [1.0, 0.2, -0.1]])
    qa, qb = q0.copy(), q0.copy()
    for _ in range(200):
        qa = model.integrate(qa, clik.step(qa, target).qdot, 0.01)
        qb = model.integrate(qb, compiled.step(qb, target).qdot, 0.01)
    np.testing.assert_allclose(qb, qa, atol=1e-8)
    assert compiled.step(qb, target).error_norm < 1e-3


def test_grasp_path_sampler_meets_its_boundary_conditions_and_derivatives() -> None:
    """The compiled GraspPath sample: rest-to-rest ends, unit axis on the great circle, velocities = d/dt."""
    from redundancy_gym.policies.grasp_clik_policy import GraspPath

    start, pregrasp, grasp = np.array([0.2, -0.3, 0.9]), np.array([0.5, 0.1, 1.1]), np.array([0.62, 0.1, 1.05])
    start_axis, approach = np.array([0.0, 0.0, 1.0]), np.array([0.8, 0.0, -0.2])
    path = GraspPath(start, start_axis, pregrasp, grasp, approach, 1.5, 0.8)
    target, velocity = path(0.0)
    np.testing.assert_allclose(target, np.concatenate([start, start_axis]), atol=1e-15)
    np.testing.assert_allclose(velocity, 0.0, atol=1e-15)
    target, velocity = path(1.5)
    np.testing.assert_allclose(target, np.concatenate([pregrasp, path.approach]), atol=1e-12)
    target, velocity = path(path.duration + 1.0)
    np.testing.assert_allclose(target, np.concatenate([grasp, path.approach]), atol=1e-12)
    np.testing.assert_allclose(velocity, 0.0, atol=1e-15)
    eps = 1e-6
    for t in (0.3, 0.75, 1.2, 1.7, 2.1):
        target, velocity = path(t)
        ahead, behind = path(t + eps)[0], path(t - eps)[0]
        assert np.linalg.norm(target[3:]) == pytest.approx(1.0, abs=1e-12)
        np.testing.assert_allclose((ahead[:3] - behind[:3]) / (2 * eps), velocity[:3], atol=1e-6)
        # the axis turns with omega: da/dt = omega x a
        np.testing.assert_allclose((ahead[3:] - behind[3:]) / (2 * eps), np.cross(velocity[3:], target[3:]), atol=1e-6)


def test_robot_segment_on_a_world_fixed_frame_is_placed_once(rng) -> None:
    """A robot segment on a frame that does not move (a base plate, off the origin and turned) is checked like
    the environment, at its world placement."""
    import pinocchio as pin

    from redundancy_gym.geometry import CollisionModel

    pm = RobotModel.from_mjcf(PLANAR_ARM_XML).pinocchio_model.copy()
    plate = pin.SE3(pin.utils.rpyToMatrix(0.3, -0.2, 0.5), np.array([0.4, 0.0, 0.1]))
    pm.addFrame(pin.Frame("plate", 0, 0, plate, pin.FrameType.OP_FRAME))
    model = RobotModel(pm)
    assert model.frame_attachment("plate")[0] == -1
    link3 = Segment("link3", (LSS([0.0, 0.0, 0.0], [0.3, 0.0, 0.0], 0.04),), frame="joint3")
    base = Segment("base", (LSS([-0.1, 0.0, 0.0], [0.1, 0.0, 0.0], 0.05),), frame="plate")
    collision = CollisionObjective(CollisionModel([base, link3]), activation_distance=0.3, weight=2.0)
    clik = Clik(model, FramePositionTask(PLANAR_ARM_TCP, "xz"), method="dls", objectives=[collision])
    compiled = CompiledClik(clik)
    active = 0
    for _ in range(60):
        q = rng.uniform(model.lower_limits, model.upper_limits)
        assert_same(clik.step(q, [0.5, 0.2]), compiled.step(q, [0.5, 0.2]))
        active += int(compiled.last_min_distance < 0.3)
    assert active > 5


@pytest.mark.parametrize("method", ["dls", "pseudoinverse"])
def test_nullspace_input_is_n_u_in_both_backends(method: str, rng: np.random.Generator) -> None:
    """(5.100): the input u adds N u to the command: J N u = 0, and the compiled kernel gives Clik's result."""
    clik, _ = agri_clik(method)
    compiled = CompiledClik(clik)
    checked = 0
    for _ in range(40):
        q = rng.uniform(clik.model.lower_limits * 0.5, clik.model.upper_limits * 0.5)
        clik.model.update(q)  # a target near the TCP: a command inside the speed limits
        target = clik.task.value(clik.model) + np.concatenate([rng.normal(0.0, 0.01, 3), np.zeros(3)])
        u = rng.normal(0.0, 0.1, clik.model.nv)
        plain, moved = clik.step(q, target), clik.step(q, target, nullspace_input=u)
        assert_same(moved, compiled.step(q, target, nullspace_input=u))
        if plain.damping > 0.0 or plain.limited or moved.limited:
            continue  # damped or bounded: N is no longer the exact projector
        checked += 1
        clik.model.update(q)
        jacobian = clik.task.jacobian(clik.model)
        projector = np.eye(clik.model.nv) - np.linalg.pinv(jacobian) @ jacobian
        np.testing.assert_allclose(moved.qdot - plain.qdot, projector @ u, atol=1e-9)
        assert np.abs(jacobian @ (moved.qdot - plain.qdot)).max() < 1e-9
    assert checked > 10


def test_nullspace_input_must_be_finite_with_nv_entries(planar_model: RobotModel) -> None:
    clik = Clik(planar_model, FramePositionTask(PLANAR_ARM_TCP, "xz"))
    compiled = CompiledClik(clik)
    q, target = np.full(4, 0.3), np.array([0.9, 0.1])
    for controller in (clik, compiled):
        with pytest.raises(ControllerError, match="nullspace_input"):
            controller.step(q, target, nullspace_input=np.zeros(3))
        with pytest.raises(ControllerError, match="nullspace_input"):
            controller.step(q, target, nullspace_input=np.array([0.0, np.nan, 0.0, 0.0]))


def test_close_pairs_give_the_distances_and_their_finite_difference_gradients(rng: np.random.Generator) -> None:
    clik, collision = agri_clik("dls")
    compiled = CompiledClik(clik)
    model = clik.model
    checked = 0
    for _ in range(200):
        q = rng.uniform(model.lower_limits, model.upper_limits)
        target = np.concatenate([[0.5, 0.0, 1.0], [1.0, 0.0, 0.0]])
        compiled.step(q, target)
        distances, rows = compiled.close_pairs(0.05, capacity=4)
        model.update(q)
        state = collision.collision_model.evaluate(model)
        near = np.sort(state.distance[state.distance < 0.05])[:4]
        np.testing.assert_allclose(np.sort(distances), near, atol=1e-9)  # the nearest four within the limit
        if distances.size == 0:
            continue
        k = int(np.argmin(distances))
        eps = 1e-6
        numeric = np.zeros(model.nv)
        for j in range(model.nv):
            step = np.zeros(model.nq)
            step[j] = eps
            model.update(q + step)
            ahead = collision.collision_model.evaluate(model).distance.min()
            model.update(q - step)
            behind = collision.collision_model.evaluate(model).distance.min()
            numeric[j] = (ahead - behind) / (2 * eps)
        np.testing.assert_allclose(rows[k], numeric, atol=1e-5)
        checked += 1
        if checked == 8:
            break
    assert checked == 8


def test_grasp_path_params_are_what_the_compiled_sampler_reads() -> None:
    """GraspPath.params (read-only) sampled by sample_grasp_path inside another kernel gives the path's own
    target and target velocity."""
    from redundancy_gym.geometry.grasp_path import GraspPath, sample_grasp_path

    path = GraspPath.plan(
        np.array([0.4, 0.1, 0.9]),
        np.array([1.0, 0.0, 0.0]),
        np.array([0.7, 0.2, 1.0]),
        np.array([0.8, 0.2, 1.0]),
        np.array([1.0, 0.0, 0.0]),
    )
    params = path.params
    assert not params.flags.writeable
    with pytest.raises(ValueError):
        params[0] = 1.0
    out = np.empty(12)
    for t in (0.0, 0.3 * path.duration, 0.9 * path.duration, 2.0 * path.duration):
        sample_grasp_path(params.copy(), t, out)
        target, velocity = path(t)
        np.testing.assert_array_equal(out[:6], target)
        np.testing.assert_array_equal(out[6:], velocity)

"""Hard cases of the CLIK controllers (issue 17, "What was seen" items 3 and 6, "Bounded commands").

Item 3: a non-finite ``q``, target or target velocity raises :class:`ControllerError` naming the argument, for
every method and both backends (before: the Python pseudoinverse and DLS returned ``error=[nan ...]`` with
status ``singular``, the transpose ``qdot = [nan nan nan nan]`` with status ``ok``; the compiled backend
raised, with another message and, for ``q``, another exception type).

Item 6: a closed loop driven towards an unreachable target commanded up to 342 rad/s and left the joint ranges
after 3,000 steps. Every CLIK command is now held to the robot's speed limits (the whole ``qdot`` scaled by one
factor, so it keeps its direction) and to the joint ranges, and ``limited`` says when.
"""

from __future__ import annotations

import numpy as np
import pytest

from redundancy_gym.assets import AGRI_ARM_TCP, AGRI_ARM_XML, BIPED_XML, PLANAR_ARM_TCP, PLANAR_ARM_XML
from redundancy_gym.controllers import (
    AccelerationClik,
    Clik,
    CompiledClik,
    ControllerError,
    FrameAxisTask,
    FramePositionTask,
    JointLimitObjective,
    resolve,
)
from redundancy_gym.model import RobotModel

METHODS = ("pseudoinverse", "dls", "transpose")
BACKENDS = ("python", "compiled")
DT = 0.01
# round-off allowance of the bounds: q + qdot dt lands on a limit to within a few ulp
TOL = 1e-12


@pytest.fixture(scope="module")
def planar() -> RobotModel:
    return RobotModel.from_mjcf(PLANAR_ARM_XML)


@pytest.fixture(scope="module")
def agri() -> RobotModel:
    return RobotModel.from_mjcf(AGRI_ARM_XML)


def _controller(clik: Clik, backend: str) -> Clik | CompiledClik:
    return CompiledClik(clik) if backend == "compiled" else clik


def _planar_clik(model: RobotModel, method: str = "dls", **kwargs) -> Clik:
    """The PlanarReach ``clik`` reference: DLS, K = 20, joint-limit objective."""
    return Clik(
        model,
        FramePositionTask(PLANAR_ARM_TCP, "xz"),
        method=method,
        gain=20.0,
        objectives=[JointLimitObjective.from_model(model, activation_distance=0.35)],
        **kwargs,
    )


def _agri_clik(model: RobotModel, method: str = "dls", **kwargs) -> Clik:
    """The AgriReach ``clik`` reference's controller without the plant: DLS, K = 10, joint-limit objective."""
    return Clik(
        model,
        FrameAxisTask(AGRI_ARM_TCP),
        method=method,
        gain=10.0,
        objectives=[JointLimitObjective.from_model(model, activation_distance=0.2, weight=0.5)],
        **kwargs,
    )


# ---------------------------------------------------------------------------------------------- item 3: NaN
PLANAR_GOOD = {
    "q": np.array([0.3, -0.5, 0.4, 0.2]),
    "target": np.array([0.9, -0.2]),
    "target_velocity": np.array([0.0, 0.1]),
}


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("argument", ["q", "target", "target_velocity"])
@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("method", METHODS)
def test_non_finite_input_raises_naming_the_argument(
    planar: RobotModel, method: str, backend: str, argument: str, value: float
) -> None:
    controller = _controller(_planar_clik(planar, method), backend)
    inputs = {k: v.copy() for k, v in PLANAR_GOOD.items()}
    inputs[argument][1] = value
    with pytest.raises(ControllerError, match=rf"^{argument} must be finite"):
        controller.step(inputs["q"], inputs["target"], inputs["target_velocity"])
    # a good step afterwards is unaffected (the compiled buffers are not left half written)
    result = controller.step(PLANAR_GOOD["q"], PLANAR_GOOD["target"], PLANAR_GOOD["target_velocity"])
    assert np.all(np.isfinite(result.qdot)) and np.all(np.isfinite(result.error))


@pytest.mark.parametrize("backend", BACKENDS)
def test_transpose_with_nan_target_raises_instead_of_nan_qdot(planar: RobotModel, backend: str) -> None:
    """The case as seen: the Python transpose returned qdot = [nan nan nan nan] with status ok."""
    controller = _controller(Clik(planar, FramePositionTask(PLANAR_ARM_TCP, "xz"), method="transpose"), backend)
    with pytest.raises(ControllerError, match="target must be finite"):
        controller.step(np.zeros(4), np.array([np.nan, 0.0]), np.zeros(2))


@pytest.mark.parametrize("method", ["pseudoinverse", "dls"])
def test_nan_target_is_not_reported_as_a_singularity(planar: RobotModel, method: str) -> None:
    """The case as seen: pseudoinverse/DLS returned error = [nan nan] with status singular."""
    clik = _planar_clik(planar, method)
    with pytest.raises(ControllerError, match="target must be finite"):
        clik.step(PLANAR_GOOD["q"], np.array([np.inf, 0.0]))
    with pytest.raises(ControllerError, match="target must be finite"):
        clik.solve(clik.build(PLANAR_GOOD["q"], np.array([0.5, np.nan])))


@pytest.mark.parametrize("backend", BACKENDS)
def test_frame_axis_task_non_finite_inputs_raise(agri: RobotModel, backend: str) -> None:
    controller = _controller(_agri_clik(agri), backend)
    good = np.array([0.6, 0.0, 1.0, 1.0, 0.0, 0.0])
    with pytest.raises(ControllerError, match="^q must be finite"):
        controller.step(np.r_[0.3, np.full(8, np.nan)], good)
    with pytest.raises(ControllerError, match="^target must be finite"):
        controller.step(np.full(9, 0.1), np.r_[good[:5], np.inf])
    with pytest.raises(ControllerError, match="^target_velocity must be finite"):
        controller.step(np.full(9, 0.1), good, np.r_[np.zeros(5), np.nan])


@pytest.mark.parametrize("argument", ["q", "qdot", "target", "target_velocity", "target_acceleration"])
def test_acceleration_clik_non_finite_input_raises(planar: RobotModel, argument: str) -> None:
    task = FramePositionTask(PLANAR_ARM_TCP, "xz")
    clik = AccelerationClik(planar, task)
    inputs = {
        "q": np.array([0.3, -0.5, 0.4, 0.2]),
        "qdot": np.zeros(4),
        "target": np.array([0.9, -0.2]),
        "target_velocity": np.zeros(2),
        "target_acceleration": np.zeros(2),
    }
    inputs[argument][0] = np.nan
    with pytest.raises(ControllerError, match=rf"^{argument} must be finite"):
        clik.step(**inputs)


# ------------------------------------------------------------------------------------ item 6: bounded commands
def test_robot_model_velocity_limits_come_from_the_mjcf_servos(planar: RobotModel, agri: RobotModel) -> None:
    """MJCF has no joint speed limit; the velocity servos' ctrlrange is the speed each joint accepts."""
    np.testing.assert_array_equal(planar.velocity_limits, np.full(4, 3.0))
    np.testing.assert_array_equal(agri.velocity_limits, np.r_[1.0, np.full(8, 3.0)])  # lift [m/s], revolute
    assert np.all(np.isinf(RobotModel.from_mjcf(BIPED_XML).velocity_limits))  # position servos: none
    np.testing.assert_array_equal(
        Clik(planar, FramePositionTask(PLANAR_ARM_TCP, "xz")).max_joint_velocity, planar.velocity_limits
    )


def _closed_loop(
    controller: Clik | CompiledClik, model: RobotModel, q: np.ndarray, target: np.ndarray, steps: int = 3000
) -> tuple[np.ndarray, np.ndarray, list[bool]]:
    """Kinematic closed loop ``q += qdot dt``: every q and qdot, and the limited flags."""
    qs, qdots, limited = [], [], []
    for _ in range(steps):
        result = controller.step(q, target)
        assert np.all(np.isfinite(result.qdot))
        qs.append(q)
        qdots.append(result.qdot)
        limited.append(result.limited)
        q = q + result.qdot * DT
    qs.append(q)
    return np.array(qs), np.array(qdots), limited


def _assert_bounded(
    model: RobotModel, qs: np.ndarray, qdots: np.ndarray, limited: list[bool], vmax: np.ndarray
) -> None:
    peak = np.abs(qdots).max(axis=0)
    assert np.all(peak <= vmax * (1 + TOL)), f"peak |qdot| {peak} above the limits {vmax}"
    assert np.all(qs >= model.lower_limits - TOL) and np.all(qs <= model.upper_limits + TOL), (
        "the commanded motion left the joint ranges"
    )
    assert any(limited)
    assert np.max(peak / vmax) > 0.99  # the reference asked for more than the limits: they were active


@pytest.mark.parametrize("backend", BACKENDS)
def test_planar_unreachable_target_3m_away_keeps_speed_and_joint_limits(planar: RobotModel, backend: str) -> None:
    """The case as seen (342 rad/s and out of the ranges after 3,000 steps of the clik reference)."""
    controller = _controller(_planar_clik(planar, period=DT), backend)
    target = np.array([2.4, -1.8])  # 3 m from the shoulder, 1.6 m beyond the reach
    qs, qdots, limited = _closed_loop(controller, planar, np.array([0.3, -0.5, 0.4, 0.2]), target)
    _assert_bounded(planar, qs, qdots, limited, planar.velocity_limits)
    planar.update(qs[-1])
    assert np.linalg.norm(target - planar.frame_position(PLANAR_ARM_TCP)[[0, 2]]) < 3.0 - 1.4 + 1e-2


@pytest.mark.parametrize("backend", BACKENDS)
def test_agri_unreachable_target_3m_away_keeps_speed_and_joint_limits(agri: RobotModel, backend: str) -> None:
    controller = _controller(_agri_clik(agri, period=DT), backend)
    target = np.array([3.0, 0.5, 1.0, 0.0, 1.0, 0.0])  # 3 m in front, tool axis sideways
    q0 = np.array([0.4, 0.2, 0.3, -0.8, 0.1, 0.5, 0.0, 0.3, 0.0])
    qs, qdots, limited = _closed_loop(controller, agri, q0, target)
    _assert_bounded(agri, qs, qdots, limited, agri.velocity_limits)


@pytest.mark.parametrize("backend", BACKENDS)
def test_without_a_period_joints_do_not_move_further_out(planar: RobotModel, backend: str) -> None:
    """No period known: a joint may overshoot a limit by one step (<= vmax dt) but never moves further out."""
    controller = _controller(_planar_clik(planar), backend)
    qs, qdots, limited = _closed_loop(
        controller, planar, np.array([0.3, -0.5, 0.4, 0.2]), np.array([2.4, -1.8]), steps=1500
    )
    vmax = planar.velocity_limits
    assert np.all(np.abs(qdots) <= vmax * (1 + TOL)) and any(limited)
    over = vmax * DT * (1 + TOL)
    assert np.all(qs >= planar.lower_limits - over) and np.all(qs <= planar.upper_limits + over)
    beyond_upper = qs[:-1] >= planar.upper_limits
    beyond_lower = qs[:-1] <= planar.lower_limits
    assert not np.any(qdots[beyond_upper] > 0.0) and not np.any(qdots[beyond_lower] < 0.0)


@pytest.mark.parametrize("method", METHODS)
def test_backends_agree_when_the_bounds_act(agri: RobotModel, method: str, rng: np.random.Generator) -> None:
    """Random states near and beyond the limits, fast references: same bounded qdot and flags to round-off."""
    clik = _agri_clik(agri, method, max_joint_velocity=0.5, period=DT)
    compiled = CompiledClik(clik)
    span = agri.upper_limits - agri.lower_limits
    flags = []
    for k in range(100):
        q = rng.uniform(agri.lower_limits - 0.02 * span, agri.upper_limits + 0.02 * span)
        if k % 3 == 0:  # some joints exactly on a limit
            at = rng.random(9) < 0.3
            q[at] = np.where(rng.random(at.sum()) < 0.5, agri.lower_limits[at], agri.upper_limits[at])
        target = np.r_[rng.normal(0.0, 0.5, 3) + [0.5, 0.0, 1.0], rng.normal(size=3)]
        velocity = rng.normal(size=6) if k % 2 else None
        a, b = clik.step(q, target, velocity), compiled.step(q, target, velocity)
        np.testing.assert_allclose(b.qdot, a.qdot, atol=1e-9)
        assert (a.limited, a.status) == (b.limited, b.status)
        flags.append(a.limited)
        assert np.all(np.abs(a.qdot) <= 0.5 * (1 + TOL))
        inside = q + a.qdot * DT
        lower, upper = agri.lower_limits, agri.upper_limits
        assert np.all((inside >= lower - TOL) | (a.qdot >= 0.0)) and np.all((inside <= upper + TOL) | (a.qdot <= 0.0))
    assert sum(flags) > 50


@pytest.mark.parametrize("backend", BACKENDS)
def test_speed_limit_scales_the_whole_command_keeping_its_direction(planar: RobotModel, backend: str) -> None:
    q = np.array([0.3, -0.5, 0.4, 0.2])
    target = np.array([0.2, -0.9])  # far: K e asks for several rad/s
    free = _planar_clik(planar, max_joint_velocity=np.inf).step(q, target)
    limits = np.array([0.4, 0.3, 0.2, 0.5])
    bounded = _controller(_planar_clik(planar, max_joint_velocity=limits), backend).step(q, target)
    assert not free.limited and bounded.limited
    scale = np.min(limits / np.abs(free.qdot))
    assert scale < 1.0
    np.testing.assert_allclose(bounded.qdot, scale * free.qdot, rtol=1e-12, atol=1e-15)
    assert np.any(np.isclose(np.abs(bounded.qdot), limits, rtol=1e-12))


@pytest.mark.parametrize("backend", BACKENDS)
def test_references_within_the_limits_are_not_touched(planar: RobotModel, backend: str) -> None:
    """Limits only act when the reference asks for more: a slow, reachable reference gives the same qdot."""
    q = np.array([0.3, -0.5, 0.4, 0.2])
    planar.update(q)
    target = planar.frame_position(PLANAR_ARM_TCP)[[0, 2]] + [0.01, -0.01]
    free = _controller(_planar_clik(planar, max_joint_velocity=np.inf), backend).step(q, target, [0.05, 0.0])
    bounded = _controller(_planar_clik(planar, period=DT), backend).step(q, target, [0.05, 0.0])
    assert not bounded.limited
    np.testing.assert_array_equal(bounded.qdot, free.qdot)


@pytest.mark.parametrize("backend", BACKENDS)
def test_joint_on_its_limit_gets_no_velocity_further_out(planar: RobotModel, backend: str) -> None:
    """Joint 2 folded onto its upper limit, a target that the unbounded solution reaches by folding it further:
    that component is held at zero, the others are the unbounded solution's."""
    q = np.array([0.3, planar.upper_limits[1], 0.4, 0.2])
    planar.update(q)
    jacobian = planar.frame_jacobian(PLANAR_ARM_TCP, "translational")[[0, 2]]
    target = planar.frame_position(PLANAR_ARM_TCP)[[0, 2]] + 0.05 * jacobian[:, 1] / np.linalg.norm(jacobian[:, 1])
    clik = _planar_clik(planar, max_joint_velocity=np.inf)
    problem = clik.build(q, target)
    free = resolve(
        problem.jacobian,
        problem.velocity,
        clik.nullspace_gain * problem.gradient,
        clik.weights,
        method="dls",
        dls_threshold=clik.dls_threshold,
        dls_max_damping=clik.dls_max_damping,
    ).x
    assert free[1] > 0.1  # the reference folds joint 2 further
    for period in (None, DT):
        result = _controller(_planar_clik(planar, max_joint_velocity=np.inf, period=period), backend).step(q, target)
        assert result.limited and result.qdot[1] == 0.0
        np.testing.assert_allclose(result.qdot[[0, 2, 3]], free[[0, 2, 3]], rtol=1e-9)
    # just inside the limit with a period: the joint may move up to the limit in one period, not past it
    q[1] -= 1e-4
    result = _controller(_planar_clik(planar, max_joint_velocity=np.inf, period=DT), backend).step(q, target)
    assert result.limited and result.qdot[1] == pytest.approx(1e-4 / DT, rel=1e-9)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        *[(dict(max_joint_velocity=v), "max_joint_velocity") for v in (0.0, -1.0, np.nan, [1.0, 2.0], "fast", True)],
        *[(dict(period=v), "period") for v in (0.0, -0.01, np.nan, np.inf, True, "0.01")],
    ],
)
def test_invalid_bounds_raise(planar: RobotModel, kwargs: dict, match: str) -> None:
    with pytest.raises(ControllerError, match=match):
        Clik(planar, FramePositionTask(PLANAR_ARM_TCP, "xz"), **kwargs)
    with pytest.raises(ControllerError, match=match):
        AccelerationClik(planar, FramePositionTask(PLANAR_ARM_TCP, "xz"), **kwargs)


def test_acceleration_clik_unreachable_target_keeps_speed_and_joint_limits(planar: RobotModel) -> None:
    """Resolved-acceleration loop towards a target 3 m away: the next velocity stays within the speed limits and
    keeps q inside its ranges."""
    task = FramePositionTask(PLANAR_ARM_TCP, "xz")
    clik = AccelerationClik(planar, task, method="dls", period=DT, objectives=[JointLimitObjective.from_model(planar)])
    q, qdot = np.array([0.3, -0.5, 0.4, 0.2]), np.zeros(4)
    target = np.array([2.4, -1.8])
    vmax = planar.velocity_limits
    limited = []
    for _ in range(3000):
        result = clik.step(q, qdot, target, np.zeros(2), np.zeros(2))
        assert np.all(np.isfinite(result.qddot))
        limited.append(result.limited)
        qdot = qdot + result.qddot * DT
        q = q + qdot * DT
        assert np.all(np.abs(qdot) <= vmax * (1 + TOL))
        assert np.all(q >= planar.lower_limits - TOL) and np.all(q <= planar.upper_limits + TOL)
    assert any(limited)

"""The IKD as the walking controller's trajectory generator: along the walking pattern its motion needs exactly the
realized contact moment (RNEA), whose ZMP stays in the support box; the hybrid stabilization keeps the CoM on the
plan; the balance feedback moves the soles against the CoM."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from redundancy_gym.assets import BIPED_XML
from redundancy_gym.controllers import ControllerError
from redundancy_gym.controllers.walking import (
    GaitConfig,
    WalkingController,
    WalkingIkd,
    WalkingIkdConfig,
    WalkingPattern,
)
from redundancy_gym.model import RobotModel
from tests.controllers.walking.biped_helpers import standing

FEET = ("r_sole", "l_sole")
DT = 0.004


@pytest.fixture(scope="module")
def biped() -> RobotModel:
    return RobotModel.from_mjcf(BIPED_XML)


def _contact_moment(model: RobotModel, q: np.ndarray, qdot: np.ndarray, qddot: np.ndarray) -> np.ndarray:
    """The ground's moment about the world origin [N m] for the motion (RNEA's floating-base rows)."""
    data = model.pinocchio_model.createData()
    tau = pin.rnea(model.pinocchio_model, data, q, qdot, qddot)
    base = pin.XYZQUATToSE3(q[:7])
    force = base.rotation @ tau[:3]
    return base.rotation @ tau[3:6] + np.cross(base.translation, force)


def _walk(biped: RobotModel, config: WalkingIkdConfig, duration: float, shift: np.ndarray | None = None) -> dict:
    """A kinematic walk of the IKD along a plain LIPM pattern at 0.4 m/s (4 ms periods, as in BipedWalk)."""
    q = standing(biped)
    biped.update(q)
    feet = [biped.frame_position(f).copy() for f in FEET]
    com = biped.com().copy()
    gait = GaitConfig()
    pattern = WalkingPattern(gait, feet[0], feet[1], com[:2], 0.4)
    ikd = WalkingIkd(biped, DT, config, omega=np.sqrt(9.81 / gait.com_height), posture=q)
    ikd.start(q)
    out = {"moment_error": [], "inside": [], "distance": [], "shift_outside_ds": [], "relative": [], "limited": False}
    offset = np.zeros(2) if shift is None else shift
    for n in range(int(round(duration / DT))):
        t = n * DT
        start, end = pattern.sample(t), pattern.sample(t + DT)
        start_ref = WalkingController._reference_array(start, np.zeros(2), np.zeros(2))
        end_ref = WalkingController._reference_array(end, np.zeros(2), np.zeros(2))
        k = start.step
        window = (pattern.step_start(k) + pattern.step_single(k), pattern.step_start(k + 1)) if k >= 0 else None
        q0, qdot0 = ikd.q.copy(), ikd.qdot.copy()
        step = ikd.step(start, start_ref, end_ref, window, offset)
        assert step.success
        if step.limited:  # run off so far that the legs stretch: the velocity bound acts, the moment is not exact
            out["limited"] = True
            break
        moment = _contact_moment(biped, q0, qdot0, step.qddot)
        out["moment_error"].append(float(np.abs(moment[:2] - step.moment).max() / np.abs(step.moment).max()))
        out["inside"].append(
            bool(np.all(step.zmp >= step.support[0] - 1e-9) and np.all(step.zmp <= step.support[1] + 1e-9))
        )
        out["distance"].append(float(np.linalg.norm(step.com[:2] - start.com[:2])))
        in_double = window is not None and window[0] - DT <= t <= window[1]
        out["shift_outside_ds"].append(bool(step.planning_shift.any()) and not in_double)
        biped.update(q0)
        out["relative"].append(step.com[:2] - np.mean([biped.frame_position(f)[:2] for f in FEET], axis=0))
    return out


def test_along_the_pattern_the_motion_needs_exactly_the_realized_moment_and_its_zmp_stays_in_the_support(biped):
    out = _walk(biped, WalkingIkdConfig(), 2.6)  # the start and three steps
    assert not out["limited"] and len(out["distance"]) == 650
    assert max(out["moment_error"]) < 1e-6
    assert all(out["inside"])
    assert max(out["distance"]) < 0.01  # hybrid stabilization: on the plan to a centimetre
    assert not any(out["shift_outside_ds"])  # the planning modifies the ZMP in double support only


def test_without_stabilization_the_ikd_runs_off_the_plan(biped):
    out = _walk(biped, WalkingIkdConfig(moment_gain=0.0, planning=False), 2.6)
    assert max(out["distance"]) > 0.03


def test_the_balance_offset_moves_the_soles_and_leaves_the_com_on_the_plan(biped):
    base = _walk(biped, WalkingIkdConfig(), 0.3)
    moved = _walk(biped, WalkingIkdConfig(), 0.3, shift=np.array([0.02, -0.01]))
    # the CoM relative to the soles moves by the offset (the soles by minus it), the CoM itself stays on the plan
    np.testing.assert_allclose(moved["relative"][-1] - base["relative"][-1], [0.02, -0.01], atol=2e-3)
    assert max(moved["distance"]) < 0.01


def test_bad_settings_are_refused_by_name():
    with pytest.raises(ControllerError, match="moment_gain"):
        WalkingIkdConfig(moment_gain=-1.0)
    with pytest.raises(ControllerError, match="planning_ramp"):
        WalkingIkdConfig(planning_ramp=0.0)
    with pytest.raises(ControllerError, match="max_velocity"):
        WalkingIkdConfig(max_velocity=0.0)
    with pytest.raises(ControllerError, match="support_margin"):
        WalkingIkdConfig(support_margin=0.2)


# ---------------------------------------------------------------- the fast step against the previous computation


def _previous_advance(planner, t: float, dt: float):
    """:meth:`PlanStabilizer.advance` as it was (on arrays)."""
    from redundancy_gym.controllers.ikd.plan_stabilizer import PlanStabilizerOutput

    shift = planner.amplitude * planner.shape(t + 0.5 * dt)
    out = PlanStabilizerOutput(shift, planner.offset.copy(), planner.offset_rate.copy())
    w = planner.omega
    c, s = math.cosh(w * dt), math.sinh(w * dt)
    relative = planner.offset - shift
    planner.offset = shift + relative * c + planner.offset_rate * (s / w)
    planner.offset_rate = relative * (w * s) + planner.offset_rate * c
    if t + dt >= planner.window[1]:
        planner.offset_rate = -w * planner.offset
        planner.amplitude = np.zeros(2)
        planner.window = (math.inf, math.inf)
    return out


def _previous_support(ikd: WalkingIkd, sample, shift: np.ndarray) -> np.ndarray:
    """The support box an independent way: each sole in contact as a rectangle (heel to toe, side to side) turned
    by its yaw matrix and moved to its shifted position, the box of all corners shrunk by the margin."""
    c = ikd.config
    rectangle = np.array(
        [
            [along, across]
            for along in (-c.heel_length, c.toe_length)
            for across in (-c.foot_half_width, c.foot_half_width)
        ]
    )
    corners = []
    for i in np.flatnonzero(sample.contact):
        yaw = sample.feet_yaw[i]
        turn = np.array([[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]])
        corners.append(rectangle @ turn.T + (sample.feet[i, :2] + shift))
    points = np.concatenate(corners)
    return np.stack([points.min(axis=0), points.max(axis=0)]) + np.array([[1.0], [-1.0]]) * c.support_margin


def _previous_step(
    ikd: WalkingIkd,
    start,
    start_reference,
    end_reference,
    double_support,
    feet_shift=(0.0, 0.0),
    feet_shift_rate=(0.0, 0.0),
    zmp=None,
):
    """:meth:`WalkingIkd.step` as it was before the compiled assembly (NumPy throughout, the planner's advance
    and the support box on arrays): the independent reference of the fast path."""
    from redundancy_gym.controllers.ikd import BipedIkdReference
    from redundancy_gym.controllers.ikd.biped_ikd import GRAVITY
    from redundancy_gym.controllers.walking import WalkingIkdStep

    dt, model, c = ikd.dt, ikd.model, ikd.config
    shift = -np.asarray(feet_shift, dtype=np.float64)
    shift_rate = -np.asarray(feet_shift_rate, dtype=np.float64)
    ref, ahead = start_reference, end_reference
    position = ref[6:12].reshape(2, 3).copy()
    position[:, :2] += shift
    velocity = ref[30:42].reshape(2, 6).copy()
    velocity[:, :2] += shift_rate
    acceleration = (ahead[30:42] - ref[30:42]).reshape(2, 6) / dt
    torso_rotation = ref[42:51].reshape(3, 3)
    torso_rate = ref[51:54]
    torso_acceleration = (ahead[51:54] - torso_rate) / dt
    t = float(start.time)
    if (
        c.planning
        and double_support is not None
        and start.step >= 0
        and start.step != ikd._step
        and t >= double_support[0] - 0.5 * dt
    ):
        ikd._step = start.step
        model.update(ikd.q)
        com, centroidal = model.com_and_centroidal_matrix()
        com_velocity = centroidal[:2] @ ikd.qdot / model.total_mass
        ikd.planner.replan(t, com[:2] - start.com[:2], com_velocity - start.com_velocity[:2], double_support)
    planned = _previous_advance(ikd.planner, t, dt) if c.planning else None
    ideal = np.asarray(start.zmp if zmp is None else zmp, dtype=np.float64)
    zmp = ideal + (planned.zmp_shift if planned is not None else 0.0)
    com_plan = np.concatenate([start.com[:2], start.com_velocity[:2]])
    if planned is not None:
        com_plan += np.concatenate([planned.com_offset, planned.com_offset_rate])
    support = _previous_support(ikd, start, shift)
    moment = ikd.force * np.array([zmp[1], -zmp[0]])
    reference = BipedIkdReference(
        position,
        ref[12:30].reshape(2, 3, 3),
        velocity,
        acceleration,
        torso_rotation,
        torso_rate,
        torso_acceleration,
        np.array([float(start.com[2]), 0.0, 0.0]),
        moment,
        com_plan if c.moment_gain > 0.0 else None,
        support,
    )
    result = ikd.ikd.step(ikd.q, ikd.qdot, reference)
    com, centroidal = ikd.ikd.terms.com, ikd.ikd.terms.centroidal
    com_velocity = centroidal[:3] @ ikd.qdot / model.total_mass
    lz = float(centroidal[5] @ ikd.qdot)
    force = model.total_mass * (GRAVITY + float(result.com_acceleration[2])) if result.success else ikd.force
    realized = np.array([-result.moment[1], result.moment[0]]) / force
    limited = False
    if result.success:
        ikd.qdot = ikd.qdot + dt * result.qddot
        fastest = float(np.max(np.abs(ikd.qdot)))
        if not fastest <= c.max_velocity:
            limited = True
            ikd.qdot = ikd.qdot * (c.max_velocity / fastest) if math.isfinite(fastest) else np.zeros(model.nv)
        ikd.q = model.integrate(ikd.q, ikd.qdot, dt)
    else:
        ikd.qdot = np.zeros(model.nv)
    return WalkingIkdStep(
        ikd.q.copy(),
        ikd.qdot.copy(),
        result.qddot,
        com,
        com_velocity,
        realized,
        ideal.copy(),
        planned.zmp_shift if planned is not None else np.zeros(2),
        result.moment,
        support,
        lz,
        result.residual,
        result.sigma_min,
        result.success,
        limited,
    )


class _Plain:
    """An objective passed through as it is: keeps BipedIkd on sum_objectives (the previous evaluation)."""

    def __init__(self, objective) -> None:
        self.objective = objective

    def evaluate(self, model, q):
        return self.objective.evaluate(model, q)


def _assert_same_step(fast, slow, rtol: float = 1e-9) -> None:
    for name in fast._fields:
        a, b = getattr(fast, name), getattr(slow, name)
        if isinstance(b, (bool, np.bool_)):
            assert bool(a) == bool(b), name
            continue
        a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
        assert a.shape == b.shape, name
        # the task residual is round-off itself (1e-13): held to an absolute bound, as _assert_same_result does
        floor = 1e-9 if name == "residual" else 1e-300
        np.testing.assert_allclose(
            a, b, rtol=0.0, atol=max(rtol * float(np.abs(b).max(initial=0.0)), floor), err_msg=name
        )


def _walker_pair(biped: RobotModel, config: WalkingIkdConfig, pattern_speed: float = 0.4):
    from redundancy_gym.controllers import JointLimitObjective
    from redundancy_gym.controllers.objectives.actuated_objective import ActuatedObjective

    q = standing(biped)
    biped.update(q)
    feet = [biped.frame_position(f).copy() for f in FEET]
    com = biped.com().copy()
    gait = GaitConfig(step_duration=0.6)
    pattern = WalkingPattern(gait, feet[0], feet[1], com[:2], pattern_speed)
    # the walking controller's joint-limit objective, with limits near enough to act along this walk
    limits = ActuatedObjective(
        JointLimitObjective(
            biped.lower_limits[7:], biped.upper_limits[7:], activation_distance=0.6, slope=2.0, weight=1.5
        ),
        biped,
    )
    walkers = [
        WalkingIkd(biped, DT, config, omega=np.sqrt(9.81 / gait.com_height), posture=q, objectives=objectives)
        for objectives in ((limits,), (_Plain(limits),))
    ]
    for walker in walkers:
        walker.start(q)
    return pattern, walkers


@pytest.mark.parametrize(
    "config",
    [WalkingIkdConfig(), WalkingIkdConfig(planning=False, max_velocity=0.9), WalkingIkdConfig(moment_gain=0.0)],
    ids=["hybrid", "limited", "planning-only"],
)
def test_the_fast_step_equals_the_previous_computation_along_300_periods(biped, config):
    # the compiled assembly, the float support box and planner, the compiled joint-limit gradient: along 300
    # periods of a walk with a moving balance offset and a prescribed ZMP, the same steps (1e-9, relative) as the
    # previous NumPy computation on its own walker
    pattern, (fast, slow) = _walker_pair(biped, config)
    planned = gradients = limited = 0
    for n in range(300):
        t = n * DT
        start, end = pattern.sample(t), pattern.sample(t + DT)
        start_ref = WalkingController._reference_array(start, np.zeros(2), np.zeros(2))
        end_ref = WalkingController._reference_array(end, np.zeros(2), np.zeros(2))
        k = start.step
        window = (pattern.step_start(k) + pattern.step_single(k), pattern.step_start(k + 1)) if k >= 0 else None
        offset = 0.01 * np.array([np.sin(3.0 * t), np.cos(2.0 * t)])
        rate = 0.01 * np.array([3.0 * np.cos(3.0 * t), -2.0 * np.sin(2.0 * t)])
        zmp = start.zmp + 0.002 * np.array([np.cos(t), np.sin(t)]) if n % 2 else None
        a = fast.step(start, start_ref, end_ref, window, offset, rate, zmp)
        b = _previous_step(slow, start, start_ref, end_ref, window, offset, rate, zmp)
        _assert_same_step(a, b)
        planned += bool(np.any(b.planning_shift != 0.0))
        limited += b.limited
        gradients += bool(np.any(slow.ikd.objectives[0].evaluate(biped, slow.q).gradient != 0.0))
    assert gradients > 100  # the joint limits act
    if config.planning:
        assert planned > 10  # the planning's double-support modification happened
    if config.max_velocity < 1.0:
        assert limited > 0


def test_other_input_types_take_the_general_step_with_the_same_result(biped):
    # a strided reference, a list or a tuple of NumPy scalars as the offset: the NumPy step, equal to the fast one
    # (which takes a list ZMP and a tuple with an int as its rate)
    pattern, (fast, slow) = _walker_pair(biped, WalkingIkdConfig())
    slow.ikd.objectives = fast.ikd.objectives
    for n in range(60):
        t = n * DT
        start, end = pattern.sample(t), pattern.sample(t + DT)
        start_ref = WalkingController._reference_array(start, np.zeros(2), np.zeros(2))
        end_ref = WalkingController._reference_array(end, np.zeros(2), np.zeros(2))
        k = start.step
        window = (pattern.step_start(k) + pattern.step_single(k), pattern.step_start(k + 1)) if k >= 0 else None
        offset = np.array([0.004, -0.002])
        strided = np.zeros(2 * start_ref.size)
        strided[::2] = start_ref
        variants = [
            (start_ref, end_ref, offset, (0.01, 0), start.zmp.tolist()),
            (strided[::2], end_ref, list(offset), (np.float64(0.01), 0.0), start.zmp),
            (start_ref, end_ref, tuple(offset), np.array([0.01, 0.0]), start.zmp),
        ]
        other = variants[1 + n % 2]
        a = fast.step(start, *variants[0][:2], window, *variants[0][2:])
        b = slow.step(start, *other[:2], window, *other[2:])
        _assert_same_step(a, b, rtol=1e-12)  # the compiled result assembly sums in its own order


def test_the_support_box_equals_the_array_computation_turned_or_not(biped):
    from redundancy_gym.controllers.walking.walking_pattern import PatternSample

    ikd = WalkingIkd(biped, DT, WalkingIkdConfig(), omega=3.5, posture=standing(biped))
    rng = np.random.default_rng(3)
    for n in range(200):
        yaw = np.zeros(2) if n % 2 else rng.uniform(-0.6, 0.6, 2)
        contact = [(True, True), (True, False), (False, True)][n % 3]
        sample = PatternSample(
            0.0,
            np.zeros(3),
            np.zeros(3),
            np.zeros(2),
            np.zeros(2),
            rng.normal(size=(2, 3)),
            np.zeros((2, 3)),
            np.zeros(2),
            np.zeros(2),
            yaw,
            np.zeros(2),
            contact,
            0.5,
            0,
        )
        shift = rng.normal(scale=0.02, size=2)
        expected = _previous_support(ikd, sample, shift)
        np.testing.assert_allclose(ikd._support(sample, shift), expected, rtol=1e-12, atol=1e-15)
        np.testing.assert_array_equal(ikd._support(sample, tuple(shift.tolist())), ikd._support(sample, shift))
    nowhere = PatternSample(
        0.0,
        np.zeros(3),
        np.zeros(3),
        np.zeros(2),
        np.zeros(2),
        np.full((2, 3), np.nan),
        np.zeros((2, 3)),
        np.zeros(2),
        np.zeros(2),
        np.zeros(2),
        np.zeros(2),
        (True, True),
        0.5,
        0,
    )
    assert np.all(np.isnan(ikd._support(nowhere, np.zeros(2))))


def test_a_copied_walker_steps_as_the_original(biped):
    # the fast step's buffer views are rebuilt in a deep copy (whose views would otherwise be separate arrays)
    import copy

    pattern, (fast, _) = _walker_pair(biped, WalkingIkdConfig())
    for n in range(40):
        t = n * DT
        start, end = pattern.sample(t), pattern.sample(t + DT)
        start_ref = WalkingController._reference_array(start, np.zeros(2), np.zeros(2))
        end_ref = WalkingController._reference_array(end, np.zeros(2), np.zeros(2))
        if n == 20:
            twin = copy.deepcopy(fast)
        if n >= 20:
            a = fast.step(start, start_ref, end_ref, None, np.array([0.003, 0.001]))
            b = twin.step(start, start_ref, end_ref, None, np.array([0.003, 0.001]))
            _assert_same_step(b, a, rtol=0.0)
        else:
            fast.step(start, start_ref, end_ref, None)


def test_the_planners_float_advance_equals_the_array_computation():
    from redundancy_gym.controllers.ikd import PlanStabilizer

    fast, slow = PlanStabilizer(3.3, ramp=0.2), PlanStabilizer(3.3, ramp=0.2)
    rng = np.random.default_rng(5)
    dt = 0.004
    for n in range(600):
        t = n * dt
        if n % 150 == 10:
            deviation, rate = rng.normal(scale=0.01, size=2), rng.normal(scale=0.05, size=2)
            for planner in (fast, slow):
                planner.replan(t, deviation, rate, (t + 0.1, t + 0.26))
        a, b = fast.advance(t, dt), _previous_advance(slow, t, dt)
        for name in a._fields:
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
        np.testing.assert_array_equal(fast.offset, slow.offset)
        np.testing.assert_array_equal(fast.offset_rate, slow.offset_rate)
        assert fast.window == slow.window

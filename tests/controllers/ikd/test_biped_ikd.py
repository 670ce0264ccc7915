"""Biped IKD (5.84)-(5.91): the motion it generates needs exactly the prescribed contact moment, by pinocchio's
inverse dynamics of the floating-base robot (RNEA) as the independent reference."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from redundancy_gym.assets import BIPED_XML
from redundancy_gym.controllers import ControllerError
from redundancy_gym.controllers.clik.redundancy_resolution import resolve
from redundancy_gym.controllers.ikd import BipedIkd, BipedIkdReference, BipedIkdResult
from redundancy_gym.controllers.ikd.biped_ikd import GRAVITY
from redundancy_gym.controllers.kernels.linalg import rotation_error
from redundancy_gym.model import RobotModel
from tests.controllers.walking.biped_helpers import standing

FEET = ("r_sole", "l_sole")


@pytest.fixture(scope="module")
def biped() -> RobotModel:
    return RobotModel.from_mjcf(BIPED_XML)


def _reference(model: RobotModel, q: np.ndarray, zmp: np.ndarray, lift: float = 0.0) -> BipedIkdReference:
    """Both soles and the torso where they are in ``q`` (the left sole raised by ``lift``), the CoM's height held,
    and the contact moment of a vertical force ``m g`` at ``zmp`` (about the origin: ``T = F_z (p_y, -p_x)``)."""
    model.update(q)
    position = np.array([model.frame_position(f) for f in FEET])
    position[1, 2] += lift
    rotation = np.array([model.frame_rotation(f) for f in FEET])
    force = model.total_mass * GRAVITY
    return BipedIkdReference(
        position,
        rotation,
        np.zeros((2, 6)),
        np.zeros((2, 6)),
        model.frame_rotation("imu"),
        np.zeros(3),
        np.zeros(3),
        np.array([model.com()[2], 0.0, 0.0]),
        np.array([force * zmp[1], -force * zmp[0]]),
    )


def _contact_moment(model: RobotModel, q: np.ndarray, qdot: np.ndarray, qddot: np.ndarray) -> np.ndarray:
    """The moment about the world origin [N m] of the wrench the ground must apply for the motion (the floating
    base's rows of RNEA, a spatial force in the base frame at its origin)."""
    data = model.pinocchio_model.createData()
    tau = pin.rnea(model.pinocchio_model, data, q, qdot, qddot)
    base = pin.XYZQUATToSE3(q[:7])
    force = base.rotation @ tau[:3]
    return base.rotation @ tau[3:6] + np.cross(base.translation, force)


def test_the_generated_motion_needs_exactly_the_prescribed_contact_moment(biped):
    # 0.6 s of a lateral ZMP sway while the left foot lifts: at every period the inverse dynamics of the IKD's
    # motion give back the prescribed moment, and the known rows are tracked
    q = standing(biped)
    qdot = np.zeros(biped.nv)
    ikd = BipedIkd(biped, posture=q)
    biped.update(q)
    start = biped.com().copy()
    dt = 0.001
    for k in range(600):
        t = k * dt
        zmp = np.array([start[0], 0.05 * np.sin(2.0 * np.pi * t / 1.2)])
        if k == 0:
            reference = _reference(biped, q, zmp)
        reference = reference._replace(moment=_reference(biped, q, zmp).moment, **_lift(reference, t))
        result = ikd.step(q, qdot, reference)
        assert result.success and result.residual < 1e-9
        moment = _contact_moment(biped, q, qdot, result.qddot)
        np.testing.assert_allclose(moment[:2], reference.moment, rtol=0.0, atol=1e-6 * np.abs(reference.moment).max())
        qdot = qdot + dt * result.qddot
        q = biped.integrate(q, qdot, dt)
    biped.update(q)
    np.testing.assert_allclose(biped.frame_position("r_sole"), reference.feet_position[0], atol=1e-4)
    np.testing.assert_allclose(biped.frame_position("l_sole"), reference.feet_position[1], atol=1e-4)


def _lift(reference: BipedIkdReference, t: float) -> dict[str, np.ndarray]:
    """The left sole raised by ``0.04 sin^2(pi s)`` [m], ``s = (t - 0.3) / 0.3`` over 0.3-0.6 s, with its rates."""
    position, velocity, acceleration = reference.feet_position.copy(), np.zeros((2, 6)), np.zeros((2, 6))
    position[1, 2] = position[0, 2]
    if t > 0.3:
        s = (t - 0.3) / 0.3
        position[1, 2] += 0.04 * np.sin(np.pi * s) ** 2
        velocity[1, 2] = 0.04 * np.pi / 0.3 * np.sin(2.0 * np.pi * s)
        acceleration[1, 2] = 0.04 * 2.0 * np.pi**2 / 0.09 * np.cos(2.0 * np.pi * s)
    return {"feet_position": position, "feet_velocity": velocity, "feet_acceleration": acceleration}


def test_the_com_accelerates_away_from_the_zmp_as_the_inverted_pendulum_does(biped):
    # at rest, the ZMP under the CoM keeps it still; 2 cm behind it, the CoM accelerates forward at about
    # g / z_c times the offset (the unknown rows, solved from the angular momentum theorem; the multi-body's own
    # angular momentum takes about a tenth of the moment that the point-mass pendulum puts into the CoM)
    q = standing(biped)
    ikd = BipedIkd(biped, posture=q)
    biped.update(q)
    com = biped.com().copy()
    still = ikd.step(q, np.zeros(biped.nv), _reference(biped, q, com[:2]))
    np.testing.assert_allclose(still.com_acceleration, 0.0, atol=1e-9)
    offset = 0.02
    pushed = ikd.step(q, np.zeros(biped.nv), _reference(biped, q, com[:2] - np.array([offset, 0.0])))
    lipm = GRAVITY / com[2] * offset
    assert pushed.com_acceleration[0] == pytest.approx(lipm, rel=0.2)
    assert abs(pushed.com_acceleration[1]) < 0.05 * lipm


def test_without_stabilization_the_com_drifts_away_from_a_balanced_plan(biped):
    # the monograph's fig. 5.21: the contact moment of a ZMP 5 mm off the CoM's start, held, lets the CoM run off
    # exponentially (about 2.6 cm in 0.5 s here), while the moment stays exactly the prescribed one
    q = standing(biped)
    qdot = np.zeros(biped.nv)
    ikd = BipedIkd(biped, posture=q)
    biped.update(q)
    start = biped.com().copy()
    reference = _reference(biped, q, start[:2] - np.array([0.005, 0.0]))
    for _ in range(500):
        result = ikd.step(q, qdot, reference)
        qdot = qdot + 0.001 * result.qddot
        q = biped.integrate(q, qdot, 0.001)
    biped.update(q)
    drift = biped.com()[0] - start[0]
    omega = np.sqrt(GRAVITY / start[2])
    assert drift == pytest.approx(0.005 * (np.cosh(omega * 0.5) - 1.0), rel=0.25)


def test_a_fixed_base_model_and_bad_references_are_refused(biped):
    from redundancy_gym.assets import PLANAR_ARM_XML

    with pytest.raises(ControllerError, match="floating-base"):
        BipedIkd(RobotModel.from_mjcf(PLANAR_ARM_XML))
    with pytest.raises(ControllerError, match="stiffness"):
        BipedIkd(biped, stiffness=-1.0)
    q = standing(biped)
    reference = _reference(biped, q, np.zeros(2))
    with pytest.raises(ControllerError, match="reference.moment"):
        BipedIkd(biped).step(q, np.zeros(biped.nv), reference._replace(moment=np.array([np.nan, 0.0])))


def _walk(biped: RobotModel, gain: float, duration: float) -> tuple[list[float], list[float], list[bool]]:
    """A kinematic IKD walk at 0.4 m/s along the DCM walking pattern (its soles, its LIPM ZMP as the contact moment,
    its CoM as the plan of (5.97)) with ``moment_gain`` ``gain``; per period: the largest relative difference of
    RNEA's contact moment from the one the IKD realized, the CoM's distance from the plan [m], and whether the
    realized moment's ZMP lies in the support box. Stops early when the IKD fails."""
    from redundancy_gym.controllers.walking import GaitConfig, WalkingPattern

    q = standing(biped)
    qdot = np.zeros(biped.nv)
    biped.update(q)
    feet = [biped.frame_position(f).copy() for f in FEET]
    start = biped.com().copy()
    pattern = WalkingPattern(GaitConfig(), feet[0], feet[1], start[:2], 0.4)
    ikd = BipedIkd(biped, posture=q, moment_gain=gain, period=0.001)
    force = biped.total_mass * GRAVITY
    errors, distances, inside = [], [], []
    dt = 0.001
    for n in range(int(round(duration / dt))):
        sample, ahead = pattern.sample(n * dt), pattern.sample((n + 1) * dt)
        velocity, acceleration = np.zeros((2, 6)), np.zeros((2, 6))
        velocity[:, :3], velocity[:, 4] = sample.feet_velocity, sample.feet_pitch_rate
        acceleration[:, :3] = (ahead.feet_velocity - sample.feet_velocity) / dt
        acceleration[:, 4] = (ahead.feet_pitch_rate - sample.feet_pitch_rate) / dt
        rotation = np.array(
            [[[np.cos(a), 0.0, np.sin(a)], [0.0, 1.0, 0.0], [-np.sin(a), 0.0, np.cos(a)]] for a in sample.feet_pitch]
        )
        standing_feet = [f for f, c in zip(sample.feet, sample.contact, strict=True) if c]
        box = np.array(
            [
                np.min([[f[0] - 0.095, f[1] - 0.075] for f in standing_feet], axis=0),
                np.max([[f[0] + 0.165, f[1] + 0.075] for f in standing_feet], axis=0),
            ]
        )
        zmp = sample.zmp
        reference = BipedIkdReference(
            sample.feet.copy(),
            rotation,
            velocity,
            acceleration,
            np.eye(3),
            np.zeros(3),
            np.zeros(3),
            np.array([start[2], 0.0, 0.0]),
            np.array([force * zmp[1], -force * zmp[0]]),
            np.array([*sample.com[:2], *sample.com_velocity[:2]]),
            box,
        )
        result = ikd.step(q, qdot, reference)
        if not result.success:
            break
        moment = _contact_moment(biped, q, qdot, result.qddot)
        errors.append(float(np.abs(moment[:2] - result.moment).max() / np.abs(result.moment).max()))
        realized = np.array([-result.moment[1], result.moment[0]]) / force
        inside.append(bool(np.all(realized >= box[0] - 1e-9) and np.all(realized <= box[1] + 1e-9)))
        biped.update(q)
        distances.append(float(np.linalg.norm(biped.com()[:2] - sample.com[:2])))
        qdot = qdot + dt * result.qddot
        q = biped.integrate(q, qdot, dt)
        if distances[-1] > 0.2:
            break
    return errors, distances, inside


def test_a_stabilized_ikd_walk_of_several_steps_realizes_its_moment_exactly_and_keeps_to_the_plan(biped):
    # three steps (2.5 s) with k = 1e-3 (K_p = 40, K_d = 10.8 at 1 ms; the pendulum needs K_p > g / z = 10.8):
    # the moment that inverse dynamics give for the motion is the realized one at every period, its ZMP never
    # leaves the support box, and the CoM stays within a centimetre of the plan
    errors, distances, inside = _walk(biped, 1e-3, 2.5)
    assert len(errors) == 2500
    assert max(errors) < 1e-6
    assert all(inside)
    assert max(distances) < 0.01
    # unstabilized (k = 0) the same walk runs off the plan (fig. 5.21): 5 cm within two steps
    _, distances, _ = _walk(biped, 0.0, 2.0)
    assert max(distances) > 0.05


def _reference_step(ikd: BipedIkd, q: np.ndarray, qdot: np.ndarray, reference: BipedIkdReference) -> BipedIkdResult:
    """:meth:`BipedIkd.step` spelled out with the separate RobotModel queries and the generic ``resolve`` (the
    implementation before the compiled one): the independent reference of the fast path."""
    model, m = ikd.model, ikd.mass
    drift = model.frames_jacobian_derivative_times_velocity(q, qdot, (*ikd.feet_frames, ikd.torso_frame), "full")
    jacobians, accelerations = [], []
    for i, frame in enumerate(ikd.feet_frames):
        jac = model.frame_jacobian(frame, "full")
        rotation, position = model.frame_placement(frame)
        error = np.concatenate(
            [reference.feet_position[i] - position, rotation_error(reference.feet_rotation[i], rotation)]
        )
        accelerations.append(
            reference.feet_acceleration[i] + ikd.kd * (reference.feet_velocity[i] - jac @ qdot) + ikd.kp * error
        )
        jacobians.append(jac)
    jac = model.frame_jacobian(ikd.torso_frame, "rotational")
    error = rotation_error(reference.torso_rotation, model.frame_rotation(ikd.torso_frame))
    accelerations.append(
        reference.torso_angular_acceleration + ikd.kd * (reference.torso_angular_velocity - jac @ qdot) + ikd.kp * error
    )
    jacobians.append(jac)
    j_known, drift_known = np.vstack(jacobians), np.concatenate([drift[0], drift[1], drift[2, 3:]])
    wddot_known = np.concatenate(accelerations)
    momentum_drift = model.centroidal_momentum_drift(q, qdot)
    com, centroidal = model.com_and_centroidal_matrix()
    j_com, drift_com = centroidal[:3] / m, momentum_drift[:3] / m
    height, moment = reference.com_height, np.asarray(reference.moment, dtype=np.float64)
    z_acceleration = height[2] + ikd.kd * (height[1] - j_com[2] @ qdot) + ikd.kp * (height[0] - com[2])
    g = GRAVITY + z_acceleration
    b_mat = np.array([[0.0, -m * com[2]], [m * com[2], 0.0]])
    if reference.com_plan is not None and ikd.moment_gain > 0.0:  # (5.97)
        plan, force = reference.com_plan, m * g
        moment = moment + b_mat @ (
            ikd.com_stiffness * (plan[:2] - com[:2]) + ikd.com_damping * (plan[2:] - j_com[:2] @ qdot)
        )
        if reference.support is not None and force > 0.0:
            zmp = np.clip(np.array([-moment[1], moment[0]]) / force, reference.support[0], reference.support[1])
            moment = force * np.array([zmp[1], -zmp[0]])
    c = momentum_drift[3:5] + np.array([m * com[1] * g - moment[0], -m * com[0] * g - moment[1]])
    b_inverse = np.array([[0.0, 1.0], [-1.0, 0.0]]) / (m * com[2])
    r_mat = np.vstack([j_known, j_com[2], j_com[:2] + b_inverse @ centroidal[3:5]])
    r_vec = np.concatenate([drift_known - wddot_known, [drift_com[2] - z_acceleration], drift_com[:2] + b_inverse @ c])
    preferred = -ikd.self_motion_damping * qdot
    if ikd.posture is not None:
        preferred = preferred - ikd.posture_stiffness * model.difference(ikd.posture, q)
    res = resolve(r_mat, -r_vec, -ikd.weights.apply(preferred), ikd.weights, singular_threshold=ikd.singular_threshold)
    if not res.success:
        return BipedIkdResult(
            np.zeros(model.nv), np.zeros(3), float(np.linalg.norm(r_vec)), res.sigma_min, False, res.status, moment
        )
    return BipedIkdResult(
        res.x,
        j_com @ res.x + drift_com,
        float(np.linalg.norm(r_mat @ res.x + r_vec)),
        res.sigma_min,
        True,
        res.status,
        moment,
    )


def _assert_same_result(fast: BipedIkdResult, slow: BipedIkdResult, rtol: float = 1e-9) -> None:
    assert fast.success == slow.success and fast.status == slow.status
    for name in ("qddot", "com_acceleration", "moment"):
        a, b = getattr(fast, name), getattr(slow, name)
        np.testing.assert_allclose(a, b, rtol=0.0, atol=rtol * max(np.abs(b).max(), 1e-300), err_msg=name)
    assert fast.sigma_min == pytest.approx(slow.sigma_min, rel=rtol, abs=1e-12)
    assert fast.residual == pytest.approx(slow.residual, rel=rtol, abs=1e-9)


def _walk_states(biped: RobotModel, duration: float) -> list[tuple[np.ndarray, np.ndarray, BipedIkdReference]]:
    """The states and references of the stabilized IKD walk of :func:`_walk` (k = 1e-3), every 10th period."""
    from redundancy_gym.controllers.walking import GaitConfig, WalkingPattern

    q = standing(biped)
    qdot = np.zeros(biped.nv)
    biped.update(q)
    feet = [biped.frame_position(f).copy() for f in FEET]
    start = biped.com().copy()
    pattern = WalkingPattern(GaitConfig(), feet[0], feet[1], start[:2], 0.4)
    ikd = BipedIkd(biped, posture=q, moment_gain=1e-3)
    force = biped.total_mass * GRAVITY
    states, dt = [], 0.001
    for n in range(int(round(duration / dt))):
        sample, ahead = pattern.sample(n * dt), pattern.sample((n + 1) * dt)
        velocity, acceleration = np.zeros((2, 6)), np.zeros((2, 6))
        velocity[:, :3], velocity[:, 4] = sample.feet_velocity, sample.feet_pitch_rate
        acceleration[:, :3] = (ahead.feet_velocity - sample.feet_velocity) / dt
        acceleration[:, 4] = (ahead.feet_pitch_rate - sample.feet_pitch_rate) / dt
        rotation = np.array(
            [[[np.cos(a), 0.0, np.sin(a)], [0.0, 1.0, 0.0], [-np.sin(a), 0.0, np.cos(a)]] for a in sample.feet_pitch]
        )
        standing_feet = [f for f, c in zip(sample.feet, sample.contact, strict=True) if c]
        box = np.array(
            [
                np.min([[f[0] - 0.095, f[1] - 0.075] for f in standing_feet], axis=0),
                np.max([[f[0] + 0.165, f[1] + 0.075] for f in standing_feet], axis=0),
            ]
        )
        reference = BipedIkdReference(
            sample.feet.copy(),
            rotation,
            velocity,
            acceleration,
            np.eye(3),
            np.zeros(3),
            np.zeros(3),
            np.array([start[2], 0.0, 0.0]),
            np.array([force * sample.zmp[1], -force * sample.zmp[0]]),
            np.array([*sample.com[:2], *sample.com_velocity[:2]]),
            box,
        )
        if n % 10 == 0:
            states.append((q.copy(), qdot.copy(), reference))
        result = ikd.step(q, qdot, reference)
        assert result.success
        qdot = qdot + dt * result.qddot
        q = biped.integrate(q, qdot, dt)
    return states


def test_the_compiled_step_equals_the_reference_computation_along_a_walk(biped):
    # on the moving states of a stabilized walk (single and double support), with the ZMP clipped to a tight box,
    # without stabilization or posture, with a full weight matrix and with other gains, the compiled step gives
    # the reference computation's result to 1e-9 (relative)
    states = _walk_states(biped, 1.2)
    posture = standing(biped)
    rng = np.random.default_rng(7)
    root = rng.normal(size=(biped.nv, biped.nv))
    variants = [
        BipedIkd(biped, posture=posture, moment_gain=1e-3),
        BipedIkd(biped, moment_gain=0.0, stiffness=100.0, damping=20.0, self_motion_damping=3.0),
        BipedIkd(
            biped, posture=posture, moment_gain=2e-3, weights=rng.uniform(0.5, 2.0, biped.nv), posture_stiffness=5.0
        ),
        BipedIkd(biped, posture=posture, moment_gain=1e-3, weights=root @ root.T + biped.nv * np.eye(biped.nv)),
    ]
    clipped = 0
    for q, qdot, reference in states:
        assert np.abs(qdot).max() > 0.0 or q is states[0][0]
        zmp = np.array([-reference.moment[1], reference.moment[0]]) / (biped.total_mass * GRAVITY)
        tight = reference._replace(support=np.array([zmp - 1e-3, zmp + 1e-3]))
        for ikd in variants:
            for ref in (reference, tight, reference._replace(support=None), reference._replace(com_plan=None)):
                fast = ikd.step(q, qdot, ref)
                _assert_same_result(fast, _reference_step(ikd, q, qdot, ref))
                assert fast.success and fast.residual < 1e-9
        result = variants[0].step(q, qdot, tight)
        clipped += bool(
            np.any(
                np.abs(np.array([-result.moment[1], result.moment[0]]) / (biped.total_mass * GRAVITY) - zmp) > 0.999e-3
            )
        )
    assert len(states) == 120 and clipped > 10


def test_inputs_of_other_types_and_layouts_give_the_same_step(biped):
    # lists, integer arrays, strided views and read-only arrays take the general checks and conversions and give
    # what float64 C arrays give; a reference row of another shape is broadcast as NumPy broadcasts it
    q, qdot, reference = _walk_states(biped, 0.45)[-1]
    ikd = BipedIkd(biped, posture=standing(biped), moment_gain=1e-3)
    expected = ikd.step(q, qdot, reference)
    _assert_same_result(expected, _reference_step(ikd, q, qdot, reference))
    as_lists = BipedIkdReference(*(None if f is None else np.asarray(f).tolist() for f in reference))
    _assert_same_result(ikd.step(q.tolist(), qdot.tolist(), as_lists), expected, rtol=0.0)
    strided = np.zeros(2 * biped.nv)
    strided[::2] = qdot
    readonly = reference.feet_velocity.copy()
    readonly.flags.writeable = False
    _assert_same_result(ikd.step(q, strided[::2], reference._replace(feet_velocity=readonly)), expected, rtol=0.0)
    _assert_same_result(
        ikd.step(q, qdot, reference._replace(torso_rotation=np.eye(3, dtype=int), torso_angular_velocity=0.0)),
        expected,
        rtol=0.0,
    )
    scalar_box = reference._replace(support=np.array([-1.0, 1.0]))  # box[0], box[1] broadcast over x and y
    _assert_same_result(ikd.step(q, qdot, scalar_box), _reference_step(ikd, q, qdot, scalar_box))
    # the plan's shape matters only when it is used; the rows must be rows
    with pytest.raises(ControllerError, match="com_plan"):
        ikd.step(q, qdot, reference._replace(com_plan=np.zeros(3)))
    unstabilized = BipedIkd(biped, posture=standing(biped))
    _assert_same_result(
        unstabilized.step(q, qdot, reference._replace(com_plan=np.zeros(3))),
        unstabilized.step(q, qdot, reference),
        rtol=0.0,
    )
    with pytest.raises(ControllerError, match="feet_rotation"):
        ikd.step(q, qdot, reference._replace(feet_rotation=np.zeros((2, 3))))
    with pytest.raises(ControllerError, match="feet_velocity"):
        ikd.step(q, qdot, reference._replace(feet_velocity=np.zeros((2, 5))))
    with pytest.raises(ControllerError, match="q must be finite"):
        ikd.step(np.full(biped.nq, np.nan), qdot, reference)
    with pytest.raises(ControllerError, match="qdot"):
        ikd.step(q, qdot[:-1], reference)
    with pytest.raises(ControllerError, match="reference.feet_acceleration"):
        ikd.step(q, qdot, reference._replace(feet_acceleration=np.full((2, 6), np.inf)))
    with pytest.raises(ControllerError, match="reference.support"):
        ikd.step(q, qdot, reference._replace(support=np.array([[0.0, np.nan], [1.0, 1.0]])))


def test_a_singular_task_is_reported_as_the_reference_computation_reports_it(biped):
    # the same sole twice: R has repeated rows, sigma_min is 0 and the step returns zeros, "singular", and the
    # residual |r| of the zero motion
    q, qdot, reference = _walk_states(biped, 0.2)[-1]
    ikd = BipedIkd(biped, feet_frames=("r_sole", "r_sole"), posture=standing(biped), moment_gain=1e-3)
    result = ikd.step(q, qdot, reference)
    slow = _reference_step(ikd, q, qdot, reference)
    assert not result.success and result.status == "singular" == slow.status
    assert np.all(result.qddot == 0.0) and np.all(result.com_acceleration == 0.0)
    assert result.sigma_min < 1e-6 and slow.sigma_min < 1e-6
    assert result.residual == pytest.approx(slow.residual, rel=1e-9)
    np.testing.assert_allclose(result.moment, slow.moment, rtol=1e-9)


class _Plain:
    """An objective passed through as it is: keeps BipedIkd on sum_objectives (the general evaluation)."""

    def __init__(self, objective) -> None:
        self.objective = objective

    def evaluate(self, model, q):
        return self.objective.evaluate(model, q)


def test_the_compiled_joint_limit_gradient_equals_the_objectives_evaluation(biped):
    # ActuatedObjective(JointLimitObjective) exactly (the walking controller's) takes one compiled call: the same
    # step as through sum_objectives along a walk with active limits, with or without a posture; a changed weight
    # counts; non-finite distances (an unbounded limit) raise the objective's own error; other objectives and
    # limits of another length take sum_objectives
    from redundancy_gym.controllers import JointLimitObjective
    from redundancy_gym.controllers.objectives.actuated_objective import ActuatedObjective
    from redundancy_gym.geometry import GeometryError

    states = _walk_states(biped, 0.6)
    limits = ActuatedObjective(
        JointLimitObjective(
            biped.lower_limits[7:], biped.upper_limits[7:], activation_distance=0.6, slope=2.0, weight=1.5
        ),
        biped,
    )
    posture = standing(biped)
    active = 0
    for kwargs in ({"posture": posture}, {}, {"posture": posture, "posture_stiffness": 0.0}):
        fast = BipedIkd(biped, moment_gain=1e-3, objectives=(limits,), objective_gain=80.0, **kwargs)
        slow = BipedIkd(biped, moment_gain=1e-3, objectives=(_Plain(limits),), objective_gain=80.0, **kwargs)
        for q, qdot, reference in states:
            _assert_same_result(fast.step(q, qdot, reference), slow.step(q, qdot, reference), rtol=1e-12)
            active += bool(np.any(limits.evaluate(biped, q).gradient != 0.0))
    assert active > 30
    q, qdot, reference = states[-1]
    fast = BipedIkd(biped, posture=posture, objectives=(limits,))
    slow = BipedIkd(biped, posture=posture, objectives=(_Plain(limits),))
    limits.objective.weight = 4.0
    _assert_same_result(fast.step(q, qdot, reference), slow.step(q, qdot, reference), rtol=1e-12)
    unbounded = ActuatedObjective(JointLimitObjective(np.full(biped.nq - 7, -np.inf), biped.upper_limits[7:]), biped)
    with pytest.raises(GeometryError, match="finite"):
        BipedIkd(biped, posture=posture, objectives=(unbounded,)).step(q, qdot, reference)
    short = ActuatedObjective(JointLimitObjective(biped.lower_limits[8:], biped.upper_limits[8:]), biped)
    with pytest.raises(ControllerError, match="q must have shape"):
        BipedIkd(biped, posture=posture, objectives=(short,)).step(q, qdot, reference)
    both = BipedIkd(biped, posture=posture, objectives=(limits, limits))
    twice = BipedIkd(biped, posture=posture, objectives=(_Plain(limits), _Plain(limits)))
    _assert_same_result(both.step(q, qdot, reference), twice.step(q, qdot, reference), rtol=0.0)

import mujoco
import numpy as np
import pytest

from redundancy_gym.assets import BIPED_XML, PLANAR_ARM_JOINTS, PLANAR_ARM_TCP, PLANAR_ARM_XML
from redundancy_gym.model import ModelError, RobotModel, UnknownFrameError

BODIES = ("link1", "link2", "link3", "link4")


@pytest.fixture(scope="module")
def plant() -> tuple[mujoco.MjModel, mujoco.MjData]:
    model = mujoco.MjModel.from_xml_path(str(PLANAR_ARM_XML))
    return model, mujoco.MjData(model)


def _random_q(model: RobotModel, rng: np.random.Generator) -> np.ndarray:
    return rng.uniform(model.lower_limits, model.upper_limits)


def test_forward_kinematics_agrees_with_mujoco(planar_model: RobotModel, plant, rng) -> None:
    mj_model, mj_data = plant
    for _ in range(50):
        q = _random_q(planar_model, rng)
        mj_data.qpos[:] = q
        mujoco.mj_kinematics(mj_model, mj_data)
        planar_model.update(q)
        assert np.allclose(planar_model.frame_position(PLANAR_ARM_TCP), mj_data.site(PLANAR_ARM_TCP).xpos, atol=1e-9)
        for body in BODIES:
            R, p = planar_model.frame_placement(body)
            assert np.allclose(p, mj_data.body(body).xpos, atol=1e-9)
            assert np.allclose(R, mj_data.body(body).xmat.reshape(3, 3), atol=1e-9)


def test_limits_and_mass_match_mujoco(planar_model: RobotModel, plant) -> None:
    mj_model, _ = plant
    ranges = np.array([mj_model.joint(j).range for j in PLANAR_ARM_JOINTS])
    assert np.allclose(planar_model.lower_limits, ranges[:, 0])
    assert np.allclose(planar_model.upper_limits, ranges[:, 1])
    assert planar_model.total_mass == pytest.approx(float(mj_model.body_mass.sum()))
    assert planar_model.joint_names == list(PLANAR_ARM_JOINTS)


@pytest.mark.parametrize("frame", [PLANAR_ARM_TCP, "link3"])
def test_frame_jacobians_match_finite_differences(planar_model: RobotModel, rng, frame: str) -> None:
    h = 1e-7
    for _ in range(10):
        q = _random_q(planar_model, rng)
        planar_model.update(q)
        jt = planar_model.frame_jacobian(frame, "translational")
        jr = planar_model.frame_jacobian(frame, "rotational")
        R0 = planar_model.frame_rotation(frame)
        fd_t = np.zeros((3, 4))
        fd_r = np.zeros((3, 4))
        for i in range(4):
            dq = np.zeros(4)
            dq[i] = h
            planar_model.update(q + dq)
            p_plus, R_plus = planar_model.frame_position(frame), planar_model.frame_rotation(frame)
            planar_model.update(q - dq)
            p_minus = planar_model.frame_position(frame)
            fd_t[:, i] = (p_plus - p_minus) / (2 * h)
            skew = (R_plus @ R0.T - np.eye(3)) / h  # world angular velocity, first order
            fd_r[:, i] = [skew[2, 1], skew[0, 2], skew[1, 0]]
        assert np.allclose(jt, fd_t, atol=1e-6)
        assert np.allclose(jr, fd_r, atol=1e-5)
        planar_model.update(q)
        full = planar_model.frame_jacobian(frame, "full")
        assert np.allclose(full, np.vstack([jt, jr]))


def test_point_jacobian_matches_finite_differences(planar_model: RobotModel, rng) -> None:
    q = _random_q(planar_model, rng)
    planar_model.update(q)
    R, p = planar_model.frame_placement("link2")
    local = np.array([0.13, 0.02, -0.04])
    point = p + R @ local
    jac = planar_model.point_jacobian("link2", point)
    h = 1e-7
    fd = np.zeros((3, 4))
    for i in range(4):
        dq = np.zeros(4)
        dq[i] = h
        planar_model.update(q + dq)
        Rp, pp = planar_model.frame_placement("link2")
        planar_model.update(q - dq)
        Rm, pm = planar_model.frame_placement("link2")
        fd[:, i] = ((pp + Rp @ local) - (pm + Rm @ local)) / (2 * h)
    assert np.allclose(jac, fd, atol=1e-6)


def test_com_and_jacobian(planar_model: RobotModel, plant, rng) -> None:
    mj_model, mj_data = plant
    q = _random_q(planar_model, rng)
    mj_data.qpos[:] = q
    mujoco.mj_forward(mj_model, mj_data)
    planar_model.update(q)
    assert np.allclose(planar_model.com(), mj_data.subtree_com[0], atol=1e-9)
    jac = planar_model.com_jacobian()
    h = 1e-7
    for i in range(4):
        dq = np.zeros(4)
        dq[i] = h
        planar_model.update(q + dq)
        c_plus = planar_model.com()
        planar_model.update(q - dq)
        c_minus = planar_model.com()
        assert np.allclose(jac[:, i], (c_plus - c_minus) / (2 * h), atol=1e-6)


def test_centroidal_momentum_matches_mujoco_bodies(planar_model: RobotModel, plant, rng) -> None:
    """A_G qdot against linear and angular momentum summed from MuJoCo's body velocities and inertias."""
    mj_model, mj_data = plant
    q = _random_q(planar_model, rng)
    qdot = rng.normal(size=4)
    mj_data.qpos[:] = q
    mj_data.qvel[:] = qdot
    mujoco.mj_forward(mj_model, mj_data)
    com = mj_data.subtree_com[0].copy()
    linear = np.zeros(3)
    angular = np.zeros(3)
    vel = np.zeros(6)
    for body in BODIES:
        b = mj_data.body(body)
        bid = mj_model.body(body).id
        mujoco.mj_objectVelocity(mj_model, mj_data, mujoco.mjtObj.mjOBJ_BODY, bid, vel, 0)  # at the body CoM, world
        omega, v = vel[:3], vel[3:]
        mass = mj_model.body_mass[bid]
        R = b.ximat.reshape(3, 3)
        inertia = R @ np.diag(mj_model.body_inertia[bid]) @ R.T
        linear += mass * v
        angular += mass * np.cross(b.xipos - com, v) + inertia @ omega
    planar_model.update(q)
    momentum = planar_model.centroidal_momentum_matrix() @ qdot
    assert np.allclose(momentum[:3], linear, atol=1e-9)
    assert np.allclose(momentum[3:], angular, atol=1e-9)
    assert np.allclose(momentum[:3], planar_model.total_mass * planar_model.com_jacobian() @ qdot, atol=1e-9)


def test_mass_matrix_matches_mujoco(planar_model: RobotModel, plant, rng) -> None:
    """Joint-space inertia including the rotor armature, which pinocchio reads from the MJCF too."""
    mj_model, mj_data = plant
    q = _random_q(planar_model, rng)
    mj_data.qpos[:] = q
    mujoco.mj_forward(mj_model, mj_data)
    full = np.zeros((4, 4))
    mujoco.mj_fullM(mj_model, mj_data, full)
    planar_model.update(q)
    assert np.allclose(planar_model.mass_matrix(), full, atol=1e-9)


def test_integration_round_trip(planar_model: RobotModel, rng) -> None:
    q = _random_q(planar_model, rng)
    v = rng.normal(size=4)
    q1 = planar_model.integrate(q, v, 0.01)
    assert np.allclose(q1, q + 0.01 * v)
    assert np.allclose(planar_model.difference(q, q1), 0.01 * v)


def test_jacobian_drift_matches_finite_differences(planar_model: RobotModel, rng) -> None:
    q = _random_q(planar_model, rng)
    qdot = rng.normal(size=4)
    drift = planar_model.frame_jacobian_derivative_times_velocity(q, qdot, PLANAR_ARM_TCP, "translational")
    h = 1e-6
    planar_model.update(q + h * qdot)
    j_plus = planar_model.frame_jacobian(PLANAR_ARM_TCP, "translational")
    planar_model.update(q - h * qdot)
    j_minus = planar_model.frame_jacobian(PLANAR_ARM_TCP, "translational")
    assert np.allclose(drift, (j_plus - j_minus) @ qdot / (2 * h), atol=1e-6)


def test_errors_name_the_valid_choices(planar_model: RobotModel) -> None:
    with pytest.raises(ModelError, match="update"):
        RobotModel.from_mjcf(PLANAR_ARM_XML).frame_position("tcp")
    planar_model.update(np.zeros(4))
    with pytest.raises(UnknownFrameError, match="tcp"):
        planar_model.frame_position("nope")
    with pytest.raises(ModelError, match="translational"):
        planar_model.frame_jacobian("tcp", "linear")  # type: ignore[arg-type]
    with pytest.raises(ModelError, match="shape"):
        planar_model.update(np.zeros(3))
    with pytest.raises(ModelError, match="non-finite"):
        planar_model.update(np.array([0, np.nan, 0, 0]))
    with pytest.raises(ModelError, match="not found"):
        RobotModel.from_mjcf("/nonexistent.xml")


def test_clamp_limits_the_joints_and_leaves_a_floating_base_alone(planar_model: RobotModel) -> None:
    q = planar_model.upper_limits + 1.0
    np.testing.assert_array_equal(planar_model.clamp(q), planar_model.upper_limits)
    biped = RobotModel.from_mjcf(BIPED_XML)
    q = np.concatenate([[3.0, -2.5, 0.9], [0.0, 0.0, 0.6, 0.8], biped.upper_limits[7:] + 0.2])
    clamped = biped.clamp(q)
    np.testing.assert_array_equal(clamped[:7], q[:7])  # 3 m away and turned: still the same base pose
    np.testing.assert_array_equal(clamped[7:], biped.upper_limits[7:])


def _random_biped_state(model: RobotModel, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    quaternion = rng.normal(size=4)
    q = np.concatenate(
        [
            rng.normal(size=3),
            quaternion / np.linalg.norm(quaternion),
            rng.uniform(model.lower_limits[7:], model.upper_limits[7:]),
        ]
    )
    return q, rng.normal(size=model.nv)


def test_measure_is_the_com_its_velocity_and_the_frame_placements_of_a_full_update(rng) -> None:
    """measure() updates only the frames it is asked for: each agrees with update() and the frame queries, the
    CoM velocity with the CoM Jacobian, and afterwards the kinematic cache is empty."""
    biped = RobotModel.from_mjcf(BIPED_XML)
    frames: tuple[str | int, ...] = ("r_sole", "l_sole", biped.frame_id("imu"), "r_sole")
    for _ in range(5):
        q, v = _random_biped_state(biped, rng)
        com, com_velocity, rotations, positions = biped.measure(q, v, frames)
        assert rotations.shape == (4, 3, 3) and positions.shape == (4, 3)
        assert rotations.flags.c_contiguous and positions.flags.c_contiguous
        with pytest.raises(ModelError, match="update"):
            biped.frame_position("r_sole")
        biped.update(q)
        np.testing.assert_allclose(com, biped.com(), atol=1e-14)
        np.testing.assert_allclose(com_velocity, biped.com_jacobian() @ v, atol=1e-12)
        for k, frame in enumerate(frames):
            rotation, position = biped.frame_placement(frame)
            np.testing.assert_array_equal(rotations[k], rotation)
            np.testing.assert_array_equal(positions[k], position)
        # the results are the caller's: another measurement leaves them as they are
        kept = [com.copy(), com_velocity.copy(), rotations.copy(), positions.copy()]
        biped.measure(*_random_biped_state(biped, rng), frames)
        for a, b in zip(kept, (com, com_velocity, rotations, positions), strict=False):
            np.testing.assert_array_equal(a, b)
    # frames as a list, no frames, and an unknown frame
    q, v = _random_biped_state(biped, rng)
    np.testing.assert_array_equal(biped.measure(q, v, list(frames))[3], biped.measure(q, v, frames)[3])
    # each tuple of frames gets its own frames (the model keeps their indices per tuple)
    for subset in (("r_sole",), ("l_sole", "r_sole"), frames[:2]):
        _, _, rotations, positions = biped.measure(q, v, subset)
        biped.update(q)
        np.testing.assert_array_equal(positions, [biped.frame_position(f) for f in subset])
    empty = biped.measure(q, v)
    assert empty[2].shape == (0, 3, 3) and empty[3].shape == (0, 3)
    with pytest.raises(UnknownFrameError, match="nope"):
        biped.measure(q, v, ("r_sole", "nope"))
    with pytest.raises(ModelError, match="velocity must have shape"):
        biped.measure(q, v[:-1], frames)
    with pytest.raises(ModelError, match="non-finite"):
        biped.measure(np.where(np.arange(biped.nq) == 9, np.nan, q), v, frames)


def test_from_mujoco_state_normalizes_reorders_and_turns_the_base_velocity_into_the_base_frame(rng) -> None:
    biped = RobotModel.from_mjcf(BIPED_XML)
    qpos = np.concatenate([[0.1, 0.2, 0.9], [2.0, 0.4, -0.6, 1.0], rng.normal(size=biped.nq - 7)])  # not unit
    qvel = rng.normal(size=biped.nv)
    given = qpos.copy(), qvel.copy()
    q, v = biped.from_mujoco_state(qpos, qvel)
    w, x, y, z = qpos[3:7] / np.linalg.norm(qpos[3:7])
    np.testing.assert_allclose(q[3:7], [x, y, z, w], rtol=1e-15)
    np.testing.assert_array_equal(q[[0, 1, 2]], qpos[:3])
    np.testing.assert_array_equal(q[7:], qpos[7:])
    # the rotation of a unit quaternion (w, x, y, z), written out
    rotation = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
    np.testing.assert_allclose(v[:3], rotation.T @ qvel[:3], atol=1e-14)
    np.testing.assert_array_equal(v[3:], qvel[3:])
    np.testing.assert_array_equal(qpos, given[0])  # the inputs are left alone
    np.testing.assert_array_equal(qvel, given[1])
    qpos[3:7] = 0.0
    with pytest.raises(ModelError, match="quaternion of qpos is zero"):
        biped.from_mujoco_state(qpos, qvel)
    with pytest.raises(ModelError, match="shapes"):
        biped.from_mujoco_state(qpos[:-1], qvel)


def test_nonlinear_effects_close_the_equations_of_motion_with_the_mass_matrix():
    # M qddot + h(q, qdot) = tau of pinocchio's recursive Newton-Euler, for any qddot
    import pinocchio as pin

    from redundancy_gym.assets import AGRI_ARM_XML

    model = RobotModel.from_mjcf(AGRI_ARM_XML)
    data = model.pinocchio_model.createData()
    rng = np.random.default_rng(3)
    for _ in range(5):
        q = 0.5 * (model.lower_limits + model.upper_limits) + rng.uniform(-0.3, 0.3, model.nq)
        qdot, qddot = rng.normal(size=model.nv), rng.normal(size=model.nv)
        h = model.nonlinear_effects(q, qdot)
        tau = pin.rnea(model.pinocchio_model, data, q, qdot, qddot)
        np.testing.assert_allclose(model.mass_matrix() @ qddot + h, tau, rtol=1e-10, atol=1e-9)
    # the kinematic cache stays at q
    np.testing.assert_allclose(model.q, q)


def test_centroidal_momentum_drift_is_the_rate_of_the_momentum_at_zero_acceleration():
    # d/dt (A_G(q) v) along q(t) = q + v t with constant v, by central differences
    model = RobotModel.from_mjcf(BIPED_XML)
    rng = np.random.default_rng(4)
    q = np.zeros(model.nq)
    q[6] = 1.0
    q[2] = 0.9
    v = rng.normal(0.0, 0.3, model.nv)
    drift = model.centroidal_momentum_drift(q, v)
    h = 1e-6

    def momentum(t: float) -> np.ndarray:
        model.update(model.integrate(q, v, t))
        return model.com_and_centroidal_matrix()[1] @ v

    np.testing.assert_allclose(drift, (momentum(h) - momentum(-h)) / (2 * h), atol=1e-6)


def test_centroidal_drift_does_not_depend_on_what_ran_before(rng) -> None:
    """pinocchio 4.1's computeCentroidalMapTimeVariation reads the CoM velocity left in its data by earlier calls:
    Adot_G qdot from both queries must be the same after a query at another state as on a fresh model, and the
    rate of A_G qdot along q(t) = q + v t (central differences)."""
    q, v = _random_biped_state(RobotModel.from_mjcf(BIPED_XML), rng)
    v *= 0.3
    fresh = RobotModel.from_mjcf(BIPED_XML)
    reference = fresh.acceleration_terms(q, v, ("r_sole",)).centroidal_drift
    h = 1e-6

    def momentum(t: float) -> np.ndarray:
        fresh.update(fresh.integrate(q, v, t))
        return fresh.com_and_centroidal_matrix()[1] @ v

    np.testing.assert_allclose(reference, (momentum(h) - momentum(-h)) / (2 * h), atol=1e-5)
    for query in ("acceleration_terms", "centroidal_momentum_drift"):
        model = RobotModel.from_mjcf(BIPED_XML)
        q_other, v_other = _random_biped_state(model, rng)
        model.measure(q_other, 5.0 * v_other)  # leaves another state's CoM velocity in pinocchio's data
        if query == "acceleration_terms":
            drift = model.acceleration_terms(q, v, ("r_sole",)).centroidal_drift
        else:
            drift = model.centroidal_momentum_drift(q, v)
        np.testing.assert_allclose(drift, reference, rtol=0.0, atol=1e-10 * np.abs(reference).max())


def test_acceleration_terms_are_the_separate_queries_from_one_pass(rng) -> None:
    """acceleration_terms() gives what update() and the frame, Jdot qdot, CoM, A_G and Adot_G qdot queries give, and
    leaves the kinematic cache at q as update() does; the frames' drift is the rate of J qdot (finite differences
    along q(t) = q + v t)."""
    biped = RobotModel.from_mjcf(BIPED_XML)
    other = RobotModel.from_mjcf(BIPED_XML)
    frames: tuple[str | int, ...] = ("r_sole", "l_sole", "imu", biped.frame_id("r_sole"))
    for _ in range(4):
        q, v = _random_biped_state(biped, rng)
        terms = biped.acceleration_terms(q, v, frames)
        assert terms.rotation.shape == (4, 3, 3) and terms.position.shape == (4, 3)
        assert terms.jacobian.shape == (4, 6, biped.nv) and terms.drift.shape == (4, 6)
        drift = other.frames_jacobian_derivative_times_velocity(q, v, frames)
        momentum_drift = other.centroidal_momentum_drift(q, v)
        com, centroidal = other.com_and_centroidal_matrix()
        for k, frame in enumerate(frames):
            rotation, position = other.frame_placement(frame)
            np.testing.assert_allclose(terms.rotation[k], rotation, rtol=0.0, atol=1e-15)
            np.testing.assert_allclose(terms.position[k], position, rtol=0.0, atol=1e-14)
            np.testing.assert_allclose(terms.jacobian[k], other.frame_jacobian(frame), rtol=0.0, atol=1e-13)
            np.testing.assert_allclose(terms.drift[k], drift[k], rtol=1e-12, atol=1e-12 * np.abs(drift[k]).max())
        np.testing.assert_allclose(terms.com, com, rtol=0.0, atol=1e-14)
        np.testing.assert_allclose(terms.centroidal, centroidal, rtol=0.0, atol=1e-12 * np.abs(centroidal).max())
        np.testing.assert_allclose(
            terms.centroidal_drift, momentum_drift, rtol=0.0, atol=1e-12 * np.abs(momentum_drift).max()
        )
        # the cache is at q: every frame and Jacobian, as after update(q)
        np.testing.assert_array_equal(biped.q, q)
        for frame in biped.frame_names[::7]:
            np.testing.assert_allclose(biped.frame_position(frame), other.frame_position(frame), atol=1e-14)
            np.testing.assert_allclose(biped.frame_jacobian(frame), other.frame_jacobian(frame), atol=1e-13)
        np.testing.assert_allclose(biped.com_jacobian(), other.com_jacobian(), atol=1e-14)
    # Jdot qdot is d/dt (J qdot) (the linear rows as classical acceleration) by central differences
    q, v = _random_biped_state(biped, rng)
    v *= 0.3
    terms = biped.acceleration_terms(q, v, frames[:3])
    h = 1e-6

    def velocities(t: float) -> np.ndarray:
        qt = biped.integrate(q, v, t)
        return biped.acceleration_terms(qt, v, frames[:3]).jacobian @ v

    np.testing.assert_allclose(terms.drift, (velocities(h) - velocities(-h)) / (2 * h), atol=1e-5)
    # a list of frames, and the errors of the separate queries
    np.testing.assert_array_equal(
        biped.acceleration_terms(q, v, list(frames)).drift, biped.acceleration_terms(q, v, frames).drift
    )
    with pytest.raises(UnknownFrameError, match="nope"):
        biped.acceleration_terms(q, v, ("r_sole", "nope"))
    with pytest.raises(ModelError, match="velocity"):
        biped.acceleration_terms(q, v[:-1], frames)
    with pytest.raises(ModelError, match="configuration"):
        biped.acceleration_terms(q[:-1], v, frames)


def test_inverse_dynamics_matches_mujoco_on_the_floating_biped() -> None:
    # MuJoCo's inverse dynamics of the biped lifted off the floor (no contact): qfrc_inverse = M qacc + bias -
    # passive, the passive force the joint damping; the base at rest (velocity and acceleration zero), where the
    # free joint's conventions (MuJoCo's world-frame linear velocity, pinocchio's local spatial one) agree
    mj_model = mujoco.MjModel.from_xml_path(str(BIPED_XML))
    mj_data = mujoco.MjData(mj_model)
    model = RobotModel.from_mjcf(BIPED_XML)
    rng = np.random.default_rng(11)
    for _ in range(3):
        mj_data.qpos[:] = mj_model.qpos0
        mj_data.qpos[2] += 2.0  # far above the floor: no contact force enters qfrc_inverse
        mj_data.qpos[7:] = 0.5 * (mj_model.jnt_range[1:, 0] + mj_model.jnt_range[1:, 1]) + rng.uniform(-0.2, 0.2, 22)
        mj_data.qvel[:] = np.r_[np.zeros(6), rng.normal(size=mj_model.nv - 6)]
        mj_data.qacc[:] = np.r_[np.zeros(6), rng.normal(size=mj_model.nv - 6)]
        mujoco.mj_inverse(mj_model, mj_data)
        q, v = model.from_mujoco_state(mj_data.qpos, mj_data.qvel)
        _, a = model.from_mujoco_state(mj_data.qpos, mj_data.qacc)
        tau = model.inverse_dynamics(q, v, a) + model.joint_damping * v
        assert np.allclose(tau, mj_data.qfrc_inverse, atol=1e-8 * np.abs(tau).max())
        # rotor inertia included: without the armature the joints' torques differ
        assert not np.allclose(tau - model.pinocchio_model.armature * a, mj_data.qfrc_inverse, atol=1e-3)

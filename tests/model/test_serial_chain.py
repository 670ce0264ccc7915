"""SerialChain and the compiled chain kernels against pinocchio (through RobotModel) and finite differences."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from redundancy_gym.assets import AGRI_ARM_TCP, AGRI_ARM_XML, BIPED_XML, PLANAR_ARM_TCP, PLANAR_ARM_XML
from redundancy_gym.model import ModelError, RobotModel
from redundancy_gym.model.chain_kernels import (
    FREE,
    chain_acceleration_terms,
    chain_difference,
    chain_forward,
    chain_rnea,
)

ARMS = ((AGRI_ARM_XML, AGRI_ARM_TCP), (PLANAR_ARM_XML, PLANAR_ARM_TCP))


@pytest.mark.parametrize(("xml", "tcp"), ARMS, ids=("agri", "planar"))
def test_forward_kinematics_and_frames_match_pinocchio(xml, tcp, rng) -> None:
    model = RobotModel.from_mjcf(xml)
    chain = model.serial_chain()
    assert chain.num_joints == model.nq == model.nv
    assert chain.joint_names == tuple(model.joint_names)
    for _ in range(20):
        q = rng.uniform(model.lower_limits, model.upper_limits)
        rotation, position = chain.forward(q)
        model.update(q)
        for j, name in enumerate(chain.joint_names):
            r, p = model.frame_placement(name)
            np.testing.assert_allclose(rotation[j], r, atol=1e-12)
            np.testing.assert_allclose(position[j], p, atol=1e-12)
        frames = (tcp, *chain.joint_names)
        # the stacked attachments, as the kernels take them, place every frame where the model does
        joints, local_rs, local_ps = model.frame_attachments(frames)
        assert joints.dtype == np.int64 and local_rs.shape == (len(frames), 3, 3) and local_ps.shape == (len(frames), 3)
        for frame, joint, local_r, local_p in zip(frames, joints, local_rs, local_ps, strict=True):
            r, p = model.frame_placement(frame)
            np.testing.assert_allclose(rotation[joint] @ local_r, r, atol=1e-12)
            np.testing.assert_allclose(rotation[joint] @ local_p + position[joint], p, atol=1e-12)


@pytest.mark.parametrize(("xml", "tcp"), ARMS, ids=("agri", "planar"))
def test_point_jacobian_matches_pinocchio_and_finite_differences(xml, tcp, rng) -> None:
    model = RobotModel.from_mjcf(xml)
    chain = model.serial_chain()
    joint, _, local_p = model.frame_attachment(tcp)
    for _ in range(10):
        q = rng.uniform(model.lower_limits, model.upper_limits)
        model.update(q)
        offset = rng.normal(size=3) * 0.1  # a point on the TCP's body, off the frame origin
        rotation, position = chain.forward(q)
        point = position[joint] + rotation[joint] @ (local_p + offset)
        jac = chain.point_jacobian(q, joint, point)
        np.testing.assert_allclose(jac[:3], model.point_jacobian(tcp, point), atol=1e-12)
        np.testing.assert_allclose(jac[3:], model.frame_jacobian(tcp, "rotational"), atol=1e-12)
        eps = 1e-6
        for k in range(model.nv):
            dq = np.zeros(model.nv)
            dq[k] = eps
            moved = [chain.forward(q + s * dq) for s in (1.0, -1.0)]
            ends = [p[joint] + r[joint] @ (local_p + offset) for r, p in moved]
            np.testing.assert_allclose((ends[0] - ends[1]) / (2 * eps), jac[:3, k], atol=1e-7)


def test_chain_rejects_joints_it_cannot_compile() -> None:
    model = pin.Model()
    model.addJoint(0, pin.JointModelSpherical(), pin.SE3.Identity(), "ball")
    with pytest.raises(ModelError, match="JointModelFreeFlyer"):
        RobotModel(model).serial_chain()


def test_chain_checks_its_inputs() -> None:
    chain = RobotModel.from_mjcf(PLANAR_ARM_XML).serial_chain()
    with pytest.raises(ModelError, match="shape"):
        chain.forward(np.zeros(3))
    with pytest.raises(ModelError, match="finite"):
        chain.forward(np.array([0.0, np.nan, 0.0, 0.0]))
    with pytest.raises(ModelError, match="joint"):
        chain.point_jacobian(np.zeros(4), 7, np.zeros(3))


def _random_floating_configuration(model: RobotModel, rng: np.random.Generator) -> np.ndarray:
    q = np.concatenate(
        [rng.normal(size=3), rng.normal(size=4), rng.uniform(model.lower_limits[7:], model.upper_limits[7:])]
    )
    q[3:7] /= np.linalg.norm(q[3:7])
    return q


def test_free_flyer_kinematics_match_pinocchio(rng) -> None:
    model = RobotModel.from_mjcf(BIPED_XML)
    chain = model.serial_chain()
    assert chain.floating_base and chain.joint_type[0] == FREE
    assert (chain.nq, chain.nv) == (model.nq, model.nv)
    for _ in range(10):
        q = _random_floating_configuration(model, rng)
        rotation, position = chain.forward(q)
        model.update(q)
        for frame in ("r_sole", "l_sole", "imu", *chain.joint_names):
            joint, local_r, local_p = model.frame_attachment(frame)
            r, p = model.frame_placement(frame)
            np.testing.assert_allclose(rotation[joint] @ local_r, r, atol=1e-12)
            np.testing.assert_allclose(rotation[joint] @ local_p + position[joint], p, atol=1e-12)
            point = p + rotation[joint] @ rng.normal(size=3) * 0.1
            jac = chain.point_jacobian(q, joint, point)
            np.testing.assert_allclose(jac[:3], model.point_jacobian(frame, point), atol=1e-12)
            np.testing.assert_allclose(jac[3:], model.frame_jacobian(frame, "rotational"), atol=1e-12)


def test_centroidal_matrix_matches_pinocchio(rng) -> None:
    model = RobotModel.from_mjcf(BIPED_XML)
    chain = model.serial_chain()
    assert chain.body_mass.sum() == pytest.approx(model.total_mass, rel=1e-12)
    for _ in range(10):
        q = _random_floating_configuration(model, rng)
        com, jac_com, jac_angular = chain.centroidal(q)
        model.update(q)
        c, ag = model.com_and_centroidal_matrix()
        np.testing.assert_allclose(com, c, atol=1e-12)
        np.testing.assert_allclose(jac_com, ag[:3] / model.total_mass, atol=1e-12)
        np.testing.assert_allclose(jac_angular, ag[3:], atol=1e-11)


def test_integrate_matches_pinocchio(rng) -> None:
    model = RobotModel.from_mjcf(BIPED_XML)
    chain = model.serial_chain()
    for scale in (1e-7, 1e-3, 1.0):  # the series and the closed-form branch of exp6
        q = _random_floating_configuration(model, rng)
        v = rng.normal(size=model.nv) * scale
        np.testing.assert_allclose(chain.integrate(q, v, 0.7), model.integrate(q, v, 0.7), atol=1e-13)
    with pytest.raises(ModelError, match="finite"):
        chain.integrate(q, np.full(model.nv, np.nan), 0.1)


def _acceleration_terms(model: RobotModel, frames: tuple[str, ...], q: np.ndarray, v: np.ndarray) -> tuple:
    """``chain_acceleration_terms`` at ``(q, v)`` for ``frames``, in :class:`AccelerationTerms`' order."""
    chain = model.serial_chain()
    n, k = chain.num_joints, len(frames)
    work = (np.empty((n, 3, 3)), *(np.empty((n, 3)) for _ in range(6)), np.empty((n, 13)))
    out = (
        np.empty((k, 3, 3)),
        np.empty((k, 3)),
        np.empty((k, 6, model.nv)),
        np.empty((k, 6)),
        np.empty(3),
        np.empty((6, model.nv)),
        np.empty(6),
    )
    mass = chain_acceleration_terms(
        *chain.kernel_arrays(),
        *model.frame_attachments(frames),
        q,
        v,
        *work,
        *out,
    )
    assert mass == pytest.approx(model.total_mass, rel=1e-12)
    return out


@pytest.mark.parametrize(
    ("xml", "frames"),
    ((BIPED_XML, ("r_sole", "l_sole", "imu")), (AGRI_ARM_XML, (AGRI_ARM_TCP,)), (PLANAR_ARM_XML, (PLANAR_ARM_TCP,))),
    ids=("biped", "agri", "planar"),
)
def test_acceleration_terms_match_pinocchio(xml, frames, rng) -> None:
    # the placements, Jacobians, Jdot qdot, CoM, A_G and Adot_G qdot of one kernel against RobotModel's pinocchio
    # passes, at random states with fast joint and base motion (the Coriolis and centripetal terms are large)
    model = RobotModel.from_mjcf(xml)
    base = model.nq - (model.nv - 6) if model.floating_base else 0
    for _ in range(10):
        q = np.zeros(model.nq)
        if model.floating_base:
            q[:3] = rng.normal(size=3)
            quaternion = rng.normal(size=4)
            q[3:7] = quaternion / np.linalg.norm(quaternion)
        q[base:] = rng.uniform(model.lower_limits[base:], model.upper_limits[base:])
        v = rng.normal(size=model.nv) * 3.0
        reference = model.acceleration_terms(q, v, frames)
        for name, expected, got in zip(
            reference._fields, reference, _acceleration_terms(model, frames, q, v), strict=True
        ):
            np.testing.assert_allclose(got, expected, atol=1e-10, rtol=1e-10, err_msg=name)


def test_acceleration_drift_is_the_rate_of_the_frame_and_momentum_velocities(rng) -> None:
    # finite differences along the motion (qddot = 0) on the fixed-base arm: d/dt (J qdot) = Jdot qdot for the TCP,
    # d/dt (A_G qdot) = Adot_G qdot for the centroidal momentum, independent of pinocchio's time variations
    model = RobotModel.from_mjcf(AGRI_ARM_XML)
    q = rng.uniform(model.lower_limits, model.upper_limits) * 0.8
    v = rng.normal(size=model.nv) * 2.0
    eps = 1e-6
    ahead, behind = (_acceleration_terms(model, (AGRI_ARM_TCP,), q + s * eps * v, v) for s in (1.0, -1.0))
    here = _acceleration_terms(model, (AGRI_ARM_TCP,), q, v)
    np.testing.assert_allclose((ahead[2][0] - behind[2][0]) @ v / (2 * eps), here[3][0], atol=1e-6)
    np.testing.assert_allclose((ahead[5] - behind[5]) @ v / (2 * eps), here[6], atol=1e-6)


def _random_state(model: RobotModel, rng: np.random.Generator) -> np.ndarray:
    """A configuration with the joints inside their limits and, on a free flyer, a random base pose."""
    q = np.zeros(model.nq)
    base = model.nq - (model.nv - 6) if model.floating_base else 0
    if model.floating_base:
        q[:3] = rng.normal(size=3)
        quaternion = rng.normal(size=4)
        q[3:7] = quaternion / np.linalg.norm(quaternion)
    q[base:] = rng.uniform(model.lower_limits[base:], model.upper_limits[base:])
    return q


@pytest.mark.parametrize("xml", (BIPED_XML, AGRI_ARM_XML), ids=("biped", "agri"))
def test_rnea_matches_pinocchio_with_armature_and_gravity(xml, rng) -> None:
    # M(q) a + h(q, v) of the compiled recursion against pinocchio's RNEA; the biped's free flyer rows are the
    # spatial force in the base frame, the armature (hips, knees, the arm's joints) enters as armature * a
    model = RobotModel.from_mjcf(xml)
    assert np.any(model.armature > 0.0) and model.gravity == pytest.approx((0.0, 0.0, -9.81))
    chain = model.serial_chain()
    n = chain.num_joints
    for _ in range(10):
        q = _random_state(model, rng)
        v, a = rng.normal(size=model.nv) * 2.0, rng.normal(size=model.nv) * 5.0
        frames = (np.empty((n, 3, 3)), np.empty((n, 3)), np.empty((n, 3)))
        chain_forward(
            chain.parent,
            chain.placement_rotation,
            chain.placement_translation,
            chain.axis,
            chain.joint_type,
            chain.q_index,
            q,
            *frames,
        )
        tau = np.empty(model.nv)
        work = [np.empty((n, 3)) for _ in range(6)]
        chain_rnea(
            chain.parent,
            chain.joint_type,
            chain.v_index,
            *frames,
            chain.body_mass,
            chain.body_com,
            chain.body_inertia,
            model.armature,
            model.gravity,
            v,
            a,
            *work,
            tau,
        )
        expected = model.inverse_dynamics(q, v, a)
        np.testing.assert_allclose(tau, expected, rtol=0.0, atol=1e-11 * np.abs(expected).max())


def test_difference_matches_pinocchio_and_inverts_integrate(rng) -> None:
    # the free flyer's log6 at random poses, at relative rotations from 1e-9 rad to near pi (the series and the
    # shorter arc) and at none; integrate(q0, q1 (-) q0) returns to q1
    model = RobotModel.from_mjcf(BIPED_XML)
    chain = model.serial_chain()
    out = np.empty(model.nv)
    cases = []
    for scale in (0.0, 1e-9, 1e-5, 1e-3, 5e-3, 2e-2, 0.3, 1.0):
        for _ in range(20):
            q0 = _random_state(model, rng)
            q1 = q0.copy()
            q1[:3] += rng.normal(size=3)
            q1[7:] += rng.normal(size=model.nq - 7) * 0.1
            quaternion = q0[3:7] + scale * rng.normal(size=4)
            q1[3:7] = quaternion / np.linalg.norm(quaternion)
            cases.append((q0, q1))
    for _ in range(20):
        q0 = _random_state(model, rng)
        q1 = q0.copy()  # a half turn less 1e-3 rad about a random axis
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        half = 0.5 * (np.pi - 1e-3)
        x, y, z, w = (float(c) for c in q0[3:7])
        rx, ry, rz = (float(c) for c in np.sin(half) * axis)
        rw = float(np.cos(half))
        q1[3:7] = (
            w * rx + x * rw + y * rz - z * ry,
            w * ry - x * rz + y * rw + z * rx,
            w * rz + x * ry - y * rx + z * rw,
            w * rw - x * rx - y * ry - z * rz,
        )
        cases.append((q0, q1))
    for q0, q1 in cases:
        chain_difference(chain.joint_type, chain.q_index, chain.v_index, q0, q1, out)
        np.testing.assert_allclose(out, model.difference(q0, q1), rtol=0.0, atol=1e-9)
        back = chain.integrate(q0, out, 1.0)
        np.testing.assert_allclose(back[:3], q1[:3], atol=1e-11)
        np.testing.assert_allclose(back[7:], q1[7:], atol=1e-12)
        assert abs(abs(float(back[3:7] @ q1[3:7])) - 1.0) < 1e-12

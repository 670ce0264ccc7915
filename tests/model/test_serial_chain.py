"""SerialChain and the compiled chain kernels against pinocchio (through RobotModel) and finite differences."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from redundancy_gym.assets import AGRI_ARM_TCP, AGRI_ARM_XML, BIPED_XML, PLANAR_ARM_TCP, PLANAR_ARM_XML
from redundancy_gym.model import ModelError, RobotModel
from redundancy_gym.model.chain_kernels import FREE

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
        for frame in (tcp, *chain.joint_names):
            joint, local_r, local_p = model.frame_attachment(frame)
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

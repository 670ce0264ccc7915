"""Biped IKD (5.84)-(5.91): the motion it generates needs exactly the prescribed contact moment, by pinocchio's
inverse dynamics of the floating-base robot (RNEA) as the independent reference."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from redundancy_gym.assets import BIPED_XML
from redundancy_gym.controllers import ControllerError
from redundancy_gym.controllers.ikd import BipedIkd, BipedIkdReference
from redundancy_gym.controllers.ikd.biped_ikd import GRAVITY
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
    return BipedIkdReference(position, rotation, np.zeros((2, 6)), np.zeros((2, 6)), model.frame_rotation("imu"),
                             np.zeros(3), np.zeros(3), np.array([model.com()[2], 0.0, 0.0]),
                             np.array([force * zmp[1], -force * zmp[0]]))


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
        rotation = np.array([[[np.cos(a), 0.0, np.sin(a)], [0.0, 1.0, 0.0], [-np.sin(a), 0.0, np.cos(a)]]
                             for a in sample.feet_pitch])
        standing_feet = [f for f, c in zip(sample.feet, sample.contact, strict=True) if c]
        box = np.array([np.min([[f[0] - 0.095, f[1] - 0.075] for f in standing_feet], axis=0),
                        np.max([[f[0] + 0.165, f[1] + 0.075] for f in standing_feet], axis=0)])
        zmp = sample.zmp
        reference = BipedIkdReference(sample.feet.copy(), rotation, velocity, acceleration, np.eye(3), np.zeros(3),
                                      np.zeros(3), np.array([start[2], 0.0, 0.0]),
                                      np.array([force * zmp[1], -force * zmp[0]]),
                                      np.array([*sample.com[:2], *sample.com_velocity[:2]]), box)
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

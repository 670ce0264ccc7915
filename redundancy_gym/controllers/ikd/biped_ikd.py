"""Inverse Kineto-Dynamics for biped walking (monograph 5.5.2, (5.84)-(5.91)): joint accelerations that realize a
prescribed contact moment exactly, with the horizontal CoM as the unknown task coordinates."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...model import RobotModel
from ..exceptions import ControllerError
from ..redundancy_resolution import WeightMatrix, check_configuration, check_finite, resolve
from ..walking.ik_kernels import rotation_error

__all__ = ["BipedIkd", "BipedIkdReference", "BipedIkdResult", "GRAVITY"]

GRAVITY = 9.81
"""Gravitational acceleration [m/s^2], acting along -z."""


class BipedIkdReference(NamedTuple):
    """The known part of the hybrid task at one instant (world frame), and the prescribed contact moment.

    Attributes:
        feet_position: sole positions [m] (2, 3), rows right, left.
        feet_rotation: sole orientations (2, 3, 3).
        feet_velocity: sole twists [m/s, rad/s] (2, 6): linear, then angular.
        feet_acceleration: their rates [m/s^2, rad/s^2] (2, 6).
        torso_rotation: torso orientation (3, 3).
        torso_angular_velocity: [rad/s] (3).
        torso_angular_acceleration: [rad/s^2] (3).
        com_height: the CoM's z [m], its rate [m/s] and acceleration [m/s^2] (3).
        moment: the contact moment ``(T_x, T_y)`` [N m] about the world origin (5.85) with the contact force
            taken to act there (the monograph's choice ``r_F = 0``); for a ZMP ``p`` on flat ground and a
            vertical force ``F_z``, ``T = F_z (p_y, -p_x)``.
        com_plan: the planned horizontal CoM ``(x, y, xdot, ydot)`` [m, m/s] that the contact-moment stabilization
            (5.97) pulls to (None: no stabilization).
        support: the support polygon's bounding box ``((x_min, y_min), (x_max, y_max))`` [m] that the stabilized
            moment's ZMP is saturated to (None: no saturation).
    """

    feet_position: NDArray[np.float64]
    feet_rotation: NDArray[np.float64]
    feet_velocity: NDArray[np.float64]
    feet_acceleration: NDArray[np.float64]
    torso_rotation: NDArray[np.float64]
    torso_angular_velocity: NDArray[np.float64]
    torso_angular_acceleration: NDArray[np.float64]
    com_height: NDArray[np.float64]
    moment: NDArray[np.float64]
    com_plan: NDArray[np.float64] | None = None
    support: NDArray[np.float64] | None = None


class BipedIkdResult(NamedTuple):
    """One step of :class:`BipedIkd`.

    Attributes:
        qddot: generalized accelerations (nv); zeros when ``success`` is False.
        com_acceleration: the CoM's acceleration [m/s^2] (3): x and y solved for, z the prescribed one.
        residual: ``|R qddot + r|`` of (5.91) (0 up to round-off unless damped).
        sigma_min: smallest singular value of ``R W^-1/2``.
        success: False at a singular task.
        status: ``"ok"``, ``"damped"`` or ``"singular"``.
        moment: the contact moment ``(T_x, T_y)`` [N m] the motion realizes: the reference's, plus the
            stabilization's modification (5.97) where it acts.
    """

    qddot: NDArray[np.float64]
    com_acceleration: NDArray[np.float64]
    residual: float
    sigma_min: float
    success: bool
    status: str
    moment: NDArray[np.float64]


class BipedIkd:
    """``R qddot + r = 0`` (5.91) from the x/y angular momentum theorem about the CoM with the contact moment
    prescribed (5.87)-(5.89) and the task split into known rows (the CoM's height, both soles' poses, the torso's
    orientation) and unknown ones (the CoM's x and y) (5.90)::

        A qddot + B wddot_u + c = 0,   A = J_L,xy,  B = [[0, -m z_c], [m z_c, 0]],
        c = Jdot_L,xy qdot + (m y_c (g + zddot_c) - T_x, -m x_c (g + zddot_c) - T_y),
        R = J_w + T_wu B^-1 A,   r = Jdot_w qdot - T_wk wddot_k + T_wu B^-1 c.

    ``J_L`` and ``Jdot_L qdot`` are the angular rows of the centroidal momentum matrix and its drift (pinocchio,
    through :class:`~redundancy_gym.model.RobotModel`). The known rows are stabilized as in (5.19) (the
    drift compensation acts on them only: ``stiffness`` ``K_P``, ``damping`` ``K_D``; the monograph's
    ``K_P = 40 / dt``, ``K_D = 2 sqrt(K_P) 0.85`` suit a 1 ms period). The redundancy (the arms, the waist) is
    resolved by the weighted minimum of ``|qddot - qddot_pref|``, ``qddot_pref = -D qdot - K (q - posture)``
    (``self_motion_damping`` ``D``, ``posture_stiffness`` ``K``).

    This is the kinematic IKD: the contact moment that the generated motion needs is the prescribed one exactly
    (pinocchio's inverse dynamics of the motion give it back); without stabilization the CoM drifts away from
    the plan the moment came from (monograph fig. 5.21). Stabilization via the contact moment (5.97): with a
    ``com_plan`` in the reference and ``moment_gain`` ``k`` > 0, ``T += sat(B [K_p (w_plan - w) + K_d (wdot_plan -
    wdot)])`` with the monograph's ``K_p = k 40 / period`` and ``K_d = 2 * 0.85 sqrt(K_p)``, its ZMP saturated to
    the reference's ``support`` box. In the pendulum limit the error dynamics are stable for ``K_p > (g +
    zddot) / z`` (monograph footnote 19: ``k`` above about 2.7e-4 at a 1 ms period).

    Args:
        model: a floating-base model of the biped.
        feet_frames: the sole frames (right, left).
        torso_frame: the torso's frame.
        posture: the posture (nq) of the nullspace term (None: no posture term).
        moment_gain: ``k`` of (5.97) (0: the prescribed moment unmodified).
        period: the control period [s] of the gains ``K_p = k 40 / period``.
    """

    def __init__(self, model: RobotModel, *, feet_frames: tuple[str, str] = ("r_sole", "l_sole"),
                 torso_frame: str = "imu", stiffness: float = 400.0, damping: float = 34.0,
                 self_motion_damping: float = 10.0, posture_stiffness: float = 25.0, posture: ArrayLike | None = None,
                 weights: ArrayLike | float = 1.0, singular_threshold: float = 1e-6, moment_gain: float = 0.0,
                 period: float = 0.001) -> None:
        if not model.floating_base:
            raise ControllerError(f"biped IKD needs a floating-base model, {model.source} has a fixed base")
        for name, value in (("stiffness", stiffness), ("damping", damping),
                            ("self_motion_damping", self_motion_damping), ("posture_stiffness", posture_stiffness),
                            ("moment_gain", moment_gain)):
            if not np.isfinite(value) or value < 0.0:
                raise ControllerError(f"{name} must be finite and >= 0, got {value!r}")
        self.model = model
        self.feet_frames = tuple(feet_frames)
        self.torso_frame = torso_frame
        for frame in (*self.feet_frames, torso_frame):
            model.frame_id(frame)  # raises naming an unknown frame
        self.kp, self.kd = float(stiffness), float(damping)
        self.self_motion_damping, self.posture_stiffness = float(self_motion_damping), float(posture_stiffness)
        self.posture = None if posture is None else model.check_configuration(posture)
        self.weights = WeightMatrix(weights, model.nv)
        self.singular_threshold = float(singular_threshold)
        self.mass = model.total_mass
        if not np.isfinite(period) or period <= 0.0:
            raise ControllerError(f"period must be finite and > 0 [s], got {period!r}")
        self.moment_gain = float(moment_gain)
        self.com_stiffness = self.moment_gain * 40.0 / float(period)
        self.com_damping = 2.0 * 0.85 * float(np.sqrt(self.com_stiffness))

    def _known(self, q: NDArray[np.float64], qdot: NDArray[np.float64], ref: BipedIkdReference
               ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """The known rows' Jacobian (15 x nv), drift ``Jdot qdot`` and stabilized acceleration: both soles (6 each)
        and the torso's orientation (3); :meth:`step` adds the CoM's height."""
        model = self.model
        drift = model.frames_jacobian_derivative_times_velocity(q, qdot, (*self.feet_frames, self.torso_frame), "full")
        jacobians, accelerations = [], []
        for i, frame in enumerate(self.feet_frames):
            jac = model.frame_jacobian(frame, "full")
            rotation, position = model.frame_placement(frame)
            error = np.concatenate([ref.feet_position[i] - position, rotation_error(ref.feet_rotation[i], rotation)])
            accelerations.append(ref.feet_acceleration[i] + self.kd * (ref.feet_velocity[i] - jac @ qdot)
                                 + self.kp * error)
            jacobians.append(jac)
        jac = model.frame_jacobian(self.torso_frame, "rotational")
        error = rotation_error(ref.torso_rotation, model.frame_rotation(self.torso_frame))
        accelerations.append(ref.torso_angular_acceleration + self.kd * (ref.torso_angular_velocity - jac @ qdot)
                             + self.kp * error)
        jacobians.append(jac)
        drifts = [drift[0], drift[1], drift[2, 3:]]
        return np.vstack(jacobians), np.concatenate(drifts), np.concatenate(accelerations)

    def step(self, q: ArrayLike, qdot: ArrayLike, reference: BipedIkdReference) -> BipedIkdResult:
        """Generalized accelerations at ``(q, qdot)`` for ``reference`` (the contact moment among it)."""
        model = self.model
        q = check_configuration(q, "q")
        qdot = check_finite(qdot, "qdot")
        if qdot.shape != (model.nv,):
            raise ControllerError(f"qdot must be finite with shape ({model.nv},), got {qdot.shape}")
        for name in reference._fields:
            if getattr(reference, name) is not None:
                check_finite(getattr(reference, name), f"reference.{name}")
        moment = np.asarray(reference.moment, dtype=np.float64)
        height = np.asarray(reference.com_height, dtype=np.float64)
        if moment.shape != (2,) or height.shape != (3,):
            raise ControllerError("reference.moment must be (T_x, T_y) and reference.com_height (z, zdot, zddot)")
        j_known, drift_known, wddot_known = self._known(q, qdot, reference)
        momentum_drift = model.centroidal_momentum_drift(q, qdot)  # updates at q
        com, centroidal = model.com_and_centroidal_matrix()
        m = self.mass
        j_com, drift_com = centroidal[:3] / m, momentum_drift[:3] / m
        z_acceleration = height[2] + self.kd * (height[1] - j_com[2] @ qdot) + self.kp * (height[0] - com[2])
        # (5.88): A qddot + B (xddot_c, yddot_c) + c = 0
        a = centroidal[3:5]
        g = GRAVITY + z_acceleration
        b_mat = np.array([[0.0, -m * com[2]], [m * com[2], 0.0]])
        if reference.com_plan is not None and self.moment_gain > 0.0:
            moment = self._stabilized(moment, reference, com[:2], j_com[:2] @ qdot, b_mat, m * g)
        c = momentum_drift[3:5] + np.array([m * com[1] * g - moment[0], -m * com[0] * g - moment[1]])
        b_inverse = np.array([[0.0, 1.0], [-1.0, 0.0]]) / (m * com[2])  # B^-1
        # (5.91): the known rows and the CoM's x, y replaced by what the angular momentum theorem gives them
        r_mat = np.vstack([j_known, j_com[2], j_com[:2] + b_inverse @ a])
        r_vec = np.concatenate([drift_known - wddot_known, [drift_com[2] - z_acceleration],
                                drift_com[:2] + b_inverse @ c])
        preferred = -self.self_motion_damping * qdot
        if self.posture is not None:
            preferred = preferred - self.posture_stiffness * model.difference(self.posture, q)
        res = resolve(r_mat, -r_vec, -self.weights.apply(preferred), self.weights,
                      singular_threshold=self.singular_threshold)
        if not res.success:
            return BipedIkdResult(np.zeros(model.nv), np.zeros(3), float(np.linalg.norm(r_vec)), res.sigma_min, False,
                                  res.status, moment)
        qddot = res.x
        com_acceleration = j_com @ qddot + drift_com
        residual = float(np.linalg.norm(r_mat @ qddot + r_vec))
        return BipedIkdResult(qddot, com_acceleration, residual, res.sigma_min, True, res.status, moment)

    def _stabilized(self, moment: NDArray[np.float64], reference: BipedIkdReference, com: NDArray[np.float64],
                    com_velocity: NDArray[np.float64], b_mat: NDArray[np.float64], force: float
                    ) -> NDArray[np.float64]:
        """(5.97): the moment plus ``B [K_p (w_plan - w) + K_d (wdot_plan - wdot)]``, its ZMP (for the vertical
        force ``force`` [N]) kept in the support box."""
        plan = np.asarray(reference.com_plan, dtype=np.float64)
        if plan.shape != (4,):
            raise ControllerError(f"reference.com_plan must be (x, y, xdot, ydot), got shape {plan.shape}")
        modified = moment + b_mat @ (self.com_stiffness * (plan[:2] - com) + self.com_damping * (plan[2:] - com_velocity))
        if reference.support is None or force <= 0.0:
            return modified
        box = np.asarray(reference.support, dtype=np.float64)
        zmp = np.clip(np.array([-modified[1], modified[0]]) / force, box[0], box[1])
        return force * np.array([zmp[1], -zmp[0]])

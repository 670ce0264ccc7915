"""Torque feedforward for position servos: the joint targets shifted by the planned motion's torques over the
servos' stiffness, so that stiff position loops deliver the torques of the plan instead of sagging under them.

A position servo ``tau = k_p (q_target - q) - k_v qdot`` that has to hold the torque ``tau`` settles ``tau / k_p``
short of its target (10-17 mrad at the biped's knees and hips while walking, where the kinematic plan assumed
none). With the inverse dynamics of the planned motion, ``tau_ff``, the target ``q_ref + tau_ff / k_p`` puts the
joint on ``q_ref`` when the plan's torques are what the joint needs.

``tau_ff`` follows from (5.92) with the contact wrenches: ``tau = M qddot + h + D qdot - sum_i J_i^T F_i``. Its six
base rows must vanish (the base is not actuated): with one foot on the ground they give the foot's wrench; with two,
the wrenches are split by the plan's load share (the smallest ``sum_i |F_i|^2 / w_i`` that balances the base rows,
``w_i`` the foot's share of the weight).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...model import RobotModel
from ...validation import check_required_real
from ..exceptions import ControllerError

__all__ = ["ServoFeedforward", "ServoFeedforwardTorques"]

MIN_LOAD = 1e-3
"""Share of the weight [-] below which a foot planned on the ground carries no wrench (the instant of its
touchdown or lift-off)."""


class ServoFeedforwardTorques(NamedTuple):
    """What :meth:`ServoFeedforward.torques` gives.

    Attributes:
        torques: joint torques [N m] of the actuated joints (nv - 6).
        offsets: the joint target offsets ``torques / k_p`` [rad].
        wrenches: contact wrench ``(F, T)`` [N, N m] on each sole at the sole point, world axes (rows right, left;
            zero for a foot without load).
        base_residual: largest entry of the base rows left after the contact wrenches [N or N m] (0 up to round-off
            when a foot carries load; the whole base wrench in flight).
    """

    torques: NDArray[np.float64]
    offsets: NDArray[np.float64]
    wrenches: NDArray[np.float64]
    base_residual: float


class ServoFeedforward:
    """Joint target offsets from the inverse dynamics of a planned motion (see the module docstring).

    Args:
        model: the floating-base robot model (the first six velocities are the base).
        stiffness: the servos' ``k_p`` [N m/rad] per actuated joint (nv - 6), all > 0.
        feet_frames: the sole frames (right, left) where the contact wrenches act.
        gain: scale [-] of the feedforward (1: the full torques).

    Raises:
        ControllerError: a stiffness of the wrong length or not finite and > 0, or a gain not finite and >= 0.
    """

    def __init__(
        self,
        model: RobotModel,
        stiffness: ArrayLike,
        feet_frames: tuple[str, str] = ("r_sole", "l_sole"),
        gain: float = 1.0,
    ) -> None:
        if not model.floating_base:
            raise ControllerError("the servo feedforward needs a floating-base model")
        k = np.asarray(stiffness, dtype=np.float64)
        if k.shape != (model.nv - 6,) or not np.all(np.isfinite(k)) or np.any(k <= 0.0):
            raise ControllerError(
                f"stiffness must hold {model.nv - 6} finite servo gains > 0 [N m/rad], got {np.asarray(stiffness)!r}"
            )
        self.model = model
        self.stiffness = k
        self.gain = check_required_real("gain", gain, low=0.0, error=ControllerError)
        self._feet = tuple(model.frame_id(f) for f in feet_frames)
        self._damping = model.joint_damping

    def torques(
        self,
        q: ArrayLike,
        qdot: ArrayLike,
        qddot: ArrayLike,
        contact: tuple[bool, bool],
        right_load: float,
    ) -> ServoFeedforwardTorques:
        """The actuated joints' torques of the motion ``(q, qdot, qddot)`` with the soles ``contact`` (right, left)
        on the ground, the right one carrying ``right_load`` [0, 1] of the weight, and the target offsets.

        Updates ``model`` at ``q``.
        """
        right_load = check_required_real("right_load", right_load, low=0.0, high=1.0, error=ControllerError)
        tau = self.model.inverse_dynamics(q, qdot, qddot)  # also the kinematic cache at q for the Jacobians
        return self._balance(tau, np.asarray(qdot, dtype=np.float64), contact, right_load)

    def _balance(
        self, tau: NDArray[np.float64], qdot: NDArray[np.float64], contact: tuple[bool, bool], right_load: float
    ) -> ServoFeedforwardTorques:
        """The torques from the RNEA torques ``tau`` at the velocity ``qdot``: the damping added, the contact
        wrenches split (the module docstring) and taken off, the offsets."""
        model = self.model
        tau = tau + self._damping * qdot
        loads = (right_load, 1.0 - right_load)
        feet = [i for i in range(2) if contact[i] and loads[i] > MIN_LOAD]
        wrenches = np.zeros((2, 6))
        if feet:
            # F_i = w_i J_ib lambda with sum_i w_i J_ib^T J_ib lambda = tau_b (J_ib the base columns of the sole's
            # Jacobian): the base rows balanced with the least sum |F_i|^2 / w_i; one foot gives w J_b^T J_b
            jacobians = [model.frame_jacobian(self._feet[i]) for i in feet]
            bases = [j[:, :6] for j in jacobians]
            normal = sum(loads[i] * (b.T @ b) for i, b in zip(feet, bases, strict=True))
            multiplier = np.linalg.solve(normal, tau[:6])
            for i, jacobian, b in zip(feet, jacobians, bases, strict=True):
                wrenches[i] = loads[i] * (b @ multiplier)
                tau -= jacobian.T @ wrenches[i]
        joint = tau[6:] * self.gain
        return ServoFeedforwardTorques(joint, joint / self.stiffness, wrenches, float(np.max(np.abs(tau[:6]))))

"""A :class:`ServoFeedforward` compiled (the same results to round-off, held equal by
``tests/controllers/walking/test_servo_feedforward.py``).

The Python reference spends most of its time on small NumPy operations around pinocchio's RNEA (about 70 us a
call against 7 us of RNEA and Jacobians); here one kernel runs the RNEA and the soles' Jacobians on the model's
exported chain (:func:`~redundancy_gym.model.chain_kernels.chain_rnea`) and another the rest (damping, the base
rows' least-squares split (5.92), ``J^T F``, the offsets).
"""

from __future__ import annotations

import math
from functools import cached_property

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

from ...kernel_options import JIT
from ...model import RobotModel
from ...model.chain_kernels import chain_forward, chain_rnea, frame_jacobian
from ...validation import check_required_real
from ..exceptions import ControllerError
from ..kernels.linalg import cholesky_factor, cholesky_solve
from .servo_feedforward import MIN_LOAD, ServoFeedforward, ServoFeedforwardTorques

__all__ = ["CompiledServoFeedforward"]


@njit(**JIT)
def _split(
    tau: np.ndarray,
    qdot: np.ndarray,
    damping: np.ndarray,
    jacobians: np.ndarray,
    loads: np.ndarray,
    gain: float,
    stiffness: np.ndarray,
    wrenches: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, float]:  # pragma: no cover - compiled
    """``(joint torques, offsets, base residual)`` from the RNEA torques ``tau``; ``loads[i]`` > 0 marks a sole
    that carries that share of the weight (its Jacobian ``jacobians[i]``, 6 x nv); the wrenches go into
    ``wrenches`` (2, 6). A base block that is not positive definite gives a NaN residual."""
    nv = tau.shape[0]
    t = tau + damping * qdot
    normal = np.zeros((6, 6))
    used = False
    for i in range(2):
        w = loads[i]
        if w <= 0.0:
            continue
        used = True
        for a in range(6):
            for b in range(6):
                s = 0.0
                for k in range(6):
                    s += jacobians[i, k, a] * jacobians[i, k, b]
                normal[a, b] += w * s
    wrenches[:] = 0.0
    if used:
        low = np.zeros((6, 6))
        if cholesky_factor(normal, 6, low) == 0.0:
            return t[6:] * gain, t[6:] * gain / stiffness, math.nan
        multiplier = t[:6].copy()
        cholesky_solve(low, 6, multiplier)
        for i in range(2):
            w = loads[i]
            if w <= 0.0:
                continue
            for k in range(6):
                f = 0.0
                for a in range(6):
                    f += jacobians[i, k, a] * multiplier[a]
                wrenches[i, k] = w * f
            for j in range(nv):
                s = 0.0
                for k in range(6):
                    s += jacobians[i, k, j] * wrenches[i, k]
                t[j] -= s
    residual = 0.0
    for a in range(6):
        residual = max(residual, abs(t[a]))
    joint = t[6:] * gain
    return joint, joint / stiffness, residual


@njit(**JIT)
def _dynamics(
    parent: np.ndarray,
    placement_rotation: np.ndarray,
    placement_translation: np.ndarray,
    axis: np.ndarray,
    joint_type: np.ndarray,
    q_index: np.ndarray,
    v_index: np.ndarray,
    body_mass: np.ndarray,
    body_com: np.ndarray,
    body_inertia: np.ndarray,
    armature: np.ndarray,
    gravity: np.ndarray,
    frame_joint: np.ndarray,
    frame_rotation: np.ndarray,
    frame_translation: np.ndarray,
    q: np.ndarray,
    qdot: np.ndarray,
    qddot: np.ndarray,
    loads: np.ndarray,
    jacobians: np.ndarray,
) -> np.ndarray:  # pragma: no cover - compiled
    """The RNEA torques (nv) at ``(q, qdot, qddot)``, and into ``jacobians[i]`` the Jacobian of sole ``i`` where
    ``loads[i] > 0`` (zeros elsewhere)."""
    n = parent.shape[0]
    rotation, position, world_axis = np.empty((n, 3, 3)), np.empty((n, 3)), np.empty((n, 3))
    chain_forward(
        parent, placement_rotation, placement_translation, axis, joint_type, q_index, q, rotation, position, world_axis
    )
    tau = np.empty(qdot.shape[0])
    work = np.empty((6, n, 3))
    chain_rnea(
        parent,
        joint_type,
        v_index,
        rotation,
        position,
        world_axis,
        body_mass,
        body_com,
        body_inertia,
        armature,
        gravity,
        qdot,
        qddot,
        work[0],
        work[1],
        work[2],
        work[3],
        work[4],
        work[5],
        tau,
    )
    sole_rotation, sole_position = np.empty((3, 3)), np.empty(3)
    for i in range(2):
        if loads[i] <= 0.0:
            jacobians[i] = 0.0
            continue
        frame_jacobian(
            parent,
            joint_type,
            v_index,
            rotation,
            position,
            world_axis,
            frame_joint[i],
            frame_rotation[i],
            frame_translation[i],
            sole_rotation,
            sole_position,
            jacobians[i],
        )
    return tau


class CompiledServoFeedforward(ServoFeedforward):
    """:class:`ServoFeedforward` compiled (same arguments, same results to round-off): its
    :meth:`~ServoFeedforward.torques` with the RNEA and the soles' Jacobians from one kernel on
    :meth:`RobotModel.serial_chain` and the split of the contact wrenches from another. Unlike the reference it
    leaves the model's kinematic cache where it was."""

    @cached_property
    def _chain(self) -> tuple[np.ndarray, ...]:
        """The kernel's leading arguments: the exported chain, armature, gravity and the soles' attachments."""
        model = self.model
        return (
            *model.serial_chain().kernel_arrays(),
            model.armature,
            model.gravity,
            *model.frame_attachments(self._feet),
        )

    def torques(
        self,
        q: ArrayLike,
        qdot: ArrayLike,
        qddot: ArrayLike,
        contact: tuple[bool, bool],
        right_load: float,
    ) -> ServoFeedforwardTorques:
        right_load = check_required_real("right_load", right_load, low=0.0, high=1.0, error=ControllerError)
        model = self.model
        q = model.check_configuration(q)
        qdot = _velocity(model, qdot, "qdot")
        qddot = _velocity(model, qddot, "qddot")
        loads = np.array((right_load, 1.0 - right_load))
        for i in range(2):
            if not (contact[i] and loads[i] > MIN_LOAD):
                loads[i] = 0.0
        jacobians = np.empty((2, 6, model.nv))
        tau = _dynamics(*self._chain, q, qdot, qddot, loads, jacobians)
        return self._finish(tau, qdot, jacobians, loads)

    def _finish(
        self,
        tau: NDArray[np.float64],
        qdot: NDArray[np.float64],
        jacobians: NDArray[np.float64],
        loads: NDArray[np.float64],
    ) -> ServoFeedforwardTorques:
        """The torques from the RNEA torques ``tau``, the soles' ``jacobians`` and their ``loads`` (0: no wrench)."""
        wrenches = np.empty((2, 6))
        joint, offsets, residual = _split(
            tau, np.ascontiguousarray(qdot), self._damping, jacobians, loads, self.gain, self.stiffness, wrenches
        )
        if math.isnan(residual):
            raise ControllerError("the soles' Jacobians give a singular base block: no contact wrench balances it")
        return ServoFeedforwardTorques(joint, offsets, wrenches, float(residual))


def _velocity(model: RobotModel, value: ArrayLike, name: str) -> NDArray[np.float64]:
    """``value`` as a finite float64 C array of ``model.nv`` entries, else :class:`ControllerError` naming it."""
    array = np.ascontiguousarray(value, dtype=np.float64)
    if array.shape != (model.nv,) or not math.isfinite(float(array.sum())):
        raise ControllerError(f"{name} must be finite with shape ({model.nv},), got shape {array.shape}")
    return array

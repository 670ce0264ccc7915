"""Acceleration-level closed-loop inverse kinematics: resolved acceleration control (monograph 5.1.3, (5.18)-(5.19))."""

from __future__ import annotations

from typing import NamedTuple, Protocol, Unpack

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...model import RobotModel
from ..exceptions import ControllerError
from ..objectives.objective import sum_objectives
from ..tasks.task import Task
from .redundancy_resolution import METHODS, ResolutionOptions, ResolvedController, check_configuration, check_finite

__all__ = ["AccelerationClik", "AccelerationClikResult", "DriftTask"]


class DriftTask(Task, Protocol):
    """A task that also knows ``Jdot_w qdot``."""

    def drift(self, model: RobotModel, q: NDArray[np.float64], qdot: NDArray[np.float64]) -> NDArray[np.float64]:
        """``Jdot_w qdot``."""
        ...


class AccelerationClikResult(NamedTuple):
    """Joint accelerations of one acceleration-level CLIK step and diagnostics.

    Attributes:
        qddot: joint accelerations [rad/s^2]; zeros when ``success`` is False.
        error: position error ``w_d - w(q)``.
        velocity_error: ``wdot_d - J qdot``.
        error_norm: ``|w_d - w(q)|``.
        sigma_min: smallest singular value of ``J W^-1/2``.
        damping: DLS damping used.
        objective: nullspace objective ``H(q)``.
        success: False on an unresolved singularity.
        status: ``"ok"``, ``"damped"`` or ``"singular"``.
        limited: True when ``qddot`` was bounded to keep the joint speeds and ranges (see
            :class:`AccelerationClik`).
    """

    qddot: NDArray[np.float64]
    error: NDArray[np.float64]
    velocity_error: NDArray[np.float64]
    error_norm: float
    sigma_min: float
    damping: float
    objective: float
    success: bool
    status: str
    limited: bool = False


class AccelerationClik(ResolvedController[DriftTask]):
    """``J qddot = wddot_d + K_D (wdot_d - J qdot) + K_P (w_d - w) - Jdot qdot`` (5.18), (5.19).

    Redundancy is resolved as at velocity level with the nullspace vector
    ``z = alpha (dH/dq)^T + nullspace_damping W qdot``, so the self-motion is damped instead of drifting:
    ``qddot = J#_W (...) - N_W (alpha W^-1 (dH/dq)^T + nullspace_damping qdot)``.

    Args:
        model: the robot model.
        task: a task with ``drift`` (``Jdot qdot``).
        method: ``"pseudoinverse"``, ``"dls"`` or ``"transpose"``.
        stiffness: ``K_P`` [1/s^2] (scalar or per task coordinate), >= 0.
        damping: ``K_D`` [1/s], >= 0.
        weights: ``W``.
        nullspace_gain: ``alpha`` >= 0.
        nullspace_damping: damping of the self-motion [1/s], >= 0.
        objectives: nullspace objectives.
        max_joint_velocity: joint speed limits [rad/s or m/s] (nv, or one for all; ``inf``: none); None takes the
            model's :attr:`~redundancy_gym.model.RobotModel.velocity_limits`.
        period: control period [s] over which ``qddot`` is applied, > 0, or None.

    The command is bounded as at velocity level (:class:`~.redundancy_resolution.JointBounds`), on the velocity
    it leads to: with ``period`` given, each ``qddot_i`` is clipped so that ``qdot_i + qddot_i period`` is
    within the speed limit and keeps ``q_i`` inside its range over the next period; without a period, a joint
    at or beyond its speed limit, or moving out of a range limit it has reached, gets no acceleration that
    pushes it further. :attr:`AccelerationClikResult.limited` says when. Non-finite inputs raise
    :class:`ControllerError` naming the argument.
    """

    def __init__(
        self,
        model: RobotModel,
        task: DriftTask,
        *,
        method: str = "pseudoinverse",
        stiffness: ArrayLike | float = 100.0,
        damping: ArrayLike | float = 20.0,
        weights: ArrayLike | float = 1.0,
        nullspace_gain: float = 1.0,
        nullspace_damping: float = 10.0,
        **options: Unpack[ResolutionOptions],
    ) -> None:
        objectives, thresholds, max_joint_velocity, period = self._read_options(options)
        if method not in METHODS:
            raise ControllerError(f"unknown method {method!r}; valid methods: {', '.join(METHODS)}")
        if not hasattr(task, "drift"):
            raise ControllerError("the acceleration-level CLIK needs a task with drift(model, q, qdot)")
        self.kp = np.broadcast_to(np.asarray(stiffness, dtype=np.float64), (task.dim,)).copy()
        self.kd = np.broadcast_to(np.asarray(damping, dtype=np.float64), (task.dim,)).copy()
        for name, value in (
            ("stiffness", self.kp),
            ("damping", self.kd),
            ("nullspace_gain", nullspace_gain),
            ("nullspace_damping", nullspace_damping),
        ):
            if not np.all(np.isfinite(value)) or np.any(np.asarray(value) < 0.0):
                raise ControllerError(f"{name} must be finite and >= 0")
        self._set_resolution(model, task, method, weights, nullspace_gain)
        self.nullspace_damping = float(nullspace_damping)
        self._set_options(objectives, thresholds, max_joint_velocity, period)

    def step(
        self,
        q: ArrayLike,
        qdot: ArrayLike,
        target: ArrayLike,
        target_velocity: ArrayLike,
        target_acceleration: ArrayLike,
    ) -> AccelerationClikResult:
        """Joint accelerations for the state ``(q, qdot)`` and the reference ``(w_d, wdot_d, wddot_d)``."""
        q = check_configuration(q, "q")  # shape checked by model.update inside task.drift
        qdot = check_finite(qdot, "qdot")
        if qdot.shape != (self.model.nv,):
            raise ControllerError(f"qdot must be finite with shape ({self.model.nv},)")
        target = check_finite(target, "target")
        target_velocity = check_finite(target_velocity, "target_velocity")
        target_acceleration = check_finite(target_acceleration, "target_acceleration")
        drift = self.task.drift(self.model, q, qdot)
        error = self.task.error(self.model, target)
        jacobian = self.task.jacobian(self.model)
        velocity_error = target_velocity - jacobian @ qdot
        acceleration = target_acceleration + self.kd * velocity_error + self.kp * error  # (5.19)
        value, gradient = sum_objectives(self.objectives, self.model, q)
        z = self.nullspace_gain * gradient + self.nullspace_damping * self.weights.apply(qdot)
        res = self._resolve(jacobian, acceleration - drift, z)
        qddot, limited = self.bound(res.x, q, qdot)
        return AccelerationClikResult(
            qddot,
            error,
            velocity_error,
            float(np.linalg.norm(error)),
            res.sigma_min,
            res.damping,
            value,
            res.success,
            res.status,
            limited,
        )

    def bound(
        self, qddot: NDArray[np.float64], q: NDArray[np.float64], qdot: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], bool]:
        """``(qddot, limited)``: the accelerations held to the speed limits and joint ranges (class docstring)."""
        bounds = self.bounds
        if not bounds.active:
            return qddot, False
        high = bounds.max_velocity.copy()
        low = -high
        if bounds.q_index.size:
            range_low, range_high = bounds.velocity_range(q)
            low[bounds.v_index] = np.maximum(low[bounds.v_index], range_low)
            high[bounds.v_index] = np.minimum(high[bounds.v_index], range_high)
        if bounds.period is not None:
            bounded = np.minimum(np.maximum(qddot, (low - qdot) / bounds.period), (high - qdot) / bounds.period)
        else:
            bounded = np.where(qdot >= high, np.minimum(qddot, 0.0), qddot)
            bounded = np.where(qdot <= low, np.maximum(bounded, 0.0), bounded)
        if np.array_equal(bounded, qddot):
            return qddot, False
        return bounded, True
